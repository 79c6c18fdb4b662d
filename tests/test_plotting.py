"""Figures of sweeps: readable colour bars, symbols and units, slices, lines, bifurcation
diagrams, period and Lyapunov maps; drawn from synthetic Datasets built here (the plotting
code reads only a Dataset's dimensions and attributes)."""

import math

import matplotlib.colors
import numpy as np
import pytest
import xarray as xr
from matplotlib.collections import QuadMesh
from matplotlib.contour import ContourSet
from matplotlib.figure import Figure
from matplotlib.image import BboxImage

from impactbeams.cli import main
from impactbeams.params import ParameterError
from impactbeams.plotting import draw, plot_dataset, trajectories
from impactbeams.plotting.labels import axis_label, power_of_ten, units_text
from impactbeams.plotting.scales import MISSING_COLOUR, NONE_COLOUR
from impactbeams.variables import attributes, parameter_attributes

# the range of first_impact_time in the shipped Fig. 5a map (s), whose colour bar had one label
FIG5A_RANGE = (0.0044150341684267526, 0.9893873136883936)
MS = 1e3  # times are drawn in ms (plotting.labels.display_units)


@pytest.fixture
def figure():
    """A Figure on the Agg canvas (no pyplot, no global backend)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    figure = Figure(layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _axis(name, values, scale="linear"):
    return xr.DataArray(values, dims=name, name=name,
                        attrs={**parameter_attributes(name), "scale": scale})


def _sweep(data, axes, variable="first_impact_time", **extra):
    """A Dataset shaped like run_sweep's: coordinates with units, long_name and scale."""
    coords = {a.name: a for a in axes}
    dims = [a.name for a in axes]
    variables = {variable: (dims, data, attributes(variable) if variable == "first_impact_time"
                            else {"units": "1", "long_name": variable})}
    variables.update({k: (dims if np.ndim(v) == len(dims) else [*dims, "period"], v, a)
                      for k, (v, a) in extra.items()})
    return xr.Dataset(variables, coords=coords,
                      attrs={"t_max": 1.0, "n_modes": 5, "clearance": 1.1e-5,
                             "contact_law": "spring"})


def fig5a_like(shape=(40, 30)):
    """first_impact_time over (omega, force_amplitude) spanning the Fig. 5a map's range, NaN
    (no impact) below a boundary, with the impact flag."""
    omega = _axis("omega", np.linspace(10.0, 400.0, shape[0]))
    force = _axis("force_amplitude", np.geomspace(1e-6, 1e-3, shape[1]), "log")
    low, high = FIG5A_RANGE
    u = np.linspace(0.0, 1.0, shape[0])[:, None] + np.linspace(0.0, 1.0, shape[1])[None, :]
    t = high * (low / high) ** ((u - 0.5) / 1.5)  # log-uniform from high (u = 0.5) to low (2)
    t[u < 0.5] = np.nan
    impacted = xr.DataArray(np.isfinite(t).astype(np.int8), dims=("omega", "force_amplitude"),
                            attrs=attributes("impacted"))
    return _sweep(t, [omega, force], impacted=(impacted.values, impacted.attrs))


def _colour_bar(figure):
    figure.canvas.draw()
    bar = figure.axes[1]
    labels = [t.get_text() for t in bar.get_yticklabels() if t.get_text()]
    return bar, labels


def _mesh(figure, axes=0):
    """The artist drawing a map's cells: an image on a regular grid, else a QuadMesh."""
    (mesh,) = [artist for artist in figure.axes[axes].get_children()
               if isinstance(artist, BboxImage | QuadMesh)]
    return mesh


# --- colour bars --------------------------------------------------------------------------------


def test_fig5a_colour_bar_has_round_labels_over_the_data_range(figure):
    draw(figure.subplots(), fig5a_like())
    bar, labels = _colour_bar(figure)
    # 4.4..989 ms spans 2.35 decades: log colours; only 2 decades inside, so 1-2-5 steps
    assert isinstance(_mesh(figure).norm, matplotlib.colors.LogNorm)
    assert labels == ["5", "10", "20", "50", "100", "200", "500"]
    low, high = FIG5A_RANGE
    assert np.all((bar.get_yticks() >= low * MS) & (bar.get_yticks() <= high * MS))


def test_log_ticks_are_decades_over_a_wide_range(figure):
    t = np.geomspace(1e-6, 1e-1, 60).reshape(6, 10)
    ds = _sweep(t, [_axis("omega", np.linspace(10.0, 20.0, 6)),
                    _axis("clearance", np.geomspace(1e-6, 1e-4, 10), "log")])
    draw(figure.subplots(), ds)
    bar, labels = _colour_bar(figure)
    # 1 us to 100 ms, in ms: decades from 10^-3 to 10^2, decimal
    assert np.allclose(bar.get_yticks(), 10.0 ** np.arange(-3, 3), rtol=1e-12)
    assert labels == ["0.001", "0.01", "0.1", "1", "10", "100"]


def test_narrow_positive_range_is_linear_with_several_round_ticks(figure):
    t = np.linspace(0.21, 0.93, 24).reshape(4, 6)  # a factor 4.4 < 10^1.5: linear
    ds = _sweep(t, [_axis("omega", np.linspace(10.0, 40.0, 4)),
                    _axis("force_amplitude", np.linspace(1e-4, 6e-4, 6))])
    draw(figure.subplots(), ds)
    bar, labels = _colour_bar(figure)
    ticks = bar.get_yticks()
    assert type(_mesh(figure).norm) is matplotlib.colors.Normalize
    assert len(labels) >= 4 and np.all((ticks >= 0.21 * MS) & (ticks <= 0.93 * MS))
    steps = np.diff(ticks)  # equal round steps (1, 2, 2.5 or 5 x 10^k)
    assert np.allclose(steps, steps[0]) and round(steps[0] / 10 ** math.floor(
        math.log10(steps[0])), 9) in (1, 2, 2.5, 5)


def test_scale_options(figure):
    draw(figure.subplots(), fig5a_like(), scale="linear")
    assert type(_mesh(figure).norm) is matplotlib.colors.Normalize
    ds = fig5a_like()
    ds["first_impact_time"][0, -1] = 0.0
    with pytest.raises(ParameterError, match="--log needs positive values"):
        draw(Figure().subplots(), ds, scale="log")


def test_no_impact_cells_are_grey_and_named(figure):
    axes = figure.subplots()
    draw(axes, fig5a_like())
    mesh = _mesh(figure)
    assert np.array_equal(mesh.get_array().mask.ravel(),
                          np.isnan(fig5a_like().first_impact_time.values.T).ravel())
    assert matplotlib.colors.same_color(mesh.cmap.get_bad(), MISSING_COLOUR)
    (text,) = figure.axes[1].get_legend().get_texts()  # under the colour bar
    assert text.get_text() == "no impact by\n$t_\\max$ = 1 s"


def no_impact_anywhere(shape=(4, 3)):
    """A valid map in which no cell impacts: first_impact_time all NaN, impacted all 0."""
    ds = fig5a_like(shape)
    ds["first_impact_time"][:] = np.nan
    ds["impacted"][:] = 0
    return ds


def test_a_map_without_impacts_is_drawn_grey_with_a_note(figure):
    axes = figure.subplots()
    notes = draw(axes, no_impact_anywhere())
    assert notes == ["first_impact_time has no value in any cell (no impact by t_max = 1 s): "
                     "drawn all grey"]
    mesh = _mesh(figure)
    assert mesh.get_array().size == 12 and len(figure.axes) == 1  # every cell; no colour bar
    assert all(matplotlib.colors.same_color(colour, MISSING_COLOUR)
               for colour in mesh.to_rgba(mesh.get_array().ravel()))
    (text,) = axes.texts  # on the figure, as on the terminal
    assert text.get_text() == "no impact by $t_\\max$ = 1 s in any cell"
    with pytest.raises(ParameterError, match="contour lines need values: first_impact_time "
                       "has none"):
        draw(Figure().subplots(), no_impact_anywhere(), contours=3)


def test_a_line_without_impacts_is_shaded_with_a_note(figure):
    axes = figure.subplots()
    notes = draw(axes, no_impact_anywhere(), indices={"force_amplitude": 0})
    assert notes[-1].startswith("first_impact_time has no value in any cell (no impact by")
    assert len(axes.patches) == 1 and axes.texts  # one grey band over the whole line


def test_contour_lines_are_labelled(figure):
    axes = figure.subplots()
    draw(axes, fig5a_like(), contours=4)
    (lines,) = [c for c in axes.get_children() if isinstance(c, ContourSet)]
    assert len(lines.levels) >= 3 and lines.labelTexts
    assert {t.get_text() for t in lines.labelTexts} <= {f"{v:g}" for v in lines.levels}

    axes = Figure().subplots()
    draw(axes, fig5a_like(), contours=[0.01, 0.1, 5.0])  # 5 s is outside the data: left out
    (lines,) = [c for c in axes.get_children() if isinstance(c, ContourSet)]
    assert list(lines.levels) == [10.0, 100.0]  # levels in s, drawn in ms


def test_crowded_contour_labels_are_one_per_level_and_apart(figure):
    """Levels broken into many pieces along a ragged edge (as along Fig. 5a's impact boundary
    at Omega 40-60) get one label each, on their longest line, and no two labels overlap
    (matplotlib's default, one label per piece, drew 46 labels here, 17 pairs overlapping)."""
    omega = _axis("omega", np.linspace(10.0, 400.0, 200))
    force = _axis("force_amplitude", np.geomspace(1e-6, 1e-3, 150), "log")
    u = np.linspace(0.0, 1.0, 200)[:, None] + np.linspace(0.0, 1.0, 150)[None, :]
    t = 0.99 * (0.0044 / 0.99) ** ((u - 0.5) / 1.5)
    band = (u > 0.5) & (u < 0.65)  # values jump from cell to cell near the edge
    t[band] *= np.random.default_rng(5).uniform(0.2, 5.0, band.sum())
    t[u < 0.5] = np.nan
    figure.set_size_inches(6.4, 4.8)
    axes = figure.subplots()
    draw(axes, _sweep(t, [omega, force]), contours=6)
    figure.canvas.draw()
    (lines,) = [c for c in axes.get_children() if isinstance(c, ContourSet)]
    assert len(lines.labelTexts) == len(lines.levels) >= 5
    boxes = [text.get_window_extent() for text in lines.labelTexts]
    for i, box in enumerate(boxes):
        assert not any(box.overlaps(other) for other in boxes[i + 1:])
        assert axes.bbox.contains(*box.p0) and axes.bbox.contains(*box.p1)


def test_no_contour_lines_without_the_option(figure):
    axes = figure.subplots()
    draw(axes, fig5a_like())
    assert not [c for c in axes.get_children() if isinstance(c, ContourSet)]


# --- labels -------------------------------------------------------------------------------------


def test_labels_are_symbols_with_units(figure):
    axes = figure.subplots()
    draw(axes, fig5a_like())
    _, _ = _colour_bar(figure)
    assert axes.get_xlabel() == "$\\Omega$ (rad/s)"
    assert axes.get_ylabel() == "$F_0$ (N)"
    assert figure.axes[1].get_ylabel() == "time before the first impact $t^*$ (ms)"
    assert axes.get_title(loc="left") == "$\\Delta$ = 11 µm, $t_\\max$ = 1 s, 5 modes"
    for name, label in (("clearance", "$\\Delta$ (m)"), ("damping_ratio", "$\\zeta$"),
                        ("uplift1", "$\\delta_1$ (m)"), ("EI2", "$EI_2$ (N m$^{2}$)")):
        assert axis_label(_axis(name, [1.0, 2.0])) == label
    assert units_text("m s-1") == "m s$^{-1}$" and units_text("kg/m^3") == "kg/m$^{3}$"
    assert power_of_ten(2e-5) == "$2\\times10^{-5}$" and power_of_ten(1e3) == "$10^{3}$"


def test_long_time_titles_name_the_sampled_periods_not_t_max(figure):
    """Long-time observables are not computed over [0, t_max]: their titles give the window."""
    ds = poincare_sweep().assign_attrs(transient_periods=500, sampled_periods=200)
    for variable in ("response_period", "poincare_deflection1"):
        axes = Figure().subplots()
        draw(axes, ds, variable)
        assert axes.get_title(loc="left") == ("$\\Delta$ = 11 µm, 500 transient + 200 sampled "
                                              "periods, 5 modes, spring law")
    axes = figure.subplots()  # the same file's other observables cover [0, t_max]
    draw(axes, fig5a_like().assign_attrs(transient_periods=500, sampled_periods=200))
    assert "$t_\\max$ = 1 s" in axes.get_title(loc="left")


def test_run_overview_writes_symbols_and_units_as_the_maps(monkeypatch, tmp_path):
    figures = []
    monkeypatch.setattr(trajectories, "save_figure", lambda figure, path, dpi=150: figures.append(
        figure))
    time = np.linspace(0.0, 0.01, 11)
    run = xr.Dataset(
        {"tip_deflection_1": ("time", 1e-6 * np.sin(time)), "tip_deflection_2": ("time", 0 * time),
         "contact_force": ("time", 0 * time), "energy": ("time", 1e-9 + 0 * time),
         "restitution_coefficient": ("impact", [0.5]), "impact_onset_time": ("impact", [0.005]),
         "impact_peak_force": ("impact", [2e-3])},
        coords={"time": time},
        attrs={"force_amplitude": 1e-3, "omega": 40.0, "clearance": 2e-5, "n_modes": 40,
               "contact_law": "spring", "contact_stiffness": 1.2345e7, "status": "complete"})
    trajectories.plot_run(run, tmp_path / "run.png")
    (figure,) = figures
    axes = figure.axes
    assert axes[0].get_title() == (
        "$F_0$ = 1 mN, $\\Omega$ = 40 rad/s (6.37 Hz), $\\Delta$ = 20 µm\n"
        "spring law, $k$ = $1.23\\times10^{7}$ N/m, 40 modes; status complete")
    assert axes[0].get_ylabel() == "tip deflection (µm)"
    assert [t.get_text() for t in axes[0].get_legend().get_texts()] == [
        "$y_1(l_1)$", "$y_2(l_2) - \\Delta$"]
    assert axes[2].get_ylabel() == "restitution $e$"
    assert axes[3].get_xlabel() == "time $t$ (s)"


# --- variables, slices, lines -------------------------------------------------------------------


def cube():
    """first_impact_time over (omega, force_amplitude, clearance); the value says the cell."""
    omega = _axis("omega", np.linspace(10.0, 400.0, 4))
    force = _axis("force_amplitude", np.geomspace(1e-6, 1e-3, 3), "log")
    clearance = _axis("clearance", np.geomspace(1e-5, 1e-3, 5), "log")
    i, j, k = np.meshgrid(np.arange(4), np.arange(3), np.arange(5), indexing="ij")
    return _sweep(1e-3 * (1 + i + 10 * j + 100 * k), [omega, force, clearance])


def test_slice_picks_the_nearest_grid_value_in_log_distance(figure):
    # clearance grid 1e-5, 3.16e-5, 1e-4, ...: 6e-5 is nearer 3.16e-5 in metres but nearer
    # 1e-4 in log distance (their geometric midpoint is 5.62e-5), as on the log axis
    axes = figure.subplots()
    notes = draw(axes, cube(), values={"clearance": "6e-5"})
    assert notes == ["slice clearance = 6e-5: nearest grid value clearance = 0.0001 m "
                     "(index 2 of 0..4)"]
    expected = cube().first_impact_time.isel(clearance=2).values.T * MS
    assert np.array_equal(_mesh(figure).get_array().reshape(expected.shape), expected)
    assert "$\\Delta$ = 100 µm" in axes.get_title(loc="left")


def test_slice_by_index_and_two_slices_give_a_line(figure):
    axes = figure.subplots()
    notes = draw(axes, cube(), indices={"clearance": "-1", "force_amplitude": 1})
    assert notes[0].startswith("slice at index 4 of 0..4: clearance = 0.001 m")
    (line,) = axes.get_lines()
    assert np.array_equal(line.get_xdata(), cube().omega.values)
    assert np.array_equal(line.get_ydata(), cube().first_impact_time[:, 1, 4].values * MS)
    assert axes.get_xlabel() == "$\\Omega$ (rad/s)"


@pytest.mark.parametrize(("values", "indices", "message"), [
    ({"period": 1.0}, {}, "cannot slice 'period': first_impact_time has dimensions omega, "
                          "force_amplitude, clearance"),
    ({"clearance": 1.0}, {}, "clearance = 1 is outside the grid, 1e-05 to 0.001 m"),
    ({"clearance": "wide"}, {}, "clearance = 'wide' is not a number"),
    ({}, {"clearance": 5}, "index 5 of clearance is out of range: it has 5 values, 0 to 4"),
    ({}, {}, "a map needs a 2-D sweep"),
])
def test_bad_slices_are_refused(values, indices, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        draw(Figure().subplots(), cube(), values=values, indices=indices)


def test_a_1d_sweep_is_a_line_with_grey_bands_where_nan(figure):
    omega = _axis("omega", np.linspace(10.0, 100.0, 10))
    t = np.array([0.1, 0.2, np.nan, np.nan, 0.3, 0.2, np.nan, 0.1, 0.15, 0.12])
    axes = figure.subplots()
    draw(axes, _sweep(t, [omega]))
    (line,) = axes.get_lines()
    assert np.array_equal(line.get_ydata(), t * MS, equal_nan=True)
    bands = [p for p in axes.patches if p.get_facecolor()[:3] == matplotlib.colors.to_rgb(
        MISSING_COLOUR)]
    assert len(bands) == 2  # two runs of NaN cells
    assert axes.get_legend().get_texts()[0].get_text() == "no value (NaN)"


# --- long-time dynamics (issue 12's variables) --------------------------------------------------


def poincare_sweep(n_omega=30, n_samples=8):
    """Stroboscopic samples along ``period``: period 1 below Omega = 50, period 2 above, NaN
    (not sampled) at the last grid value; a period and a Lyapunov exponent per cell."""
    omega = _axis("omega", np.linspace(10.0, 100.0, n_omega))
    doubling = omega.values[:, None] > 50.0
    branch = np.where(doubling & (np.arange(n_samples) % 2 == 1), -1.0, 1.0)
    deflection = 1e-5 * branch * (1 + omega.values[:, None] / 100)
    deflection[-1] = np.nan
    period = np.where(doubling[:, 0], 2, 1)
    return _sweep(period.astype(np.int64), [omega], "response_period",
                  poincare_deflection1=(deflection, {"units": "m", "long_name":
                                        "stroboscopic tip deflection of beam 1"}))


def test_bifurcation_diagram_draws_every_finite_sample(figure):
    ds = poincare_sweep()
    axes = figure.subplots()
    draw(axes, ds, "poincare_deflection1")
    (dots,) = axes.get_lines()
    samples = ds.poincare_deflection1.values
    assert len(dots.get_xdata()) == np.isfinite(samples).sum() == 29 * 8
    assert dots.get_linestyle() == "None"
    # the doubled branch shows as two y values per Omega above 50 rad/s
    above = dots.get_xdata() > 50.0
    assert len(np.unique(np.round(dots.get_ydata()[above] / 1e-3))) == 2 * len(
        np.unique(dots.get_xdata()[above]))  # drawn in µm: 1e-3 µm is the nm of before
    assert axes.get_ylabel() == "stroboscopic tip deflection of beam 1 (µm)"
    finite = samples[np.isfinite(samples)]
    np.testing.assert_array_equal(np.sort(dots.get_ydata()), np.sort(1e6 * finite))


def test_samples_over_two_axes_need_a_slice():
    ds = poincare_sweep()
    ds = xr.concat([ds, ds], dim=_axis("force_amplitude", [1e-4, 2e-4]))
    with pytest.raises(ParameterError, match="a bifurcation diagram needs one swept axis"):
        draw(Figure().subplots(), ds, "poincare_deflection1")
    axes = Figure().subplots()  # one sample of each cell: a map
    draw(axes, ds, "poincare_deflection1", indices={"period": 0})
    assert _mesh(axes.figure)


def test_period_map_is_categorical_with_none(figure):
    omega = _axis("omega", np.linspace(10.0, 100.0, 5))
    force = _axis("force_amplitude", np.geomspace(1e-4, 1e-3, 4), "log")
    period = np.array([[1, 1, 2, 0], [1, 2, 4, 0], [1, 1, 1, 2], [0, 0, 1, 1], [1, 4, 4, 2]],
                      dtype=float)
    period[2, 3] = np.nan  # a cell not computed: grey, not a category
    axes = figure.subplots()
    draw(axes, _sweep(period, [omega, force], "response_period"))
    _, labels = _colour_bar(figure)
    assert labels == ["none", "1", "2", "4"]
    mesh = _mesh(figure)
    codes = {0.0: 0, 1.0: 1, 2.0: 2, 4.0: 3}
    expected = np.array([codes.get(p, np.nan) for p in period.T.ravel()])
    drawn = mesh.get_array().ravel()
    assert np.array_equal(drawn.filled(np.nan), expected, equal_nan=True)
    assert np.array_equal(drawn.mask, np.isnan(expected))
    assert matplotlib.colors.same_color(mesh.cmap(mesh.norm(0)), NONE_COLOUR)
    assert len({matplotlib.colors.to_hex(mesh.cmap(mesh.norm(c))) for c in range(4)}) == 4


def test_cf_flags_are_categories_with_nan_where_none_applies(figure):
    """A float variable with CF flag_values (NaN where no flag applies, e.g. cells where no
    sweep impacts) is drawn as its named categories, NaN cells grey: not as a colour scale."""
    omega = _axis("omega", np.linspace(10.0, 100.0, 4))
    force = _axis("force_amplitude", np.linspace(1e-4, 1e-3, 3))
    codes = np.array([[0.0, 1.0, np.nan], [2.0, 1.0, 0.0], [np.nan, 2.0, 1.0], [0.0, 0.0, 2.0]])
    dataset = _sweep(codes, [omega, force], "which")
    dataset["which"].attrs.update(flag_values=[0.0, 1.0, 2.0],
                                  flag_meanings="both up_only down_only")
    draw(figure.subplots(), dataset, "which")
    _, labels = _colour_bar(figure)
    assert labels == ["both", "up only", "down only"]
    drawn = _mesh(figure).get_array()
    assert np.array_equal(drawn.filled(np.nan), codes.T, equal_nan=True)


def test_period_over_one_axis_is_a_step_line(figure):
    axes = figure.subplots()
    draw(axes, poincare_sweep(), "response_period")
    figure.canvas.draw()
    assert [t.get_text() for t in axes.get_yticklabels()] == ["1", "2"]
    assert axes.get_lines()[0].get_drawstyle() == "steps-mid"


def test_lyapunov_map_is_diverging_centred_at_zero(figure):
    omega = _axis("omega", np.linspace(10.0, 100.0, 6))
    force = _axis("force_amplitude", np.geomspace(1e-4, 1e-3, 5), "log")
    exponent = np.linspace(-40.0, 3.0, 30).reshape(6, 5)
    axes = figure.subplots()
    draw(axes, _sweep(exponent, [omega, force], "lyapunov_exponent"))
    _, labels = _colour_bar(figure)
    mesh = _mesh(figure)
    assert mesh.cmap.name.startswith("RdBu_r") and mesh.norm(0.0) == 0.5
    assert mesh.norm(-40.0) == 0.0 and mesh.norm(3.0) == 1.0
    assert labels == [f"$\\mathdefault{{{v}}}$" for v in ("\N{MINUS SIGN}40",
                                                            "\N{MINUS SIGN}20", 0, 1, 2, 3)]
    # all negative (no chaos): still centred, so that blue says "stable"
    axes = Figure().subplots()
    draw(axes, _sweep(-exponent - 50.0, [omega, force], "lyapunov_exponent"))
    assert _mesh(axes.figure).norm(0.0) == 0.5


# --- files and the command line -----------------------------------------------------------------


def test_plot_dataset_writes_the_file(tmp_path):
    path = tmp_path / "map.png"
    assert plot_dataset(fig5a_like(), path, contours=3, dpi=60) == []
    assert path.stat().st_size > 5_000


@pytest.fixture
def saved(tmp_path):
    path = tmp_path / "cube.nc"
    cube().to_netcdf(path)
    return path


def _error(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("impactbeams: error: ")
    return err


def test_cli_plot_write_error_is_one_line_exit_1(saved, tmp_path, capsys, monkeypatch):
    def full_disk(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", full_disk)
    png = tmp_path / "x.png"
    assert main(["plot", str(saved), "-o", str(png), "--slice", "clearance=1e-4"]) == 1
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"impactbeams: error: could not write {png}: No space left on device")
    assert list(tmp_path.iterdir()) == [saved]


def test_cli_errors_are_one_line(saved, tmp_path, capsys):
    png = str(tmp_path / "x.png")
    assert "no variable 'nope' in the dataset; it has first_impact_time" in _error(
        capsys, ["plot", str(saved), "-o", png, "--var", "nope"])
    assert "cannot slice 'gap'" in _error(
        capsys, ["plot", str(saved), "-o", png, "--slice", "gap=1"])
    assert "--slice 'clearance' is not NAME=VALUE" in _error(
        capsys, ["plot", str(saved), "-o", png, "--slice", "clearance"])
    assert "--contours 'few'" in _error(
        capsys, ["plot", str(saved), "-o", png, "--slice", "clearance=1e-4", "--contours",
                 "few"])


def test_cli_draws_a_slice_and_says_which(saved, tmp_path, capsys):
    png = tmp_path / "slice.png"
    assert main(["plot", str(saved), "-o", str(png), "--slice", "clearance=1.2e-4",
                 "--contours", "3", "--linear", "--title", ""]) == 0
    err = capsys.readouterr().err
    assert "nearest grid value clearance = 0.0001 m (index 2 of 0..4)" in err
    assert png.stat().st_size > 5_000


def test_integers_with_many_values_are_continuous(figure):
    omega = _axis("omega", np.linspace(10.0, 100.0, 4))
    force = _axis("force_amplitude", np.geomspace(1e-4, 1e-3, 3), "log")
    twelve = np.arange(1, 13).reshape(4, 3)  # ten or fewer values would be categories
    draw(figure.subplots(), _sweep(twelve, [omega, force], "response_period"))
    assert type(_mesh(figure).norm) is matplotlib.colors.Normalize
    assert np.array_equal(_mesh(figure).get_array().reshape(3, 4), twelve.T)


def test_a_variable_without_samples_is_not_told_to_slice_a_period():
    """A stepped sweep's final_displacement (sweep_direction, omega, coordinate) was told to
    draw one sample with --slice-index period=I, a dimension it does not have."""
    import xarray as xr
    from matplotlib.figure import Figure

    from impactbeams.plotting import draw

    dataset = xr.Dataset({"final_displacement": (("sweep_direction", "omega", "coordinate"),
                                                 np.zeros((2, 3, 4)))},
                         coords={"sweep_direction": ["up", "down"], "omega": [1.0, 2.0, 3.0],
                                 "coordinate": np.arange(4)})
    with pytest.raises(ParameterError) as error:
        draw(Figure().subplots(), dataset, "final_displacement")
    assert "period" not in str(error.value)
    assert str(error.value).startswith("a map needs a 2-D sweep (a line a 1-D one): "
                                       "final_displacement has dimensions sweep_direction (2), "
                                       "omega (3), coordinate (4)")


def test_a_title_of_several_contacts_gives_each_contacts_clearance():
    """With several contacts the title gives each contact's clearance (its own, or the run's
    for a contact without one), not the flat ``clearance`` alone; a contact's clearance on
    an axis (a curve's or branch's parameter, a sweep's dimension) is left out."""
    from impactbeams import Contact, Params
    from impactbeams.plotting.labels import case_title
    from impactbeams.variables import global_attributes

    params = Params(counterpart="stop", clearance=1.1e-5,
                    contacts=(Contact(), Contact(0.05, clearance=4e-6)))
    attrs = global_attributes("t", "h", params.as_dict())
    branch = xr.Dataset(attrs={**attrs, "continued_parameter": "omega"})
    title = case_title(branch, "tip_amplitude_1", ("branch_point",))
    assert "$\\Delta_{0}$ = 11 µm, $\\Delta_{1}$ = 4 µm, spring law" in title
    assert "$\\Delta$ =" not in title
    curve = xr.Dataset(attrs={**attrs, "curve_parameters": "omega contacts.1.clearance"})
    title = case_title(curve, "contacts.1.clearance", ("branch_point",))
    assert "$\\Delta_{0}$ = 11 µm" in title and "Delta_{1}" not in title
    swept = xr.Dataset({"impact_count": ("contacts.0.clearance", [1, 2])}, attrs=attrs)
    title = case_title(swept, "impact_count", ("contacts.0.clearance",))
    assert "$\\Delta_{1}$ = 4 µm" in title and "Delta_{0}" not in title
    # one contact: the flat clearance, as before
    single = xr.Dataset(attrs=global_attributes("t", "h", Params(clearance=1.1e-5).as_dict()))
    assert "$\\Delta$ = 11 µm" in case_title(single, "impact_count", ())
