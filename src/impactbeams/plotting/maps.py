"""Maps of a variable over two swept axes (the paper's Fig. 5): every cell drawn, grey if NaN."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING

import matplotlib.colors
import numpy as np
from matplotlib.axes import Axes
from matplotlib.colorbar import Colorbar
from matplotlib.contour import ContourSet
from matplotlib.image import BboxImage
from matplotlib.path import Path
from matplotlib.transforms import Bbox, TransformedBbox

from impactbeams.params import ParameterError
from impactbeams.plotting.labels import axis_label, display_units, format_number
from impactbeams.plotting.missing import add_missing_legend, missing_note
from impactbeams.plotting.scales import (
    MISSING_COLOUR,
    ColourScale,
    colour_scale,
    edges,
    grid_axis,
    nice_levels,
)

if TYPE_CHECKING:
    from matplotlib.cm import ScalarMappable

    from impactbeams.plotting.arrays import PlainArray, PlainDataset

# cells equal on the axes within this fraction of their width (relative to their mean): a
# boundary then lies within cells x UNIFORM widths of the mesh's, 0.01 of a cell for 10^4 cells
UNIFORM = 1e-6


def draw_map(axes: Axes, dataset: PlainDataset, variable: str, scale: str | None = None,
             contours: int | Sequence[float] | None = None, *,
             fill: bool = True) -> Colorbar | None:
    """Colour map of the 2-D ``variable`` on ``axes``, with its colour bar; returns the bar.

    The variable's first dimension is the x axis, its second the y axis; log grid axes stay
    log. ``scale`` ("log", "linear" or None for automatic) is the colour scale of a continuous
    variable; ``contours`` adds labelled contour lines: a number of round levels, or levels
    (in the variable's units). Lengths, forces and times are drawn in the prefix of their
    size (`display_units`: a first-impact time in ms), the bar labelled so.
    A variable without any value (no cell impacts) is drawn all grey, without a colour bar
    (None is returned). ``fill``: as `draw_cells` (False for a map under layers that may
    reach past its edges).
    """
    field, factor = _in_display_units(dataset[variable])
    if contours is not None and not isinstance(contours, int):
        contours = [level * factor for level in contours]
    x_name, y_name = field.dims
    x, x_log = grid_axis(axes, "x", dataset[x_name])
    y, y_log = grid_axis(axes, "y", dataset[y_name])
    cells = (edges(x, x_log), edges(y, y_log))
    values = np.asarray(field.transpose(y_name, x_name).values, dtype=float)
    if not np.isfinite(values).any():
        if contours is not None:
            raise ParameterError(f"contour lines need values: {variable} has none (all NaN)")
        draw_cells(axes, cells, (x_log, y_log), np.zeros_like(values), fill=fill,
                   cmap=matplotlib.colors.ListedColormap([MISSING_COLOUR]))
        return None
    colours = colour_scale(field, scale)
    values = colours.encode(values)
    mesh = draw_cells(axes, cells, (x_log, y_log), np.ma.masked_invalid(values), fill=fill,
                      norm=colours.norm, cmap=colours.cmap)
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


def _in_display_units(field: PlainArray) -> tuple[PlainArray, float]:
    """``field`` in the units it is drawn in (`display_units`), and the factor applied."""
    factor, units = display_units(np.asarray(field.values, dtype=float),
                                  field.attrs.get("units", ""))
    if factor == 1.0:
        return field, factor
    return dataclasses.replace(field, values=field.values * factor,
                               attrs={**field.attrs, "units": units}), factor


def draw_cells(axes: Axes, cells: tuple[np.ndarray, np.ndarray], logs: tuple[bool, bool],
               values: np.ndarray, fill: bool = True, **colours: object) -> ScalarMappable:
    """Every cell of ``values`` (y, x) between its ``cells`` edges (x, y) in its colour.

    ``logs``: whether the x and y axes are log. On a regular grid (cells equal on the axes,
    in log on a log axis: linspace and geomspace axes, named choices) an image, each screen
    pixel the colour of the cell under its centre: the picture of a mesh of quadrilaterals,
    which is drawn otherwise, at a small part of its cost (10^6 cells: 10 ms, not 0.3 s).
    The axes' limits are the outer edges. ``fill``: the image is the axes' own box (the
    limits stay the edges: the cheapest); False: it is its cells' box in data coordinates, so
    that a caller may widen the limits (the image then covers its cells only).
    ``colours``: norm and cmap.
    """
    if not all(_uniform(e, log) for e, log in zip(cells, logs, strict=True)):
        return axes.pcolormesh(*cells, values, rasterized=True, **colours)
    extent = []
    for axis, (which, e) in enumerate(zip("xy", cells, strict=True)):
        if e[-1] < e[0]:  # a descending grid: the axis ascends, as a mesh's would
            values, e = np.flip(values, axis=1 - axis), e[::-1]
        (axes.set_xlim if which == "x" else axes.set_ylim)(e[0], e[-1])
        extent.append((e[0], e[-1]))
    # the limits are the outer edges: the image fills the axes, or its cells' box wherever
    # the limits go (on a log axis too: its cells are equal in log, as the screen's pixels)
    (x0, x1), (y0, y1) = extent
    box = axes.bbox if fill else TransformedBbox(Bbox.from_extents(x0, y0, x1, y1),
                                                 axes.transData)
    image = BboxImage(box, origin="lower", interpolation="nearest",
                      interpolation_stage="data", **colours)
    image.set_data(values)
    axes.add_artist(image)
    return image


def _uniform(cell_edges: np.ndarray, log: bool) -> bool:
    """Whether cells of ``cell_edges`` are equal on their axis (in log on a log axis)."""
    widths = np.diff(np.log(cell_edges) if log else cell_edges)
    return bool(np.all(np.abs(widths - widths.mean()) <= UNIFORM * np.abs(widths.mean())))


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
