"""Periodic orbits: the period map and its monodromy, shooting, Floquet multipliers.

The orbit of the tests: k = 1e4 N/m resolved by 12 modes per beam, zeta = 0.05, a stable
period-1 orbit with 6 contacts (one episode) per period (tests/test_lyapunov.py).
"""

import math

import numpy as np
import pytest

from impactbeams import ParameterError, Params, simulate
from impactbeams.kernels.layout import CONTACT, FREE, ROW_EVENT, TIP_Y1
from impactbeams.orbits import OrbitNotConverged, PeriodMap, periodic_orbit
from impactbeams.orbits.period_map import refined
from impactbeams.packing import pack_run
from impactbeams.trajectory import InitialFields
from impactbeams.trajectory.start import phase_state, projected_fields
from orbit_reference import central_jacobian, reference_orbit, settled
from orbit_reference import energy_scale as reference_energy_scale
from orbit_reference import map_energy_scale as energy_scale
from spring_modal_reference import SpringModal

N_MODES = 12
PERIODIC = {"contact_stiffness": 1e4, "damping_ratio": 0.05}
DASHPOT = {**PERIODIC, "contact_damping": 0.5}


@pytest.fixture(scope="module")
def dashpot_map():
    period_map = PeriodMap(Params(**DASHPOT), n_modes=N_MODES)
    return period_map, settled(period_map)


def central_differences(period_map, z, step):
    """dP/dz by central differences of the nonlinear map (relative step in the energy norm)."""
    return central_jacobian(lambda x: period_map(x, measures=False).state, z,
                            energy_scale(period_map), step)


def test_monodromy_matches_finite_differences(dashpot_map):
    """With a dashpot (saltation at the onsets): the tangent Jacobian against central
    differences of the map at relative step 1e-4 in the energy norm (their truncation and
    round-off: measured 1.2e-9)."""
    period_map, z = dashpot_map
    result = period_map(z, directions="all", measures=False)
    scale = energy_scale(period_map)
    carried = scale[:, None] * result.jacobian / scale[None, :]
    reference = scale[:, None] * central_differences(period_map, z, 1e-4) / scale[None, :]
    assert np.linalg.norm(carried - reference, 2) < 1e-7 * np.linalg.norm(reference, 2)


def test_jacobian_columns_are_the_monodromy_applied_to_directions(dashpot_map):
    """A block of directions gets the same tangent propagation as the identity's columns:
    equal to round-off of the sums (the rows are carried independently, 1e-12 relative)."""
    period_map, z = dashpot_map
    full = period_map(z, directions="all", measures=False).jacobian
    block = np.random.default_rng(1).standard_normal((z.size, 3))
    carried = period_map(z, directions=block, measures=False).jacobian
    assert np.allclose(carried, full @ block, rtol=0, atol=1e-12 * np.abs(full @ block).max())


def test_period_map_counts_and_measures(dashpot_map):
    period_map, z = dashpot_map
    result = period_map(z)
    assert result.status == "complete"
    assert result.contacts >= 1 and result.episodes >= 1
    assert result.peak_force > 0 and result.impulse > 0
    assert result.max_tip1 > 0 and result.max_tip2 > 0
    # one peak per contact, the same searches as the impact table's
    assert result.peak_forces.size == result.contacts
    assert result.peak_force == result.peak_forces.max()
    assert period_map(z, measures=False).peak_forces.size == 0
    # the least peak (a grazing's value), searched alone, is the same search's
    assert result.least_peak_force == result.peak_forces.min()
    # read from a run without them (a continuation's last corrector run): the same values
    later = period_map.measured(period_map(z, measures=False))
    names = ("min_gap", "min_gap_time", "peak_force", "impulse", "max_tip1", "max_tip2",
             "peak_forces", "least_peak_force")
    np.testing.assert_equal([getattr(later, name) for name in names],
                            [getattr(result, name) for name in names])  # NaN equal to NaN
    tips = period_map.tip_motions(result, np.linspace(0.0, period_map.horizon, 7))
    assert 0 < np.abs(tips[:, TIP_Y1]).max() <= result.max_tip1  # the maximum bounds them
    two = PeriodMap(Params(**DASHPOT), n_modes=N_MODES, periods=2)(z)
    assert two.contacts == 2 * result.contacts  # a period-1 orbit
    assert two.impulse == pytest.approx(2 * result.impulse, rel=1e-8)


def test_least_peak_force_is_the_least_of_all_contacts_searched():
    """A stiff stop chattering on a shaker (8 to 9 contacts per period, the least peak not the
    first): the pruned search of the least peak gives the full search's least one,
    bit for bit (the same search of that contact)."""
    shaker = Params(l1=0.2, width1=0.02, thickness1=0.001, counterpart="stop", clearance=5e-4,
                    shaker="beam1", base_amplitude=1e-4, force_amplitude=0.0,
                    damping_ratio=0.01)
    for omega in (140.0, 165.0):
        period_map = PeriodMap(shaker.replace(omega=omega), n_modes=8)
        z = settled(period_map)
        result = period_map(z)
        assert result.contacts >= 8 and np.argmin(result.peak_forces) > 0
        approached = period_map.approach(period_map(z, measures=False))
        assert approached.least_peak_force == result.peak_forces.min()
        assert approached.peak_forces.size == 0  # the others are not searched


def test_period_map_refuses_what_it_cannot_do():
    with pytest.raises(ParameterError, match="spring contact law"):
        PeriodMap(Params(contact_law="tied"))
    with pytest.raises(ParameterError, match="omega"):
        PeriodMap(Params(**PERIODIC, omega=0.0), n_modes=N_MODES)
    period_map = PeriodMap(Params(**PERIODIC), n_modes=N_MODES)
    with pytest.raises(ParameterError, match=r"state = array\(\[0\., 0\., 0\.\]\) \(shape "
                       r"\(3,\)\) is not allowed: must be 48"):
        period_map(np.zeros(3))
    bad = period_map.rest_state()
    bad[0] = math.nan
    with pytest.raises(ParameterError, match="state"):
        period_map(bad)
    with pytest.raises(ParameterError, match="directions"):
        period_map(period_map.rest_state(), directions=np.zeros((5, 2)))


# --- start from a state -------------------------------------------------------------------------

PERIOD = 2 * math.pi / Params().omega


def test_restart_from_the_final_state_continues_the_run():
    """0 -> 2T against 0 -> T then T -> 2T from the first run's final state (given as its
    Dataset, on the section t = T): the restart differs in the forcing's time argument only,
    sin(Omega (t + T)) against sin(Omega t), round-off that a stable orbit does not amplify
    (measured 2e-15 relative on the tips, 7e-15 on the final state)."""
    params = Params(**DASHPOT)
    whole = simulate(params, 2 * PERIOD, n_modes=N_MODES, dt_output=PERIOD / 64)
    first = simulate(params, PERIOD, n_modes=N_MODES, dt_output=PERIOD / 64)
    second = simulate(params, PERIOD, n_modes=N_MODES, dt_output=PERIOD / 64,
                      initial_state=first)
    tail = whole.tip_deflection_1.values[64:]
    scale = np.abs(tail).max()
    assert np.abs(second.tip_deflection_1.values - tail).max() < 1e-13 * scale
    assert second.impact.size == whole.impact.size - first.impact.size
    end = np.concatenate([whole.final_displacement, whole.final_velocity])
    restarted = np.concatenate([second.final_displacement, second.final_velocity])
    assert np.abs(restarted - end).max() < 1e-13 * np.abs(end).max()
    # the same state given as an array: bit for bit the Dataset's
    state = np.concatenate([first.final_displacement, first.final_velocity])
    again = simulate(params, PERIOD, n_modes=N_MODES, dt_output=PERIOD / 64,
                     initial_state=state)
    assert np.array_equal(again.tip_deflection_1, second.tip_deflection_1)


@pytest.mark.parametrize("extra", [{}, {"base_amplitude": 1e-6, "force_amplitude": 1e-3},
                                   {"counterpart": "stop"}])
def test_fields_of_the_rest_state_start_as_rest(extra):
    """Zero deflection and velocity fields (at rest in the absolute frame) project on q = 0
    and the rest velocity of the tip force and the shaker: bit for bit start = "rest"."""
    params = Params(**PERIODIC, **extra)
    rest = simulate(params, 0.3 * PERIOD, n_modes=N_MODES)
    zero = lambda x: np.zeros_like(x)  # noqa: E731
    fields = InitialFields(deflection1=zero, velocity1=zero)
    started = simulate(params, 0.3 * PERIOD, n_modes=N_MODES, initial_state=fields)
    assert np.array_equal(rest.tip_deflection_1, started.tip_deflection_1)
    assert np.array_equal(rest.gap, started.gap)


def test_fields_project_on_the_modes_with_the_mass_matrix():
    """A field that is a combination of the modes' shapes projects on its coefficients (to
    the quadrature's round-off, 1e-12)."""
    params = Params(**PERIODIC)
    packed = pack_run(params, N_MODES, PERIOD, PERIOD)
    free = packed.dynamics.free
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal(N_MODES) * 1e-6, rng.standard_normal(N_MODES) * 1e-6
    fields = InitialFields(deflection1=lambda x: a @ free.beam1.shapes(x),
                           velocity2=lambda x: b @ free.beam2.shapes(x))
    z = projected_fields(packed, fields)
    expected_q = np.concatenate([a, np.zeros(N_MODES)])
    expected_v = np.concatenate([np.zeros(N_MODES), b]) + packed.v0
    assert np.allclose(z[:2 * N_MODES], expected_q, rtol=0, atol=1e-12 * np.abs(a).max())
    assert np.allclose(z[2 * N_MODES:], expected_v, rtol=0, atol=1e-12 * np.abs(b).max())


def test_a_start_in_contact_begins_with_the_contact_phase():
    """A state whose tips overlap while closing (the spring pushes) starts in contact."""
    params = Params(**PERIODIC)
    packed = pack_run(params, N_MODES, PERIOD, PERIOD)
    weights = packed.tables[FREE, ROW_EVENT]
    z = np.concatenate([-2 * params.clearance * weights / (weights @ weights),
                        -1e-3 * weights / np.linalg.norm(weights)])
    assert phase_state(packed, z)[2] == CONTACT
    run_dataset = simulate(params, 0.1 * PERIOD, n_modes=N_MODES, initial_state=z)
    assert bool(run_dataset.in_contact[0])


def test_bad_initial_states_are_refused_in_one_line():
    params = Params(**PERIODIC)
    with pytest.raises(ParameterError, match=r"initial_state = array.* \(shape \(5,\)\) is "
                       r"not allowed: must be 48 finite"):
        simulate(params, PERIOD, n_modes=N_MODES, initial_state=np.zeros(5))
    with pytest.raises(ParameterError, match="initial_state replaces params.start"):
        simulate(Params(**PERIODIC, uplift1=1e-6), PERIOD, n_modes=N_MODES,
                 initial_state=np.zeros(4 * N_MODES))
    with pytest.raises(ParameterError, match="whole number of periods"):
        short = simulate(params, 0.5 * PERIOD, n_modes=N_MODES)
        simulate(params, PERIOD, n_modes=N_MODES, initial_state=short)
    with pytest.raises(ParameterError, match="deflection1: must return"):
        simulate(params, PERIOD, n_modes=N_MODES,
                 initial_state=InitialFields(deflection1=lambda x: 0.0))
    tied = Params(contact_law="tied")
    packed = pack_run(tied, 5, PERIOD, PERIOD)
    weights = packed.tables[FREE, ROW_EVENT]
    overlap = np.concatenate([-2 * tied.clearance * weights / (weights @ weights),
                              np.zeros(weights.size)])
    with pytest.raises(ParameterError, match="tied law starts from an open gap"):
        simulate(tied, PERIOD, n_modes=5, initial_state=overlap)


# --- periodic orbits ----------------------------------------------------------------------------

REFERENCE_CASE = {"contact_stiffness": 1e4, "damping_ratio": 0.05, "omega": 60.0}


@pytest.mark.slow
def test_orbit_matches_the_independent_reference():
    """4 modes per beam, Omega = 60 rad/s (7 contacts per period, no dashpot): the orbit by
    Newton with the exact monodromy against tests/orbit_reference.py (DOP853 at rtol 1e-13
    with refined events, Newton with central-difference Jacobians at relative step 1e-5,
    started from the package's state). Their maps differ by 2e-13 over the period; the section
    state agrees to 1e-10 relative (energy norm; measured 3e-13), the multipliers to 1e-6
    (measured 2.5e-9: the differences' truncation and round-off). At Omega = 50 rad/s the
    4-mode orbit has a contact of only 11 us (near grazing, where the map's sensitivity is
    large) and the two maps differ by 8e-9 there: not a test case."""
    params = Params(**REFERENCE_CASE)
    orbit = periodic_orbit(params, n_modes=4, method="newton", tolerance=1e-13)
    model = SpringModal.build(params, 4, params.contact_stiffness, 0.0)
    state, multipliers = reference_orbit(model, orbit.state, 2 * math.pi / params.omega)
    scale = reference_energy_scale(model)
    assert (np.linalg.norm(scale * (orbit.state - state))
            < 1e-10 * np.linalg.norm(scale * state))
    assert np.abs(orbit.multipliers - multipliers).max() < 1e-6


@pytest.fixture(scope="module")
def newton_orbit():
    """The dashpot orbit by Newton from a rough guess (3 periods from rest)."""
    return periodic_orbit(Params(**DASHPOT), n_modes=N_MODES, method="newton",
                          transient_periods=3, tolerance=1e-12)


def test_newton_converges_quadratically_to_a_fixed_point_of_the_map(newton_orbit):
    orbit = newton_orbit
    assert orbit.residual <= 1e-12 and orbit.iterations >= 2
    history = np.array(orbit.history)
    # quadratic: each residual at most ~ the square of the previous (relative), once small
    small = history[:-1] < 1e-3
    assert np.all(history[1:][small] <= 10 * history[:-1][small] ** 2 + 1e-14)
    period_map = PeriodMap(Params(**DASHPOT), n_modes=N_MODES)
    end = period_map(orbit.state, measures=False).state
    assert np.linalg.norm(energy_scale(period_map) * (end - orbit.state)) <= 1e-12 * (
        np.linalg.norm(energy_scale(period_map) * orbit.state))
    assert orbit.stable and orbit.contacts >= 1 and orbit.episodes >= 1
    leading = orbit.multipliers[:8]  # far above round-off (the rest reach 0: exponent -inf)
    assert np.allclose(orbit.exponents[:8], np.log(np.abs(leading)) / PERIOD, rtol=1e-14)


def test_newton_picard_equals_newton(newton_orbit):
    """8 leading directions exactly, the rest by Picard: the same state (1e-12 relative) and
    6 leading multipliers (1e-9: their Ritz values settle to 1e-10) as the full Newton
    (measured 4e-14 and 3e-15)."""
    orbit = periodic_orbit(Params(**DASHPOT), n_modes=N_MODES, method="newton-picard",
                           transient_periods=3, tolerance=1e-12)
    reference = newton_orbit
    scale = np.abs(reference.state).max()
    assert np.abs(orbit.state - reference.state).max() < 1e-12 * scale
    assert orbit.multipliers.size == 6
    assert np.abs(orbit.multipliers - reference.multipliers[:6]).max() < 1e-9
    # the others are smaller than the smallest computed
    assert np.abs(reference.multipliers[6]) <= np.abs(orbit.multipliers[-1]) * (1 + 1e-8)


def test_floquet_exponent_is_the_lyapunov_exponent(newton_orbit):
    """The largest Floquet exponent (exact) against Benettin's estimate from a run started on
    the orbit, within the latter's standard error."""
    orbit = newton_orbit
    run_dataset = simulate(orbit.params, 40 * PERIOD, n_modes=N_MODES, dt_output=PERIOD,
                           lyapunov=True, initial_state=orbit.state)
    error = float(run_dataset.lyapunov_exponent_error)
    assert orbit.exponents[0] == pytest.approx(float(run_dataset.lyapunov_exponent),
                                               abs=3 * error)


def test_orbit_dataset_has_one_period_with_units(newton_orbit):
    dataset = newton_orbit.to_dataset(samples_per_period=64)
    assert dataset.time.size == 65 and float(dataset.time[-1]) == pytest.approx(PERIOD)
    assert dataset.tip_deflection_1.attrs["units"] == "m"
    assert dataset.floquet_exponent.attrs["units"] == "s-1"
    assert dataset.impact.size == newton_orbit.contacts
    # periodic: the end is the start
    assert float(dataset.tip_deflection_1[-1]) == pytest.approx(
        float(dataset.tip_deflection_1[0]), abs=1e-10 * float(abs(dataset.tip_deflection_1).max()))
    assert dataset.attrs["orbit_stable"] == 1


def test_shooting_failures_are_errors_not_results():
    params = Params(**DASHPOT)
    with pytest.raises(OrbitNotConverged, match="did not reach tolerance"):
        periodic_orbit(params, n_modes=N_MODES, transient_periods=0, max_iterations=1,
                       method="newton")
    with pytest.raises(ParameterError, match="spring contact law"):
        periodic_orbit(Params(contact_law="tied"))
    with pytest.raises(ParameterError, match="method"):
        periodic_orbit(params, n_modes=N_MODES, method="secant")
    with pytest.raises(ParameterError, match="guess"):
        periodic_orbit(params, n_modes=N_MODES, guess=np.zeros(3))


@pytest.mark.parametrize("shaker", ["beam1", "both"])
def test_monodromy_against_a_stop_on_a_shaker(shaker):
    """Beam 1 against a stop, the shaker moving beam 1's clamp (a harmonic term in the gap) or
    both (the stop's mount too), with the tip force: the orbit found by Newton, its monodromy
    against central differences at relative step 1e-5 (measured 3e-8 and 8e-9)."""
    params = Params(**PERIODIC, counterpart="stop", base_amplitude=1e-6, shaker=shaker,
                    force_amplitude=1e-3)
    orbit = periodic_orbit(params, n_modes=6, method="newton", transient_periods=20)
    assert orbit.residual <= 1e-11 and orbit.contacts >= 1
    period_map = PeriodMap(params, n_modes=6)
    scale = energy_scale(period_map)
    carried = scale[:, None] * orbit.monodromy / scale[None, :]
    reference = scale[:, None] * central_differences(period_map, orbit.state, 1e-5) / scale[None, :]
    assert np.linalg.norm(carried - reference, 2) < 3e-7 * np.linalg.norm(reference, 2)



def _gap_rate(period_map, trajectory, t):
    """dg/dt (m/s) at t of the gap read from the free coordinates, from one exact sample."""
    from impactbeams.kernels.layout import FREE, ROW_EVENT, SCALAR_COSINE, SCALAR_SINE
    from impactbeams.trajectory.phases import sample

    _, _, v = sample(period_map.packed, trajectory, np.array([t]))
    scalars, omega = period_map.packed.phase_scalars[FREE], period_map.params.omega
    return float(omega * (scalars[SCALAR_SINE] * math.cos(omega * t)
                          - scalars[SCALAR_COSINE] * math.sin(omega * t))
                 + v[0] @ period_map.packed.tables[FREE, ROW_EVENT])

def test_the_gaps_minimum_is_refined_at_the_root_of_its_rate():
    """The gap's rate dg/dt, from the sampled q', is its derivative (central differences,
    to their error ~1e-9 relative), and the free-flight minimum found at its root is the one
    found by minimising the gap itself (Brent, 60 samples of the run instead of ~10), to 2 eps
    of the gap's scale."""
    params = Params.from_mapping({
        "l1": 0.2, "width1": 0.02, "thickness1": 0.001, "counterpart": "stop",
        "clearance": 5e-4, "shaker": "beam1", "base_amplitude": 1e-4, "damping_ratio": 0.01,
        "contact_stiffness": 1e4, "omega": 100.0})  # a shaken beam below its stop's reach
    period_map = PeriodMap(params, n_modes=8)
    z = period_map.rest_state()
    for _ in range(60):
        z = period_map(z, measures=False).state
    result = period_map.approach(period_map(z, measures=False))
    trajectory = result.trajectory
    assert math.isfinite(result.min_gap)
    h = 1e-7
    for t in np.linspace(0.1, 0.9, 9) * period_map.horizon:
        free = period_map._gap(trajectory, np.array([t - h, t, t + h]))
        if not free[1].all():
            continue
        difference = (free[0][2] - free[0][0]) / (2 * h)
        rate = _gap_rate(period_map, trajectory, t)
        assert rate == pytest.approx(difference, rel=1e-7, abs=1e-9 * abs(rate) + 1e-12)
    spacing = period_map.horizon / 512
    brent = refined(lambda t: period_map._gap(trajectory, np.array([t]))[0][0],
                    result.min_gap_time - spacing, result.min_gap_time + spacing, math.inf,
                    math.nan)
    assert abs(brent[0] - result.min_gap) <= 2 * np.finfo(float).eps * params.clearance
    # the flat minimum pins Brent's time to ~sqrt(eps) of the period only; the rate's root
    # to Brent's root-finding tolerance, 1e-14 s: the rate there is within its slope times that
    assert brent[1] == pytest.approx(result.min_gap_time, abs=1e-9)
    slope = abs(_gap_rate(period_map, trajectory, result.min_gap_time + spacing)) / spacing
    assert abs(_gap_rate(period_map, trajectory, result.min_gap_time)) <= 2e-14 * slope


def test_a_branch_reuses_the_geometry_bit_for_bit():
    """Maps at another Omega, F0 or clearance reuse the geometry's modes and contact phase:
    the same bits as a map built afresh."""
    from impactbeams.orbits import period_map as module

    first = Params(**DASHPOT)
    z = PeriodMap(first, n_modes=N_MODES).rest_state()
    for change in ({"omega": 51.0}, {"force_amplitude": 2e-3}, {"clearance": 2e-5}):
        params = first.replace(**change)
        reused = PeriodMap(params, n_modes=N_MODES)
        assert reused.packed.dynamics.spring is PeriodMap(first, N_MODES).packed.dynamics.spring
        module._GEOMETRY_CACHE.clear()
        fresh = PeriodMap(params, n_modes=N_MODES)
        assert fresh.packed.dynamics.spring is not reused.packed.dynamics.spring
        at = PeriodMap(first, n_modes=N_MODES).at(params)  # a continuation's way to it
        assert at.params is params and at.horizon == fresh.horizon
        for a in (reused(z, directions="all"), at(z, directions="all")):
            b = fresh(z, directions="all")
            assert np.array_equal(a.state, b.state) and np.array_equal(a.jacobian, b.jacobian)
            assert a.peak_force == b.peak_force and a.max_tip1 == b.max_tip1


def test_segment_samples_and_the_interval_value_against_exact_samples():
    """A shaken beam hitting its stop 7 times per period (Hertz contact, 16 modes). The
    stepped samples of each segment are `sample`'s closed-form ones at the same times to
    round-off (a step's roundings, 4 eps of the motion per step); the interval
    value (the gap's local maximum nearest 0 between or within contacts) is the one a dense
    exact scan of every segment finds (20001 samples: its grid error, the gap's curvature
    times (spacing / 2)^2 / 2, measured 8e-14 of the clearance here)."""
    from impactbeams.orbits.period_map import INTERVAL_SAMPLES
    from impactbeams.trajectory.phases import sample, sample_segments

    params = Params.from_mapping({
        "l1": 0.2, "width1": 0.02, "thickness1": 0.001, "counterpart": "stop",
        "clearance": 5e-4, "shaker": "beam1", "base_amplitude": 1e-4, "damping_ratio": 0.01,
        "omega": 160.0})
    period_map = PeriodMap(params, n_modes=16)
    trajectory = period_map(settled(period_map), measures=False).trajectory
    contact = trajectory.phase == CONTACT
    assert contact.sum() == 7
    times = np.linspace(trajectory.time, trajectory.segment_end, INTERVAL_SAMPLES, axis=1)
    _, q_exact, v_exact = sample(period_map.packed, trajectory, times.ravel())
    q, v = sample_segments(period_map.packed, trajectory, INTERVAL_SAMPLES)
    steps = INTERVAL_SAMPLES - 1
    assert np.max(np.abs(q - q_exact)) <= 4 * steps * np.finfo(float).eps * np.max(np.abs(q))
    assert np.max(np.abs(v - v_exact)) <= 4 * steps * np.finfo(float).eps * np.max(np.abs(v))
    dense = np.linspace(trajectory.time, trajectory.segment_end, 20001, axis=1)
    gap = period_map._gap(trajectory, dense.ravel())[0].reshape(dense.shape)
    maxima = [gap[k, i] for k in range(gap.shape[0]) for i in range(1, gap.shape[1] - 1)
              if gap[k, i] > gap[k, i - 1] and gap[k, i] >= gap[k, i + 1]
              and (contact[k] or (contact[k - 1] and contact[(k + 1) % contact.size]))]
    nearest = min(maxima, key=abs)
    assert period_map._interval_gap(trajectory) == pytest.approx(nearest,
                                                                 abs=1e-12 * params.clearance)


def test_episode_count_is_the_labels_count():
    # the period map counts a run's episodes on lists (`episode_count`); the rule is
    # `episode_labels`': random contacts, with free intervals below, at and above the separation
    from impactbeams.trajectory.episodes import episode_count, episode_labels

    rng = np.random.default_rng(7)
    separation = 1e-3
    for size in [0, 1, 2, 5, 40] * 20:
        durations = rng.uniform(0.0, 2e-3, size)
        intervals = rng.choice([0.0, 0.5e-3, separation, 2e-3], size)
        onset = np.cumsum(durations + intervals)
        release = onset + durations
        if size and rng.random() < 0.3:
            release[-1] = np.nan  # open at the run's end
        labels = episode_labels(onset, release, separation)
        expected = int(labels[-1]) + 1 if labels.size else 0
        assert episode_count(onset.tolist(), release.tolist(), separation) == expected


def test_the_default_subspace_fits_a_small_model():
    """A stop with 3 modes has 2 N = 6 coordinates, fewer than the default Newton-Picard
    basis (8): Newton (``auto`` there) and the continuation take the defaults without a word
    about a subspace they do not use; Newton-Picard on it carries all 6; a subspace the caller
    gives that does not fit is still refused."""
    from impactbeams.continuation import Continuation
    from impactbeams.continuation.run import orbits_problem

    stop = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                  force_amplitude=1e-4, omega=300.0)
    newton = periodic_orbit(stop, 3, measures=False)
    picard = periodic_orbit(stop, 3, guess=newton.state, method="newton-picard",
                            measures=False)
    assert newton.state.size == 6 and picard.basis.shape == (6, 6)
    np.testing.assert_allclose(picard.state, newton.state, rtol=0, atol=1e-9 * np.abs(
        newton.state).max())
    assert orbits_problem(Continuation(stop, "omega", 195.0, 330.0, n_modes=3)).subspace == 6
    with pytest.raises(ParameterError, match="subspace = 7 is not allowed"):
        periodic_orbit(stop, 3, subspace=7)


def test_a_map_run_longer_than_its_first_window_is_the_same_run(dashpot_map, monkeypatch):
    """A map's run starts in a short window (`period_map.PERIOD_WINDOW`); one of 13 phases
    (4 contacts) in windows of 2 phases, resumed between them, is the same run bit for bit:
    its end state, its monodromy and its contacts."""
    from impactbeams.orbits import period_map as module

    period_map, z = dashpot_map
    whole = period_map(z, directions="all", measures=False)
    assert whole.trajectory.time.size < module.PERIOD_WINDOW
    monkeypatch.setattr(module, "PERIOD_WINDOW", 2)
    windowed = period_map(z, directions="all", measures=False)
    assert whole.trajectory.time.size > 2 * period_map.periods
    for name in ("time", "phase", "q", "v", "end_q", "end_v"):
        assert np.array_equal(getattr(windowed.trajectory, name), getattr(whole.trajectory, name))
    assert np.array_equal(windowed.state, whole.state)
    assert np.array_equal(windowed.jacobian, whole.jacobian)
    assert windowed.contacts == whole.contacts
