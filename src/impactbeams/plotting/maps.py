"""Maps of a variable over two swept axes (the paper's Fig. 5): every cell drawn, grey if NaN."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib.colors
import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.colorbar import Colorbar
from matplotlib.contour import ContourSet
from matplotlib.path import Path

from impactbeams.params import ParameterError
from impactbeams.plotting.labels import axis_label, format_number
from impactbeams.plotting.missing import add_missing_legend, missing_note
from impactbeams.plotting.scales import (
    MISSING_COLOUR,
    ColourScale,
    colour_scale,
    edges,
    grid_axis,
    nice_levels,
)


def draw_map(axes: Axes, dataset: xr.Dataset, variable: str, scale: str | None = None,
             contours: int | Sequence[float] | None = None) -> Colorbar | None:
    """Colour map of the 2-D ``variable`` on ``axes``, with its colour bar; returns the bar.

    The variable's first dimension is the x axis, its second the y axis; log grid axes stay
    log. ``scale`` ("log", "linear" or None for automatic) is the colour scale of a continuous
    variable; ``contours`` adds labelled contour lines: a number of round levels, or levels.
    A variable without any value (no cell impacts) is drawn all grey, without a colour bar
    (None is returned).
    """
    field = dataset[variable]
    x_name, y_name = field.dims
    x, x_log = grid_axis(axes, "x", dataset[x_name])
    y, y_log = grid_axis(axes, "y", dataset[y_name])
    cells = (edges(x, x_log), edges(y, y_log))
    values = np.asarray(field.transpose(y_name, x_name).values, dtype=float)
    if not np.isfinite(values).any():
        if contours is not None:
            raise ParameterError(f"contour lines need values: {variable} has none (all NaN)")
        axes.pcolormesh(*cells, np.zeros_like(values), rasterized=True,
                        cmap=matplotlib.colors.ListedColormap([MISSING_COLOUR]))
        return None
    colours = colour_scale(field, scale)
    values = colours.encode(values)
    mesh = axes.pcolormesh(*cells, np.ma.masked_invalid(values),
                           norm=colours.norm, cmap=colours.cmap, rasterized=True)
    bar = axes.get_figure().colorbar(mesh, ax=axes, shrink=0.9, anchor=(0.0, 1.0))
    bar.set_ticks(colours.ticks)
    bar.formatter = colours.formatter
    if not colours.log:
        bar.minorticks_off()
    bar.set_label(axis_label(field))
    if contours is not None:
        _contour_lines(axes, bar, (x, y, values), colours, contours, variable)
    if np.isnan(values).any():
        add_missing_legend(bar.ax, missing_note(dataset, variable), below=True)
    return bar


def _contour_lines(axes: Axes, bar: Colorbar, grid: tuple[np.ndarray, np.ndarray, np.ndarray],
                   colours: ColourScale, contours: int | Sequence[float], variable: str) -> None:
    """Labelled black contour lines at round levels (or the given ones), marked on the bar."""
    if colours.categories is not None:
        raise ParameterError(f"contour lines need a continuous variable; {variable} is drawn "
                             "as categories")
    x, y, values = grid
    vmin, vmax = float(np.nanmin(values)), float(np.nanmax(values))
    if isinstance(contours, int):
        levels = nice_levels(vmin, vmax, contours, colours.log)
    else:
        levels = np.array([v for v in contours if vmin <= v <= vmax])
    if levels.size == 0:
        raise ParameterError(f"no contour level lies within the range of {variable}, "
                             f"{vmin:g} to {vmax:g}")
    lines = axes.contour(x, y, np.ma.masked_invalid(values), levels=levels, colors="k",
                         linewidths=0.6)
    axes.clabel(lines, fmt=format_number, fontsize="x-small", inline_spacing=2,
                manual=label_positions(axes, lines))
    bar.add_lines(lines)


def label_positions(axes: Axes, lines: ContourSet) -> list[tuple[float, float]]:
    """One label per level, each as far as it can be from the others and the frame.

    Labels placed by default (one per line piece) pile up where levels crowd together, as
    along Fig. 5a's boundary of the impact region; here each level gets a single label on its
    longest line (not on a fragment of a jagged boundary), at the point farthest, in axes
    fractions, from the labels already placed and from the axes' frame. Returns data
    coordinates (for ``clabel(manual=...)``).
    """
    to_fraction = axes.transData + axes.transAxes.inverted()
    placed: list[np.ndarray] = []
    positions = []
    for path in lines.get_paths():
        if not len(path.vertices):
            continue
        starts = np.flatnonzero(path.codes == Path.MOVETO)[1:] if path.codes is not None else []
        pieces = np.split(to_fraction.transform(path.vertices), starts)
        points = max(pieces, key=lambda p: np.hypot(*np.diff(p, axis=0).T).sum())
        clearance = np.min(np.concatenate([points, 1.0 - points], axis=1), axis=1)
        for label in placed:
            clearance = np.minimum(clearance, np.hypot(*(points - label).T))
        best = points[int(np.argmax(clearance))]
        placed.append(best)
        positions.append(tuple(to_fraction.inverted().transform(best)))
    return positions
