"""Basins of attraction (issue 34, item 3) on a beam against a soft stop in its hysteresis band.

The model is tests/test_hysteresis.py's (sweeps/continuation-stop-fold.toml: a cantilever against
a stop of 100 N/m, 5 modes, zeta = 0.02, F0 = 0.1 mN) at Omega = 300 rad/s, between its folds
(282.60 and 317.95 rad/s), where a stable impacting orbit (one contact per period) and the
stable non-impacting orbit coexist. The plane is beam 1's first mode at t = 0: tip deflection
+-40 um (4 clearances), tip velocity +-12 mm/s.

Checks, each against an independent computation: every sampled cell's label is the attractor
a direct long `simulate` from its state ends on (one uninterrupted run, its own stroboscopic
samples); the attractors' states are `periodic_orbit`'s (Newton on the period map) and their
multipliers its monodromy's; the fractions of an 11 x 11 grid, a 21 x 21 grid and 400 random
states agree within their sampling errors; the Wilson interval is SciPy's.
"""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.stats import binomtest

from impactbeams import LongTime, ParameterError, Params, simulate
from impactbeams.kernels.basins import settled_from
from impactbeams.orbits import Settling, basin_stability, basins, periodic_orbit
from impactbeams.orbits.basin_cells import NOT_SETTLED, STOPPED, CellRunner, periodic
from impactbeams.orbits.basin_map import wilson

PARAMS = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                force_amplitude=1e-4, omega=300.0)
N_MODES = 5
BOX = ((-4e-5, 4e-5), (-1.2e-2, 1.2e-2))  # m, m/s


def grid(num):
    return tuple(np.linspace(low, high, num) for low, high in BOX)


@pytest.fixture(scope="module")
def coarse():
    return basins(PARAMS, grid(11), n_modes=N_MODES)


@pytest.fixture(scope="module")
def fine():
    return basins(PARAMS, grid(21), n_modes=N_MODES)


def state_of(dataset, attractor):
    return np.concatenate([dataset.attractor_displacement[attractor].values,
                           dataset.attractor_velocity[attractor].values])


def ends_apart(params, dataset, n_modes, cell, periods=300):
    """How far a direct `simulate` of ``periods`` forcing periods from the basin map
    ``dataset``'s ``cell`` ends from each attractor's section point (beam 1's deflection and
    velocity / Omega), relative to those points' largest: one value per attractor."""
    omega, period = params.omega, 2 * math.pi / params.omega
    points = np.stack([dataset.attractor_section_deflection1[:, 0],
                       dataset.attractor_section_velocity1[:, 0] / omega], axis=-1)
    starts = np.concatenate([dataset.start_displacement.values, dataset.start_velocity.values],
                            axis=-1).reshape(dataset.basin.size, -1)
    run = simulate(params, periods * period, n_modes, dt_output=period,
                   initial_state=starts[cell],
                   long_time=LongTime(sampled_periods=periods, max_period=8))
    end = np.array([run.poincare_deflection1[-1], run.poincare_velocity1[-1] / omega])
    return np.abs(points - end).max(axis=-1) / np.abs(points).max()


def test_two_coexisting_attractors(coarse):
    """The impacting orbit (one contact per period) and the non-impacting one, both period 1,
    every cell settled on one of them, each basin a sizeable share of the plane."""
    assert coarse.attractor.size == 2
    assert sorted(coarse.attractor_contacts.values.tolist()) == [0, 1]
    assert coarse.attractor_period.values.tolist() == [1, 1]
    assert set(np.unique(coarse.basin.values)) == {0, 1}
    assert np.all(coarse.basin_fraction.values > 0.1)
    assert coarse.basin_fraction.sum() == pytest.approx(1.0, abs=1e-15)
    # the rest state, the plane's centre, ends on the non-impacting orbit
    centre = coarse.basin.isel(start_tip_deflection=5, start_tip_velocity=5)
    assert coarse.attractor_contacts[int(centre)] == 0


def test_sampled_cells_agree_with_a_direct_long_simulation(coarse):
    """A direct run of 600 periods from every cell next to a basin boundary (a neighbour with
    another label) and 6 others ends on the cell's attractor: its last samples lie within 1e-6
    of the scale of that attractor's section point (the transient, decaying by |mu| = 0.90 per
    period, leaves 0.9^600 = 3e-28), and at more than 10 % of it from the other one. Its
    samples repeat from the period the basin map says the cell needed (the same number: the
    map's runs restart each block on the section, the direct run does not)."""
    rng = np.random.default_rng(1)
    label_map = coarse.basin.values
    padded = np.pad(label_map, 1, mode="edge")
    boundary = np.zeros(label_map.shape, bool)
    for shift in ((0, 1), (2, 1), (1, 0), (1, 2)):
        boundary |= padded[shift[0]:shift[0] + 11, shift[1]:shift[1] + 11] != label_map
    labels, needed = label_map.ravel(), coarse.settle_periods.values.ravel()
    chosen = [*np.flatnonzero(boundary), *rng.choice(np.flatnonzero(~boundary), 6,
                                                     replace=False)]
    assert np.flatnonzero(boundary).size > 20 and set(labels[chosen]) == {0, 1}
    omega, period = PARAMS.omega, 2 * math.pi / PARAMS.omega
    points = np.stack([coarse.attractor_section_deflection1[:, 0],
                       coarse.attractor_section_velocity1[:, 0] / omega], axis=-1)
    scale = np.abs(points).max()
    starts = np.concatenate([coarse.start_displacement.values, coarse.start_velocity.values],
                            axis=-1).reshape(labels.size, -1)
    for cell in chosen:
        z = starts[cell]
        run = simulate(PARAMS, 600 * period, N_MODES, dt_output=period, initial_state=z,
                       long_time=LongTime(sampled_periods=600, max_period=8))
        end = np.array([run.poincare_deflection1[-1], run.poincare_velocity1[-1] / omega])
        apart = np.abs(points - end).max(axis=-1) / scale
        assert apart[labels[cell]] < 1e-6, (cell, apart)
        assert apart[1 - labels[cell]] > 0.1, (cell, apart)
        # the periods it needed: the direct samples x_k, k >= 1, repeat from the same one on
        x = np.stack([run.poincare_deflection1, run.poincare_deflection2 + PARAMS.clearance,
                      run.poincare_velocity1 / omega, run.poincare_velocity2 / omega], -1)[1:]
        assert settled_from(x, x.shape[0], 1, Settling().tolerance) == needed[cell]


def test_attractors_are_periodic_orbit_s(coarse):
    """Each attractor's state, run on to state_tolerance = 1e-10 of its samples, is the orbit
    Newton converges to from it (tolerance 1e-11) to 1e-9 of the state's largest coordinate:
    a leftover transient changing by r per period lies r / (1 - |mu|) = 10 r away (|mu| =
    0.90); measured 1.2e-11 and 1.8e-11. Its leading multipliers are the monodromy's (1e-8),
    its tip amplitude the orbit's maximum."""
    for k in coarse.attractor.values:
        z = state_of(coarse, k)
        orbit = periodic_orbit(PARAMS, N_MODES, int(coarse.attractor_period[k]), guess=z)
        assert np.abs(orbit.state - z).max() < 1e-9 * np.abs(z).max()
        # the tip amplitude sampled 256 times a period: within 1 - cos(pi / 256) = 7.5e-5 of
        # the orbit's maximum, which Brent's method refines
        amplitude = float(coarse.attractor_amplitude[k])
        assert orbit.max_tip1 * (1 - 1e-4) < amplitude <= orbit.max_tip1 * (1 + 1e-9)
        assert orbit.stable and orbit.contacts == int(coarse.attractor_contacts[k])
        mu = (coarse.attractor_multiplier_real[k] + 1j * coarse.attractor_multiplier_imag[k])
        np.testing.assert_allclose(np.abs(mu.values[:4]), np.abs(orbit.multipliers[:4]),
                                   rtol=1e-8)


def test_the_tip_plane_moves_beam_1_s_first_mode_alone(coarse):
    """Each state is the rest state plus beam 1's first mode: its tip deflection and velocity
    at t = 0 (a simulate from it, read back) are the cell's axis values; the other
    coordinates are at rest (the rest state: no deflection, and the velocity that cancels the
    tip force's quasi-static part, as far as 5 modes resolve it: 3.6e-7 m/s of tip velocity
    left). (A state whose tip starts in the spring's contact reads back the static correction
    of the contact force too: 1.2e-3 of the tip at -24 um.)"""
    cell = coarse.isel(start_tip_deflection=7, start_tip_velocity=8)  # gap open at t = 0
    z = np.concatenate([cell.start_displacement.values, cell.start_velocity.values])
    centre = coarse.isel(start_tip_deflection=5, start_tip_velocity=5)  # (0, 0): at rest
    rest = np.concatenate([centre.start_displacement.values, centre.start_velocity.values])
    assert np.flatnonzero(z != rest).tolist() == [0, N_MODES]
    period = 2 * math.pi / PARAMS.omega
    tips = [simulate(PARAMS, period, N_MODES, dt_output=period, initial_state=state)
            for state in (z, rest)]
    moved = [float(tips[0][name][0] - tips[1][name][0])
             for name in ("tip_deflection_1", "tip_velocity_1")]
    np.testing.assert_allclose(moved, [float(cell.start_tip_deflection),
                                       float(cell.start_tip_velocity)], rtol=1e-12)
    # the rest state's tip: still, up to the 5 modes' truncation of the quasi-static velocity
    assert abs(float(tips[1].tip_deflection_1[0])) < 1e-18  # the centre: linspace round-off
    assert abs(float(tips[1].tip_velocity_1[0])) < 1e-3 * float(cell.start_tip_velocity)


def test_given_orbits_label_the_same_basins(coarse):
    """With periodic_orbit's orbits given, they are the labels and the map is the same."""
    orbits = [periodic_orbit(PARAMS, N_MODES, 1, guess=state_of(coarse, k), measures=False)
              for k in (1, 0)]
    given = basins(PARAMS, grid(11), n_modes=N_MODES, attractors=orbits)
    assert given.attractor.size == 2 and given.attractor_given.values.tolist() == [1, 1]
    np.testing.assert_allclose(given.attractor_amplitude.values,
                               coarse.attractor_amplitude.values[::-1], rtol=1e-9)
    np.testing.assert_array_equal(given.basin.values, 1 - coarse.basin.values)
    np.testing.assert_array_equal(given.settle_periods.values, coarse.settle_periods.values)


def test_fractions_stable_under_refining_and_sampling(coarse, fine):
    """11 x 11, 21 x 21 and 400 random states: the non-impacting orbit's basin fraction agrees
    between them within 2 combined standard errors (measured: 0.132 +- 0.031, 0.147 +- 0.017,
    0.145 +- 0.018)."""
    sampled = basin_stability(PARAMS, 400, BOX, n_modes=N_MODES, seed=3)
    fractions = {}
    for name, dataset in (("11", coarse), ("21", fine), ("random", sampled)):
        quiet = int(np.flatnonzero(dataset.attractor_contacts.values == 0)[0])
        fractions[name] = (float(dataset.basin_fraction[quiet]),
                           float(dataset.basin_fraction_error[quiet]))
        assert dataset.attrs["not_settled_fraction"] == 0.0
    print("basin fraction of the non-impacting orbit (fraction, standard error):", fractions)
    for first, second in (("11", "21"), ("21", "random"), ("11", "random")):
        (f1, e1), (f2, e2) = fractions[first], fractions[second]
        assert abs(f1 - f2) < 2 * math.hypot(e1, e2), (first, second, fractions)
    quiet = int(np.flatnonzero(sampled.attractor_contacts.values == 0)[0])
    assert sampled.basin_fraction_low[quiet] < fractions["21"][0] < sampled.basin_fraction_high[
        quiet]
    assert sampled.cell.size == 400 and sampled.start_tip_deflection.dims == ("cell",)


def test_wilson_interval_is_scipy_s():
    for count, total in ((0, 10), (3, 10), (50, 400), (400, 400)):
        ci = binomtest(count, total).proportion_ci(0.95, method="wilson")
        np.testing.assert_allclose(wilson(np.array(count), total), (ci.low, ci.high),
                                   rtol=1e-12, atol=1e-15)


def interrupted_at_third_chunk(monkeypatch, runner=CellRunner):
    """``runner.run_cells`` raising KeyboardInterrupt at its third call (Ctrl-C in the third
    chunk); the list of the calls' cell counts, which grows as they are made."""
    calls, original = [], runner.run_cells

    def interrupted(self, states, periods=None):
        calls.append(states.shape[0])
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(self, states, periods)

    monkeypatch.setattr(runner, "run_cells", interrupted)
    return calls


def counting_chunks(monkeypatch, original, calls, runner=CellRunner):
    """``runner.run_cells`` as ``original``, each chunk's cell count appended to ``calls``
    (not the runs again of the cells that settled on a multiple of their period)."""

    def counted(self, states, periods=None):
        if periods is None:
            calls.append(states.shape[0])
        return original(self, states, periods)

    monkeypatch.setattr(runner, "run_cells", counted)


def test_an_interrupted_run_resumes_from_its_saved_chunks(tmp_path, monkeypatch, coarse):
    """Chunks of 16 cells: the third chunk fails; the two before it are saved, and the same
    call then computes only the other six and gives the uninterrupted map bit for bit."""
    output = tmp_path / "basins.nc"
    original = CellRunner.run_cells
    calls = interrupted_at_third_chunk(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        basins(PARAMS, grid(11), n_modes=N_MODES, output=output, workers=1, chunk_cells=16)
    assert not output.exists()
    assert len(list((tmp_path / "basins.nc.partial").glob("chunk_*.npz"))) == 2
    calls.clear()
    counting_chunks(monkeypatch, original, calls)
    resumed = basins(PARAMS, grid(11), n_modes=N_MODES, output=output, workers=1,
                     chunk_cells=16)
    assert len(calls) == 6 and not (tmp_path / "basins.nc.partial").exists()
    for name in ("basin", "settle_periods", "attractor_displacement", "basin_fraction"):
        np.testing.assert_array_equal(resumed[name].values, coarse[name].values)
    again = basins(PARAMS, grid(11), n_modes=N_MODES, output=output, workers=1,
                   chunk_cells=16)  # complete: read back, nothing run
    assert len(calls) == 6
    np.testing.assert_array_equal(again.basin.values, coarse.basin.values)
    with pytest.raises(ParameterError, match="different result"):
        basins(PARAMS, grid(5), n_modes=N_MODES, output=output)


def block_by_block(runner, z, known=None):
    """One cell settled a block at a time in Python (`CellRunner.block`, NumPy's tests): the
    path cells took before one kernel call ran a chunk. (period, contacts, settle periods,
    status, samples, end q, end q', end phase)."""
    s = runner.settling
    start, history, found = runner.start(z), [], None
    while start is not None and len(history) * s.block_periods < s.max_periods:
        result = runner.block(start)
        if result is None:
            start = None
            break
        trajectory, x, start, _ = result
        history.append(x)
        x = np.concatenate(history)
        tail = x[-s.window:]
        if x.shape[0] < s.window:
            continue
        if known is None:
            period = periodic(tail, s)
        else:
            step = np.abs(tail[known:] - tail[:-known]).max()
            period = known if step <= s.tolerance * np.abs(tail).max() else 0
        if period:
            step = np.max(np.abs(x[period:] - x[:-period]), axis=-1)
            scale = np.maximum.accumulate(np.max(np.abs(x), axis=-1)[::-1])[::-1][:-period]
            apart = np.flatnonzero(step > s.tolerance * scale)
            found = (period, runner.contacts(trajectory, period),
                     int(apart[-1] + 2 if apart.size else 1), 0, x[-period:])
            break
    run = len(history) * s.block_periods
    if start is None:
        return 0, 0, run, STOPPED, None, None, None, -1
    if found is None:
        return 0, 0, run, NOT_SETTLED, None, *start
    return *found, *start


@pytest.mark.parametrize(("params", "n_modes", "settling", "known"), [
    (PARAMS, N_MODES, Settling(), None),
    (PARAMS, N_MODES, Settling(), 2),
    (Params(counterpart="stop", contact_law="tied", omega=300.0, force_amplitude=1e-4), 2,
     Settling(block_periods=8, window=8, max_period=4, max_periods=64), None),
    (Params(counterpart="stop", contact_law="tied", omega=300.0, force_amplitude=1e-4,
            damping_ratio=0.02), 2, Settling(), None),  # settles: two contacts per orbit
])
def test_a_chunk_kernel_call_is_the_block_by_block_run_bit_for_bit(params, n_modes, settling,
                                                                  known):
    """A chunk's cells in one kernel call (`kernels.basins.settle_cells`) give the bits the
    Python loop over blocks gives: starts in contact (spring law) and refused (tied law),
    settled, unsettled (a known period that is not the cells') and stopped cells."""
    from impactbeams.orbits.basin_map import Plane, _Setup

    setup = _Setup.checked(params, n_modes, settling, (), None, 1, None, False)
    a, b = np.meshgrid(*grid(3), indexing="ij")
    states = Plane.checked(setup, None).states(a.ravel(), b.ravel())
    runner = setup.runner
    cells = runner.run_cells(states, None if known is None else np.full(9, known))
    statuses = set()
    for i, z in enumerate(states):
        period, contacts, settle, status, x, q, v, phase = block_by_block(runner, z, known)
        statuses.add((status, contacts))
        assert (cells.period[i], cells.contacts[i], cells.settle_periods[i], cells.status[i],
                cells.end_phase[i]) == (period, contacts, settle, status, phase)
        if period:
            np.testing.assert_array_equal(cells.samples[i, :period], x)
            assert np.isnan(cells.samples[i, period:]).all()
        if q is not None:
            np.testing.assert_array_equal(np.concatenate([cells.end_q[i], cells.end_v[i]]),
                                          np.concatenate([q, v]))
    assert len(statuses) >= 2  # not all alike: both attractors, or more than one status


def test_unsettled_cells_are_labelled_not_settled():
    """Too few periods to settle: -1, never a silent NaN; the periods run are reported."""
    short = Settling(block_periods=8, window=8, max_period=4, max_periods=16)
    dataset = basins(PARAMS, (np.array([3e-5]), np.array([0.0, 1e-2])), n_modes=N_MODES,
                     settling=short)
    assert dataset.basin.values.tolist() == [[NOT_SETTLED, NOT_SETTLED]]
    assert dataset.settle_periods.values.tolist() == [[16, 16]]
    assert dataset.attractor.size == 0 and dataset.attrs["not_settled_fraction"] == 1.0


def test_tied_law_start_with_overlapping_tips_is_stopped():
    """The tied law starts from an open gap only: such a cell is labelled -2 (stopped)."""
    params = Params(counterpart="stop", contact_law="tied", omega=300.0, force_amplitude=1e-4)
    settling = Settling(block_periods=8, window=8, max_period=4, max_periods=16)
    dataset = basins(params, (np.array([-2e-5, 1e-5]), np.array([0.0])), n_modes=2,
                     settling=settling)
    # the gap is Delta + y1: 20 um down is through the stop 11 um below the tip
    assert dataset.basin.values.tolist() == [[STOPPED], [NOT_SETTLED]]


@pytest.mark.parametrize(("change", "match"), [
    ({"params": dataclasses.replace(PARAMS, omega=0.0)}, "omega"),
    ({"params": dataclasses.replace(PARAMS, start="steady")}, "^start = 'steady'"),
    ({"params": dataclasses.replace(PARAMS, uplift1=1e-6)}, "^uplift1 = 1e-06 is not allowed"),
    ({"axes": (np.array([1e-5, 0.0]), np.array([0.0]))}, "start_tip_deflection"),
    ({"axes": (np.array([np.nan]), np.array([0.0]))}, "start_tip_deflection"),
    ({"axes": np.zeros(3)}, "axes"),
    ({"coordinates": (0, 0)}, "coordinates"),
    ({"coordinates": (0, 99)}, "coordinates"),
    ({"axes": None, "initial_states": np.zeros((2, 3))}, "initial_states"),
    ({"initial_states": np.zeros((2, 10))}, "axes"),
    ({"settling": "fast"}, "settling"),
    ({"chunk_cells": 0}, "chunk_cells"),
    ({"workers": 0}, "workers"),
    ({"attractors": ["orbit"]}, "attractors"),
    ({"axes": (np.array([1.0]), np.array([0.0]))}, "initial_state"),  # a 1 m tip: too far
])
def test_bad_input_is_one_line_before_any_run(change, match, monkeypatch):
    monkeypatch.setattr(CellRunner, "run_cells", lambda *_: pytest.fail("ran"))
    arguments = {"params": PARAMS, "axes": grid(2), "n_modes": N_MODES, **change}
    with pytest.raises(ParameterError, match=match) as error:
        basins(arguments.pop("params"), arguments.pop("axes"), **arguments)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(("change", "match"), [
    ({"samples": 0}, "samples"),
    ({"box": ((1.0, 0.0), (0.0, 1.0))}, "box"),
    ({"box": (0.0, 1.0)}, "box"),
    ({"seed": -1}, "seed"),
])
def test_bad_sampling_input(change, match, monkeypatch):
    monkeypatch.setattr(CellRunner, "run_cells", lambda *_: pytest.fail("ran"))
    arguments = {"samples": 4, "box": BOX, **change}
    with pytest.raises(ParameterError, match=match):
        basin_stability(PARAMS, arguments["samples"], arguments["box"], n_modes=N_MODES,
                        seed=change.get("seed", 0))


def test_settling_refuses_a_window_shorter_than_two_periods():
    with pytest.raises(ParameterError, match="window"):
        Settling(window=10, max_period=8)


def test_basin_map_plots_from_its_file(tmp_path, coarse):
    """`impactbeams plot` of a basins file: the map and its legend, one entry per attractor;
    a random sample as points; a slice option is refused (the map is drawn whole)."""
    from matplotlib.figure import Figure

    from impactbeams.io import write_netcdf
    from impactbeams.plotting import plot_dataset
    from impactbeams.plotting.arrays import read_figure_data
    from impactbeams.plotting.basins import draw_basins

    path = tmp_path / "basins.nc"
    write_netcdf(coarse, path)
    dataset = read_figure_data(path, "input")
    plot_dataset(dataset, tmp_path / "basins.png")
    assert (tmp_path / "basins.png").stat().st_size > 10_000
    axes = Figure().subplots()
    draw_basins(axes, dataset)
    texts = [text.get_text() for text in axes.get_legend().get_texts()]
    assert len(texts) == 2 and texts[0].startswith("0: period 1, 1 contact per orbit, fraction")
    assert axes.get_xlabel().endswith("(µm)")  # tens of µm: no offset, no 1e-5 m
    sampled = basin_stability(PARAMS, 8, BOX, n_modes=N_MODES)
    plot_dataset(sampled, tmp_path / "sampled.png")
    # a random sample's legend gives each fraction's confidence interval, the grid's does not
    draw_basins(axes := Figure().subplots(), sampled)
    texts = [text.get_text() for text in axes.get_legend().get_texts()]
    low, high = sampled.basin_fraction_low.values, sampled.basin_fraction_high.values
    assert [text.endswith(f"(95 % interval {low[k]:.3f} to {high[k]:.3f})")
            for k, text in enumerate(texts)] == [True] * sampled.attractor.size
    assert "interval" not in " ".join(t.get_text() for t in draw_and_read(dataset))
    with pytest.raises(ParameterError, match="--slice"):
        plot_dataset(dataset, tmp_path / "x.png", values={"start_tip_velocity": 0.0})


def draw_and_read(dataset):
    from matplotlib.figure import Figure

    from impactbeams.plotting.basins import draw_basins

    axes = Figure().subplots()
    draw_basins(axes, dataset)
    return axes.get_legend().get_texts()


def test_cli_basins_writes_and_refuses(tmp_path, capsys):
    """The command writes its file and says what it found; bad input: one line, exit 2."""
    from impactbeams.cli import main

    model = ["--counterpart", "stop", "--contact-stiffness", "100", "--damping-ratio", "0.02",
             "--force-amplitude", "1e-4", "--omega", "300", "--n-modes", "5"]
    output = tmp_path / "basins.nc"
    assert main(["basins", *model, "--axis1", "-4e-5,4e-5", "--axis2", "-1.2e-2,1.2e-2",
                 "--points", "3", "-o", str(output)]) == 0
    assert "9 initial states, 2 attractors" in capsys.readouterr().err
    # random states: each fraction with its confidence interval (basin stability)
    sampled = tmp_path / "sampled.nc"
    assert main(["basins", *model, "--axis1", "-4e-5,4e-5", "--axis2", "-1.2e-2,1.2e-2",
                 "--random", "6", "--seed", "2", "-o", str(sampled)]) == 0
    err = capsys.readouterr().err
    written = xr.open_dataset(sampled)
    for k in written.attractor.values:
        assert (f"{float(written.basin_fraction_low[k]):.3f} to "
                f"{float(written.basin_fraction_high[k]):.3f})") in err
    for bad, word in ((["--axis1", "4e-5,-4e-5"], "--axis1"), (["--axis1", "1"], "--axis1"),
                      (["--coordinates", "0,x"], "--coordinates"),
                      (["--random", "4", "--points", "3"], "--points"),
                      (["--seed", "3"], "--seed")):  # a grid draws nothing: not ignored
        arguments = {"--axis1": "-4e-5,4e-5", "--axis2": "0,1e-2"}
        arguments.update(dict(zip(bad[::2], bad[1::2], strict=True)))
        flat = [item for pair in arguments.items() for item in pair]
        assert main(["basins", *model, *flat, "-o", str(tmp_path / "x.nc")]) == 2
        err = capsys.readouterr().err
        assert word in err and "Traceback" not in err
        assert err.strip().splitlines()[-1].startswith("impactbeams: error:")
    assert not (tmp_path / "x.nc").exists()


def test_chunks_on_a_dask_cluster_give_the_same_map(coarse):
    """Each chunk one task on a local cluster (the model packed on the worker): the same map,
    bit for bit, as the threads here."""
    from test_distributed import local_cluster

    with local_cluster(1) as client:
        remote = basins(PARAMS, grid(11), n_modes=N_MODES, client=client, chunk_cells=40)
    for name in ("basin", "settle_periods", "attractor_displacement", "attractor_velocity"):
        np.testing.assert_array_equal(remote[name].values, coarse[name].values)


BASINS_FILE = """n_modes = 5
[params]
counterpart = "stop"
contact_stiffness = 100.0
damping_ratio = 0.02
force_amplitude = 1e-4
omega = 300.0
[basins]
axis1 = [-4e-5, 4e-5]
axis2 = [-1.2e-2, 1.2e-2]
"""


def test_a_basins_file_is_a_sweep_kind_of_run(tmp_path, monkeypatch, capsys, coarse):
    """``impactbeams run`` of a file with a [basins] table: the same map as `basins`, bit
    for bit; interrupted (Ctrl-C in the third chunk) it exits 130 keeping the finished chunks,
    and the same command resumes to the same map; random states as `basin_stability`'s."""
    from impactbeams.cli import main

    path, output = tmp_path / "basins.toml", tmp_path / "basins.nc"
    path.write_text(BASINS_FILE + "points = 11\n")
    original = CellRunner.run_cells
    interrupted_at_third_chunk(monkeypatch)
    assert main(["run", str(path), "-o", str(output), "--threads", "1", "--quiet"]) == 130
    assert len(list((tmp_path / "basins.nc.partial").glob("chunk_*.npz"))) == 2
    monkeypatch.setattr(CellRunner, "run_cells", original)
    assert main(["run", str(path), "-o", str(output), "--threads", "1"]) == 0
    assert "121 initial states, 2 attractors" in capsys.readouterr().err
    written = xr.open_dataset(output)
    for name in ("basin", "settle_periods", "attractor_displacement", "basin_fraction"):
        np.testing.assert_array_equal(written[name].values, coarse[name].values)
    path.write_text(BASINS_FILE + "random = 8\nseed = 4\n")
    assert main(["run", str(path), "-o", str(tmp_path / "random.nc"), "--quiet"]) == 0
    sampled = basin_stability(PARAMS, 8, BOX, n_modes=N_MODES, seed=4)
    np.testing.assert_array_equal(xr.open_dataset(tmp_path / "random.nc").basin.values,
                                  sampled.basin.values)


@pytest.mark.parametrize(("change", "options", "message"), [
    ("points = 11\nrandom = 8\n", [], "points in [basins] of b.toml is not allowed with random"),
    ("seed = 3\n", [], "seed in [basins] of b.toml = 3 is not allowed without random"),
    ("pionts = 3\n", [], "unknown key 'pionts' in [basins] of b.toml (did you mean 'points'?)"),
    ("coordinates = [0]\n", [], "coordinates in [basins] of b.toml = [0] is not allowed"),
    ("points = 2.5\n", [], "points in [basins] of b.toml = 2.5 is not allowed: must be an int"),
    ("", ["--discard-corrupt"], "--discard-corrupt is not allowed with a basins file"),
    ("[axes.omega]\nmin = 1.0\nmax = 2.0\nnum = 2\n", [],
     "unknown top-level key 'axes' in b.toml (a basins file)"),
])
def test_a_bad_basins_file_is_one_line_before_any_run(tmp_path, monkeypatch, capsys, change,
                                                      options, message):
    from impactbeams.cli import main

    monkeypatch.setattr(CellRunner, "run_cells", lambda *_: pytest.fail("ran"))
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(BASINS_FILE + change)
    assert main(["run", "b.toml", "-o", "b.nc", *options]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [f"impactbeams: error: {err.split('error: ')[1].strip()}"]
    assert message in err
    Path("b.toml").write_text(BASINS_FILE.replace("axis1 = [-4e-5, 4e-5]", "axis1 = [4e-5, 0]"))
    assert main(["run", "b.toml", "-o", "b.nc"]) == 2
    assert "axis1 in [basins] of b.toml = 4e-05,0.0 is not allowed: need LOW < HIGH" in (
        capsys.readouterr().err)



@pytest.fixture(scope="module")
def files(tmp_path_factory, coarse):
    """The coarse map's states in a .npz, and a continuation of its model in Omega across
    300 rad/s (the branch crosses it three times: impacting stable, unstable, non-impacting)."""
    from impactbeams.continuation import Continuation, continue_orbits

    folder = tmp_path_factory.mktemp("files")
    np.savez(folder / "starts.npz", states=coarse_states(coarse))
    continue_orbits(Continuation(PARAMS, "omega", 250.0, 330.0, n_modes=N_MODES,
                                 max_branches=1)).to_netcdf(folder / "curve.nc")
    coarse.to_netcdf(folder / "coarse.nc")
    return folder


def coarse_states(dataset):
    n = dataset.coordinate.size
    return np.concatenate([dataset.start_displacement.values.reshape(-1, n),
                           dataset.start_velocity.values.reshape(-1, n)], axis=1)


MODEL = ["--counterpart", "stop", "--contact-stiffness", "100", "--damping-ratio", "0.02",
         "--force-amplitude", "1e-4", "--omega", "300", "--n-modes", "5"]


def test_cli_states_and_attractors_from_files(files, coarse, capsys):
    """``--states`` (a .npz of the coarse map's states) and ``--attractors`` (a continuation):
    the continuation's three orbits at 300 rad/s label the cells, each cell on the given orbit
    whose state is the coarse map's own attractor's (found by running, to 1e-8), none on the
    unstable one; a basin map's .nc gives its states again."""
    from impactbeams.cli import main

    output = files / "given.nc"
    assert main(["basins", *MODEL, "--states", str(files / "starts.npz"), "--attractors",
                 str(files / "curve.nc"), "-o", str(output), "--quiet"]) == 0
    given = xr.open_dataset(output)
    assert given.attractor_given.values.tolist() == [1, 1, 1]
    labels = given.basin.values
    for found in coarse.attractor.values:
        state = state_of(coarse, found)
        apart = [np.abs(state_of(given, k) - state).max() / np.abs(state).max()
                 for k in given.attractor.values]
        match = int(np.argmin(apart))
        assert apart[match] < 1e-8, apart
        np.testing.assert_array_equal(labels == match, coarse.basin.values.ravel() == found)
    unstable = set(given.attractor.values) - set(labels)
    assert len(unstable) == 1 and given.basin_fraction[unstable.pop()] == 0.0
    np.testing.assert_array_equal(given.start_displacement.values,
                                  coarse_states(coarse)[:, :N_MODES])
    again = files / "again.nc"
    assert main(["basins", *MODEL, "--states", str(files / "coarse.nc"), "-o", str(again),
                 "--quiet"]) == 0
    np.testing.assert_array_equal(xr.open_dataset(again).basin.values, coarse.basin.values.ravel())


@pytest.mark.parametrize(("change", "message"), [
    (["--states", "bad.npy"], "--states = 'bad.npy' holds an array of shape (3, 4): must be "
                              "rows of 10 numbers"),
    (["--states", "two.npz"], "--states = 'two.npz' holds arrays a, b: name the initial"),
    (["--states", "none.npz"], "--states = 'none.npz': no such file"),
    (["--states", "starts.txt"], "--states = 'starts.txt' is not allowed: must be a .npy"),
    (["--states", "starts.npz", "--n-modes", "4"], "rows of 8 numbers"),
    (["--states", "starts.npz", "--axis1", "0,1"], "--axis1 is not allowed with --states"),
    (["--axis1", "0,1"], "--axis2 is needed: the plane's two axes --axis1 and --axis2, or "
                         "--states"),
    (["--states", "starts.npz", "--attractors", "coarse.nc"],
     "--attractors = 'coarse.nc' is not a continuation's output"),
    (["--states", "starts.npz", "--attractors", "curve.nc", "--force-amplitude", "2e-4"],
     "its orbits are of force_amplitude = 0.0001, the map's force_amplitude is 0.0002"),
    (["--states", "starts.npz", "--attractors", "curve.nc", "--omega", "400"],
     "its branches do not reach omega = 400 (they cover 250 to 330)"),
    (["--states", "starts.npz", "--attractors", "curve.nc", "--n-modes", "4"],
     "its orbits have n_modes = 5, the map's 4"),
])
def test_bad_states_and_attractors_files_are_one_line(files, monkeypatch, capsys, change,
                                                      message):
    from impactbeams.cli import main

    monkeypatch.setattr(CellRunner, "run_cells", lambda *_: pytest.fail("ran"))
    monkeypatch.chdir(files)
    np.save("bad.npy", np.zeros((3, 4)))
    np.savez("two.npz", a=np.zeros((2, 10)), b=np.zeros((2, 10)))
    assert main(["basins", *MODEL, *change, "-o", "x.nc"]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [f"impactbeams: error: {err.split('error: ')[1].strip()}"]
    assert message in err
    assert not Path("x.nc").exists()


def test_a_basins_file_names_its_states_and_attractors(files, coarse, capsys):
    """``states`` and ``attractors`` in a [basins] table, relative to the file's folder: the
    map of ``--states`` and ``--attractors``; with axis1 beside states: one line."""
    from impactbeams.cli import main

    table = BASINS_FILE.split("axis1")[0]
    (files / "given.toml").write_text(table + 'states = "starts.npz"\nattractors = "curve.nc"\n')
    output = files / "from_file.nc"
    assert main(["run", str(files / "given.toml"), "-o", str(output), "--quiet"]) == 0
    np.testing.assert_array_equal(xr.open_dataset(output).basin.values,
                                  xr.open_dataset(files / "given.nc").basin.values)
    (files / "both.toml").write_text(BASINS_FILE + 'states = "starts.npz"\n')
    assert main(["run", str(files / "both.toml"), "-o", str(output)]) == 2
    assert "axis1 in [basins] of" in capsys.readouterr().err
