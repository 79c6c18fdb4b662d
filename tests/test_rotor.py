"""The event walk's rotating amplitudes and the certified rise, against exact propagation."""

import math

import numpy as np
import pytest

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels import events
from impactbeams.kernels.events import (
    evaluate,
    event_acceleration,
    event_value,
    phase_event_function,
    phase_oscillators,
)
from impactbeams.kernels.layout import CONTACT, ROW_FREQUENCY, ROW_ZETA
from impactbeams.kernels.propagation import advance, steady_phasor
from impactbeams.kernels.records import EventFunction, Oscillators
from impactbeams.kernels.rotor import (
    LEVELS,
    LOWEST,
    modulus_bound,
    rotor_arrays,
    rotor_event,
    rotor_load,
    rotor_step,
)
from impactbeams.packing import pack_run
from impactbeams.params import Params
from impactbeams.trajectory.phases import run

EPS = np.finfo(float).eps
FORCING = 300.0  # rad/s


def oscillators(seed=1, n=64, driven=(3, 40)):
    """n modes from 200 to 7e5 rad/s (the Hertz contact's range), two of them driven."""
    rng = np.random.default_rng(seed)
    omega = np.geomspace(200.0, 7e5, n)
    zeta = np.full(n, 0.03)
    force = np.zeros(n, dtype=complex)
    force[list(driven)] = rng.normal(size=len(driven)) + 1j * rng.normal(size=len(driven))
    q, v = rng.normal(size=n) * 1e-6 / omega, rng.normal(size=n) * 1e-6
    return omega, zeta, force, rng.normal(size=n), q, v


def gap(weights):
    """An event function of these weights alone (what the rotor's load reads)."""
    return EventFunction(weights, 0.0, 0j, FORCING)


@pytest.mark.parametrize("step", [3e-9, 1e-7, 0.7e-6, 0.75e-6, 0.99e-6, 1e-6, 2.5e-3, 1e9])
def test_a_step_is_rounded_down_to_two_factors(step):
    """2^k or 3 2^(k-1), the largest not above the request (capped at the table's top)."""
    omega, zeta, force, weights, q, v = oscillators()
    rotor = rotor_arrays(omega.size)
    rotor_load(rotor, q, v, 0.0, Oscillators(omega, zeta, force, FORCING), gap(weights))
    taken = rotor_step(rotor, step)
    fraction, exponent = math.frexp(taken)
    assert fraction in (0.5, 0.75) and taken <= step
    assert taken > step * 2.0 / 3.0 or taken >= 2.0 ** (LOWEST + LEVELS - 1)  # the cap


def test_a_step_below_the_table_moves_nothing():
    omega, zeta, force, weights, q, v = oscillators()
    rotor = rotor_arrays(omega.size)
    rotor_load(rotor, q, v, 0.0, Oscillators(omega, zeta, force, FORCING), gap(weights))
    before = rotor.amplitudes.copy()
    assert rotor_step(rotor, 2.0**LOWEST) == 0.0  # it would need the factor of 2^(LOWEST - 1)
    assert np.array_equal(rotor.amplitudes, before)


def test_the_rotor_follows_exact_propagation():
    """200 steps of random sizes (as a walk takes them) against ``advance`` from the start: e,
    e' and e'' to 1e-13 of their scales. Each step rounds every amplitude once (the factors
    to an ulp each), so after n steps the error is about n eps; 200 steps: under 5e-14."""
    omega, zeta, force, weights, q_s, v_s = oscillators()
    t_s, const, sine_amp = 0.37, 2e-7, 1e-7 + 3e-8j
    rotor = rotor_arrays(omega.size)
    modes = Oscillators(omega, zeta, force, FORCING)
    event = EventFunction(weights, const, sine_amp, FORCING)
    rotor_load(rotor, q_s, v_s, t_s, modes, event)
    rng = np.random.default_rng(2)
    offset = 0.0
    q, v = np.empty_like(q_s), np.empty_like(q_s)
    for step in rng.uniform(1e-8, 2e-5, 200):
        offset += rotor_step(rotor, step)
        t = t_s + offset
        value, slope, scale, acceleration = rotor_event(rotor, q_s, v_s, t_s, t, modes, event)
        advance(q_s, v_s, t_s, t - t_s, omega, zeta, force, FORCING, q, v)
        exact, exact_slope, exact_scale = evaluate(q, v, t, event)
        exact_acceleration = event_acceleration(q, v, t, modes, event)
        assert abs(value - exact) <= 1e-13 * exact_scale
        slope_scale = np.sum(np.abs(weights * v)) + FORCING * abs(sine_amp)
        assert abs(slope - exact_slope) <= 1e-13 * slope_scale
        acceleration_scale = (np.sum(np.abs(weights) * omega**2 * np.hypot(q, v / omega))
                              + FORCING**2 * abs(sine_amp))
        assert abs(acceleration - exact_acceleration) <= 1e-13 * acceleration_scale
        assert scale == pytest.approx(exact_scale, rel=1e-12)


def test_stored_factors_are_cleared_when_the_modes_change():
    """A rotor reused for other eigenvalues steps as a fresh one does, bit for bit."""
    omega, zeta, force, weights, q, v = oscillators()
    used, fresh = rotor_arrays(omega.size), rotor_arrays(omega.size)
    rotor_load(used, q, v, 0.0, Oscillators(omega, zeta, force, FORCING), gap(weights))
    rotor_step(used, 1e-6)
    for rotor in (used, fresh):
        rotor_load(rotor, q, v, 0.0, Oscillators(1.5 * omega, zeta, force, FORCING),
                   gap(weights))
        rotor_step(rotor, 1e-6)
    assert np.array_equal(used.amplitudes[:omega.size], fresh.amplitudes[:omega.size])


def test_the_modulus_bound_is_an_upper_bound():
    """At least |x + i y| and within 8 eps of it; |x| + |y| where the squares would underflow."""
    rng = np.random.default_rng(3)
    pairs = rng.normal(size=(2000, 2)) * 10.0 ** rng.uniform(-200, 150, (2000, 1))
    for x, y in [*pairs, (1e-200, 3e-201), (0.0, 0.0), (1e150, -1e-300)]:
        exact, bound = math.hypot(x, y), modulus_bound(x, y)
        assert exact <= bound
        assert bound <= (abs(x) + abs(y) if exact < 1e-140 else exact * (1 + 8 * EPS))


@pytest.fixture(scope="module")
def hertz_run():
    """60 forcing periods of the bifurcation diagram's cell at Omega = 300 rad/s (Hertz
    contact, 32 modes): a few hundred contacts."""
    params = Params(force_amplitude=1e-2, damping_ratio=0.03, omega=300.0)
    horizon = 60 * 2 * math.pi / 300.0
    packed = pack_run(params, 32, horizon, horizon)
    return packed, run(packed, 10**6)


def test_the_certified_rise_finds_the_peak_following_search_root(hertz_run):
    """From every contact onset (force 0, rising), the search that certifies the rise and the
    one that follows the force to its peak first (rate_root, as before the certificate) find
    the same release, to within the force's round-off over its slope at the release."""
    packed, trajectory = hertz_run
    table, force, scalars = (packed.tables[CONTACT], packed.forces[CONTACT],
                             packed.phase_scalars[CONTACT])
    settings = packed.settings
    n = trajectory.q.shape[1]
    q, v, rotor = np.empty(n), np.empty(n), rotor_arrays(n)
    checked = 0
    for k in np.flatnonzero(trajectory.phase[:-1] == CONTACT):
        q_s, v_s, t_s = trajectory.q[k], trajectory.v[k], trajectory.time[k]
        event = phase_event_function(table, scalars, settings["forcing_frequency"])
        value, slope = event_value(q_s, v_s, t_s, event)
        if value > 0.0 or slope <= 0.0:
            continue
        risen = dyn.find_event(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor,
                               True)
        assert risen != dyn.NOT_RISEN
        peak = dyn.rate_root(table, force, scalars, 1.0, q_s, v_s, t_s, settings["t_max"],
                             settings, q, v, rotor)
        t_up = dyn.first_root(q_s, v_s, t_s, peak,
                              phase_oscillators(table, force, settings["forcing_frequency"]),
                              dyn._opposite(table, scalars, settings["forcing_frequency"]), q, v,
                              rotor)
        t_up = dyn._step_until(table, force, scalars, q_s, v_s, t_s, t_up, False, settings, q,
                               v)
        followed = dyn.find_event(table, force, scalars, q.copy(), v.copy(), t_up, settings, q,
                                  v, rotor)
        dyn.propagate(table, force, q_s, v_s, t_s, risen, settings, q, v)
        release_slope = abs(event_value(q, v, risen, event)[1])
        _, _, scale = evaluate(q, v, risen, event)
        band = 16 * EPS * scale / release_slope + 8 * np.spacing(risen)
        assert abs(risen - followed) <= band, k
        checked += 1
    assert checked >= 20


def test_one_evaluation_pins_a_root_to_the_ulp_newton_reaches(hertz_run):
    """At every switch of the Hertz run, Newton that ends on a certified local quadratic
    (``_quadratic_root``) returns the root that Newton iterated to an ulp returns, to within
    e's round-off over its slope plus 4 ulps of time, after one evaluation at the start point
    (the state it leaves is at the start, 1e-10 s from the root) in at least 9 cases in 10.

    e's round-off is measured: e at 33 times 8 ulps apart around the root, less its secant
    (phases of 1e4 rad at 7e5 rad/s round to 1e-12 rad: up to hundreds of ulps of time on a
    gap closing slowly)."""
    packed, trajectory = hertz_run
    forcing = float(packed.settings["forcing_frequency"])
    n = trajectory.q.shape[1]
    q, v = np.empty(n), np.empty(n)
    checked = single = 0
    for k in range(trajectory.time.size - 1):
        phase, t_s, root = trajectory.phase[k], trajectory.time[k], trajectory.time[k + 1]
        if root - t_s < 1e-8:
            continue
        table, scalars = packed.tables[phase], packed.phase_scalars[phase]
        modes = phase_oscillators(table, packed.forces[phase].copy(), forcing)
        q_s, v_s = trajectory.q[k].copy(), trajectory.v[k].copy()
        event = events.split_steady_states(q_s, v_s, t_s, modes,
                                           phase_event_function(table, scalars, forcing))
        _, _, curvature, jerk, any_span = events.phase_bounds(q_s, v_s, t_s, root - t_s + 1e-8,
                                                             modes, event)
        lo, hi = root - 1e-9, root + 1e-9
        advance(q_s, v_s, t_s, lo - t_s, *modes, q, v)
        e_lo, slope, scale = evaluate(q, v, lo, event)
        advance(q_s, v_s, t_s, hi - t_s, *modes, q, v)
        e_hi = evaluate(q, v, hi, event)[0]
        if not (any_span and e_lo > 0.0 >= e_hi and slope + curvature * (hi - lo) < 0.0):
            continue
        start = root + 1e-10
        args = (q_s, v_s, t_s, lo, hi, e_lo, e_hi, start, modes, event, 0.0, q, v)
        newton, _ = events._newton_in_bracket(*args)
        quadratic, state_time = events._newton_in_bracket(*args, curvature, jerk)
        band = 4 * _round_off(q_s, v_s, t_s, newton, modes, event) / abs(slope) \
            + 4 * np.spacing(root)
        assert abs(quadratic - newton) <= band, k
        checked += 1
        single += state_time == start
    assert checked >= 100 and single >= 0.9 * checked, (checked, single)


def _round_off(q_s, v_s, t_s, t, modes, event):
    """Largest deviation of e from its secant over 33 times 8 ulps apart around t (s)."""
    times = t + 8 * np.spacing(t) * np.arange(-16, 17)
    values = []
    q, v = np.empty(q_s.size), np.empty(q_s.size)
    for time in times:
        advance(q_s, v_s, t_s, time - t_s, *modes, q, v)
        values.append(evaluate(q, v, time, event)[0])
    line = np.linspace(values[0], values[-1], times.size)
    return np.max(np.abs(np.array(values) - line))


@pytest.mark.parametrize("detuning, split", [(1.001 / 16, True), (0.999 / 16, False),
                                             (0.0, False)])
def test_a_steady_state_is_split_off_down_to_a_sixteenth_of_omega_squared(detuning, split):
    """|D| >= omega^2 / 16 (|P| at most 16 times the quasi-static |A| / omega^2): split; nearer
    resonance, and at it (D = 0, zeta = 0), the mode stays driven (P = 0)."""
    w, force = 1000.0, 2.0 - 1.0j
    forcing = math.sqrt(w * w * (1.0 - detuning))  # zeta = 0: D = omega^2 - Omega^2, real
    phasor = steady_phasor(w, 0.0, force, forcing)
    assert (phasor != 0) == split
    if split:
        assert phasor == pytest.approx(force / (w * w - forcing**2), rel=4 * EPS)
        assert abs(phasor) <= 16.0 * abs(force) / w**2


def test_no_mode_stays_driven_beside_the_contact_resonance():
    """The bifurcation diagram's contact phase at Omega = 200 rad/s, 8 rad/s below its first
    resonance (208 rad/s, zeta = 0.03): every driven mode's steady state is split off, so the
    walk steps on the rotor alone. With the former threshold omega^2 / 4 the resonant mode
    stayed driven, and was propagated exactly at every step of every contact's search."""
    packed = pack_run(Params(force_amplitude=1e-2, damping_ratio=0.03, omega=200.0), 32, 0.01,
                      0.01)
    table, force = packed.tables[CONTACT], packed.forces[CONTACT]
    driven = [j for j in range(force.size) if force[j] != 0]
    assert len(driven) > 1
    resonant = int(np.argmin(np.abs(table[ROW_FREQUENCY] - 200.0)))
    w, zeta = table[ROW_FREQUENCY, resonant], table[ROW_ZETA, resonant]
    assert resonant in driven
    assert abs(complex(w * w - 200.0**2, 2 * zeta * w * 200.0)) < w * w / 4  # once driven
    for j in driven:
        assert steady_phasor(table[ROW_FREQUENCY, j], table[ROW_ZETA, j], force[j], 200.0) != 0
