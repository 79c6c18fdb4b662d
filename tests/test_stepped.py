"""Stepped-sine sweeps (issue 22): each cell starts from its neighbour's end state on the section.

The case: beam 1 against a soft stop (k = 100 N/m, contact frequency 505 rad/s against the
free 246 rad/s), driven at its tip (F0 = 30 uN: the linear resonance would reach five
clearances), zeta = 0.02, Omega = 220..340 rad/s. Its impacting resonance bends to higher
frequency (the contact stiffens the beam) and folds: swept up, the response stays on the
impacting branch up to 285 rad/s and drops to the non-impacting one at 290; swept down, it
stays off the stop down to 260 rad/s and jumps onto the impacting branch at 255. Every orbit
is period 1. Five modes resolve this contact (`contact.spring.required_modes`).
"""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

from impactbeams import simulate
from impactbeams.cli import main
from impactbeams.kernels import layout, stroboscope
from impactbeams.kernels.records import geometry_switching
from impactbeams.longtime import hysteresis
from impactbeams.params import ParameterError
from impactbeams.plotting import draw
from impactbeams.sweep import run_sweep, sweep_from_mapping, write_sweep
from impactbeams.sweep.definition import LONG_TIME_OBSERVABLES
from impactbeams.sweep.plan import (
    LONG_RUN_CAPACITY,
    MAX_PHASES_PER_PERIOD,
    _stepped_run,
    build_plan,
    chunk_cells,
    stepped_rows,
)
from test_resume import assert_same_map

FOLD = {"n_modes": 5, "transient_periods": 300, "sampled_periods": 8, "stepping": "both",
        "observables": ["poincare_deflection1", "poincare_velocity1", "response_period",
                        "steady_impact_rate"],
        "params": {"counterpart": "stop", "force_amplitude": 3e-5, "contact_stiffness": 100.0,
                   "damping_ratio": 0.02},
        "axes": {"omega": {"min": 220.0, "max": 340.0, "num": 25}}}
BAND = [260.0, 265.0, 270.0, 275.0, 280.0, 285.0]  # where up and down differ (measured)
# Outside the band both directions and the run from rest reach one attractor, each after 300
# periods of transient: at least 5.5 s at 340 rad/s, 27 time constants of the slowest mode
# (zeta omega_1 = 4.9 /s), e^-27 = 2e-12 of the initial offset; 2.2e-13 of the scale measured.
SAME_ATTRACTOR = 1e-9


def _from_rest(definition):
    return {key: value for key, value in definition.items() if key != "stepping"}


@pytest.fixture(scope="module")
def fold():
    """The stepped sweep (up and down) and the from-rest diagram of the fold case."""
    return run_sweep(sweep_from_mapping(FOLD)), run_sweep(sweep_from_mapping(_from_rest(FOLD)))


def _section(dataset):
    """(y1, v1 / Omega) of every sample, components first (m)."""
    return np.stack([dataset.poincare_deflection1, dataset.poincare_velocity1 / dataset.omega])


def test_outside_the_band_both_directions_equal_the_diagram_from_rest_period_by_period(fold):
    stepped, rest = fold
    outside = ~np.isin(rest.omega, BAND)
    scale = np.abs(_section(rest)).max()
    for direction in ("up", "down"):
        row = stepped.sel(sweep_direction=direction)
        error = np.abs(_section(row) - _section(rest)).max(axis=(0, 2)) / scale
        assert error[outside].max() < SAME_ATTRACTOR, direction
        np.testing.assert_array_equal(row.response_period, rest.response_period)
    assert (rest.response_period == 1).all()


def test_in_the_band_up_and_down_reach_different_attractors(fold):
    """Up stays on the impacting branch, down off the stop; the hysteresis() band is BAND."""
    stepped, rest = fold
    band = np.isin(rest.omega, BAND)
    up, down = (stepped.sel(sweep_direction=d) for d in ("up", "down"))
    np.testing.assert_array_equal(hysteresis(stepped).values, band)
    assert (up.steady_impact_rate[band] > 0).all() and (down.steady_impact_rate[band] == 0).all()
    # the jumps: up falls off after the band's last cell, down jumps on below its first
    assert up.steady_impact_rate.sel(omega=290.0) == 0
    assert down.steady_impact_rate.sel(omega=255.0) > 0
    apart = np.abs(_section(up) - _section(down)).max(axis=(0, 2)) / np.abs(_section(rest)).max()
    assert (apart[band] > 0.5).all()  # a sizeable jump, not a drift (1e-9 outside, above)


# beam 1 against the default (Hertz) stop on a shaker: at 370 rad/s the impacting orbit is in
# contact at the section, so the next cell starts in the contact phase (the spring law's
# contact coordinates rebuilt from the carried free ones with that cell's drive)
SHAKER = {"n_modes": 5, "transient_periods": 40, "sampled_periods": 4, "stepping": "up",
          "observables": ["poincare_deflection1"],
          "params": {"counterpart": "stop", "force_amplitude": 0.0, "base_amplitude": 5e-6,
                     "damping_ratio": 0.03, "shaker": "both"},
          "axes": {"omega": {"min": 150.0, "max": 450.0, "num": 16}}}


TIED = {**FOLD, "stepping": "up", "params": {**FOLD["params"], "contact_law": "tied"}}


@pytest.mark.parametrize(("definition", "phases"), [(FOLD, {layout.FREE}),
                                                    (SHAKER, {layout.FREE, layout.CONTACT}),
                                                    (TIED, {layout.FREE})])
def test_each_cell_starts_from_its_predecessors_end_state_bitwise(definition, phases):
    """Cell k's start is cell k-1's end, bit for bit; run alone from that state, cell k gives
    the same samples and end bit for bit; the first cell of a row starts from rest
    (NO_STATE). ``phases``: those carried."""
    sweep = sweep_from_mapping(definition)
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, sweep.size)
    rows = stepped_rows(sweep, 0, sweep.size)
    values, carried = _stepped_run(sweep, plan, cells, rows, parallel=False)
    for row in rows:
        assert carried["start_phase"][row[0]] == stroboscope.NO_STATE
        assert np.isnan(carried["start_state"][row[0]]).all()
        np.testing.assert_array_equal(carried["start_phase"][row[1:]],
                                      carried["end_phase"][row[:-1]])
        np.testing.assert_array_equal(carried["start_state"][row[1:]],
                                      carried["end_state"][row[:-1]])
    assert set(carried["end_phase"]) == phases
    assert (values["dynamics_status"] == 0).all()
    samples = values["poincare_deflection1"]
    starts = [k for k in rows.ravel() if carried["start_phase"][k] != stroboscope.NO_STATE]
    for k in [*starts[1::7], *[k for k in starts if carried["start_phase"][k] == layout.CONTACT]]:
        alone, end = _alone(sweep, plan, cells[k], carried["start_phase"][k],
                            carried["start_state"][k])
        np.testing.assert_array_equal(alone[:, layout.TIP_Y1], samples[k])
        np.testing.assert_array_equal(end, carried["end_state"][k])


def test_the_stepped_rows_are_the_dataset_rows(fold):
    """The map's up row is the kernel's first row, its down row the second in reverse (the
    serial kernel, as the local runner's threads run a row each)."""
    sweep = sweep_from_mapping(FOLD)
    rows = stepped_rows(sweep, 0, sweep.size)
    np.testing.assert_array_equal(rows, [np.arange(25), np.arange(49, 24, -1)])
    plan = build_plan(sweep)
    values, _ = _stepped_run(sweep, plan, chunk_cells(sweep, plan, 0, sweep.size), rows,
                             parallel=False)
    np.testing.assert_array_equal(values["poincare_deflection1"], stepped_samples(fold[0]))


def stepped_samples(dataset):
    """The stored y1 samples in flat cell order."""
    return dataset.poincare_deflection1.values.reshape(-1, dataset.sizes["period"])


def _alone(sweep, plan, cell, start_phase, start_state):
    """One cell's long run from the given start, by the cell kernel itself."""
    long_time, transient = sweep.long_time, sweep.transient_periods
    omega = cell[layout.CELL_FORCING_FREQUENCY]
    samples = np.empty((long_time.sampled_periods, len(layout.TIP_COLUMNS)))
    summary, end = np.empty(len(layout.STROBOSCOPE_COLUMNS)), np.empty_like(start_state)
    stroboscope.cell_stroboscope(cell, plan.tables[0], geometry_switching(plan.switching, 0),
                                 plan.geometry[0], long_time.sample_times(omega, transient),
                                 long_time.horizon(omega, transient), LONG_RUN_CAPACITY,
                                 MAX_PHASES_PER_PERIOD, start_phase, start_state, samples,
                                 summary, end)
    return samples, end


def test_stepping_along_the_force_jumps_at_the_folds_in_force():
    """The fold case at 275 rad/s (inside the band above), stepped along F0 from 10 to 200 uN:
    up stays off the stop up to 63 uN and impacts from 80 uN; down impacts down to 25 uN."""
    definition = {**FOLD, "stepped_axis": "force_amplitude",
                  "params": {**{key: value for key, value in FOLD["params"].items()
                                if key != "force_amplitude"}, "omega": 275.0},
                  "axes": {"force_amplitude": {"min": 1e-5, "max": 2e-4, "num": 14,
                                               "scale": "log"}}}
    stepped = run_sweep(sweep_from_mapping(definition))
    impacting = (stepped.steady_impact_rate > 0).values
    np.testing.assert_array_equal(impacting, [[False] * 9 + [True] * 5,
                                              [False] * 4 + [True] * 10])
    np.testing.assert_array_equal(hysteresis(stepped).values, impacting[1] & ~impacting[0])


# Stepping along the drive's other axes at 240 rad/s, just below the free resonance (246 rad/s):
# along the clearance (3 to 12 um; F0 = 30 uN: the linear response's tip reaches 8.8 um), and
# along the base amplitude U0 (0.2 to 1.6 um, F0 = 0). Damped more than the fold case (zeta =
# 0.05, zeta omega_1 = 12.3 /s), so that 100 periods of dwell leave e^-32 = 1e-14 of a jump's
# offset: no hysteresis along either axis here (up, down and from rest agree to 8e-14 of the
# scale, measured), impacting and non-impacting cells both.
AXES_CASE = {"n_modes": 5, "transient_periods": 100, "sampled_periods": 4,
             "observables": ["poincare_deflection1", "poincare_velocity1", "steady_impact_rate"],
             "params": {"counterpart": "stop", "contact_stiffness": 100.0, "damping_ratio": 0.05,
                        "omega": 240.0}}
ALONG = {
    "clearance": {**AXES_CASE, "params": {**AXES_CASE["params"], "force_amplitude": 3e-5},
                  "axes": {"clearance": {"min": 3e-6, "max": 1.2e-5, "num": 10}}},
    "base_amplitude": {**AXES_CASE, "params": {**AXES_CASE["params"], "force_amplitude": 0.0,
                                               "shaker": "both"},
                       "axes": {"base_amplitude": {"min": 2e-7, "max": 1.6e-6, "num": 8}}},
}
# a linear response (no contact) from rest, along an axis it does not depend on or scales
# with: equal to round-off of the samples (measured 0 along the clearance, 2e-16 along U0)
LINEAR = 1e-13


@pytest.fixture(scope="module", params=sorted(ALONG))
def along(request):
    """(axis, the stepped sweep up and down along it, the same cells from rest)."""
    definition = ALONG[request.param]
    stepped = run_sweep(sweep_from_mapping({**definition, "stepping": "both",
                                            "stepped_axis": request.param}))
    return request.param, stepped, run_sweep(sweep_from_mapping(definition))


def test_stepping_along_the_clearance_and_the_base_amplitude(along):
    """Up and down equal the cells from rest (one attractor per cell here); where the tip
    does not reach the stop, the response is the linear one: the same at every clearance, and
    proportional to U0."""
    axis, stepped, rest = along
    scale = np.abs(_section(rest)).max()
    for direction in ("up", "down"):
        row = stepped.sel(sweep_direction=direction)
        assert np.abs(_section(row) - _section(rest)).max() < SAME_ATTRACTOR * scale, direction
    assert not hysteresis(stepped).any()
    free = (rest.steady_impact_rate == 0).values
    assert 2 < free.sum() < free.size  # both kinds of cells
    linear = _section(rest)[:, free]
    if axis == "base_amplitude":
        linear = linear / rest.base_amplitude.values[free][:, None]
    assert np.abs(linear - linear[:, :1]).max() < LINEAR * np.abs(linear).max(), axis


def test_a_restart_from_a_cells_stored_end_state_is_the_next_cell(along):
    """The stepped Dataset stores each cell's end state (final_displacement, final_velocity,
    as simulate() does): simulate() from it with the next cell's parameters gives that
    cell's samples and end state (measured: bit for bit, but for the end velocity along U0,
    2.3e-13 of its largest component: round-off of the clamp's motion, taken out in another
    order)."""
    axis, stepped, _ = along
    up = stepped.sel(sweep_direction="up")
    assert up.final_displacement.dims == (axis, "coordinate")
    assert up.final_velocity.attrs["units"] == "kg^1/2 m^1/2 s-1"
    sweep = sweep_from_mapping(ALONG[axis])
    for cell in (0, up.sizes[axis] // 2):
        state = np.concatenate([up.final_displacement[cell], up.final_velocity[cell]])
        following = up.isel({axis: cell + 1})
        params = sweep.base.replace(**{axis: float(following[axis])})
        run = simulate(params, (sweep.transient_periods + 4) * 2 * math.pi / params.omega,
                       n_modes=5, initial_state=state, transient_periods=sweep.transient_periods,
                       long_time=sweep.long_time)
        scale = np.abs(following.poincare_deflection1).max().item()
        assert np.abs(run.poincare_deflection1 - following.poincare_deflection1).max() < (
            1e-13 * scale)
        for name in ("final_displacement", "final_velocity"):
            end = following[name].values
            assert np.abs(run[name].values - end).max() < 1e-12 * np.abs(end).max()


def test_a_cell_of_a_stepped_sweep_is_a_start_and_the_whole_sweep_is_refused(along):
    """simulate(initial_state=) of a stepped sweep's Dataset raised KeyError 't_end': one cell
    (on the section, after whole forcing periods) starts the run its state array starts, bit
    for bit; the whole sweep, with an end state per cell, is refused in one line."""
    axis, stepped, _ = along
    up = stepped.sel(sweep_direction="up")
    cell = up.isel({axis: 2})
    state = np.concatenate([cell.final_displacement, cell.final_velocity])
    params = sweep_from_mapping(ALONG[axis]).base.replace(**{axis: float(up[axis][3])})
    t_max = 2 * 2 * math.pi / params.omega
    from_cell = simulate(params, t_max, n_modes=5, initial_state=cell)
    from_state = simulate(params, t_max, n_modes=5, initial_state=state)
    for name in ("tip_deflection_1", "final_displacement", "final_velocity"):
        np.testing.assert_array_equal(from_cell[name], from_state[name])
    with pytest.raises(ParameterError, match=(
            "initial_state: the Dataset holds an end state per cell \\(dimensions "
            f"sweep_direction, {axis}\\): give one cell, e.g. dataset.isel\\(sweep_direction=0, "
            f"{axis}=0\\)")):
        simulate(params, t_max, n_modes=5, initial_state=stepped)


# a stepped sweep of two parallel rows per direction: four chunks of one row each
ROWS = {**FOLD, "transient_periods": 40, "sampled_periods": 4, "stepped_axis": "omega",
        "params": {key: value for key, value in FOLD["params"].items()
                   if key != "force_amplitude"},
        "axes": {"force_amplitude": {"min": 2e-5, "max": 3e-5, "num": 2},
                 "omega": {"min": 250.0, "max": 300.0, "num": 6}}}


def test_an_interrupted_stepped_sweep_resumes_to_the_same_file(tmp_path):
    """A row is a chunk: an interrupt loses at most the rows being computed."""
    sweep = sweep_from_mapping(ROWS)
    assert sweep.shape == (2, 2, 6)
    reference = tmp_path / "reference.nc"
    write_sweep(sweep, reference, threads=1)
    out = tmp_path / "resumed.nc"

    def stop(chunk):
        if chunk == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_sweep(sweep, out, threads=1, on_chunk=stop)
    assert len(list((tmp_path / "resumed.nc.partial").glob("chunk_*.npz"))) == 2
    computed = []
    write_sweep(sweep, out, threads=1, on_chunk=computed.append)
    assert sorted(computed) == [2, 3]
    assert_same_map(out, reference)
    with xr.open_dataset(out) as dataset:
        assert dataset.poincare_deflection1.dims == ("sweep_direction", "force_amplitude",
                                                     "omega", "period")
        assert list(dataset.sweep_direction.values) == ["up", "down"]
        assert dataset.attrs["stepping"] == "both" and dataset.attrs["stepped_axis"] == "omega"


def test_a_row_is_one_chunk_and_smaller_chunks_are_refused(tmp_path):
    sweep = sweep_from_mapping(ROWS)
    with pytest.raises(ParameterError, match="whole rows along omega: at least 6 cells"):
        write_sweep(sweep, tmp_path / "out.nc", chunk_cells=5)
    assert not list(tmp_path.iterdir())


def _mapping(**changes):
    return {**FOLD, **changes}


@pytest.mark.parametrize(("definition", "message"), [
    ({key: value for key, value in FOLD.items() if key not in ("transient_periods",
                                                               "sampled_periods")}
     | {"observables": ["first_impact_time"]},
     "stepping in sweep = ['both'] is not allowed: stepped-sine sweeps carry a long run's state: "
     "only long-time observables use it (" + ", ".join(LONG_TIME_OBSERVABLES) + ")"),
    (_mapping(stepping="sideways"),
     "stepping = 'sideways' is not allowed: must be one of 'up', 'down', 'both' (in sweep)"),
    (_mapping(stepped_axis="force_amplitude"),
     "stepped_axis in sweep = 'force_amplitude' is not allowed: is not swept: step along one of "
     "the swept axes (omega), given by stepped_axis, or add [axes.force_amplitude]"),
    (_mapping(stepped_axis="damping_ratio"),
     "stepped_axis = 'damping_ratio' is not allowed: must be one of omega, force_amplitude, "
     "base_amplitude, clearance or, with several contacts, contacts.INDEX.clearance (a drive "
     "parameter or a clearance: the carried modal state needs the same modes from step to "
     "step) (in sweep)"),
    ({key: value for key, value in FOLD.items() if key != "stepping"} | {"stepped_axis": "omega"},
     "stepped_axis in sweep = 'omega' is not allowed: needs stepping = \"up\", \"down\" or "
     "\"both\""),
])
def test_bad_stepping_is_refused_in_one_line(definition, message):
    with pytest.raises(ParameterError) as error:
        sweep_from_mapping(definition)
    assert str(error.value) == message


def test_the_cli_refuses_stepping_on_a_first_impact_map_with_exit_2(tmp_path, capsys):
    path = tmp_path / "first.toml"
    path.write_text('stepping = "up"\n[axes.omega]\nmin = 100.0\nmax = 200.0\nnum = 3\n')
    assert main(["run", str(path), "-o", str(tmp_path / "out.nc")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("impactbeams: error: stepping in ")
    assert "only long-time observables use it" in err[0]
    assert not (tmp_path / "out.nc").exists()


def test_a_down_row_is_the_up_row_reversed_in_order_only():
    """The Dataset keeps the axis ascending in both directions; only the order of the runs
    differs: the first cell of the down row is the last value of the axis."""
    sweep = sweep_from_mapping(ROWS)
    rows = stepped_rows(sweep, 0, sweep.size)
    np.testing.assert_array_equal(rows, [np.arange(6), np.arange(6, 12),
                                         np.arange(17, 11, -1), np.arange(23, 17, -1)])
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, sweep.size)
    np.testing.assert_array_equal(cells[:12], cells[12:])
    assert math.isclose(cells[rows[2][0], layout.CELL_FORCING_FREQUENCY], 300.0)


SHIPPED = Path(__file__).resolve().parent.parent / "sweeps" / "stepped-stop-shaker.toml"
# the shipped stepped sweep on a reduced grid: its keys as shipped, a few cells and periods
REDUCED = {"n_modes = 28": "n_modes = 6", "num = 400": "num = 12",
           "transient_periods = 500": "transient_periods = 30",
           "sampled_periods = 200": "sampled_periods = 10"}


def test_the_shipped_stepped_sweep_runs_and_plots_both_directions(tmp_path, monkeypatch,
                                                                  capsys):
    text = SHIPPED.read_text()
    for old, new in REDUCED.items():
        assert old in text
        text = text.replace(old, new)
    monkeypatch.chdir(tmp_path)
    Path("stepped.toml").write_text(text)
    with warnings.catch_warnings():  # 6 modes do not resolve the Hertz contact: a reduced grid
        warnings.simplefilter("ignore", RuntimeWarning)
        assert main(["run", "stepped.toml", "-o", "out.nc"]) == 0
    assert ("2 x 12 = 24 cells over omega (stepped up and down along omega)"
            in capsys.readouterr().err)
    assert main(["plot", "out.nc", "-o", "out.png"]) == 0
    assert Path("out.png").stat().st_size > 10_000
    with xr.open_dataset("out.nc") as result:
        assert result.poincare_deflection1.dims == ("sweep_direction", "omega", "period")
        assert result.attrs["stepping"] == "both"
        assert (result.steady_impact_rate > 0).any()
        assert (result.dynamics_status == 0).all()


def test_plot_overlays_the_directions_in_two_colours(fold):
    stepped, _ = fold
    for variable, kind in (("poincare_deflection1", "None"), ("steady_impact_rate", "-")):
        figure = Figure()
        axes = figure.subplots()
        draw(axes, stepped, variable)
        lines = [line for line in axes.get_lines() if line.get_label().startswith("swept")]
        assert [line.get_label() for line in lines] == ["swept up", "swept down"]
        assert lines[0].get_color() != lines[1].get_color()
        assert {line.get_linestyle() for line in lines} == {kind}
        legend = [text.get_text() for text in axes.get_legend().get_texts()]
        assert legend == ["swept up", "swept down"]
        assert "300 dwell + 8 sampled periods" in axes.get_title(loc="left")
    with pytest.raises(ParameterError, match="a bifurcation diagram needs one swept axis"):
        draw(Figure().subplots(), run_sweep(sweep_from_mapping(ROWS)), "poincare_deflection1")


@pytest.mark.slow  # compiles the parallel row kernel (about 45 s), which only Dask workers use
def test_parallel_rows_equal_serial_rows_bitwise():
    sweep = sweep_from_mapping(ROWS)
    plan = build_plan(sweep)
    cells, rows = chunk_cells(sweep, plan, 0, sweep.size), stepped_rows(sweep, 0, sweep.size)
    serial, parallel = (_stepped_run(sweep, plan, cells, rows, parallel=flag)
                        for flag in (False, True))
    for name in ("poincare_deflection1", "response_period", "dynamics_status"):
        np.testing.assert_array_equal(serial[0][name], parallel[0][name])
    for name in serial[1]:
        np.testing.assert_array_equal(serial[1][name], parallel[1][name])
