"""Bifurcation curves in the plane of two parameters (`impactbeams.continuation.twoparameter`).

The first parameter across, the second up, in the prefixed units of their size; the orbits
solid where stable but for the bifurcating multiplier (`curve_stable`), dashed where not; the
codimension-two points marked and labelled where a label fits (`branches.place_labels`), the
start circled. Draw several curves on one axes by calling `draw_curve` for each.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.axes import Axes

from impactbeams.plotting.branches import _draw_branch, place_labels
from impactbeams.plotting.labels import axis_label, display_units
from impactbeams.variables import CURVE_EVENTS

MARKERS = {"end": ("s", "E"), "turning_point": ("v", "T"), "cusp": ("D", "CP"),
           "grazing": ("^", "G")}
KIND_NAMES = {"grazing": "grazing", "fold": "fold", "period_doubling": "period doubling",
              "neimark_sacker": "Neimark-Sacker"}


def draw_curve(axes: Axes, dataset: xr.Dataset, colour: str = "C0",
               label_events: bool = True) -> None:
    """Draw one curve's Dataset on ``axes``: the first parameter across, the second up.

    Its codimension-two points are marked (and labelled where a label fits if
    ``label_events``; place them after everything is drawn, since the labels are placed on
    the laid-out axes).
    """
    first, second = dataset.attrs["curve_parameters"].split()
    (x_factor, x_units) = display_units(dataset[first].values, dataset[first].attrs["units"])
    (y_factor, y_units) = display_units(dataset[second].values,
                                        dataset[second].attrs["units"])
    x, y = x_factor * dataset[first].values, y_factor * dataset[second].values
    # one line in the parameters' plane: drawn as a period-1 branch is (full width)
    _draw_branch(axes, x, y[:, None], dataset.curve_stable.values, np.ones(x.size, dtype=bool),
                 colour, f"{KIND_NAMES[dataset.attrs['curve_kind']]} curve", period=1)
    axes.plot(x[:1], y[:1], "o", color=colour, markerfacecolor="none", markersize=7)
    codes = dataset.curve_event.values
    labelled = []
    for code in np.unique(codes[codes > 0]):
        name = CURVE_EVENTS[code]
        marker, text = MARKERS[name]
        at = codes == code
        axes.plot(x[at], y[at], marker, color="k", markersize=6, linestyle="none")
        labelled += [(px, py, text) for px, py in zip(x[at], y[at], strict=True)]
    axes.set_xlabel(axis_label(dataset[first], x_units))
    axes.set_ylabel(axis_label(dataset[second], y_units))
    axes.ticklabel_format(useOffset=False)
    if label_events:
        place_labels(axes, labelled)
