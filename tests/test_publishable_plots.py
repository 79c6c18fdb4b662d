"""Figures that can be published as they come (issue 32): contact forces drawn at their peaks,
titles that name every drive and fit the figure, continuation plots with labels apart and axes
in the units people use. Drawn on the Agg canvas and measured there (no pyplot)."""

import itertools

import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.text import Annotation, Text

from impactbeams import Params, simulate
from impactbeams.plotting import draw, plot_dataset, trajectories
from impactbeams.plotting.labels import display_units, with_units
from impactbeams.variables import BIFURCATIONS, attributes, parameter_attributes

TIED = Params(contact_law="tied")  # the paper's case: 10 contacts in 0.06 s


def _largest_drawn(axis):
    """The largest y drawn on ``axis`` by its lines and line collections (data units)."""
    values = [np.nanmax(np.asarray(line.get_ydata(), dtype=float)) for line in axis.lines
              if len(line.get_ydata())]
    values += [max(np.max(segment[:, 1]) for segment in collection.get_segments())
               for collection in axis.collections
               if isinstance(collection, LineCollection) and collection.get_segments()]
    return max(values)


@pytest.fixture(scope="module")
def coarse_run():
    """The paper's case under the tied law sampled every ms: most contacts fall between."""
    return simulate(TIED, 0.06, n_modes=5, dt_output=1e-3, energy_balance=False)


def test_run_overview_draws_the_peak_of_every_contact(coarse_run, captured, tmp_path):
    """The drawn maximum of the force panel is the largest contact's certified peak
    (impact_peak_force), where the output samples reach barely a fraction of it."""
    run = coarse_run
    peak_mN = 1e3 * float(run.impact_peak_force.max())
    assert 1e3 * float(run.contact_force.max()) < 0.6 * peak_mN  # the samples miss it
    trajectories.plot_run(run, tmp_path / "run.png")
    (figure,) = captured
    force = figure.axes[1]
    assert _largest_drawn(force) == peak_mN
    assert force.get_ylim()[1] >= peak_mN
    # one marker per contact, at its onset
    (markers,) = [line for line in force.lines if line.get_label() == "peak of each contact"]
    assert np.array_equal(markers.get_xdata(), run.impact_onset_time.values)


def test_a_runs_force_drawn_alone_shows_the_peaks_too(coarse_run, captured, tmp_path):
    """`impactbeams plot RUN.nc --var contact_force`: the same peaks as the overview."""
    plot_dataset(coarse_run, tmp_path / "force.png", "contact_force")
    axes = captured[0].axes[0]
    assert _largest_drawn(axes) == 1e3 * float(coarse_run.impact_peak_force.max())
    assert axes.get_ylabel() == "contact force $R$ (mN)"


def test_fig3_panels_draw_every_peak_and_are_lettered_once(coarse_run, captured, tmp_path):
    trajectories.plot_paper_fig3_laws([coarse_run, coarse_run], tmp_path / "fig3.png")
    (figure,) = captured
    axes = np.array(figure.axes).reshape(3, 2)
    for force in axes[2]:
        assert _largest_drawn(force) == 1e3 * float(coarse_run.impact_peak_force.max())
    letters = [axis.get_title(loc="left") for axis in axes.T.ravel()]
    assert letters == ["(a)", "(b)", "(c)", "(d)", "(e)", "(f)"]


SHAKER = {"force_amplitude": 0.0, "base_amplitude": 5e-6, "shaker": "both", "omega": 250.0,
          "counterpart": "stop", "clearance": 1.1e-5}


def _run_like(**attrs):
    time = np.linspace(0.0, 0.01, 11)
    zero = ("time", 0.0 * time)
    return xr.Dataset(
        {"tip_deflection_1": zero, "tip_deflection_2": zero, "contact_force": zero,
         "energy": zero, "restitution_coefficient": ("impact", [0.5]),
         "impact_onset_time": ("impact", [0.005]), "impact_peak_force": ("impact", [1e-3])},
        coords={"time": time}, attrs={"n_modes": 28, "contact_law": "spring",
                                      "contact_stiffness": 4.31e5, "status": "complete",
                                      **attrs})


def _left_title(axes):
    """The artist of ``axes``'s left title (the package titles on the left)."""
    (title,) = [child for child in axes.get_children() if isinstance(child, Text)
                and child.get_text() and child.get_text() == axes.get_title(loc="left")]
    return title


def _inside_figure(figure, text):
    """Whether ``text``'s rendered box lies within the figure (pixels, after layout)."""
    box = text.get_window_extent(figure.canvas.get_renderer())
    frame = figure.bbox
    return (frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0
            and box.y1 <= frame.y1)


def test_a_shaker_runs_title_names_its_drive_and_not_an_absent_force(captured, tmp_path):
    trajectories.plot_run(_run_like(**SHAKER, contact_damping=0.01), tmp_path / "run.png")
    (figure,) = captured
    title = figure.axes[0].title
    text = title.get_text()
    assert "$U_0$ = 5 µm on beam 1's clamp and the stop" in text
    assert "$F_0$" not in text  # no tip force: not named
    assert "$\\Omega$ = 250 rad/s (39.8 Hz)" in text and "$\\Delta$ = 11 µm" in text
    assert _inside_figure(figure, title)


@pytest.mark.parametrize(("shaker", "counterpart", "words"), [
    ("both", "beam", "on both clamps"), ("beam1", "beam", "on beam 1's clamp"),
    ("beam2", "beam", "on beam 2's clamp"), ("beam2", "stop", "on the stop")])
def test_the_title_says_which_clamps_the_shaker_moves(captured, tmp_path, shaker, counterpart,
                                                      words):
    trajectories.plot_run(_run_like(**{**SHAKER, "shaker": shaker,
                                       "counterpart": counterpart, "force_amplitude": 1e-4}),
                          tmp_path / "run.png")
    text = captured[0].axes[0].get_title()
    assert f"$U_0$ = 5 µm {words}" in text and "$F_0$ = 100 µN" in text


def _map_of_many_parameters():
    """A line over Omega with every case parameter fixed: a long title."""
    omega = np.linspace(100.0, 400.0, 5)
    return xr.Dataset(
        {"first_impact_time": ("omega", np.linspace(0.1, 0.5, 5),
                               attributes("first_impact_time"))},
        coords={"omega": ("omega", omega, parameter_attributes("omega"))},
        attrs={"force_amplitude": 2.5e-4, "base_amplitude": 3e-6, "shaker": "beam1",
               "clearance": 1.1e-5, "uplift1": 2e-6, "uplift2": 1e-6, "damping_ratio": 0.03,
               "t_max": 1.0, "n_modes": 28, "contact_law": "spring", "counterpart": "stop"})


def test_a_long_map_title_is_wrapped_within_the_figure(captured, tmp_path):
    plot_dataset(_map_of_many_parameters(), tmp_path / "map.png")
    (figure,) = captured
    title = _left_title(figure.axes[0])
    assert "$U_0$ = 3 µm on beam 1's clamp" in title.get_text()
    assert _inside_figure(figure, title)


def test_units_a_reader_uses():
    assert [with_units(v, "m") for v in (1.1e-5, 2.5e-3, 0.2, 5e-8)] == [
        "11 µm", "2.5 mm", "0.2 m" if False else "200 mm", "50 nm"]
    assert [with_units(v, "N") for v in (1e-3, 2.5e-5, 3.0)] == ["1 mN", "25 µN", "3 N"]
    assert with_units(4.31e5, "N/m") == "$4.31\\times10^{5}$ N/m"
    assert display_units(np.array([np.nan, 8.2e-5, -1e-6]), "m") == (1e6, "µm")
    assert display_units(np.array([0.0, 0.0]), "m") == (1.0, "m")


# --- a continuation's branch ---------------------------------------------------------------


def _branch(n=60):
    """A synthetic branch along Omega (metres, ~80 µm) with events crowded together: a fold,
    a grazing and a period doubling within 0.3 rad/s of one another, two more apart."""
    omega = np.linspace(150.0, 450.0, n)
    amplitude = 8e-5 / (1.0 + ((omega - 300.0) / 20.0) ** 2)
    codes = np.zeros(n, dtype=np.int8)
    crowded = np.argmin(abs(omega - 300.0))
    omega[crowded:crowded + 3] = 300.0 + np.array([0.0, 0.1, 0.2])
    codes[crowded:crowded + 3] = [BIFURCATIONS.index(k) for k in
                                  ("fold", "grazing", "period_doubling")]
    codes[[5, n - 5]] = BIFURCATIONS.index("grazing")
    stable = (omega < 300.0).astype(np.int8)
    variables = {"omega": omega, "tip_amplitude_1": amplitude, "bifurcation": codes,
                 "stable": stable, "branch": np.zeros(n, np.int32),
                 "orbit_period": np.ones(n, np.int32),
                 "peak_contact_force": np.where(omega > 250, 2e-3, 0.0)}
    dataset = xr.Dataset(
        {name: ("branch_point", values, attributes(name)) for name, values in variables.items()
         if name != "omega"},
        coords={"branch_point": ("branch_point", np.arange(n), attributes("branch_point")),
                "omega": ("branch_point", omega, parameter_attributes("omega"))},
        attrs={**SHAKER, "continued_parameter": "omega", "n_modes": 5, "contact_law": "spring",
               "damping_ratio": 0.02})
    return dataset


def _labels(axes):
    return [text for text in axes.texts if isinstance(text, Annotation)]


def test_continuation_labels_are_apart_and_axes_in_micrometres(captured, tmp_path):
    plot_dataset(_branch(), tmp_path / "branch.png")
    (figure,) = captured
    axes = figure.axes[0]
    renderer = figure.canvas.get_renderer()
    labels = _labels(axes)
    assert sorted(label.get_text() for label in labels) == ["F", "G", "G", "G", "PD"]
    boxes = [Text.get_window_extent(label, renderer) for label in labels]
    for a, b in itertools.combinations(boxes, 2):
        assert not a.overlaps(b)
    legend = axes.get_legend().get_window_extent(renderer)
    assert not any(box.overlaps(legend) for box in boxes)
    assert axes.get_ylabel().endswith("(µm)") and axes.get_xlabel() == "$\\Omega$ (rad/s)"
    assert axes.yaxis.get_offset_text().get_text() == ""  # no "1e-5" above the axis
    drawn = max(np.max(line.get_ydata()) for line in axes.lines if len(line.get_ydata()))
    assert drawn == pytest.approx(1e6 * float(_branch().tip_amplitude_1.max()), rel=1e-12)
    title = _left_title(axes)
    assert "$U_0$ = 5 µm on beam 1's clamp and the stop" in title.get_text()
    assert _inside_figure(figure, title)
    styles = {line.get_linestyle() for line in axes.lines if line.get_label().startswith(
        "branch") or line.get_label() == "_child0"}
    assert styles <= {"-", "--"}


def test_continuation_stability_is_solid_and_dashed(captured, tmp_path):
    branch = _branch()
    plot_dataset(branch, tmp_path / "branch.png")
    axes = captured[0].axes[0]
    curves = [line for line in axes.lines if line.get_color() == "C0"]
    stable_x = branch.omega.values[branch.stable.values == 1]
    for line in curves:
        x = np.asarray(line.get_xdata())
        inside = np.isin(x[:-1], stable_x)  # a run's points but its joint to the next
        assert line.get_linestyle() == ("-" if inside.all() else "--")


def test_continuation_in_hz_and_forces_in_millinewtons(captured, tmp_path):
    plot_dataset(_branch(), tmp_path / "branch.png", "peak_contact_force", hz=True)
    axes = captured[0].axes[0]
    assert axes.get_xlabel() == "$\\Omega / 2\\pi$ (Hz)"
    assert axes.get_ylabel().endswith("(mN)")
    x = np.concatenate([line.get_xdata() for line in axes.lines if len(line.get_xdata())])
    assert x.min() == pytest.approx(150.0 / (2 * np.pi)) and x.max() == pytest.approx(
        450.0 / (2 * np.pi))
    assert axes.xaxis.get_offset_text().get_text() == ""


def test_hz_is_refused_off_a_continuation(tmp_path):
    from impactbeams.params import ParameterError

    with pytest.raises(ParameterError, match="--hz is for a continuation's file only"):
        plot_dataset(_map_of_many_parameters(), tmp_path / "m.png", hz=True)


def test_draw_on_a_given_axes_keeps_its_figure(tmp_path):
    """`draw` on a user's Axes: the title wraps within that figure too."""
    figure = Figure(figsize=(4, 3), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots()
    draw(axes, _map_of_many_parameters())
    figure.canvas.draw()
    assert _inside_figure(figure, _left_title(axes))


def test_a_shaker_studys_bifurcation_diagram_names_its_drive_in_micrometres(captured,
                                                                           tmp_path):
    """The shipped stop-shaker diagram's case: the title named "F0 = 0 N" and not the shaker,
    and the samples were drawn in metres under a "x10^-5" offset."""
    omega = np.linspace(100.0, 1000.0, 30)
    samples = 1e-5 * np.sin(omega[:, None] / 50.0 + np.arange(8)[None, :])
    dataset = xr.Dataset(
        {"poincare_deflection1": (("omega", "period"), samples,
                                  attributes("poincare_deflection1"))},
        coords={"omega": ("omega", omega, parameter_attributes("omega"))},
        attrs={**SHAKER, "damping_ratio": 0.03, "transient_periods": 500,
               "sampled_periods": 200, "n_modes": 28, "contact_law": "spring"})
    plot_dataset(dataset, tmp_path / "diagram.png")
    (figure,) = captured
    axes = figure.axes[0]
    title = _left_title(axes)
    assert "$U_0$ = 5 µm on beam 1's clamp and the stop" in title.get_text()
    assert "$F_0$" not in title.get_text() and _inside_figure(figure, title)
    assert axes.get_ylabel().endswith("(µm)")
    assert axes.yaxis.get_offset_text().get_text() == ""
    (dots,) = axes.lines
    np.testing.assert_array_equal(np.sort(dots.get_ydata()), np.sort(1e6 * samples.ravel()))


def test_a_map_over_the_base_amplitude_says_where_the_shaker_sits(captured, tmp_path):
    omega, amplitude = np.linspace(10.0, 400.0, 4), np.geomspace(1e-7, 1e-2, 3)
    dataset = xr.Dataset(
        {"first_impact_time": (("omega", "base_amplitude"), np.full((4, 3), 0.1),
                               attributes("first_impact_time"))},
        coords={"omega": ("omega", omega, parameter_attributes("omega")),
                "base_amplitude": ("base_amplitude", amplitude,
                                   parameter_attributes("base_amplitude"))},
        attrs={**SHAKER, "t_max": 1.0, "n_modes": 5})
    plot_dataset(dataset, tmp_path / "map.png")
    text = _left_title(captured[0].axes[0]).get_text()
    assert "shaker on beam 1's clamp and the stop" in text
    assert "$F_0$" not in text and "$U_0$ =" not in text  # U0 is an axis


def test_labels_are_placed_on_a_figure_without_an_agg_canvas():
    """`draw_branches` on a bare Figure measures with an Agg renderer and leaves the canvas."""
    from impactbeams.plotting.branches import draw_branches

    figure = Figure(figsize=(7, 5), layout="constrained")
    canvas = figure.canvas
    axes = figure.subplots()
    draw_branches(axes, _branch())
    assert figure.canvas is canvas
    FigureCanvasAgg(figure)
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    boxes = [Text.get_window_extent(label, renderer) for label in _labels(axes)]
    assert len(boxes) == 5
    for a, b in itertools.combinations(boxes, 2):
        assert not a.overlaps(b)


def test_a_first_impact_map_is_coloured_in_milliseconds(captured, tmp_path):
    """The colour bar in the prefix of the times' size (3 to 300 ms: ms, no powers of ten);
    contour levels given in s are drawn where those times are, labelled in ms."""
    omega, force = np.linspace(100.0, 400.0, 20), np.geomspace(1e-5, 1e-3, 20)
    times = np.geomspace(3e-3, 0.3, 400).reshape(20, 20)
    dataset = xr.Dataset(
        {"first_impact_time": (("omega", "force_amplitude"), times,
                               attributes("first_impact_time"))},
        coords={"omega": ("omega", omega, parameter_attributes("omega")),
                "force_amplitude": ("force_amplitude", force,
                                    parameter_attributes("force_amplitude"))},
        attrs={"clearance": 1.1e-5, "t_max": 1.0, "n_modes": 5})
    plot_dataset(dataset, tmp_path / "map.png", contours=[0.01, 0.1])
    (figure,) = captured
    bar = figure.axes[1]
    assert bar.get_ylabel().endswith("(ms)")
    ticks = [label.get_text() for label in bar.get_yticklabels() if label.get_text()]
    assert ticks == ["5", "10", "20", "50", "100", "200"]
    levels = sorted(text.get_text() for text in figure.axes[0].texts)
    assert levels == ["10", "100"]
    assert display_units(np.array([2e-3, 0.3]), "s") == (1e3, "ms")
