"""Frequency-response curves: a continuation's branches against the continued parameter.

Stable orbits solid, unstable dashed, one colour per branch, bifurcations marked and
labelled (the labels placed apart, `place_labels`); optionally over a brute-force bifurcation
diagram (its stroboscopic samples as grey dots, against the branches' own samples
``section_deflection_1``: p curves for a period-p branch, one per section t = k T). Lengths
and forces are drawn in the prefixed units of their size (µm, mm, mN), never in metres with an
offset; Omega in rad/s, or in Hz if asked.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Annotation, Text
from matplotlib.transforms import Bbox

from impactbeams.params import ParameterError
from impactbeams.plotting.labels import axis_label, display_units
from impactbeams.variables import BIFURCATIONS

DEFAULT_MEASURE = "tip_amplitude_1"
OVERLAY_MEASURE = "section_deflection_1"  # what a diagram's poincare_deflection1 shows
DIAGRAM_SAMPLES = "poincare_deflection1"
ALONG = (("branch_point",), ("branch_point", "section"))  # what can be drawn
MARKERS = {"fold": ("o", "F"), "period_doubling": ("s", "PD"), "neimark_sacker": ("D", "NS"),
           "grazing": ("^", "G"), "branch_point": ("v", "BP"), "contact_merge": ("<", "M"),
           "contact_split": (">", "S"), "chatter": ("x", "C")}
OTHER_MARKER = "*"  # an event kind without a marker of its own
# where an event's label may go, in points from its marker, tried in this order: beside it,
# then further up or down (joined to it by a line)
_OFFSETS = ((5, 5), (5, -13), (-17, 5), (-17, -13), *((dx, dy) for dy in (18, -26, 30, -38,
            42, -50, 54, -62) for dx in (5, -17)))
_MARKER_HALF_WIDTH = 4.0  # points: a marker's extent, kept free of labels


def draw_branches(axes: Axes, dataset: xr.Dataset, variable: str | None = None,
                  diagram: xr.Dataset | None = None, hz: bool = False) -> None:
    """Draw ``variable`` (default max |y1|, or y1 on the section over a ``diagram``).

    ``hz``: a frequency axis in Hz (Omega / 2 pi) instead of rad/s. Lengths and forces are
    drawn in the units `branch_units` gives; draw anything else first, in those units, and set
    the axes' limits before: the event labels are placed last, on the laid-out axes.
    """
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
    for branch in np.unique(dataset.branch.values):
        _draw_branch(axes, x, y, dataset.stable.values, dataset.branch.values == branch,
                     f"C{int(branch)}", f"branch {int(branch)} (period "
                     f"{int(dataset.orbit_period.values[dataset.branch.values == branch][0])})")
    events = _mark_bifurcations(axes, x, y[:, 0], dataset.bifurcation.values)
    axes.set_xlabel(r"$\Omega / 2\pi$ (Hz)" if x_units == "Hz"
                    else axis_label(dataset[parameter], x_units))
    axes.set_ylabel(axis_label(dataset[name], y_units))
    axes.ticklabel_format(useOffset=False)  # values as read, never "+2.523e2" beside an axis
    axes.plot([], [], "k-", label="stable")
    axes.plot([], [], "k--", label="unstable")
    axes.legend(fontsize="small", loc="best")
    place_labels(axes, events)


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


def _marker(kind: str) -> tuple[str, str]:
    """An event kind's marker and short label (its initials if it has none of its own)."""
    return MARKERS.get(kind, (OTHER_MARKER, "".join(w[0] for w in kind.split("_")).upper()))


def _mark_bifurcations(axes: Axes, x: np.ndarray, y: np.ndarray, codes: np.ndarray,
                       ) -> list[tuple[float, float, str]]:
    """Mark each located event; returns (x, y, short label) of each, for `place_labels`."""
    events = []
    for code in np.unique(codes[codes > 0]):
        kind = BIFURCATIONS[code] if code < len(BIFURCATIONS) else f"event_{code}"
        marker, short = _marker(kind)
        where = np.flatnonzero(codes == code)
        axes.plot(x[where], y[where], marker, color="k", markerfacecolor="none",
                  label=f"{short}: {kind.replace('_', ' ')}")
        events += [(float(x[i]), float(y[i]), short) for i in where]
    return sorted(events)


def place_labels(axes: Axes, events: list[tuple[float, float, str]]) -> None:
    """Label each event (x, y, text) near its point, clear of the labels, legend and markers.

    Greedy, left to right: each label takes the first of ``_OFFSETS`` whose box is free and
    inside the axes (a far one is joined to its point by a line); if none is, it is left out
    (on a branch with hundreds of events: the markers and the legend still name them).
    Positions are measured on the laid-out figure; events out of the
    axes' view are not labelled.
    """
    figure = axes.get_figure(root=True)
    figure.draw_without_rendering()  # the layout: positions as they will be drawn
    renderer = _renderer(figure)
    points_to_pixels = figure.dpi / 72.0
    inside = axes.get_window_extent(renderer)
    taken = [_marker_box(axes, x, y, points_to_pixels) for x, y, _ in events]
    legend = axes.get_legend()
    if legend is not None:  # kept where it is now: it would move away from the labels
        box = legend.get_window_extent(renderer)
        legend.set_loc(tuple(axes.transAxes.inverted().transform((box.x0, box.y0))))
        taken.append(box)
    for x, y, text in events:
        if not inside.contains(*axes.transData.transform((x, y))):
            continue  # out of view (limits set by the caller): no label
        label = axes.annotate(text, (x, y), textcoords="offset points", xytext=_OFFSETS[0],
                              fontsize="x-small", annotation_clip=False,
                              arrowprops={"arrowstyle": "-", "color": "0.5", "lw": 0.5,
                                          "shrinkA": 0, "shrinkB": 4})
        label.set_in_layout(False)
        offset = _free_offset(label, renderer, taken, inside)
        if offset is None:  # no room: its marker and the legend name it
            label.remove()
            continue
        label.xyann = offset
        label.arrow_patch.set_visible(abs(label.xyann[1]) > 15)  # a line to a far label
        taken.append(_text_box(label, renderer))


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


def _free_offset(label: Annotation, renderer: RendererBase, taken: list[Bbox],
                 inside: Bbox) -> tuple[float, float] | None:
    """The first offset of ``_OFFSETS`` putting ``label`` clear of ``taken``, inside ``inside``.

    None if there is none (a crowded branch: the label is left out).
    """
    for offset in _OFFSETS:
        label.xyann = offset
        box = _text_box(label, renderer)
        if _contains(inside, box) and not any(box.overlaps(other) for other in taken):
            return offset
    return None


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
