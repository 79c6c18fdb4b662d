"""Curves over one swept axis: a variable as a line, Poincare samples as a bifurcation diagram."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.axes import Axes

from impactbeams.plotting.labels import axis_label, display_units
from impactbeams.plotting.missing import add_missing_legend, missing_note, shade_missing
from impactbeams.plotting.scales import (
    CENTRED,
    category_names,
    edges,
    find_categories,
    fixed_labels,
    grid_axis,
    set_log_ticks,
    use_log,
)
from impactbeams.plotting.selection import OVERLAID_DIMENSIONS, SAMPLE_DIMENSIONS

if TYPE_CHECKING:
    from impactbeams.plotting.arrays import PlainArray, PlainDataset

# a stepped sweep's directions: up (increasing) in blue over down in red, whose dots are drawn
# larger, so that where both reach the same response both colours show
DIRECTION_STYLES = {"up": {"color": "tab:blue", "zorder": 3},
                    "down": {"color": "tab:red", "zorder": 2}}
DIRECTION_DOTS = {"up": 2.5, "down": 5.0}  # times a single diagram's dots

_MARKED = 100  # lines over at most this many grid values mark each value


def y_units(field: PlainArray) -> tuple[float, str]:
    """The factor and units ``field``'s values are drawn in on a y axis (`display_units`)."""
    return display_units(np.asarray(field.values, dtype=float), field.attrs.get("units", ""))


def draw_line(axes: Axes, dataset: PlainDataset, variable: str, scale: str | None = None,
              units: tuple[float, str] | None = None, **style: Any) -> None:
    """``variable`` of one dimension against its grid values; grey bands where it is NaN.

    ``scale`` ("log", "linear" or None for automatic) is the y axis'. Integer data with few
    values (a period, a flag) are drawn as steps with named levels; lengths and forces in the
    prefixed units of their size (``units``: the factor and units, default `y_units`).
    ``style``: of the curve (colour, label).
    """
    field = dataset[variable]
    x, x_log = grid_axis(axes, "x", dataset[field.dims[0]])
    values = np.asarray(field.values, dtype=float)
    finite = values[np.isfinite(values)]
    levels = find_categories(field, finite) if finite.size else None
    factor, unit = (1.0, field.attrs.get("units", "")) if levels is not None else (
        units or y_units(field))
    values, finite = factor * values, factor * finite
    axes.set_ylabel(axis_label(field, unit))
    marker = "." if x.size <= _MARKED else None
    if levels is not None:
        axes.plot(x, values, drawstyle="steps-mid", marker=marker, lw=1, **style)
        axes.yaxis.set_ticks(levels)
        axes.yaxis.set_major_formatter(fixed_labels(levels, category_names(field, levels)))
    else:
        axes.plot(x, values, marker=marker, lw=1, **style)
        if finite.size and use_log(finite, scale, variable):
            axes.set_yscale("log")
            set_log_ticks(axes.yaxis, float(finite.min()), float(finite.max()))
        else:
            axes.yaxis.get_major_formatter().set_useMathText(True)
            if variable in CENTRED or (finite.size and finite.min() < 0 < finite.max()):
                axes.axhline(0.0, color="0.6", lw=0.6, zorder=0)
    missing = np.isnan(values)
    if missing.any():
        shade_missing(axes, edges(x, x_log), missing)
        add_missing_legend(axes, missing_note(dataset, variable))


def draw_bifurcation(axes: Axes, dataset: PlainDataset, variable: str, size_factor: float = 1.0,
                     units: tuple[float, str] | None = None, **style: Any) -> None:
    """Every sample of ``variable`` (one axis plus a sample dimension) as a dot at its grid value.

    A bifurcation diagram when the samples are stroboscopic (Poincare) samples of the steady
    response: one dot per forcing period and grid value; NaN samples are left out. ``style``:
    of the dots (default black), ``size_factor`` times their size; ``units`` as `draw_line`'s.
    """
    field = dataset[variable]
    factor, unit = units or y_units(field)
    (x_name,) = [d for d in field.dims if d not in SAMPLE_DIMENSIONS]
    x, _ = grid_axis(axes, "x", dataset[x_name])
    samples = np.asarray(field.transpose(x_name, ...).values, dtype=float)
    xs = np.repeat(x, samples[0].size)
    ys = factor * samples.ravel()
    drawn = np.isfinite(ys)
    # dots small enough that 10^5 of them still show structure, large enough for 10^3
    size = size_factor * float(np.clip(150.0 / np.sqrt(max(drawn.sum(), 1)), 0.5, 3.0))
    axes.plot(xs[drawn], ys[drawn], ls="none", marker=".", ms=size, mew=0, rasterized=True,
              **{"color": "k", **style})
    axes.set_ylabel(axis_label(field, unit))
    axes.yaxis.get_major_formatter().set_useMathText(True)


def draw_directions(axes: Axes, dataset: PlainDataset, variable: str,
                    scale: str | None = None) -> None:
    """A stepped sweep's directions overlaid over its one swept axis, one colour each.

    Samples along ``period`` as bifurcation diagrams (the down sweep's dots drawn larger, under
    the up sweep's: where both reach one response both colours show), other variables as lines;
    a legend names the directions.
    """
    (dimension,) = [d for d in dataset[variable].dims if d in OVERLAID_DIMENSIONS]
    sampled = any(d in dataset[variable].dims for d in SAMPLE_DIMENSIONS)
    units = y_units(dataset[variable])  # one scale for both directions
    for direction in dataset[dimension].values:
        row = dataset.sel({dimension: direction})
        style = {**DIRECTION_STYLES.get(str(direction), {}), "label": f"swept {direction}"}
        if sampled:
            draw_bifurcation(axes, row, variable, DIRECTION_DOTS.get(str(direction), 1.0),
                             units, **style)
        else:
            draw_line(axes, row, variable, scale, units, **style)
    # the dots of a dense diagram are too small for the legend
    axes.legend(loc="best", fontsize="small", markerscale=4.0 if sampled else 1.0)
