"""Cheap repeated evaluation of an event function along a certified walk.

A walk (:func:`impactbeams.kernels.events.walk`) evaluates e, e' and e'' at a few dozen points
per phase. Propagating every mode from the phase's start to each point costs an exponential,
a sine and a cosine per mode. An undriven mode (``events.split_steady_states`` moves the steady
states of the others into the event's sinusoid) is instead a rotating complex amplitude,

    q(t) = Re z(t),   q'(t) = Re(lambda z),   q'' = Re(lambda^2 z),   z(t + h) = z(t) e^(lambda h),

with lambda = -zeta omega + i omega_d; a step multiplies z by a stored e^(lambda h). Steps are
rounded down to ``2^k`` or ``3 * 2^(k-1)`` (one or two stored factors, so that a walk computes
the factors of a handful of step sizes), and the walk's time offset is a sum of such numbers,
exact in floating point unless the steps span more than 2^53. Each product rounds once: after n steps z carries a relative error of
about n ulps, far below what the walk certifies; roots are resolved by exact propagation.
Driven modes (near resonance) are propagated exactly to each point.

The rotor is a tuple of arrays ``(z, lam, driven, slot_exponent, slot_factor)``: the
amplitudes, the eigenvalues, which modes are driven, and ``SLOTS`` stored step factors
e^(lambda 2^k), keyed by k in ``slot_exponent[:SLOTS]`` (``slot_exponent[SLOTS]`` is the
slot replaced next, in turn, so that the two factors of one step never evict each other).
"""

import math

import numpy as np

from impactbeams.kernels.jit import kernel
from impactbeams.kernels.propagation import advance_mode

SLOTS = 16
_EMPTY = -(2**31)  # no exponent is stored in the slot


@kernel
def rotor_arrays(n_modes):
    """An empty rotor for ``n_modes`` modes."""
    return (np.empty(n_modes, dtype=np.complex128), np.empty(n_modes, dtype=np.complex128),
            np.empty(n_modes, dtype=np.bool_), _empty_slots(),
            np.empty((SLOTS, n_modes), dtype=np.complex128))


@kernel
def _empty_slots():
    """``slot_exponent`` with every slot empty and slot 0 next."""
    slots = np.full(SLOTS + 1, _EMPTY, dtype=np.int64)
    slots[SLOTS] = 0
    return slots


@kernel
def rotor_load(rotor, q, v, omega, zeta, force):
    """Set the rotor's amplitudes from the modal state (q, v) (undriven modes only)."""
    z, lam, driven = rotor[0], rotor[1], rotor[2]
    for j in range(omega.size):
        w = omega[j]
        lam[j] = complex(-zeta[j] * w, w * math.sqrt(1.0 - zeta[j] * zeta[j]))
        driven[j] = force[j] != 0
        z[j] = complex(q[j], (lam[j].real * q[j] - v[j]) / lam[j].imag)


@kernel
def _factor(rotor, exponent):
    """The stored e^(lambda 2^exponent) of every mode, computed on first use."""
    lam, slot_exponent, slot_factor = rotor[1], rotor[3], rotor[4]
    for i in range(SLOTS):
        if slot_exponent[i] == exponent:
            return slot_factor[i]
    i = slot_exponent[SLOTS]
    slot_exponent[SLOTS] = (i + 1) % SLOTS
    slot_exponent[i] = exponent
    h = math.ldexp(1.0, exponent)
    for j in range(lam.size):
        growth = lam[j] * h
        slot_factor[i, j] = math.exp(growth.real) * complex(math.cos(growth.imag),
                                                            math.sin(growth.imag))
    return slot_factor[i]


@kernel
def rotor_step(rotor, step):
    """Rotate the undriven modes by the largest 2^k or 3 * 2^(k-1) not above ``step`` (s > 0).

    Returns the step taken (s).
    """
    z, driven = rotor[0], rotor[2]
    fraction, exponent = math.frexp(step)  # step = fraction 2^exponent, 1/2 <= fraction < 1
    first = _factor(rotor, exponent - 1)
    taken = math.ldexp(1.0, exponent - 1)
    if fraction >= 0.75:
        second = _factor(rotor, exponent - 2)
        taken += math.ldexp(1.0, exponent - 2)
        for j in range(z.size):
            if not driven[j]:
                z[j] = z[j] * first[j] * second[j]
        return taken
    for j in range(z.size):
        if not driven[j]:
            z[j] = z[j] * first[j]
    return taken


@kernel
def rotor_event(rotor, q_s, v_s, t_s, t, omega, zeta, force, weights, const, sine_amp,
                forcing_frequency):
    """e, e', its evaluation scale and e'' at time t (s): ``events.evaluate`` and
    ``events.event_acceleration`` with the undriven modes taken from the rotor and the driven
    ones propagated exactly from their state (q_s, v_s) at t_s (s).
    """
    z, lam, driven = rotor[0], rotor[1], rotor[2]
    sine, cosine = math.sin(forcing_frequency * t), math.cos(forcing_frequency * t)
    sine_term, cosine_term = sine_amp.real * sine, sine_amp.imag * cosine
    value = const + sine_term + cosine_term
    slope = forcing_frequency * (sine_amp.real * cosine - sine_amp.imag * sine)
    acceleration = -forcing_frequency**2 * (sine_term + cosine_term)
    scale = abs(const) + abs(sine_term) + abs(cosine_term)
    h = t - t_s
    phase_plus = step_plus = 0j  # the drive's phases, computed for the first driven mode
    for j in range(z.size):
        if driven[j]:
            if step_plus == 0:
                phase_plus = complex(math.cos(forcing_frequency * t_s),
                                     math.sin(forcing_frequency * t_s))
                step_plus = complex(math.cos(forcing_frequency * h),
                                    math.sin(forcing_frequency * h))
            w = omega[j]
            qj, vj = advance_mode(q_s[j], v_s[j], h, w, zeta[j], force[j], forcing_frequency,
                                  phase_plus, step_plus)
            aj = (force[j].real * sine + force[j].imag * cosine - 2.0 * zeta[j] * w * vj
                  - w * w * qj)
        else:
            rate = lam[j] * z[j]
            qj, vj, aj = z[j].real, rate.real, (lam[j] * rate).real
        term = weights[j] * qj
        value += term
        scale += abs(term)
        slope += weights[j] * vj
        acceleration += weights[j] * aj
    return value, slope, scale, acceleration
