"""The event walk's rotating amplitudes and the certified rise, against exact propagation."""

import math

import numpy as np
import pytest

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.events import (
    evaluate,
    event_acceleration,
    event_value,
    phase_event_function,
    phase_oscillators,
)
from impactbeams.kernels.layout import CONTACT
from impactbeams.kernels.propagation import advance
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
