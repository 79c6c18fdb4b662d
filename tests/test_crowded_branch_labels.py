"""A frequency-response curve with hundreds of events stays readable (issue 31, item 4).

A synthetic continuation Dataset with the variables of `branches_dataset` and the events of
the stiff stop-and-shaker case at the default Hertz contact (docs/benchmarks/
stiff_continuation.md, up: 24 folds, 82 period doublings, 75 Neimark-Sacker points, 67
grazings, 46 contact merges, 46 splits along 5005 points, crowded in the resonance) is drawn
as `impactbeams plot` draws it, and its labels are measured with the Agg renderer: none
overlaps another, a marker or the legend, all lie inside the axes, and every event is
accounted for in the legend (drawn and counted, or counted as not drawn).
"""

import itertools
import re

import numpy as np
import pytest
import xarray as xr
from matplotlib.text import Annotation, Text
from matplotlib.transforms import Bbox

from impactbeams.cli import main
from impactbeams.params import ParameterError
from impactbeams.plotting import plot_dataset
from impactbeams.plotting.branches import MARKERS
from impactbeams.variables import BIFURCATIONS, attributes, parameter_attributes

COUNTS = {"fold": 24, "period_doubling": 82, "neimark_sacker": 75, "grazing": 67,
          "contact_merge": 46, "contact_split": 46}
POINTS = 6000
SHORT = {kind: short for kind, (_, short) in MARKERS.items()}
KIND_OF = {short: kind for kind, short in SHORT.items()}


def crowded_branch():
    """Two branches (period 1, then a period-2 one from a doubling) along Omega, 65.6 to 262.5
    rad/s, their 340 events at random points, two thirds of them within 110-170 rad/s."""
    rng = np.random.default_rng(31)
    omega = np.concatenate([np.linspace(65.6, 262.5, 4500), np.linspace(120.0, 160.0, 1500)])
    amplitude = 4e-4 / np.sqrt((1 - (omega / 140.0) ** 2) ** 2 + 0.05 ** 2) * 1e-2
    amplitude[4500:] *= 1.3
    resonance = np.flatnonzero((omega > 110.0) & (omega < 170.0))
    anywhere = np.arange(POINTS)
    where = np.concatenate([rng.choice(resonance, 227, replace=False),
                            rng.choice(np.setdiff1d(anywhere, resonance), 113, replace=False)])
    codes = np.zeros(POINTS, dtype=np.int8)
    codes[where] = rng.permutation(np.repeat([BIFURCATIONS.index(kind) for kind in COUNTS],
                                             list(COUNTS.values())))
    variables = {
        "branch": np.repeat(np.array([0, 1], np.int32), [4500, 1500]),
        "orbit_period": np.repeat(np.array([1, 2], np.int32), [4500, 1500]),
        "stable": (np.sin(omega / 3.0) > 0).astype(np.int8), "bifurcation": codes,
        "tip_amplitude_1": amplitude,
        "contacts_per_orbit": (amplitude > 5e-4).astype(np.int32)}
    return xr.Dataset(
        {name: ("branch_point", values, attributes(name)) for name, values in variables.items()},
        coords={"branch_point": ("branch_point", np.arange(POINTS), attributes("branch_point")),
                "omega": ("branch_point", omega, parameter_attributes("omega"))},
        attrs={"continued_parameter": "omega", "counterpart": "stop", "clearance": 5e-4,
               "shaker": "beam1", "base_amplitude": 1e-4, "force_amplitude": 0.0,
               "damping_ratio": 0.01, "n_modes": 16, "contact_law": "spring"})


@pytest.fixture(scope="module")
def branch():
    return crowded_branch()


def drawn(branch, captured, tmp_path, events=None):
    """The figure's axes, its labels, their texts and boxes, its event markers by short
    label, its legend's box and its legend's texts."""
    plot_dataset(branch, tmp_path / "branch.png", events=events)
    (figure,) = captured
    axes = figure.axes[0]
    renderer = figure.canvas.get_renderer()
    labels = [text for text in axes.texts if isinstance(text, Annotation)]
    boxes = [Text.get_window_extent(label, renderer) for label in labels]
    markers = {line.get_label().split(":")[0]: line for line in axes.lines
               if re.match(r"^[A-Z]+: ", line.get_label())}
    legend = axes.get_legend()
    return (axes, labels, [label.get_text() for label in labels], boxes, markers,
            legend.get_window_extent(renderer), [t.get_text() for t in legend.get_texts()])


def marker_boxes(axes, markers):
    """Each event marker's drawn extent (its marker size), display units."""
    half = axes.get_figure(root=True).dpi / 72.0 / 2
    return [Bbox([[cx - half * line.get_markersize(), cy - half * line.get_markersize()],
                  [cx + half * line.get_markersize(), cy + half * line.get_markersize()]])
            for line in markers.values()
            for cx, cy in axes.transData.transform(np.column_stack([line.get_xdata(),
                                                                    line.get_ydata()]))]


def assert_apart(axes, labels, boxes, markers, legend):
    """No label box overlaps another, a marker or the legend; all inside the axes; no leader
    line meets another, a label, the legend or a marker but its own event's (matplotlib's own
    path intersections, not the layout's)."""
    inside = axes.get_window_extent()
    for a, b in itertools.combinations(boxes, 2):
        assert not a.overlaps(b)
    at = marker_boxes(axes, markers)
    for box in boxes:
        assert not any(marker.overlaps(box) for marker in at)
        assert not box.overlaps(legend)
        assert inside.x0 <= box.x0 and box.x1 <= inside.x1
        assert inside.y0 <= box.y0 and box.y1 <= inside.y1
    leaders = [(label, label.arrow_patch.get_path()) for label in labels
               if label.arrow_patch.get_visible()]
    for label, path in leaders:
        point = axes.transData.transform(label.xy)
        assert not path.intersects_bbox(legend)
        assert not any(path.intersects_bbox(box) for box, other in zip(boxes, labels,
                                                                      strict=True)
                       if other is not label)
        assert not any(path.intersects_bbox(marker) for marker in at
                       if not marker.contains(*point))
    for (_, a), (_, b) in itertools.combinations(leaders, 2):
        assert not a.intersects_path(b)


def counted(texts, crowded=True):
    """Each drawn kind's legend count and unlabelled count, by short label; the not-drawn
    entry's counts by kind name. On a ``crowded`` curve an entry counts its labelled events
    (none if it does not say), the others are ticks in the strip only."""
    kinds = {}
    for text in texts:
        match = re.match(r"^([A-Z]+): [a-z ]+ \((\d+)(?:; (\d+) (un)?labelled|, (unlabelled))?\)$",
                         text)
        if match:
            count, number = int(match[2]), int(match[3] or 0)
            # a crowded curve's entry says how many are labelled: the others are ticks only
            kinds[match[1]] = (count, count if match[5] else number if match[4] else (
                count - number if match[3] else count if crowded else 0))
    hidden = [text for text in texts if text.startswith("not drawn: ")]
    not_drawn = {kind.replace(" ", "_"): int(count) for count, kind in re.findall(
        r"(\d+) ([a-z ]+?)(?:,|$)", hidden[0].removeprefix("not drawn: "), re.M)} \
        if hidden else {}
    return kinds, not_drawn


def strip_rows(axes):
    """The parameters of each row's ticks in the strip under a crowded curve, by short label
    (a tick: two points and a NaN)."""
    return {line.get_label().removeprefix("_strip "): np.asarray(line.get_xdata())[::3]
            for line in axes.lines if line.get_label().startswith("_strip ")}


def test_a_crowded_branch_ticks_every_event_in_a_strip_and_marks_only_those_apart(
        branch, captured, tmp_path):
    """338 of the 340 markers met another's (main drew them all, and labelled the first
    that fitted): every event is now a tick in a strip under the curves, a row per kind at
    its parameter, and on the curves only the labelled kinds' events whose markers stand apart
    are marked (merges and splits not at all); the legend counts each kind's events and the
    labelled ones, and the curves stay above the strip."""
    axes, labels, texts, boxes, markers, legend, entries = drawn(branch, captured, tmp_path)
    rows = strip_rows(axes)
    assert list(rows) == ["F", "PD", "NS", "G", "M", "S"]
    codes, omega = branch.bifurcation.values, branch.omega.values
    for short, ticks in rows.items():
        assert np.array_equal(np.sort(ticks),
                              np.sort(omega[codes == BIFURCATIONS.index(KIND_OF[short])]))
    assert set(texts) <= {"F", "PD", "NS", "G"}
    assert len(markers["M"].get_xdata()) == 0 and len(markers["S"].get_xdata()) == 0
    on_curve = marker_boxes(axes, markers)
    assert 0 < len(on_curve) < 20
    assert not any(a.overlaps(b) for a, b in itertools.combinations(on_curve, 2))
    kinds, not_drawn = counted(entries)
    assert not_drawn == {}
    for short, (count, unlabelled) in kinds.items():
        assert count == COUNTS[KIND_OF[short]]
        assert count - unlabelled == texts.count(short), short  # the labels drawn
    strip_top = max(np.nanmax(line.get_transform().transform(np.column_stack(
        [line.get_xdata(), line.get_ydata()]))[:, 1]) for line in axes.lines
        if line.get_label().startswith("_strip"))
    curves = [line for line in axes.lines if line.get_label().startswith("branch")
              or line.get_label().startswith("_child")]
    lowest = min(np.nanmin(line.get_transform().transform(np.column_stack(
        [line.get_xdata(), line.get_ydata()]))[:, 1]) for line in curves if len(line.get_xdata()))
    assert lowest > strip_top
    assert_apart(axes, labels, boxes, markers, legend)


def test_labels_are_placed_kind_by_kind_folds_first(branch, captured, tmp_path):
    """The kinds' order (folds, period doublings, Neimark-Sacker, grazings): the first get
    the room, so a larger share of the folds is labelled than of the grazings."""
    axes, labels, texts, *_ = drawn(branch, captured, tmp_path)
    order = ["F", "PD", "NS", "G"]
    assert len(set(texts)) > 1
    assert [order.index(text) for text in texts] == sorted(order.index(text) for text in texts)


def test_all_labels_every_kind_where_it_fits(branch, captured, tmp_path):
    axes, labels, texts, boxes, markers, legend, entries = drawn(branch, captured, tmp_path,
                                                                 "all")
    kinds, not_drawn = counted(entries)
    assert not_drawn == {} and set(kinds) == {"F", "PD", "NS", "G", "M", "S"}
    for short, (count, unlabelled) in kinds.items():
        assert count - unlabelled == texts.count(short)
        assert markers[short].get_markersize() == markers["F"].get_markersize()
    assert_apart(axes, labels, boxes, markers, legend)


@pytest.mark.parametrize("events", ["fold,grazing", ["fold", "grazing"], " fold , grazing"])
def test_a_list_of_kinds_draws_those_and_counts_the_rest_as_not_drawn(branch, captured,
                                                                      tmp_path, events):
    axes, labels, texts, boxes, markers, legend, entries = drawn(branch, captured, tmp_path,
                                                                 events)
    assert set(markers) == {"F", "G"} and set(texts) <= {"F", "G"} and "G" in texts
    kinds, not_drawn = counted(entries)
    assert {short: count for short, (count, _) in kinds.items()} == {"F": 24, "G": 67}
    assert not_drawn == {kind: count for kind, count in COUNTS.items()
                         if kind not in ("fold", "grazing")}
    assert_apart(axes, labels, boxes, markers, legend)


def test_none_draws_no_event_and_says_so(branch, captured, tmp_path):
    axes, labels, texts, boxes, markers, legend, entries = drawn(branch, captured, tmp_path,
                                                                 "none")
    assert texts == [] and markers == {}
    assert counted(entries) == ({}, COUNTS)


BAD = {
    "flod": "events = 'flod' is not allowed: 'flod' is not an event kind (did you mean 'fold'?)",
    "fold,Grazing": "'Grazing' is not an event kind",
    "none,fold": "'all' and 'none' stand alone",
    "": "'' is not an event kind",
    "fold,": "'' is not an event kind",
    5: "events = 5 (int) is not allowed: must be None, 'all', 'none', or event kinds",
    ("fold", 3): "events = ('fold', 3) (tuple) is not allowed",
}


@pytest.mark.parametrize(("events", "message"), BAD.items(), ids=[repr(k) for k in BAD])
def test_bad_events_are_refused_before_drawing(branch, captured, tmp_path, events, message):
    with pytest.raises(ParameterError) as error:
        plot_dataset(branch, tmp_path / "branch.png", events=events)
    assert message in str(error.value)
    assert "fold, period_doubling, neimark_sacker" in str(error.value) or isinstance(events, (
        int, tuple))
    assert captured == [] and not (tmp_path / "branch.png").exists()


def test_events_on_a_sweep_are_refused(tmp_path):
    sweep = xr.Dataset({"first_impact_time": ("omega", np.ones(3), attributes(
        "first_impact_time"))}, coords={"omega": ("omega", [1.0, 2.0, 3.0],
                                                  parameter_attributes("omega"))})
    with pytest.raises(ParameterError, match="events \\(--events\\) is for a continuation's "
                                             "file only"):
        plot_dataset(sweep, tmp_path / "map.png", events="fold")


def test_the_command_line_refuses_a_bad_kind_in_one_line_before_reading(tmp_path, capsys):
    """Exit 2, one line naming the option, the value and what is allowed; the file is not even
    read (it does not exist)."""
    code = main(["plot", str(tmp_path / "missing.nc"), "--events", "fold,pd"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    (line,) = err.splitlines()
    assert line == ("impactbeams: error: --events = 'fold,pd' is not allowed: 'pd' is not an "
                    "event kind; give all, none, or kinds separated by commas from fold, "
                    "period_doubling, neimark_sacker, grazing, branch_point, contact_merge, "
                    "contact_split, chatter")


def test_the_command_line_draws_the_chosen_kinds(branch, captured, tmp_path, capsys):
    path = tmp_path / "branch.nc"
    branch.to_netcdf(path)
    assert main(["plot", str(path), "--events", "neimark_sacker", "--quiet"]) == 0
    (figure,) = captured
    lines = [line for line in figure.axes[0].lines if re.match(r"^[A-Z]+: ", line.get_label())]
    assert [line.get_label().split(":")[0] for line in lines] == ["NS"]
    rows = strip_rows(figure.axes[0])  # crowded: a tick each, a few marked on the curve
    assert list(rows) == ["NS"] and len(rows["NS"]) == 75


def test_the_layouts_geometry_agrees_with_matplotlibs_paths():
    """Segments against boxes and segments, on random ones (crossing or not), as matplotlib's
    `Path.intersects_bbox` and `Path.intersects_path` find them."""
    from matplotlib.path import Path

    from impactbeams.plotting.room import _segments_cross, _segments_meet_boxes

    rng = np.random.default_rng(4)
    segments = rng.uniform(0.0, 100.0, (300, 4))
    corners = rng.uniform(0.0, 100.0, (200, 2))
    boxes = np.column_stack([corners, corners + rng.uniform(1.0, 20.0, (200, 2))])
    paths = [Path(segment.reshape(2, 2)) for segment in segments]
    expected = [[path.intersects_bbox(Bbox(box.reshape(2, 2))) for box in boxes]
                for path in paths]
    met = _segments_meet_boxes(segments, boxes)
    np.testing.assert_array_equal(met, expected)
    assert 0.05 < met.mean() < 0.95  # both answers tested
    crossed = np.array([_segments_cross(segment, segments[:100]) for segment in segments[100:]])
    np.testing.assert_array_equal(crossed, [[a.intersects_path(b) for b in paths[:100]]
                                            for a in paths[100:]])
    assert 0.05 < crossed.mean() < 0.95
    # a box a segment lies in, or one it only passes by; a vertical and a horizontal segment
    assert _segments_meet_boxes(np.array([[1.0, 1.0, 2.0, 2.0], [0.0, 5.0, 5.0, 5.0],
                                          [3.0, 0.0, 3.0, 9.0]]),
                                np.array([[0.0, 0.0, 4.0, 4.0]])).ravel().tolist() == [
        True, False, True]
