"""Colour scales and ticks: round tick values, decades on log scales, categories, zero-centred.

A colour bar always gets several labelled ticks at round values (1, 2, 2.5, 5 x 10^k on a
linear scale; decades, or 1-2-5 / 1-3 steps when the range holds few decades, on a log scale).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import matplotlib.colors
import matplotlib.ticker
import numpy as np
from matplotlib.axes import Axes
from matplotlib.axis import Axis

from impactbeams.params import ParameterError
from impactbeams.plotting.labels import axis_label, tick_labels
from impactbeams.variables import VARIABLES

if TYPE_CHECKING:
    from impactbeams.plotting.arrays import PlainArray

# a colour scale is logarithmic by default when positive data span more than this many decades
LOG_DECADES = 1.5
MISSING_COLOUR = "0.85"  # light grey: cells without a value (NaN), e.g. no impact by t_max
NONE_COLOUR = "0.35"  # dark grey: the category "none" (e.g. no period detected)
SEQUENTIAL, DIVERGING = "viridis", "RdBu_r"
# variables whose sign matters, drawn with a diverging colour map centred at 0 whatever
# their range (a Lyapunov exponent: negative is stable, positive chaotic)
CENTRED = frozenset({"lyapunov_exponent"})
# names of categories for variables without CF flag_values/flag_meanings attributes
CATEGORY_NAMES = {"response_period": {0: "none"}}
# integer data with at most this many distinct values are categories: one colour of tab10
# each, and dark grey for "none"
MAX_CATEGORIES = 10
_LOG_STEPS = ((1.0,), (1.0, 3.0), (1.0, 2.0, 5.0), (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0))
TICKS = 6  # wanted number of ticks on a scale without 4 decades (4 to 8 in practice)
MAX_DECADE_TICKS = 8  # decades beyond this are thinned (every second one, ...)


@dataclasses.dataclass(frozen=True)
class ColourScale:
    """How values become colours: norm, colour map and the colour bar's ticks and labels.

    ``categories``: for categorical data, the category values (data are drawn by their
    index in it, see `encode`); None otherwise.
    """

    norm: matplotlib.colors.Normalize
    cmap: matplotlib.colors.Colormap
    ticks: np.ndarray
    formatter: matplotlib.ticker.Formatter
    log: bool = False
    categories: np.ndarray | None = None

    def encode(self, values: np.ndarray) -> np.ndarray:
        """Values as drawn: category indices for categorical data (NaN kept), else as is."""
        if self.categories is None:
            return values
        codes = np.searchsorted(self.categories, values).astype(float)
        return np.where(np.isfinite(values), codes, np.nan)


def use_log(values: np.ndarray, scale: str | None, what: str) -> bool:
    """Whether ``values`` go on a log scale: ``scale`` if given, else wide positive ranges.

    Raises ParameterError for ``scale = "log"`` with values <= 0 (``what`` names them).
    """
    finite = values[np.isfinite(values)]
    positive = finite.size > 0 and finite.min() > 0
    if scale == "log" and not positive:
        raise ParameterError(f"--log needs positive values; {what} has values <= 0 "
                             "(or none): use --linear")
    if scale is not None:
        return scale == "log"
    return bool(positive and math.log10(finite.max() / finite.min()) > LOG_DECADES)


def nice_levels(vmin: float, vmax: float, n: int, log: bool) -> np.ndarray:
    """About ``n`` round values within [vmin, vmax] (contour levels)."""
    if log:
        levels = _log_levels(vmin, vmax, n)
        if levels.size >= 2:
            return levels
    locator = matplotlib.ticker.MaxNLocator(nbins=n, steps=[1, 2, 2.5, 5, 10],
                                            min_n_ticks=min(n, 4))
    return _inside(locator.tick_values(vmin, vmax), vmin, vmax)


def tick_values(vmin: float, vmax: float, log: bool) -> np.ndarray:
    """Tick values of a scale over [vmin, vmax]: decades when a log range holds 4 or more."""
    if log:
        decades = _steps(vmin, vmax, (1.0,))
        if decades.size >= 4:
            return decades[::math.ceil(decades.size / MAX_DECADE_TICKS)]
    return nice_levels(vmin, vmax, TICKS, log)


def _log_levels(vmin: float, vmax: float, n: int) -> np.ndarray:
    """Decades (thinned when many), or finer 1-3 / 1-2-5 steps: the count nearest ``n``."""
    best = np.array([])
    for steps in _LOG_STEPS:
        candidates = _steps(vmin, vmax, steps)
        stride = max(1, round(candidates.size / n)) if len(steps) == 1 else 1
        levels = candidates[::stride]
        if abs(levels.size - n) < abs(best.size - n):
            best = levels
    return best


def _steps(vmin: float, vmax: float, steps: tuple[float, ...]) -> np.ndarray:
    """The values ``steps`` x 10^k within [vmin, vmax] (vmin > 0), ascending."""
    decades = np.arange(math.floor(math.log10(vmin)), math.ceil(math.log10(vmax)) + 1)
    return _inside((np.array(steps)[None, :] * 10.0 ** decades[:, None]).ravel(), vmin, vmax)


def _inside(values: np.ndarray, vmin: float, vmax: float) -> np.ndarray:
    """``values`` within [vmin, vmax], allowing round-off of the range's ends (1e-9 relative)."""
    slack = 1e-9 * (vmax - vmin)
    return values[(values >= vmin - slack) & (values <= vmax + slack)]


def colour_scale(field: PlainArray, scale: str | None) -> ColourScale:
    """The colour scale of a map of ``field``: categorical, zero-centred, log or linear."""
    values = np.asarray(field.values, dtype=float)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        raise ParameterError(f"{field.name} has no finite value to draw (all NaN)")
    found = find_categories(field, finite)
    if found is not None:
        return _categorical(field, found)
    vmin, vmax = float(finite.min()), float(finite.max())
    if vmin == vmax:  # a constant: any small range around it shows one colour
        vmin, vmax = vmin - (abs(vmin) or 1.0) * 0.01, vmax + (abs(vmax) or 1.0) * 0.01
    if scale != "log" and (field.name in CENTRED or vmin < 0 < vmax):
        return _diverging(vmin, vmax)
    log = use_log(finite, scale, str(field.name))
    norm = (matplotlib.colors.LogNorm if log else matplotlib.colors.Normalize)(vmin, vmax)
    ticks = tick_values(vmin, vmax, log)
    formatter = (fixed_labels(ticks, tick_labels(ticks)) if log
                 else matplotlib.ticker.ScalarFormatter(useMathText=True))
    return ColourScale(norm, _with_missing(SEQUENTIAL), ticks, formatter, log=log)


def find_categories(field: PlainArray, finite: np.ndarray) -> np.ndarray | None:
    """The distinct values of integer data with few of them (a period, a flag), else None.

    CF flags (``flag_values``) are categories whatever their type: NaN where none applies.
    """
    integral = (field.dtype.kind in "iub" or field.name in CATEGORY_NAMES
                or "flag_values" in field.attrs)
    if not integral or not np.all(finite == np.round(finite)):
        return None
    distinct = np.unique(finite)
    return distinct if distinct.size <= MAX_CATEGORIES else None


def category_names(field: PlainArray, categories: np.ndarray) -> list[str]:
    """Names of the categories: CF flag_meanings, else the registry's or CATEGORY_NAMES, or numbers.

    A file of an earlier version has no flag attributes: the registry's flags name its codes.
    """
    registered = VARIABLES[str(field.name)].flags if field.name in VARIABLES else ()
    names = dict(CATEGORY_NAMES.get(str(field.name), enumerate(registered)))
    if "flag_values" in field.attrs and "flag_meanings" in field.attrs:
        names = dict(zip(np.atleast_1d(field.attrs["flag_values"]).tolist(),
                         str(field.attrs["flag_meanings"]).split(), strict=True))
    return [str(names.get(int(c), int(c))).replace("_", " ") for c in categories]


def _categorical(field: PlainArray, categories: np.ndarray) -> ColourScale:
    names = category_names(field, categories)
    palette = iter(matplotlib.colormaps["tab10"].colors)
    colours = [NONE_COLOUR if name == "none" else next(palette) for name in names]
    cmap = matplotlib.colors.ListedColormap(colours).with_extremes(bad=MISSING_COLOUR)
    norm = matplotlib.colors.BoundaryNorm(np.arange(len(names) + 1) - 0.5, len(names))
    codes = np.arange(len(names))
    return ColourScale(norm, cmap, codes, fixed_labels(codes, names), categories=categories)


def _diverging(vmin: float, vmax: float) -> ColourScale:
    """Blue below 0, red above, white at 0; each side spans its own range."""
    if vmin < 0 < vmax:
        norm = matplotlib.colors.TwoSlopeNorm(0.0, vmin, vmax)
        ticks = np.union1d(nice_levels(vmin, 0.0, TICKS // 2, False),
                           nice_levels(0.0, vmax, TICKS // 2, False))
    else:  # one sign only: symmetric about 0, so that the colour still says the sign
        bound = max(abs(vmin), abs(vmax))
        norm = matplotlib.colors.Normalize(-bound, bound)
        ticks = tick_values(-bound, bound, False)
    return ColourScale(norm, _with_missing(DIVERGING), ticks,
                       matplotlib.ticker.ScalarFormatter(useMathText=True))


def _with_missing(name: str) -> matplotlib.colors.Colormap:
    return matplotlib.colormaps[name].with_extremes(bad=MISSING_COLOUR)


def set_log_ticks(axis: Axis, vmin: float, vmax: float) -> None:
    """Round log ticks over [vmin, vmax] on ``axis`` (x or y), labels in one style."""
    ticks = tick_values(vmin, vmax, True)
    axis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
    axis.set_major_formatter(fixed_labels(ticks, tick_labels(ticks)))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def fixed_labels(ticks: np.ndarray, labels: list[str]) -> matplotlib.ticker.Formatter:
    """A formatter giving each of ``ticks`` its label.

    By value, unlike matplotlib's FixedFormatter, whose labels go by position and shift when
    an axis drops a tick outside its range.
    """

    def label(value: float, _: int | None = None) -> str:
        return labels[int(np.argmin(np.abs(np.asarray(ticks) - value)))]

    return matplotlib.ticker.FuncFormatter(label)


def edges(values: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around grid ``values`` (midpoints; geometric on a log axis), for pcolormesh."""
    points = np.log(values) if log else np.asarray(values, dtype=float)
    if points.size == 1:
        inner = np.array([points[0] - 0.5, points[0] + 0.5])
    else:
        middle = (points[1:] + points[:-1]) / 2
        inner = np.concatenate([[2 * points[0] - middle[0]], middle,
                                [2 * points[-1] - middle[-1]]])
    return np.exp(inner) if log else inner


def grid_axis(axes: Axes, which: str, coordinate: PlainArray) -> tuple[np.ndarray, bool]:
    """Put a grid ``coordinate`` on the ``which`` ("x" or "y") axis: label, scale and ticks.

    Returns the positions of the grid values on the axis and whether the axis is log
    (the coordinate's ``scale`` attribute); named choices sit at 0, 1, 2, ...
    """
    axis = axes.xaxis if which == "x" else axes.yaxis
    axis.set_label_text(axis_label(coordinate))
    values = coordinate.values
    if values.dtype.kind in "OUS":
        positions = np.arange(values.size, dtype=float)
        axis.set_major_locator(matplotlib.ticker.FixedLocator(positions))
        axis.set_major_formatter(fixed_labels(positions, [str(v) for v in values]))
        return positions, False
    log = coordinate.attrs.get("scale") == "log"
    if log:
        (axes.set_xscale if which == "x" else axes.set_yscale)("log")
        set_log_ticks(axis, float(values.min()), float(values.max()))
    if isinstance(axis.get_major_formatter(), matplotlib.ticker.ScalarFormatter):
        axis.get_major_formatter().set_useMathText(True)  # an offset as x 10^k, not 1e-5
    return values.astype(float), log
