"""Frequency-response curves: a continuation's branches against the continued parameter.

Stable orbits solid, unstable dashed, one colour per branch, events marked and labelled (the
labels placed apart, `place_labels`; which kinds, `impactbeams.plotting.events`; a crowded
curve's events as ticks in a strip under it; a narrow period-p branch zoomed in an inset);
optionally over a brute-force bifurcation diagram (its stroboscopic samples as grey dots,
against the branches' own samples ``section_deflection_1``: p curves for a period-p branch, one
per section t = k T). Lengths and forces are drawn in the prefixed units of their size (µm,
mm, mN), never in metres with an offset; Omega in rad/s, or in Hz if asked.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import ConnectionPatch
from matplotlib.text import Annotation, Text
from matplotlib.ticker import MaxNLocator
from matplotlib.transforms import Bbox

from impactbeams.params import ParameterError
from impactbeams.plotting.events import EventChoice, chosen_events, priority
from impactbeams.plotting.labels import axis_label, display_units
from impactbeams.plotting.room import Room
from impactbeams.variables import BIFURCATIONS, located_events

DEFAULT_MEASURE = "tip_amplitude_1"
OVERLAY_MEASURE = "section_deflection_1"  # what a diagram's poincare_deflection1 shows
DIAGRAM_SAMPLES = "poincare_deflection1"
ALONG = (("branch_point",), ("branch_point", "section"))  # what can be drawn
MARKERS = {"fold": ("o", "F"), "period_doubling": ("s", "PD"), "neimark_sacker": ("D", "NS"),
           "grazing": ("^", "G"), "branch_point": ("v", "BP"), "contact_merge": ("<", "M"),
           "contact_split": (">", "S"), "chatter": ("x", "C")}
OTHER_MARKER = "*"  # an event kind without a marker of its own
MARKER_SIZE, SMALL_MARKER_SIZE = 6.0, 3.5  # points: a labelled kind's markers, the others'
# A period-p branch leaves its period-1 origin at a period doubling and runs close to it (the
# same largest deflection there): drawn over the period-1 curve and over the event markers,
# and thinner, so that the period-1 curve shows on both sides of it and neither hides the
# other (each branch keeps its own colour; stable solid, unstable dashed, whatever its period)
LINE_WIDTH, LONGER_PERIOD_LINE_WIDTH = 1.4, 0.8  # points
PERIOD_ONE_ZORDER, EVENT_ZORDER, LONGER_PERIOD_ZORDER = 2.0, 2.5, 3.0
# a curve is crowded when more than this many drawn events, and more than this share of them,
# have markers that meet another's (on the stiff stop-and-shaker branch going down 420 of 422
# do): then only the events whose markers stand apart are marked on the curve, and every event
# is a tick in a strip under the curves, a row per kind (`_draw_strip`)
CROWDED, CROWDED_SHARE = 10, 0.5
APART = 2.0  # points: kept free between markers that stand apart
STRIP_ROW, STRIP_TICK = 8.0, 5.5  # points: a row of the strip, and its ticks' height
STRIP_GAP = 6.0  # points: between the strip and the lowest point of the curves
# a period-p branch narrower than this fraction of the axes' parameter range is drawn again in
# an inset, zoomed (the stiff stop's period-2 branch going down spans 0.44 of 197 rad/s)
NARROW = 0.02
INSET_SIZE = (0.3, 0.3)  # axes fractions
INSET_TICK_ROOM = (34.0, 14.0)  # points left of and below an inset for its tick labels
LEGEND_CANDIDATES = 11  # legend positions tried along each axis, corners and edges first
LEGEND_MARGIN = 3.0  # points: kept free between the legend and anything drawn
# where an event's label may go, in points from its marker, tried in this order: beside it,
# then further up or down (joined to it by a line)
_OFFSETS = ((5, 5), (5, -13), (-17, 5), (-17, -13), *((dx, dy) for dy in (18, -26, 30, -38,
            42, -50, 54, -62) for dx in (5, -17)))
_LINE_FROM = 15  # points: a label further above or below its point is joined to it
_MARKER_HALF_WIDTH = 4.0  # points: a marker's half extent and a margin, kept free of labels


def draw_branches(axes: Axes, dataset: xr.Dataset, variable: str | None = None,
                  diagram: xr.Dataset | None = None, hz: bool = False,
                  events: str | Sequence[str] | None = None) -> None:
    """Draw ``variable`` (default max |y1|, or y1 on the section over a ``diagram``).

    ``hz``: a frequency axis in Hz (Omega / 2 pi) instead of rad/s. Lengths and forces are
    drawn in the units `branch_units` gives; draw anything else first, in those units, and set
    the axes' limits before: the event labels are placed last, on the laid-out axes.

    ``events``: which located events are drawn and labelled (`chosen_events`). By default every
    event is marked, and folds, period doublings, Neimark-Sacker and branch points, then
    grazings, are labelled where a label fits, in that order; contact merges, splits and
    chatter get small markers and no label. A branch on a stiff contact carries hundreds of
    events, many of them changes within the contact sequence (92 merges and splits of 340
    events on the stop-and-shaker case of issue 31, up): labelled, they would take the room of
    the bifurcations a reader looks for; marked, where the contacts change still shows. "all"
    labels every kind where it fits, "none" draws none, a list of kinds draws and labels those.
    Nothing is left out unsaid: each kind's legend entry counts its events and those without a
    label (no room, or out of view), and one entry counts the kinds not drawn.

    A crowded curve (``CROWDED``: 420 of the 422 markers of the stiff case going down met
    another) gets a strip of ticks under it instead, every drawn event a tick in its kind's
    row; on the curve only the labelled kinds' events whose markers stand apart are marked,
    and their entries count the labelled ones. A period-p branch narrower than ``NARROW`` of
    the range is drawn again, zoomed, in an inset where one fits (its entry says "inset"),
    else its entry gives its range.
    """
    choice = chosen_events(events)
    parameter = dataset.attrs["continued_parameter"]
    name = variable or (OVERLAY_MEASURE if diagram is not None else DEFAULT_MEASURE)
    if name not in dataset or dataset[name].dims not in ALONG:
        raise ParameterError(f"--var {name!r} is not a variable along the branch; choose one "
                             "of " + ", ".join(v for v in dataset.data_vars
                                                if dataset[v].dims in ALONG))
    (x_factor, x_units), (y_factor, y_units) = branch_units(dataset, name, hz)
    if diagram is not None:
        _draw_diagram(axes, diagram, parameter, x_factor, y_factor)
    x = x_factor * dataset[parameter].values
    y = y_factor * dataset[name].values.reshape(dataset.branch_point.size, -1)
    curves, narrow = [], []
    for branch in np.unique(dataset.branch.values):
        mask = dataset.branch.values == branch
        period = int(dataset.orbit_period.values[mask][0])
        drawn = _draw_branch(axes, x, y, dataset.stable.values, mask, f"C{int(branch)}",
                             f"branch {int(branch)} (period {period})", period)
        if period > 1 and np.ptp(x[mask]) < NARROW * np.ptp(x):
            narrow.append((mask, drawn[0], f"{_span(x[mask])} {x_units}"))
        curves += drawn
    kinds = _event_kinds(x, y[:, 0], dataset.bifurcation.values, located_events(dataset),
                         choice)
    strip = _draw_strip(axes, kinds) if _crowded(axes, kinds) else None
    lines = _mark_events(axes, kinds)
    axes.set_xlabel(r"$\Omega / 2\pi$ (Hz)" if x_units == "Hz"
                    else axis_label(dataset[parameter], x_units))
    axes.set_ylabel(axis_label(dataset[name], y_units))
    axes.ticklabel_format(useOffset=False)  # values as read, never "+2.523e2" beside an axis
    axes.plot([], [], "k-", label="stable")
    axes.plot([], [], "k--", label="unstable")
    clear = [] if strip is None else [strip]
    if narrow:  # too narrow to see: drawn again in an inset, else its range said
        inset = _zoom(axes, x, y, dataset, np.any([mask for mask, *_ in narrow], axis=0),
                      kinds, clear)
        clear += inset
        for _, line, span in narrow:
            line.set_label(line.get_label()[:-1] + ("; inset)" if inset else f"; {span})"))
    place_legend(axes, clear)
    if strip is not None:  # beside the axes, the legend shrank them: markers nearer
        _mark_apart(axes, kinds, lines)
    labelled = [(x, y, _marker(kind.name)[1]) for kind in kinds if kind.labelled
                for x, y in sorted(kind.marked)]
    marked = [point for kind in kinds if kind.drawn and not kind.labelled
              for point in kind.marked]
    _count_unlabelled(axes, kinds, lines, place_labels(axes, labelled, marked, curves, clear))


def branch_units(dataset: xr.Dataset, name: str, hz: bool = False,
                 ) -> tuple[tuple[float, str], tuple[float, str]]:
    """The factors and units `draw_branches` draws the continued parameter and ``name`` in.

    Lengths and forces in the prefix of their size (`display_units`), Omega in Hz if ``hz``:
    what else is drawn on the same axes must be scaled alike.
    """
    coordinate = dataset[dataset.attrs["continued_parameter"]]
    if hz:
        if coordinate.name != "omega":
            raise ParameterError(f"--hz is for a branch along omega, not {coordinate.name!r}")
        x = (1.0 / (2.0 * math.pi), "Hz")
    else:
        x = display_units(coordinate.values, coordinate.attrs.get("units", ""))
    return x, display_units(dataset[name].values, dataset[name].attrs.get("units", ""))


def _draw_branch(axes: Axes, x: np.ndarray, y: np.ndarray, stable: np.ndarray,
                 mask: np.ndarray, colour: str, label: str, period: int) -> list[Line2D]:
    """Runs of equal stability, each joined to the next point so that the curve is whole.

    One curve per column of ``y`` (a section of the orbit; NaN columns draw nothing). A
    branch of period above 1 is drawn thinner and on top (``LONGER_PERIOD_ZORDER``).
    """
    index = np.flatnonzero(mask)
    runs = np.split(index, np.flatnonzero(np.diff(stable[index])) + 1)
    width, order = ((LINE_WIDTH, PERIOD_ONE_ZORDER) if period == 1
                    else (LONGER_PERIOD_LINE_WIDTH, LONGER_PERIOD_ZORDER))
    drawn = []
    for run in runs:
        joined = np.append(run, run[-1] + 1) if run[-1] + 1 <= index[-1] else run
        for column in range(y.shape[1]):
            drawn += axes.plot(x[joined], y[joined, column], color=colour,
                               linestyle="-" if stable[run[0]] else "--", linewidth=width,
                               zorder=order,
                               label=label if run is runs[0] and column == 0 else None)
    return drawn


def _marker(kind: str) -> tuple[str, str]:
    """An event kind's marker and short label (its initials if it has none of its own)."""
    return MARKERS.get(kind, (OTHER_MARKER, "".join(w[0] for w in kind.split("_")).upper()))


@dataclasses.dataclass
class _Kind:
    """The events of one kind on the branches, drawn or not.

    ``apart``: on a crowded curve (a strip of ticks under it), whether each event's marker
    stands apart from the others (only those are marked on the curve); None otherwise.
    """

    name: str
    points: list[tuple[float, float]]  # (x, y) of each, drawn units
    drawn: bool
    labelled: bool
    apart: list[bool] | None = None

    @property
    def marked(self) -> list[tuple[float, float]]:
        """The events marked on the curve."""
        if self.apart is None:
            return self.points
        return [point for point, apart in zip(self.points, self.apart, strict=True) if apart]

    def legend_text(self, unlabelled: int) -> str:
        """Its legend entry: short label, name, count, and how many are unlabelled.

        (No room, or out of view.) On a crowded curve, where each is a tick in the strip under
        it, how many are labelled on the curve instead.
        """
        count = len(self.points)
        if self.apart is not None:  # each is a tick in the strip; some marked on the curve
            labelled = len(self.marked) - unlabelled
            tally = f"{count}; {labelled} labelled" if labelled > 0 else f"{count}"
        elif not self.labelled:
            tally = f"{count}, unlabelled"
        else:
            tally = f"{count}; {unlabelled} unlabelled" if unlabelled else f"{count}"
        return f"{_marker(self.name)[1]}: {self.name.replace('_', ' ')} ({tally})"


def _event_kinds(x: np.ndarray, y: np.ndarray, codes: np.ndarray, events: np.ndarray,
                 choice: EventChoice) -> list[_Kind]:
    """The events of each kind the branches carry, in the order their labels are placed.

    ``events``: the indices of the labelled points to draw, each event once (the run's
    summary counts the same, `located_events`).
    """
    kinds = []
    for code in np.unique(codes[events]):
        name = BIFURCATIONS[code] if code < len(BIFURCATIONS) else f"event_{code}"
        where = events[codes[events] == code]
        kinds.append(_Kind(name, [(float(x[i]), float(y[i])) for i in where],
                           choice.is_drawn(name), choice.is_labelled(name)))
    return sorted(kinds, key=lambda kind: priority(kind.name))


def _mark_events(axes: Axes, kinds: list[_Kind]) -> dict[str, Line2D]:
    """A marker at each drawn event (small for the kinds not labelled); one line a kind.

    The legend text of each is the longest it can be (every event unlabelled), for the legend
    to shrink, not grow, when the count of unlabelled ones is known (`_count_unlabelled`).
    """
    lines = {}
    for kind in kinds:
        if kind.drawn:
            x, y = np.array(kind.marked).reshape(-1, 2).T
            lines[kind.name] = axes.plot(
                x, y, _marker(kind.name)[0], color="k", markerfacecolor="none",
                markersize=MARKER_SIZE if kind.labelled else SMALL_MARKER_SIZE,
                zorder=EVENT_ZORDER, label=kind.legend_text(len(kind.points)))[0]
    hidden = [kind for kind in kinds if not kind.drawn]
    if hidden:  # nothing left out unsaid
        names = [f"{len(kind.points)} {kind.name.replace('_', ' ')}" for kind in hidden]
        rows = [", ".join(names[i:i + 2]) for i in range(0, len(names), 2)]
        axes.plot([], [], linestyle="none", label="not drawn: " + ",\n".join(rows))
    return lines


def _span(x: np.ndarray) -> str:
    """``x``'s range as "low to high", with the decimals that tell its ends apart."""
    decimals = max(0, 1 - math.floor(math.log10(np.ptp(x)))) if np.ptp(x) > 0 else 2
    return f"{x.min():.{decimals}f} to {x.max():.{decimals}f}"


def _marker_boxes(axes: Axes, kinds: Sequence[_Kind]) -> np.ndarray:
    """The display boxes (x0, y0, x1, y1) of the markers ``kinds`` would draw, in order.

    Each with ``APART`` / 2 around it: two boxes that meet are markers closer than that.
    """
    to_pixels = axes.get_figure(root=True).dpi / 72.0
    boxes = [np.empty((0, 4))]
    for kind in kinds:
        if kind.points:
            half = 0.5 * (to_pixels * (MARKER_SIZE if kind.labelled else SMALL_MARKER_SIZE)
                          + to_pixels * APART)
            xy = axes.transData.transform(np.array(kind.points, dtype=float))
            boxes.append(np.hstack([xy - half, xy + half]))
    return np.vstack(boxes)


def _meeting(boxes: np.ndarray) -> np.ndarray:
    """Whether each box meets another of ``boxes``."""
    meets = ((boxes[:, None, 0] <= boxes[None, :, 2]) & (boxes[None, :, 0] <= boxes[:, None, 2])
             & (boxes[:, None, 1] <= boxes[None, :, 3])
             & (boxes[None, :, 1] <= boxes[:, None, 3]))
    np.fill_diagonal(meets, False)
    return meets.any(axis=1)


def _crowded(axes: Axes, kinds: list[_Kind]) -> bool:
    """Whether more than ``CROWDED`` drawn events (and ``CROWDED_SHARE``) meet another.

    Meet: their markers are closer than ``APART``.
    """
    axes.get_figure(root=True).draw_without_rendering()  # the layout: the markers' places
    meeting = _meeting(_marker_boxes(axes, [kind for kind in kinds if kind.drawn]))
    crowded = int(np.count_nonzero(meeting))
    return crowded > CROWDED and crowded > CROWDED_SHARE * meeting.size


def _draw_strip(axes: Axes, kinds: list[_Kind]) -> Bbox:
    """Every drawn event as a tick in a strip under the curves, a row per kind; its box.

    The y axis is extended down for the strip (``STRIP_GAP`` under the lowest point drawn),
    and its ticks there left out: the strip's height means nothing. On the curves, only the
    labelled kinds' events whose markers stand apart (``APART``) are marked (``apart``).
    """
    figure = axes.get_figure(root=True)
    to_pixels = figure.dpi / 72.0
    rows = [kind for kind in kinds if kind.drawn]
    height = axes.get_window_extent().height
    row, tick = (STRIP_ROW * to_pixels / height, STRIP_TICK * to_pixels / height)
    top = row * len(rows)
    low, high = axes.get_ylim()
    lowest = axes.dataLim.y0
    floor = top + STRIP_GAP * to_pixels / height  # axes fraction the curves stay above
    low = min(low, (lowest - floor * high) / (1.0 - floor))
    axes.set_yticks([value for value in axes.get_yticks()
                     if low + floor * (high - low) <= value <= high])
    axes.set_ylim(low, high)
    for number, kind in enumerate(rows):
        centre = top - (number + 0.5) * row
        x = np.array([point[0] for point in kind.points])
        axes.plot(np.repeat(x, 3), np.tile([centre - tick / 2, centre + tick / 2, np.nan],
                                           x.size),
                  color="k", linewidth=0.6, zorder=EVENT_ZORDER,
                  transform=axes.get_xaxis_transform(), label=f"_strip {_marker(kind.name)[1]}")
        axes.text(-0.01, centre, _marker(kind.name)[1], transform=axes.transAxes,
                  ha="right", va="center", fontsize="xx-small")
    axes.plot([0.0, 1.0], [top, top], color="0.6", linewidth=0.6, transform=axes.transAxes,
              label="_strip")
    _mark_apart(axes, kinds)
    return Bbox([[0.0, 0.0], [1.0, top]])


def _mark_apart(axes: Axes, kinds: list[_Kind], lines: dict[str, Line2D] | None = None,
                ) -> None:
    """Choose the events marked on a crowded curve: the labelled kinds' that stand apart.

    On the laid-out axes (``APART`` between markers, in display units): chosen when the strip
    is drawn, for the legend and an inset to keep clear of, and again once the legend is
    placed (beside the axes it shrinks them, and markers that stood apart may meet; fewer
    stand apart then, none that the legend or an inset covers), with the kinds' ``lines``
    drawn again at the events chosen.
    """
    axes.get_figure(root=True).draw_without_rendering()
    labelled = [kind for kind in kinds if kind.drawn and kind.labelled]
    apart = ~_meeting(_marker_boxes(axes, labelled))
    start = 0
    for kind in kinds:
        if kind.drawn and kind.labelled:
            kind.apart = [bool(flag) for flag in apart[start:start + len(kind.points)]]
            start += len(kind.points)
        elif kind.drawn:
            kind.apart = [False] * len(kind.points)
        if lines is not None and kind.name in lines:
            lines[kind.name].set_data(*np.array(kind.marked).reshape(-1, 2).T)


def _zoom(axes: Axes, x: np.ndarray, y: np.ndarray, dataset: xr.Dataset, narrow: np.ndarray,
          kinds: list[_Kind], clear: list[Bbox]) -> list[Bbox]:
    """The ``narrow`` points' branches drawn again, zoomed, in an inset where it fits.

    The inset (``INSET_SIZE``, with room for its tick labels) goes at the place nearest its
    window, of those tried for the legend, that covers no line, marker, legend or box of
    ``clear``; a frame marks its window on the axes, joined to the inset. Returns its box
    (axes fractions) to keep clear, none if no room.
    """
    figure = axes.get_figure(root=True)
    to_pixels = figure.dpi / 72.0
    figure.draw_without_rendering()
    inside = axes.get_window_extent()
    room = (np.array(INSET_TICK_ROOM) * to_pixels)
    size = np.array(INSET_SIZE) * [inside.width, inside.height]
    taken = [_marker_extents(axes.lines, to_pixels), *_display(axes, clear)]
    legend = axes.get_legend()
    if legend is not None:
        taken.append(legend.get_window_extent().extents)
    free = Room(np.vstack(taken), _segments(axes.lines))
    margin = LEGEND_MARGIN * to_pixels
    shrunk = Bbox([[inside.x0 + room[0], inside.y0 + room[1]], [inside.x1, inside.y1]])
    window = axes.transData.transform([np.mean(x[narrow]), np.nanmean(y[narrow])])
    for corner in sorted(_legend_corners(shrunk, size, margin),
                         key=lambda corner: float(np.hypot(*(corner + size / 2 - window)))):
        box = np.concatenate([corner - room - margin, corner + size + margin])
        if free.is_free(box, None, 0):
            break
    else:
        return []
    bounds = [*axes.transAxes.inverted().transform(corner), *INSET_SIZE]
    inset = axes.inset_axes(bounds)
    for branch in np.unique(dataset.branch.values):
        mask = dataset.branch.values == branch
        _draw_branch(inset, x, y, dataset.stable.values, mask, f"C{int(branch)}", "",
                     int(dataset.orbit_period.values[mask][0]))
    for kind in kinds:
        if kind.drawn:
            points = np.array(kind.points).reshape(-1, 2)
            inset.plot(*points.T, _marker(kind.name)[0], color="k", markerfacecolor="none",
                       markersize=SMALL_MARKER_SIZE, zorder=EVENT_ZORDER)
    x_window, y_window = x[narrow], y[narrow][np.isfinite(y[narrow])]
    for window, limits in ((x_window, inset.set_xlim), (y_window, inset.set_ylim)):
        pad = 0.3 * np.ptp(window) if np.ptp(window) > 0 else 1e-3 * abs(window.max())
        limits(window.min() - pad, window.max() + pad)
    inset.tick_params(labelsize="xx-small")
    inset.ticklabel_format(useOffset=False)
    for axis in (inset.xaxis, inset.yaxis):
        axis.set_major_locator(MaxNLocator(3))
    indicator = axes.indicate_inset_zoom(inset, edgecolor=INSET_EDGE)
    figure.draw_without_rendering()  # (the connectors' visibility is decided at a draw)
    if not any(connector.get_visible() for connector in indicator.connectors):
        _side_connectors(axes, inset, bounds[0])
    return [axes.transAxes.inverted().transform_bbox(Bbox([corner - room, corner + size]))]


def _side_connectors(axes: Axes, inset: Axes, inset_left: float) -> None:
    """Join the zoomed region's side facing the inset to the inset's facing side.

    Matplotlib joins a region's corners to the inset's same corners only, and shows none
    where the region lies level with an inset beside it (each such line would cross one of
    them): the two lines are then drawn from the facing sides' corners. ``inset_left``: the
    inset's left edge (axes fraction).
    """
    (x0, x1), (y0, y1) = inset.get_xlim(), inset.get_ylim()
    region_right = axes.transLimits.transform((x1, y1))[0]  # axes fraction
    x_region, x_inset = (x1, 0.0) if inset_left >= region_right else (x0, 1.0)
    for y_region, y_inset in ((y0, 0.0), (y1, 1.0)):
        axes.add_artist(ConnectionPatch((x_region, y_region), (x_inset, y_inset),
                                        axes.transData, inset.transAxes, color=INSET_EDGE,
                                        linewidth=0.8))


INSET_EDGE = "0.4"  # the zoomed region's frame and its connectors


def _display(axes: Axes, boxes: Sequence[Bbox]) -> list[np.ndarray]:
    """The extents (x0, y0, x1, y1), display units, of ``boxes`` given in axes fractions."""
    return [axes.transAxes.transform_bbox(box).extents for box in boxes]


def _count_unlabelled(axes: Axes, kinds: list[_Kind], lines: dict[str, Line2D],
                      unlabelled: list[tuple[float, float, str]]) -> None:
    """Each drawn kind's legend entry with the count of its events left without a label."""
    legend = axes.get_legend()
    texts = {text.get_text(): text for text in legend.get_texts()}
    for kind in kinds:
        if kind.name in lines:
            short = _marker(kind.name)[1]
            text = kind.legend_text(sum(1 for *_, label in unlabelled if label == short))
            texts[lines[kind.name].get_label()].set_text(text)
            lines[kind.name].set_label(text)


def place_legend(axes: Axes, clear: Sequence[Bbox] = ()) -> None:
    """The axes' legend where it covers nothing drawn, else beside the axes (on the right).

    matplotlib's "best" only keeps the legend's cover of the data least: on a crowded curve it
    covers some (the top of the stiff stop-and-shaker branch of issue 31, 165-172 rad/s).
    Here the legend's places in the axes are tried, corners and edges first, and the first
    whose box (and ``LEGEND_MARGIN``) meets no segment of a drawn line, no marker and no box
    of ``clear`` (axes fractions) is taken. Measured on the laid-out figure; the labels, placed
    after, keep clear of it.
    """
    legend = axes.legend(fontsize="small", loc=(0.0, 0.0))
    figure = axes.get_figure(root=True)
    figure.draw_without_rendering()
    renderer = _renderer(figure)
    inside = axes.get_window_extent(renderer)
    size = legend.get_window_extent(renderer).size
    margin = LEGEND_MARGIN * figure.dpi / 72.0
    room = Room(np.vstack([_marker_extents(axes.lines, figure.dpi / 72.0),
                           *_display(axes, clear)]), _segments(axes.lines))
    for corner in _legend_corners(inside, size, margin):
        if room.is_free(np.concatenate([corner - margin, corner + size + margin]), None, 0):
            legend.set_loc(tuple(axes.transAxes.inverted().transform(corner)))
            return
    legend.set_loc("upper left")  # no room inside: beside the axes, which shrink for it
    legend.set_bbox_to_anchor((1.02, 1.0), transform=axes.transAxes)


def _legend_corners(inside: Bbox, size: np.ndarray, margin: float) -> list[np.ndarray]:
    """The lower-left corners (display) of a box of ``size`` within ``inside`` to try, in order.

    ``LEGEND_CANDIDATES`` along each axis, nearest a corner of the axes first (upper right,
    upper left, lower right, lower left: where a reader looks for a legend).
    """
    low = np.array([inside.x0, inside.y0]) + margin
    high = np.array([inside.x1, inside.y1]) - margin - size
    if (high < low).any():
        return []
    steps = np.arange(LEGEND_CANDIDATES)
    grid = [(i, j) for j in steps[::-1] for i in steps]
    last = LEGEND_CANDIDATES - 1
    corners = ((last, last), (0, last), (last, 0), (0, 0))

    def order(ij: tuple[int, int]) -> tuple[int, int]:
        away = [abs(ij[0] - ci) + abs(ij[1] - cj) for ci, cj in corners]
        return min(away), int(np.argmin(away))

    return [low + (high - low) * np.array(ij) / last for ij in sorted(grid, key=order)]


def _segments(lines: Sequence[Line2D]) -> np.ndarray:
    """The segments (x0, y0, x1, y1), display units, of the lines drawn with a line style."""
    segments = [np.empty((0, 4))]
    for line in lines:
        if line.get_linestyle() in ("None", "") or len(line.get_xdata()) < 2:
            continue
        xy = line.get_transform().transform(np.column_stack(
            [line.get_xdata(), line.get_ydata()]).astype(float))
        pairs = np.hstack([xy[:-1], xy[1:]])
        segments.append(pairs[np.isfinite(pairs).all(axis=1)])
    return np.vstack(segments)


def _marker_extents(lines: Sequence[Line2D], points_to_pixels: float) -> np.ndarray:
    """The boxes (x0, y0, x1, y1), display units, of the markers drawn by ``lines``."""
    boxes = [np.empty((0, 4))]
    for line in lines:
        if line.get_marker() in ("None", "", " ", None) or not len(line.get_xdata()):
            continue
        xy = line.get_transform().transform(np.column_stack(
            [line.get_xdata(), line.get_ydata()]).astype(float))
        xy = xy[np.isfinite(xy).all(axis=1)]
        half = 0.5 * line.get_markersize() * points_to_pixels
        boxes.append(np.hstack([xy - half, xy + half]))
    return np.vstack(boxes)


def place_labels(axes: Axes, events: list[tuple[float, float, str]],
                 marked: Sequence[tuple[float, float]] = (),
                 curves: Sequence[Line2D] = (),
                 clear: Sequence[Bbox] = ()) -> list[tuple[float, float, str]]:
    """Label each event (x, y, text) near its point, clear of the labels, legend and markers.

    Greedy, in the order given (the first get the room): each label takes the first of
    ``_OFFSETS`` whose box is free and inside the axes; a far one is joined to its point by a
    line, which crosses no other line, label, marker or the legend. If none is free the label
    is left out. The markers of ``events`` and of ``marked`` (points drawn without a label)
    are kept free, and no label covers a line of ``curves`` (its leader line may cross them:
    it starts on one), nor a box of ``clear`` (axes fractions: a strip of ticks, an inset).
    Positions are measured on the laid-out figure; events out of the axes'
    view are not labelled. Returns the events left without a label (on a branch with
    hundreds of events, the caller says how many).
    """
    figure = axes.get_figure(root=True)
    figure.draw_without_rendering()  # the layout: positions as they will be drawn
    renderer = _renderer(figure)
    points_to_pixels = figure.dpi / 72.0
    inside = axes.get_window_extent(renderer)
    taken = [_marker_box(axes, x, y, points_to_pixels)
             for x, y in [(x, y) for x, y, _ in events] + list(marked)]
    legend = axes.get_legend()
    if legend is not None:  # placed (`place_legend`): it stays where it is
        taken.append(legend.get_window_extent(renderer))
    taken += [Bbox(box.reshape(2, 2)) for box in _display(axes, clear)]
    room = Room(np.array([box.extents for box in taken]), _segments(curves))
    left_out = []
    for own, (x, y, text) in enumerate(events):
        point = axes.transData.transform((x, y))
        if not inside.contains(*point):
            left_out.append((x, y, text))  # out of view (limits set by the caller)
            continue
        label = axes.annotate(text, (x, y), textcoords="offset points", xytext=_OFFSETS[0],
                              fontsize="x-small", annotation_clip=False,
                              arrowprops={"arrowstyle": "-", "color": "0.5", "lw": 0.5,
                                          "shrinkA": 0, "shrinkB": 4})
        label.set_in_layout(False)
        if not _place(label, point, renderer, room, own, inside):  # no room: the legend counts it
            label.remove()
            left_out.append((x, y, text))
    return left_out


def _renderer(figure: Figure) -> RendererBase:
    """A renderer to measure texts with: the canvas's own, else an Agg one (canvas kept)."""
    if hasattr(figure.canvas, "get_renderer"):
        return figure.canvas.get_renderer()
    canvas = figure.canvas
    renderer = FigureCanvasAgg(figure).get_renderer()
    figure.set_canvas(canvas)
    return renderer


def _text_box(label: Annotation, renderer: RendererBase) -> Bbox:
    """The display box of ``label``'s text alone (an Annotation's own box holds its line)."""
    label.update_positions(renderer)
    return Text.get_window_extent(label, renderer)


def _place(label: Annotation, point: np.ndarray, renderer: RendererBase, room: Room,
           own: int, inside: Bbox) -> bool:
    """Put ``label`` at the first offset of ``_OFFSETS`` where it and its line are free.

    ``point``: its event's, display units. The line (drawn to a label more than ``_LINE_FROM``
    points above or below its point) is the segment from the point to the text's centre: the
    drawn one is part of it. False if no offset is free (a crowded branch: the label is left
    out); ``room`` then is unchanged.
    """
    for offset in _OFFSETS:
        label.xyann = offset
        box = _text_box(label, renderer)
        far = abs(offset[1]) > _LINE_FROM
        line = np.concatenate([point, box.get_points().mean(axis=0)]) if far else None
        if _contains(inside, box) and room.is_free(box.extents, line, own):
            label.arrow_patch.set_visible(line is not None)
            room.take(box.extents, line)
            return True
    return False


def _marker_box(axes: Axes, x: float, y: float, points_to_pixels: float) -> Bbox:
    """The display box of an event's marker at data (x, y)."""
    cx, cy = axes.transData.transform((x, y))
    half = _MARKER_HALF_WIDTH * points_to_pixels
    return Bbox([[cx - half, cy - half], [cx + half, cy + half]])


def _contains(outer: Bbox, inner: Bbox) -> bool:
    return (outer.x0 <= inner.x0 and inner.x1 <= outer.x1 and outer.y0 <= inner.y0
            and inner.y1 <= outer.y1)


def _draw_diagram(axes: Axes, diagram: xr.Dataset, parameter: str, x_factor: float,
                  y_factor: float) -> None:
    """The brute-force diagram's samples along the same parameter, grey dots."""
    if DIAGRAM_SAMPLES not in diagram or diagram[DIAGRAM_SAMPLES].dims != (parameter, "period"):
        raise ParameterError(f"--over needs a bifurcation diagram over {parameter!r}: a "
                             f"long-time sweep's {DIAGRAM_SAMPLES} along ({parameter}, period)")
    samples = diagram[DIAGRAM_SAMPLES]
    x = np.broadcast_to(diagram[parameter].values[:, None], samples.shape)
    axes.plot(x_factor * x.ravel(), y_factor * samples.values.ravel(), ".", markersize=3,
              color="0.55", zorder=0, label="from rest (long-time sweep)")
