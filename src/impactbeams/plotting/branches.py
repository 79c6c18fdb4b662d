"""Frequency-response curves: a continuation's branches against the continued parameter.

Stable orbits solid, unstable dashed, one colour per branch, bifurcations marked and
labelled; optionally over a brute-force bifurcation diagram (its stroboscopic samples as grey
dots, against the branches' own samples ``section_deflection_1``: p curves for a period-p
branch, one per section t = k T).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.axes import Axes

from impactbeams.params import ParameterError
from impactbeams.plotting.labels import axis_label
from impactbeams.variables import BIFURCATIONS

DEFAULT_MEASURE = "tip_amplitude_1"
OVERLAY_MEASURE = "section_deflection_1"  # what a diagram's poincare_deflection1 shows
DIAGRAM_SAMPLES = "poincare_deflection1"
ALONG = (("branch_point",), ("branch_point", "section"))  # what can be drawn
MARKERS = {"fold": ("o", "F"), "period_doubling": ("s", "PD"), "neimark_sacker": ("D", "NS"),
           "grazing": ("^", "G"), "branch_point": ("v", "BP"), "contact_merge": ("<", "M"),
           "contact_split": (">", "S"), "chatter": ("x", "C")}


def draw_branches(axes: Axes, dataset: xr.Dataset, variable: str | None = None,
                  diagram: xr.Dataset | None = None) -> None:
    """Draw ``variable`` (default max |y1|, or y1 on the section over a ``diagram``)."""
    parameter = dataset.attrs["continued_parameter"]
    name = variable or (OVERLAY_MEASURE if diagram is not None else DEFAULT_MEASURE)
    if name not in dataset or dataset[name].dims not in ALONG:
        raise ParameterError(f"--var {name!r} is not a variable along the branch; choose one "
                             "of " + ", ".join(v for v in dataset.data_vars
                                                if dataset[v].dims in ALONG))
    if diagram is not None:
        _draw_diagram(axes, diagram, parameter)
    x, y = dataset[parameter].values, dataset[name].values.reshape(dataset.branch_point.size, -1)
    for branch in np.unique(dataset.branch.values):
        _draw_branch(axes, x, y, dataset.stable.values, dataset.branch.values == branch,
                     f"C{int(branch)}", f"branch {int(branch)} (period "
                     f"{int(dataset.orbit_period.values[dataset.branch.values == branch][0])})")
    _mark_bifurcations(axes, x, y[:, 0], dataset.bifurcation.values)
    axes.set_xlabel(axis_label(dataset[parameter]))
    axes.set_ylabel(axis_label(dataset[name]))
    axes.plot([], [], "k-", label="stable")
    axes.plot([], [], "k--", label="unstable")
    axes.legend(fontsize="small", loc="best")


def _draw_branch(axes: Axes, x: np.ndarray, y: np.ndarray, stable: np.ndarray,
                 mask: np.ndarray, colour: str, label: str) -> None:
    """Runs of equal stability, each joined to the next point so that the curve is whole.

    One curve per column of ``y`` (a section of the orbit; NaN columns draw nothing).
    """
    index = np.flatnonzero(mask)
    runs = np.split(index, np.flatnonzero(np.diff(stable[index])) + 1)
    for run in runs:
        joined = np.append(run, run[-1] + 1) if run[-1] + 1 <= index[-1] else run
        for column in range(y.shape[1]):
            axes.plot(x[joined], y[joined, column], color=colour,
                      linestyle="-" if stable[run[0]] else "--", linewidth=1.4,
                      label=label if run is runs[0] and column == 0 else None)


def _mark_bifurcations(axes: Axes, x: np.ndarray, y: np.ndarray, codes: np.ndarray) -> None:
    for code in np.unique(codes[codes > 0]):
        marker, short = MARKERS[BIFURCATIONS[code]]
        where = np.flatnonzero(codes == code)
        axes.plot(x[where], y[where], marker, color="k", markerfacecolor="none",
                  label=f"{short}: {BIFURCATIONS[code].replace('_', ' ')}")
        for i in where:
            axes.annotate(short, (x[i], y[i]), textcoords="offset points", xytext=(4, 4),
                          fontsize="x-small")


def _draw_diagram(axes: Axes, diagram: xr.Dataset, parameter: str) -> None:
    """The brute-force diagram's samples along the same parameter, grey dots."""
    if DIAGRAM_SAMPLES not in diagram or diagram[DIAGRAM_SAMPLES].dims != (parameter, "period"):
        raise ParameterError(f"--over needs a bifurcation diagram over {parameter!r}: a "
                             f"long-time sweep's {DIAGRAM_SAMPLES} along ({parameter}, period)")
    samples = diagram[DIAGRAM_SAMPLES]
    x = np.broadcast_to(diagram[parameter].values[:, None], samples.shape)
    axes.plot(x.ravel(), samples.values.ravel(), ".", markersize=3, color="0.55", zorder=0,
              label="from rest (long-time sweep)")
