"""A basin map: each initial state coloured by the attractor it settles on, with their legend.

Drawn from `impactbeams.orbits.basins`' Dataset: over the plane of initial states a colour per
attractor (grey where a state did not settle, black where its run stopped), as cells of the
grid or as points of a random sample; in the tip plane the attractors' own stroboscopic points
(y1, v1 at forcing phase 0) are marked on it, in the same coordinates. The legend names each
attractor by its period, contacts per orbit and basin fraction with its standard error (and,
for random states, its confidence interval).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.patches import Patch

from impactbeams.params import ParameterError
from impactbeams.plotting.labels import axis_label, display_units
from impactbeams.variables import BASIN_LABELS, basin_fraction_text

if TYPE_CHECKING:
    import xarray as xr

# the label codes that name no attractor (-1 not settled, -2 stopped) and their colours
_STATUS_COLOURS = {-1: "0.75", -2: "black"}
_TIP_PLANE = ("start_tip_deflection", "start_tip_velocity")


def draw_basins(axes: Axes, dataset: xr.Dataset) -> None:
    """The basin map of ``dataset`` on ``axes`` with the attractors' legend."""
    count = dataset.sizes["attractor"]
    colours = [f"C{k % 10}" for k in range(count)]
    codes = sorted(BASIN_LABELS)  # -2, -1
    cmap = ListedColormap([_STATUS_COLOURS[code] for code in codes] + colours)
    norm = BoundaryNorm(np.arange(codes[0] - 0.5, count + 0.5), cmap.N)
    labels = dataset["basin"]
    first, second = (_sampled_plane(dataset) if "cell" in labels.dims
                     else (dataset[name] for name in labels.dims))
    # lengths in the prefixed unit of their size (µm), as every plot draws them
    (x_factor, x_units), (y_factor, y_units) = (
        display_units(coordinate.values, coordinate.attrs.get("units", ""))
        for coordinate in (first, second))
    x, y = x_factor * first.values, y_factor * second.values
    if "cell" in labels.dims:
        axes.scatter(x, y, c=labels.values, cmap=cmap, norm=norm, s=12, linewidths=0)
    else:
        axes.pcolormesh(x, y, labels.values.T, cmap=cmap, norm=norm, shading="nearest")
    axes.set_xlabel(axis_label(first, x_units))
    axes.set_ylabel(axis_label(second, y_units))
    if (first.name, second.name) == _TIP_PLANE:
        for k in range(count):
            axes.plot(x_factor * dataset.attractor_section_deflection1[k].values,
                      y_factor * dataset.attractor_section_velocity1[k].values, "o",
                      color=colours[k], markeredgecolor="white", markersize=7)
    handles = [Patch(color=colours[k], label=_attractor_label(dataset, k)) for k in range(count)]
    handles += [Patch(color=_STATUS_COLOURS[code], label=f"{BASIN_LABELS[code].replace('_', ' ')}"
                      f" {dataset.attrs[BASIN_LABELS[code] + '_fraction']:.3g}")
                for code in codes[::-1] if np.any(labels.values == code)]
    axes.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0),
                title=f"attractors ({dataset.attrs['cells']} initial states)")


def _attractor_label(dataset: xr.Dataset, k: int) -> str:
    """``k: period p, c contacts per orbit, fraction f ± e`` (``given``: a caller's orbit).

    For states sampled rather than a grid, the fraction's confidence interval too.
    """
    given = " (given)" if int(dataset.attractor_given[k]) else ""
    contacts = int(dataset.attractor_contacts[k])
    return (f"{k}{given}: period {int(dataset.attractor_period[k])}, {contacts} "
            f"contact{'' if contacts == 1 else 's'} per orbit, fraction "
            f"{basin_fraction_text(dataset, k, 'cell' in dataset['basin'].dims)}")


def _sampled_plane(dataset: xr.Dataset) -> tuple[xr.DataArray, xr.DataArray]:
    """The two plane coordinates of a sample of states along ``cell``."""
    plane = [name for name in dataset.coords if dataset[name].dims == ("cell",)
             and name != "cell"]
    if len(plane) != 2:
        raise ParameterError("a basin map needs a plane: this Dataset holds a list of initial "
                             "states without plane coordinates (draw its variables instead, "
                             "e.g. --var basin_fraction)")
    return dataset[plane[0]], dataset[plane[1]]
