"""A frequency-response figure that can be published as drawn (issue 31, item 4).

The branches have the shape of the stiff stop-and-shaker case of docs/continuation.md at
contact_stiffness = 1e4 N/m and 4 modes (the branch from 65.6 to 262.5 rad/s bends right to
1.53 mm at 174 rad/s, folds back unstable to 152 rad/s and goes on below), with a period-2
branch that leaves the upper part at a period doubling and runs a hair above it. Drawn as
`impactbeams plot` draws it, on the Agg canvas, and measured with matplotlib's own path
geometry and the rendered pixels (not the placement code's): the legend covers no line or
marker, no event label covers a branch, the period-2 branch shows over the period-1 one and
its markers while the period-1 one shows beside it.
"""

import itertools
import re

import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.patches import ConnectionPatch
from matplotlib.text import Annotation, Text
from matplotlib.transforms import Bbox

from impactbeams.plotting import plot_dataset
from impactbeams.plotting.branches import MARKERS, _side_connectors, place_legend
from impactbeams.variables import BIFURCATIONS, attributes, parameter_attributes

SHAKER = {"l1": 0.2, "width1": 0.02, "thickness1": 0.001, "counterpart": "stop",
          "clearance": 5e-4, "shaker": "beam1", "base_amplitude": 1e-4,
          "force_amplitude": 0.0, "damping_ratio": 0.01}
# (Omega rad/s, max |y1| m) along the period-1 branch: up the stable impacting part to the top,
# back down the unstable part to the fold, on along the non-impacting part
KNOTS = ((65.6, 1.5e-4), (100.0, 3.2e-4), (112.0, 5.0e-4), (140.0, 8.0e-4), (160.0, 1.05e-3),
         (175.0, 1.53e-3), (174.0, 1.2e-3), (170.0, 8.0e-4), (152.5, 5.0e-4), (160.0, 4.0e-4),
         (200.0, 1.8e-4), (262.5, 1.2e-4))
TOP = 5  # the knot at the top: stable before it, unstable from there to the fold
FOLD = 8
PER_KNOT = 40
EVENTS = ("period_doubling", "neimark_sacker", "grazing", "fold", "contact_merge",
          "contact_split")


def stiff_shaped_branches(every=5, period_two=(130.0, 150.0), upper=True):
    """The period-1 branch along KNOTS, an event every ``every``-th point of its impacting
    part, and a stable period-2 branch from a doubling at ``period_two[0]`` rad/s to
    ``period_two[1]``, 0.4 % above the upper part (or the unstable part, not ``upper``)."""
    t = np.linspace(0.0, len(KNOTS) - 1, PER_KNOT * (len(KNOTS) - 1) + 1)
    knots = np.array(KNOTS)
    omega = np.interp(t, np.arange(len(KNOTS)), knots[:, 0])
    amplitude = np.interp(t, np.arange(len(KNOTS)), knots[:, 1])
    stable = ((t <= TOP) | (t >= FOLD)).astype(np.int8)
    codes = np.zeros(t.size, np.int8)
    impacting = np.flatnonzero((t >= 2) & (t <= FOLD))[::every]
    codes[impacting] = [BIFURCATIONS.index(EVENTS[i % len(EVENTS)])
                        for i in range(impacting.size)]
    part = (t < TOP) if upper else (t > TOP) & (t < FOLD)
    on_part = (omega >= period_two[0]) & (omega <= period_two[1]) & part
    doubling = np.flatnonzero(on_part)[0]
    codes[doubling] = BIFURCATIONS.index("period_doubling")
    order = np.argsort(omega[part])
    period_two_amplitude = 1.004 * np.interp(np.linspace(*period_two, 120),
                                             omega[part][order], amplitude[part][order])
    period_two = np.linspace(*period_two, 120)
    variables = {
        "omega": np.concatenate([omega, period_two]),
        "tip_amplitude_1": np.concatenate([amplitude, period_two_amplitude]),
        "stable": np.concatenate([stable, np.ones(period_two.size, np.int8)]),
        "bifurcation": np.concatenate([codes, np.zeros(period_two.size, np.int8)]),
        "branch": np.repeat(np.array([0, 1], np.int32), [t.size, period_two.size]),
        "orbit_period": np.repeat(np.array([1, 2], np.int32), [t.size, period_two.size])}
    n = t.size + period_two.size
    return xr.Dataset(
        {name: ("branch_point", values, attributes(name)) for name, values in variables.items()
         if name != "omega"},
        coords={"branch_point": ("branch_point", np.arange(n), attributes("branch_point")),
                "omega": ("branch_point", variables["omega"], parameter_attributes("omega"))},
        attrs={**SHAKER, "continued_parameter": "omega", "n_modes": 4, "contact_law": "spring",
               "contact_stiffness": 1e4})


@pytest.fixture
def figure(captured, tmp_path):
    plot_dataset(stiff_shaped_branches(), tmp_path / "branch.png")
    (drawn,) = captured
    return drawn


def _paths(axes):
    """Each drawn line with data: its display path and whether it is drawn with a line."""
    return [(line, line.get_path().transformed(line.get_transform())) for line in axes.lines
            if len(line.get_xdata())]


def _markers(line):
    """The display boxes of ``line``'s markers (none if it has no marker)."""
    if line.get_marker() in ("None", "", " ", None):
        return []
    half = 0.5 * line.get_markersize() * line.get_figure(root=True).dpi / 72.0
    xy = line.get_transform().transform(np.column_stack([line.get_xdata(),
                                                          line.get_ydata()]))
    return [Bbox([[x - half, y - half], [x + half, y + half]]) for x, y in xy]


def _assert_legend_covers_nothing(axes):
    legend = axes.get_legend().get_window_extent(axes.get_figure(root=True).canvas.get_renderer())
    for line, path in _paths(axes):
        if line.get_linestyle() not in ("None", ""):
            assert not path.intersects_bbox(legend, filled=False), line.get_label()
        assert not any(marker.overlaps(legend) for marker in _markers(line)), line.get_label()


def test_the_legend_covers_no_line_and_no_marker(figure):
    """On main ("best") the legend covered the branch's top, 165-172 rad/s."""
    _assert_legend_covers_nothing(figure.axes[0])


def plot_filling_the_axes(dataset, path):
    """Plot ``dataset`` with its curve swept over the whole axes (no room for a legend)."""
    wiggle = (1.0 + np.sin(np.linspace(0.0, 400.0, dataset.omega.size))) * 8e-4
    plot_dataset(dataset.assign(tip_amplitude_1=("branch_point", wiggle,
                                                 dataset.tip_amplitude_1.attrs)), path)


def test_a_legend_with_no_room_inside_goes_beside_the_axes(captured, tmp_path):
    """A curve that sweeps the whole axes leaves no free place: the legend goes beside them,
    within the figure."""
    plot_filling_the_axes(stiff_shaped_branches(), tmp_path / "full.png")
    figure = captured[0]
    axes = figure.axes[0]
    legend = axes.get_legend().get_window_extent(figure.canvas.get_renderer())
    assert legend.x0 > axes.get_window_extent().x1
    assert figure.bbox.contains(legend.x1, legend.y1) and figure.bbox.contains(legend.x0,
                                                                               legend.y0)
    _assert_legend_covers_nothing(axes)


def test_place_legend_keeps_a_free_place_inside(tmp_path):
    """A line across the lower half only: the legend goes in the upper right corner."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6, 4), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots()
    x = np.linspace(0.0, 1.0, 50)
    axes.plot(x, 0.3 * x, label="a line")
    axes.set_ylim(0.0, 1.0)
    place_legend(axes)
    figure.canvas.draw()
    legend = axes.get_legend().get_window_extent(figure.canvas.get_renderer())
    inside = axes.get_window_extent()
    assert inside.contains(legend.x0, legend.y0) and inside.contains(legend.x1, legend.y1)
    assert inside.x1 - legend.x1 < 0.05 * inside.width  # the upper right corner
    assert inside.y1 - legend.y1 < 0.05 * inside.height
    _assert_legend_covers_nothing(axes)


def test_no_event_label_covers_a_branch(figure):
    axes = figure.axes[0]
    renderer = figure.canvas.get_renderer()
    labels = [text for text in axes.texts if isinstance(text, Annotation)]
    assert len(labels) > 10
    branches = [path for line, path in _paths(axes) if line.get_linestyle() not in ("None", "")]
    for label in labels:
        box = Text.get_window_extent(label, renderer)
        assert not any(path.intersects_bbox(box, filled=False) for path in branches), label


def _rendered(figure):
    figure.canvas.draw()
    return np.asarray(figure.canvas.buffer_rgba())[..., :3] / 255.0


def _colour_near(image, figure, xy, colour):
    """The smallest distance of ``colour`` to the pixels within 1 of display point ``xy``."""
    column, row = int(round(xy[0])), int(round(figure.bbox.height - xy[1]))
    patch = image[row - 1:row + 2, column - 1:column + 2].reshape(-1, 3)
    return float(np.min(np.linalg.norm(patch - np.array(to_rgb(colour)), axis=1)))


def test_the_period_two_branch_shows_over_the_period_one_branch_and_its_markers(figure):
    """On main the period-2 line lay under the period-1 branch's event markers, same width:
    where it ran within a marker of the period-1 branch it was hidden. Now it is drawn over
    them, thinner: its colour shows at each of its points, and the period-1 colour shows
    beside it where they overlap."""
    axes = figure.axes[0]
    dataset = stiff_shaped_branches()
    period_two = dataset.where(dataset.branch == 1, drop=True)
    image = _rendered(figure)
    points = axes.transData.transform(np.column_stack([period_two.omega.values,
                                                       period_two.tip_amplitude_1.values
                                                       * 1e3]))
    far = [_colour_near(image, figure, xy, "C1") for xy in points]
    # its own colour, up to the anti-aliasing of a 1.7-pixel line: C1 lies 1.07 or more from
    # white, black and C0 (RGB distance), a pixel within 0.3 of it reads as C1
    assert max(far) < 0.3
    # the period-1 line, wider, shows on each side of the period-2 one above it
    (one,) = [line for line in axes.lines if line.get_label() == "branch 0 (period 1)"]
    (two,) = [line for line in axes.lines if line.get_label() == "branch 1 (period 2)"]
    assert two.get_linewidth() < one.get_linewidth()
    markers = [line for line in axes.lines if ":" in line.get_label()]
    assert all(two.get_zorder() > line.get_zorder() for line in [one, *markers])
    below = [xy - [0.0, 0.45 * one.get_linewidth() * figure.dpi / 72.0] for xy in points]
    assert np.median([_colour_near(image, figure, xy, "C0") for xy in below]) < 0.2


def test_the_stiff_cases_figure_says_its_drive_in_millimetres(figure):
    axes = figure.axes[0]
    assert "$U_0$ = 100 µm on beam 1's clamp" in axes.get_title(loc="left")
    assert "F_0" not in axes.get_title(loc="left")  # no tip force: not named
    assert axes.get_ylabel().endswith("(mm)") and axes.get_xlabel() == "$\\Omega$ (rad/s)"
    styles = {line.get_label(): line.get_linestyle() for line in axes.lines
              if line.get_label() in ("stable", "unstable")}
    assert styles == {"stable": "-", "unstable": "--"}


NARROW_PERIOD_TWO = (160.16, 160.60)  # rad/s: the stiff case's period-2 branch going down


def crowded_with_a_narrow_period_two_branch():
    """An event at every point of the impacting part (205 along 0.66 of the axes' width: as
    crowded as the stiff case at its default contact), and the period-2 branch 0.44 of 197
    rad/s wide on the unstable part, as the stiff case's going down."""
    return stiff_shaped_branches(every=1, period_two=NARROW_PERIOD_TWO, upper=False)


@pytest.fixture
def crowded(captured, tmp_path):
    plot_dataset(crowded_with_a_narrow_period_two_branch(), tmp_path / "crowded.png")
    (drawn,) = captured
    return drawn


def _event_lines(axes):
    return [line for line in axes.lines if re.match(r"^[A-Z]+: ", line.get_label())]


def test_a_crowded_curves_markers_stand_apart_and_every_event_is_a_tick(crowded):
    """Main drew a marker at each of the 206 events, one over the other; now no two markers
    on the curve meet, and each event is a tick in the strip under the curves, a row per
    kind, at its parameter."""
    axes = crowded.axes[0]
    boxes = [box for line in _event_lines(axes) for box in _markers(line)]
    assert not any(a.overlaps(b) for a, b in itertools.combinations(boxes, 2))
    dataset = crowded_with_a_narrow_period_two_branch()
    codes, omega = dataset.bifurcation.values, dataset.omega.values
    rows = {line.get_label().removeprefix("_strip "): np.asarray(line.get_xdata())[::3]
            for line in axes.lines if line.get_label().startswith("_strip ")}
    assert sum(ticks.size for ticks in rows.values()) == np.count_nonzero(codes)
    for kind in EVENTS:
        short = MARKERS[kind][1]
        assert np.array_equal(np.sort(rows[short]),
                              np.sort(omega[codes == BIFURCATIONS.index(kind)]))


def test_a_narrow_period_two_branch_is_zoomed_in_an_inset_drawn_above(crowded):
    """0.44 of 197 rad/s: on main a line 2 pixels long among the markers, not to be found.
    Now an inset shows its window, its line over the period-1 branch's and the markers, its
    colour at each of its points in the rendered pixels; the inset covers no line or marker
    of the axes, nor the legend, and the legend says where the branch is drawn."""
    axes = crowded.axes[0]
    (inset,) = axes.child_axes
    low, high = inset.get_xlim()
    width = NARROW_PERIOD_TWO[1] - NARROW_PERIOD_TWO[0]
    assert low < NARROW_PERIOD_TWO[0] and NARROW_PERIOD_TWO[1] < high and high - low < 2 * width
    (two,) = [line for line in inset.lines if line.get_color() == "C1"]
    assert all(two.get_zorder() > line.get_zorder() for line in inset.lines if line is not two)
    image = _rendered(crowded)
    points = inset.transData.transform(np.column_stack([two.get_xdata(), two.get_ydata()]))
    assert max(_colour_near(image, crowded, xy, "C1") for xy in points) < 0.3
    renderer = crowded.canvas.get_renderer()
    box = inset.get_tightbbox(renderer)
    for line, path in _paths(axes):
        if line.get_linestyle() not in ("None", ""):
            assert not path.intersects_bbox(box, filled=False), line.get_label()
        assert not any(marker.overlaps(box) for marker in _markers(line)), line.get_label()
    assert not axes.get_legend().get_window_extent(renderer).overlaps(box)
    assert "branch 1 (period 2; inset)" in [t.get_text() for t in axes.get_legend().get_texts()]


def test_an_inset_level_with_its_window_is_joined_to_it_from_the_facing_sides():
    """Matplotlib shows none of its four connectors where the zoomed window lies level with an
    inset beside it (the stiff case going down: the period-2 branch at 160 rad/s, the inset to
    its right; on main the inset stood unjoined): two lines then join the window's right
    corners to the inset's left ones."""
    figure = Figure()
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    axes.plot([0.0, 300.0], [0.0, 1.2])
    inset = axes.inset_axes([0.6, 0.35, 0.3, 0.3])
    inset.set_xlim(160.2, 160.7)
    inset.set_ylim(0.578, 0.601)
    indicator = axes.indicate_inset_zoom(inset)
    figure.draw_without_rendering()
    assert not any(connector.get_visible() for connector in indicator.connectors)
    _side_connectors(axes, inset, 0.6)
    joined = sorted((tuple(map(float, line.xy1)), tuple(map(float, line.xy2)))
                    for line in axes.patches if isinstance(line, ConnectionPatch))
    assert joined == [((160.7, 0.578), (0.0, 0.0)), ((160.7, 0.601), (0.0, 1.0))]


def test_a_narrow_branch_without_room_for_an_inset_says_its_range(captured, tmp_path):
    """A curve that sweeps the whole axes leaves no room: the legend gives the range."""
    plot_filling_the_axes(crowded_with_a_narrow_period_two_branch(), tmp_path / "full.png")
    axes = captured[0].axes[0]
    assert axes.child_axes == []
    assert ("branch 1 (period 2; 160.16 to 160.60 rad/s)"
            in [t.get_text() for t in axes.get_legend().get_texts()])


def test_the_legend_counts_the_events_the_summary_counts(captured, tmp_path):
    """An event stored on two neighbouring points (a grazing on its near side's last point and
    its far side's first, 1e-12 rad/s apart, as main stored one on the stiff stop going down
    at 163.3051438 rad/s): main's summary counted it once and the legend twice ("G: grazing
    (95)" beside "94 grazing"). Both count each event once now, whatever the kind."""
    from impactbeams.cli import _branch_summary

    dataset = stiff_shaped_branches()
    codes = dataset.bifurcation.values
    twins = [np.flatnonzero(codes == BIFURCATIONS.index(kind))[0]
             for kind in ("grazing", "contact_merge")]
    order = np.sort(np.r_[np.arange(codes.size), twins])
    doubled = dataset.isel(branch_point=order)
    omega = doubled.omega.values.copy()
    omega[np.flatnonzero(np.diff(order) == 0) + 1] += 1e-12
    doubled = doubled.assign_coords(
        branch_point=("branch_point", np.arange(order.size), attributes("branch_point")),
        omega=("branch_point", omega, doubled.omega.attrs)).assign_attrs(
        branch_covered="65.6:262.5 130.0:150.0", branch_endings="bound bound")
    plot_dataset(doubled, tmp_path / "twins.png")
    legend = [text.get_text() for text in captured[0].axes[0].get_legend().get_texts()]
    summary = _branch_summary(doubled)
    for kind in EVENTS:
        (entry,) = [text for text in legend if text.startswith(f"{MARKERS[kind][1]}: ")]
        counted = int(re.search(r"\((\d+)", entry).group(1))
        assert f"{counted} {kind}" in summary
        assert counted == np.count_nonzero(codes == BIFURCATIONS.index(kind))


def test_a_crowded_curves_markers_stand_apart_with_the_legend_beside_the_axes(captured,
                                                                                tmp_path):
    """A curve that leaves the legend no room inside: beside the axes, it shrinks them. Main
    chose the markers that stand apart before, on the wider axes, and some met on the figure
    as drawn; now they are chosen after, and none meet."""
    plot_filling_the_axes(crowded_with_a_narrow_period_two_branch(), tmp_path / "full.png")
    figure = captured[0]
    axes = figure.axes[0]
    legend = axes.get_legend().get_window_extent(figure.canvas.get_renderer())
    assert legend.x0 > axes.get_window_extent().x1  # beside the axes
    boxes = [box for line in _event_lines(axes) for box in _markers(line)]
    assert len(boxes) > 3
    assert not any(a.overlaps(b) for a, b in itertools.combinations(boxes, 2))
