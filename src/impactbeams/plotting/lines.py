"""Curves over one swept axis: a variable as a line, Poincare samples as a bifurcation diagram."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.axes import Axes

from impactbeams.plotting.labels import axis_label
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
from impactbeams.plotting.selection import SAMPLE_DIMENSIONS

_MARKED = 100  # lines over at most this many grid values mark each value


def draw_line(axes: Axes, dataset: xr.Dataset, variable: str, scale: str | None = None) -> None:
    """``variable`` of one dimension against its grid values; grey bands where it is NaN.

    ``scale`` ("log", "linear" or None for automatic) is the y axis'. Integer data with few
    values (a period, a flag) are drawn as steps with named levels.
    """
    field = dataset[variable]
    x, x_log = grid_axis(axes, "x", dataset[field.dims[0]])
    values = np.asarray(field.values, dtype=float)
    finite = values[np.isfinite(values)]
    axes.set_ylabel(axis_label(field))
    marker = "." if x.size <= _MARKED else None
    levels = find_categories(field, finite) if finite.size else None
    if levels is not None:
        axes.plot(x, values, drawstyle="steps-mid", marker=marker, lw=1)
        axes.yaxis.set_ticks(levels)
        axes.yaxis.set_major_formatter(fixed_labels(levels, category_names(field, levels)))
    else:
        axes.plot(x, values, marker=marker, lw=1)
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


def draw_bifurcation(axes: Axes, dataset: xr.Dataset, variable: str) -> None:
    """Every sample of ``variable`` (one axis plus a sample dimension) as a dot at its grid value.

    A bifurcation diagram when the samples are stroboscopic (Poincare) samples of the steady
    response: one dot per forcing period and grid value; NaN samples are left out.
    """
    field = dataset[variable]
    (x_name,) = [d for d in field.dims if d not in SAMPLE_DIMENSIONS]
    x, _ = grid_axis(axes, "x", dataset[x_name])
    samples = np.asarray(field.transpose(x_name, ...).values, dtype=float)
    xs = np.repeat(x, samples[0].size)
    ys = samples.ravel()
    drawn = np.isfinite(ys)
    # dots small enough that 10^5 of them still show structure, large enough for 10^3
    size = float(np.clip(150.0 / np.sqrt(max(drawn.sum(), 1)), 0.5, 3.0))
    axes.plot(xs[drawn], ys[drawn], ls="none", marker=".", ms=size, mew=0, color="k",
              rasterized=True)
    axes.set_ylabel(axis_label(field))
    axes.yaxis.get_major_formatter().set_useMathText(True)
