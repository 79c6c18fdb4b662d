"""Lyapunov exponents by tangent propagation against what is known independently.

Closed forms without contact (0 undamped; -zeta omega_min damped), the nonlinear run itself
(two-trajectory Benettin estimate, finite-difference Jacobians of the flow map and their
Floquet multipliers: tests/benettin_reference.py), and convergence in n_modes.
"""

import math

import numpy as np
import pytest

from benettin_reference import flow_map_jacobian, two_trajectory_exponent
from impactbeams.kernels import lyapunov as lyapunov_kernels
from impactbeams.kernels import tangent
from impactbeams.kernels.contact_spring import to_contact, to_free
from impactbeams.kernels.layout import CONTACT, FREE, ROW_FREQUENCY, SPRING_DRIVE_ROWS
from impactbeams.kernels.records import SWITCH_SPRING, Segments, Tangent
from impactbeams.packing import cell_rows, pack_run
from impactbeams.params import Params
from impactbeams.sweep import run_sweep, sweep_from_mapping
from impactbeams.trajectory import run, simulate
from impactbeams.trajectory.lyapunov import lyapunov_exponents

# k = 1e4 N/m is resolved by 4 n* = 12 modes per beam (docs/model.md, "Resolution")
SOFT = {"contact_stiffness": 1e4}
N_MODES = 12
PERIOD = 2 * math.pi / Params().omega
OMEGA_MIN = 170.917409  # rad/s, beam 2's first cantilever mode (docs/model.md)
# zeta = 0.05 settles on a period-1 orbit with ~6 contacts per period within 50 periods
# (stroboscopic samples repeat to 3e-13); without damping the motion is chaotic
PERIODIC = {**SOFT, "damping_ratio": 0.05}
DASHPOT = {**PERIODIC, "contact_damping": 0.5}  # contact damping ratio ~12 %
CHAOTIC = SOFT


def recorded(params, t_max, n_modes=N_MODES):
    packed = pack_run(Params(**params), n_modes, t_max, t_max)
    return packed, run(packed, 10**6)


def energy_scaled(packed, jacobian):
    """D J D^-1 with D = diag(omega, 1): the Jacobian in the energy norm's coordinates."""
    omega = packed.tables[FREE, ROW_FREQUENCY]
    scale = np.concatenate([omega, np.ones(omega.size)])
    return scale[:, None] * jacobian / scale[None, :]


def _map_rows(rows_q, rows_v, to_phase, spring):
    """Linear part of the spring law's change of coordinates, row by row."""
    no_drive = np.zeros((len(SPRING_DRIVE_ROWS), rows_q.shape[1]), complex)
    left, right, modes = spring
    for c in range(rows_q.shape[0]):
        q, v = np.empty(rows_q.shape[1]), np.empty(rows_q.shape[1])
        if to_phase == CONTACT:
            to_contact(rows_q[c].copy(), rows_v[c].copy(), 0.0, left, modes, no_drive, 0.0, q, v)
        else:
            to_free(rows_q[c].copy(), rows_v[c].copy(), 0.0, right, modes, no_drive, 0.0, q, v)
        rows_q[c], rows_v[c] = q, v


def tangent_jacobian(packed, trajectory, t0, t1, settings=None):
    """Jacobian (in (q, q')) of the flow map from t0 to t1 carried by the tangent kernel.

    The recorded segments are cut to [t0, t1]; no renormalisation (an empty schedule).
    ``settings``: the run's, or a modified copy (only the saltation reads c_e).
    """
    first = np.searchsorted(trajectory.time, t0, side="right") - 1
    stop = np.searchsorted(trajectory.time, t1, side="left")
    seg_time = trajectory.time[first:stop].copy()
    seg_time[0] = t0
    seg_phase = trajectory.phase[first:stop].copy()
    m = trajectory.q.shape[1]
    identity = np.eye(2 * m)
    rows_q, rows_v = identity[:, :m].copy(), identity[:, m:].copy()
    spring = packed.switching[SWITCH_SPRING]
    if seg_phase[0] == CONTACT:
        _map_rows(rows_q, rows_v, CONTACT, spring)
    state = Tangent(rows_q, rows_v, np.array([t0, 0.0]), np.zeros((1, 2 * m)),
                    np.zeros(1, np.int64))
    cut = Segments(seg_time, seg_phase, *(array[first:stop].copy() for array in (
        trajectory.sustained, trajectory.q, trajectory.v, trajectory.end_q, trajectory.end_v)))
    tangent.carry_tangents(packed.tables, packed.phase_scalars, packed.switching,
                           packed.settings if settings is None else settings, cut, t1,
                           (math.inf, t1, 0, 0), state)
    if seg_phase[-1] == CONTACT:
        _map_rows(rows_q, rows_v, FREE, spring)
    return np.hstack([rows_q, rows_v]).T


def exponent(params, t_max, transient, n_modes=N_MODES, count=1):
    packed, trajectory = recorded(params, t_max, n_modes)
    return lyapunov_exponents(packed, trajectory, count, transient)


def test_undamped_motion_without_contact_has_exponent_zero():
    """Every undamped mode rotates its (omega dq, dq') exactly: the energy norm of a tangent
    vector is invariant, so the estimate is round-off only (~eps per mode and step)."""
    params = {"clearance": 1e-2}  # the tips never meet
    packed, trajectory = recorded(params, 5.0, 10)
    assert np.all(trajectory.phase == FREE)
    result = lyapunov_exponents(packed, trajectory, 4, 5)
    assert np.max(np.abs(result.values)) < 1e-12


def test_damped_motion_without_contact_decays_at_zeta_omega_min():
    """-zeta omega_min (beam 2's first mode). Finite-time bound: a damped mode's energy norm
    is e^(-zeta omega t) times a factor within sqrt(1 +- zeta), so the log growth over the
    averaged 9.9 s is off by at most zeta; beam 1's first mode (decay 2.46 1/s vs 1.71 1/s)
    is left with e^(-0.75 * 10) = 6e-4 of the norm after the 10-s transient:
    |error| <= (0.01 + 6e-4) / 9.9 s = 1.1e-3 1/s."""
    zeta = 0.01
    result = exponent({"clearance": 1e-2, "damping_ratio": zeta}, 20.0, 80, n_modes=10)
    assert result.values[0] == pytest.approx(-zeta * OMEGA_MIN, abs=1.1e-3)


@pytest.mark.parametrize("case", ["chaotic", "periodic"])
def test_tangent_and_two_trajectory_estimates_agree(case):
    """Along the same recorded run, the tangent estimate and Benettin's two-trajectory one
    (perturbation 1e-9 of the state, renormalised every T/8: within one step it grows by at
    most e^(60 T / 8) = 2.6, linear) agree within their combined standard error."""
    params, t_max, transient = {"chaotic": (CHAOTIC, 6.0, 8),
                                "periodic": (PERIODIC, 6.0, 20)}[case]
    packed, trajectory = recorded(params, t_max)
    tangent_result = lyapunov_exponents(packed, trajectory, 1, transient)
    end = tangent.interval_count(t_max, PERIOD) * PERIOD
    value, error = two_trajectory_exponent(packed, trajectory, PERIOD / 8, transient * PERIOD,
                                           end, 1e-9)
    combined = math.hypot(tangent_result.errors[0], error)
    assert (tangent_result.values[0] > 10 * combined) == (case == "chaotic")
    assert tangent_result.values[0] == pytest.approx(value, abs=combined)


@pytest.fixture(scope="module")
def dashpot_orbit():
    """A period-1 orbit with a dashpot (stroboscopic samples repeat to 1e-12 after 59 periods)."""
    return recorded(DASHPOT, 60 * PERIOD)


def test_flow_map_jacobian_matches_finite_differences_only_with_saltation(dashpot_orbit):
    """One forcing period with ~4 contacts: the tangent Jacobian against central differences
    of the nonlinear run (relative step 1e-4: their round-off, ~2e-10 / 1e-4, dominates;
    measured 2e-6), in the energy norm. With the identity in place of the saltation matrix
    (settings with c_e = 0: only the saltation reads it) the Jacobian is 13 % off."""
    packed, trajectory = dashpot_orbit
    t0, t1 = 59 * PERIOD, 60 * PERIOD
    reference = energy_scaled(packed, flow_map_jacobian(packed, trajectory, t0, t1, 1e-4))
    with_saltation = energy_scaled(packed, tangent_jacobian(packed, trajectory, t0, t1))
    identity = packed.settings.copy()
    identity["contact_damping"] = 0.0
    without = energy_scaled(packed, tangent_jacobian(packed, trajectory, t0, t1, identity))
    size = np.linalg.norm(reference, 2)
    assert np.linalg.norm(with_saltation - reference, 2) < 2e-5 * size
    assert np.linalg.norm(without - reference, 2) > 0.1 * size


def test_chaotic_flow_map_jacobian_matches_finite_differences():
    """Undamped spring (S = I at every switch) over T/8 from just before an episode of a
    chaotic run (8 switches; the map stretches by 180). The events make the flow map strongly
    nonlinear: central differences err by 4e-4 at relative step 1e-4 and 4e-6 at 1e-5
    (truncation, ~h^2), by 2e-7 at 1e-7 (round-off, ~1/h); at 1e-6 both are below 1e-7
    (measured 4e-8), and the tangent must match to 1e-6."""
    packed, trajectory = recorded(CHAOTIC, 1.0)
    onsets = trajectory.time[trajectory.phase == CONTACT]
    t0 = onsets[onsets > 0.5][0] - PERIOD / 64
    t1 = t0 + PERIOD / 8
    assert np.count_nonzero((trajectory.time > t0) & (trajectory.time < t1)) >= 4
    reference = energy_scaled(packed, flow_map_jacobian(packed, trajectory, t0, t1, 1e-6))
    carried = energy_scaled(packed, tangent_jacobian(packed, trajectory, t0, t1))
    assert np.linalg.norm(carried - reference, 2) < 1e-6 * np.linalg.norm(reference, 2)


def test_stroboscopic_map_exponent_is_period_times_flow_exponent(dashpot_orbit):
    """On a period-1 orbit the stroboscopic map's exponent is ln max|mu| (its Floquet
    multipliers, from the finite-difference Jacobian of one period of the nonlinear run):
    T times the flow's exponent from the tangent over the 40 periods after a transient of 20,
    within the latter's standard error."""
    packed, trajectory = dashpot_orbit
    jacobian = flow_map_jacobian(packed, trajectory, 59 * PERIOD, 60 * PERIOD, 1e-4)
    map_exponent = math.log(np.max(np.abs(np.linalg.eigvals(jacobian))))
    flow = lyapunov_exponents(packed, trajectory, 1, 20)
    assert map_exponent == pytest.approx(PERIOD * flow.values[0],
                                         abs=PERIOD * flow.errors[0])
    assert flow.values[0] < -5.0  # a stable orbit, contracting


def test_exponent_converges_in_n_modes():
    """The resolution rule's 4 n* = 12 and 8 n* = 24 modes. The orbit, and so its exponent,
    carries the contact's modal error, below 1e-2 at 10 modes and 1e-4 at 20 (contact
    durations, docs/model.md): the two agree to 1e-3 (measured 1.1e-5). Both estimates
    average the same periods from the same initial direction, so their statistical errors
    (0.2 %) largely cancel in the difference."""
    coarse = exponent(PERIODIC, 60 * PERIOD, 20, n_modes=12)
    fine = exponent(PERIODIC, 60 * PERIOD, 20, n_modes=24)
    assert coarse.values[0] == pytest.approx(fine.values[0], rel=1e-3)


def test_spectrum_is_ordered_and_leads_with_the_largest():
    """Gram-Schmidt gives descending exponents (within their errors), the first the
    single-vector one (the same first direction, untouched by the others)."""
    packed, trajectory = recorded(PERIODIC, 60 * PERIOD)
    single = lyapunov_exponents(packed, trajectory, 1, 20)
    spectrum = lyapunov_exponents(packed, trajectory, 6, 20)
    # the same log growths, summed in another order by NumPy
    assert spectrum.values[0] == pytest.approx(single.values[0], rel=1e-14)
    assert np.all(np.diff(spectrum.values) <= spectrum.errors[:-1] + spectrum.errors[1:])


def test_windowed_cell_run_gives_the_exponent_in_bounded_memory():
    """The sweep's windowed run (one forcing period per run_events call) with room for only
    64 phases per window over a run of 725 phases: the same orbit's exponent."""
    params = Params(**PERIODIC)
    packed, trajectory = recorded(PERIODIC, 60 * PERIOD)
    assert trajectory.time.size > 64 * 10
    d = packed.dynamics
    cell = cell_rows({**params.as_dict(), "geometry": 0.0}, 1)[0]
    value, status = lyapunov_kernels.cell_exponent(cell, d.tables, d.switching, d.geometry,
                                                   60 * PERIOD, 20, 64)
    recorded_result = lyapunov_exponents(packed, trajectory, 1, 20)
    assert status == 0
    # a stable orbit: restarting each window changes the run at round-off only
    assert value == pytest.approx(recorded_result.values[0], rel=1e-9)


def test_simulate_and_sweep_report_the_exponent():
    params = Params(**PERIODIC)
    run_dataset = simulate(params, 60 * PERIOD, n_modes=N_MODES, dt_output=PERIOD,
                           lyapunov=True, transient_periods=20)
    value = float(run_dataset.lyapunov_exponent)
    assert run_dataset.lyapunov_exponent.attrs["units"] == "s-1"
    assert run_dataset.lyapunov_exponent.attrs["averaged_periods"] == 40
    assert float(run_dataset.lyapunov_exponent_error) > 0
    sweep = sweep_from_mapping({"t_max": 60 * PERIOD, "n_modes": N_MODES,
                                "observables": ["lyapunov_exponent"], "transient_periods": 20,
                                "params": PERIODIC,
                                "axes": {"omega": {"min": params.omega, "max": 60.0,
                                                   "num": 2}}})
    maps = run_sweep(sweep)
    assert float(maps.lyapunov_exponent[0]) == pytest.approx(value, rel=1e-9)
    assert np.all(maps.dynamics_status == 0)


def test_exponent_requests_that_are_not_defined_are_refused():
    with pytest.raises(ValueError, match="spring contact law"):
        simulate(Params(contact_law="tied"), 0.1, lyapunov=True)
    with pytest.raises(ValueError, match="transient_periods"):
        simulate(Params(**SOFT), 0.5, n_modes=N_MODES, lyapunov=True, transient_periods=4)
    with pytest.raises(ValueError, match="lyapunov"):
        simulate(Params(**SOFT), 0.5, n_modes=N_MODES, lyapunov=4 * N_MODES + 1)
    with pytest.raises(ValueError, match="spring contact law"):
        sweep_from_mapping({"observables": ["lyapunov_exponent"],
                            "params": {"contact_law": "tied"},
                            "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 2}}})


def test_cli_simulate_reports_the_exponent_and_refuses_the_tied_law(tmp_path, capsys):
    import xarray as xr

    from impactbeams.cli import main

    output = tmp_path / "run.nc"
    common = ["simulate", "--t-max", str(30 * PERIOD), "--n-modes", str(N_MODES),
              "--dt-output", str(PERIOD), "--contact-stiffness", "1e4", "--damping-ratio", "0.05",
              "-o", str(output)]
    assert main([*common, "--lyapunov", "1", "--transient-periods", "10"]) == 0
    assert "largest Lyapunov exponent" in capsys.readouterr().err
    with xr.open_dataset(output) as dataset:
        assert float(dataset.lyapunov_exponent) < 0
    assert main([*common, "--lyapunov", "1", "--contact-law", "tied"]) == 2
    error = capsys.readouterr().err
    assert error.startswith("impactbeams: error: Lyapunov exponents need the spring contact law")
    assert error.count("\n") == 1


def test_paper_fig4_case_is_chaotic():
    """The paper's Fig. 4 parameters, Hertz spring at the resolving 32 modes, over the figure's
    horizon: a positive exponent far above its error (247 +- 14 1/s; docs/lyapunov.md)."""
    from impactbeams.compliant import recommended_modes

    params = Params()
    n_modes = recommended_modes(params)
    assert n_modes == 32
    result = exponent({}, 3.0, 4, n_modes=n_modes)
    assert result.values[0] > 10 * result.errors[0] > 0
    assert 100 < result.values[0] < 400  # 1/s: e-folding in a few milliseconds


def test_lyapunov_map_parallel_equals_serial_and_transient_is_part_of_the_sweep():
    definition = {"t_max": 20 * PERIOD, "n_modes": N_MODES, "transient_periods": 5,
                  "observables": ["lyapunov_exponent"], "params": SOFT,
                  "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3}}}
    sweep = sweep_from_mapping(definition)
    parallel = run_sweep(sweep, parallel=True)
    serial = run_sweep(sweep, parallel=False)
    assert np.array_equal(parallel.lyapunov_exponent, serial.lyapunov_exponent)
    assert np.all(np.isfinite(parallel.lyapunov_exponent))
    assert sweep.definition()["transient_periods"] == 5
    assert sweep.fingerprint() != sweep_from_mapping({**definition,
                                                      "transient_periods": 0}).fingerprint()
    with pytest.raises(ValueError, match="transient_periods"):
        sweep_from_mapping({**definition, "transient_periods": -1})
