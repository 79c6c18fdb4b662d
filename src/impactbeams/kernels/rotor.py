"""Cheap repeated evaluation of an event function along a certified walk.

A walk (`impactbeams.kernels.events.walk`) evaluates e, e' and e'' at a few dozen points
per phase. Propagating every mode from the phase's start to each point costs an exponential,
a sine and a cosine per mode. An undriven mode (``events.split_steady_states`` moves the steady
states of the others into the event's sinusoid) is instead a rotating complex amplitude,

    q(t) = Re z(t),   q'(t) = Re(lambda z),   q'' = Re(lambda^2 z),   z(t + h) = z(t) e^(lambda h),

with lambda = -zeta omega + i omega_d; a step multiplies z by a stored e^(lambda h). Steps are
rounded down to ``2^k`` or ``3 * 2^(k-1)`` (one or two stored factors e^(lambda 2^k), computed
on first use), and the walk's time offset is a sum of such numbers, exact in floating point
unless the steps span more than 2^53. Each product rounds once: after n steps z carries a
relative error of about n ulps, far below what the walk certifies; roots are resolved by exact
propagation. Driven modes (near resonance) are propagated exactly to each point. The forcing's
phasor e^(i Omega t) turns along as one more amplitude (lambda = i Omega), after the modes.

The rotor is a `records.Rotor` of arrays ``(amplitudes, eigenvalues, driven, levels, factors,
rates, split, split_force)`` (below z, lam, driven, levels, factors, rates), sized for at most
``capacity`` modes (a phase uses the first ``frequencies.size``, and the next for the forcing): the
amplitudes, the eigenvalues, which modes are driven, the factors
``factors[k - LOWEST] = e^(lambda 2^k)`` of the steps 2^k, k from ``LOWEST`` to
``LOWEST + LEVELS - 1``, and the event's weights of the undriven modes with their products by
lambda and lambda^2 (rows of ``rates``). ``levels[k - LOWEST]`` is 1 once a factor is
computed, ``levels[LEVELS]`` the number of modes they were computed for, ``levels[LEVELS + 1]``
the number of driven modes. A rotor kept across the searches of one phase
(``dynamics.run_events`` keeps one per phase) computes each factor once per run:
``rotor_load`` clears them only when the eigenvalues change. ``split`` (rows q, q') and
``split_force`` hold the search's state and drives with the steady states split off
(``events.first_root``): work arrays that a search would otherwise allocate.
"""

import math

import numpy as np

from impactbeams.kernels.drive import compiled_modal_acceleration
from impactbeams.kernels.jit import borrowing_kernel, kernel
from impactbeams.kernels.propagation import advance_mode
from impactbeams.kernels.records import Rotor

# Factors of the steps 2^-80 s (a walk's steps are at least 4 eps times a period of the
# slowest mode) to 2^19 s; a longer certified step is taken as 2^19 or 3 2^18 s.
LOWEST, LEVELS = -80, 100
_EPS = np.finfo(np.float64).eps


@kernel
def modulus_bound(x, y):
    """An upper bound of |x + i y|, cheaper than ``math.hypot`` (which guards against overflow).

    x^2, y^2, their sum and the square root each round once, by at most eps / 2: together
    under 2 eps of the result, and 4 eps more covers them. Where the squares could underflow,
    |x| + |y|.
    """
    square = x * x + y * y
    if square < 1e-280:
        return abs(x) + abs(y)
    return math.sqrt(square) * (1.0 + 4.0 * _EPS)


@kernel
def rotor_arrays(capacity):
    """An empty rotor for up to ``capacity`` modes."""
    return Rotor(np.empty(capacity + 1, dtype=np.complex128),
                 np.empty(capacity + 1, dtype=np.complex128), np.empty(capacity, dtype=np.bool_),
                 np.zeros(LEVELS + 2, dtype=np.int64),
                 np.empty((LEVELS, capacity + 1), dtype=np.complex128),
                 np.empty((3, capacity), dtype=np.complex128), np.empty((2, capacity)),
                 np.empty(capacity, dtype=np.complex128))


@borrowing_kernel
def rotor_load(rotor, q, v, t, oscillators, event):
    """Set the rotor's amplitudes from the modal state (q, v) at t (s); return the driven count.

    The stored step factors are kept if the eigenvalues are those they were computed for.
    ``weights``: the event function's; ``rates`` holds, for the undriven modes (0 for the
    driven), the weights and their products with lambda and lambda^2, which give e, e', e''.
    """
    z, lam, driven = rotor.amplitudes, rotor.eigenvalues, rotor.driven
    levels, rates = rotor.levels, rotor.rates
    forcing_frequency = oscillators.forcing_frequency
    same = levels[LEVELS] == oscillators.frequencies.size
    count = 0
    for j in range(oscillators.frequencies.size):
        w, zeta = oscillators.frequencies[j], oscillators.zeta[j]
        eigenvalue = complex(-zeta * w, w * math.sqrt(1.0 - zeta * zeta))
        same = same and lam[j] == eigenvalue
        lam[j] = eigenvalue
        driven[j] = oscillators.force[j] != 0
        count += driven[j]
        z[j] = complex(q[j], (eigenvalue.real * q[j] - v[j]) / eigenvalue.imag)
        free_weight = 0.0 if driven[j] else event.weights[j]
        rates[0, j] = free_weight
        rates[1, j] = free_weight * eigenvalue
        rates[2, j] = rates[1, j] * eigenvalue
    n = oscillators.frequencies.size
    same = same and lam[n] == complex(0.0, forcing_frequency)
    lam[n] = complex(0.0, forcing_frequency)
    z[n] = complex(math.cos(forcing_frequency * t), math.sin(forcing_frequency * t))
    if not same:
        levels[:LEVELS] = 0
        levels[LEVELS] = oscillators.frequencies.size
    levels[LEVELS + 1] = count
    return count


@borrowing_kernel
def rotor_bounds(rotor, oscillators, event, coherent):
    """``events.phase_bounds`` from now on, for a rotor without driven modes.

    A free mode's amplitude |z| bounds |q| and, times omega^k, its k-th derivative for all
    later times (it decays): the transients' band, curvature and jerk shrink as the fast
    modes die out, and the walk's certified steps grow.
    """
    z = rotor.amplitudes
    forcing_frequency = oscillators.forcing_frequency
    band = curvature = jerk = 0.0
    for j in range(oscillators.frequencies.size):
        term = abs(event.weights[j]) * modulus_bound(z[j].real, z[j].imag)
        w2 = oscillators.frequencies[j] * oscillators.frequencies[j]
        band += term
        curvature += w2 * term
        jerk += w2 * oscillators.frequencies[j] * term
    forced = abs(coherent)
    return (coherent, band, curvature + forcing_frequency**2 * forced,
            jerk + forcing_frequency**3 * forced, True)


@borrowing_kernel
def _compute_factor(eigenvalues, levels, factors, exponent):
    """Store e^(lambda 2^exponent) of every mode (``factors[exponent - LOWEST]``)."""
    level = exponent - LOWEST
    levels[level] = 1
    h = math.ldexp(1.0, exponent)
    for j in range(levels[LEVELS] + 1):
        growth = eigenvalues[j] * h
        factors[level, j] = math.exp(growth.real) * complex(math.cos(growth.imag),
                                                            math.sin(growth.imag))


@borrowing_kernel
def rotor_step(rotor, step):
    """Rotate the undriven modes by the largest 2^k or 3 * 2^(k-1) not above ``step`` (s > 0).

    Returns the step taken (s), 0 if ``step`` is below the table's smallest (nothing moved).
    """
    return turn(rotor.amplitudes, rotor.eigenvalues, rotor.levels, rotor.factors, step)


@borrowing_kernel
def turn(amplitudes, eigenvalues, levels, factors, step):
    """``rotor_step`` on the rotor's arrays that it uses.

    The walk calls this form at every step: a kernel increfs and decrefs each array it
    receives (an atomic update each, `records`), and a whole `records.Rotor` is six of them.
    Each factor e^(lambda 2^k) is computed on first use.
    """
    fraction, exponent = math.frexp(step)  # step = fraction 2^exponent, 1/2 <= fraction < 1
    if exponent - 2 < LOWEST:
        return 0.0
    if exponent > LOWEST + LEVELS:  # not min(): frexp's int32 against an int64 compiles its own
        exponent = LOWEST + LEVELS
    first = exponent - 1 - LOWEST
    if levels[first] == 0:
        _compute_factor(eigenvalues, levels, factors, exponent - 1)
    taken = math.ldexp(1.0, exponent - 1)
    # every mode turns (a driven mode's z is never read), which the compiler can vectorise
    if fraction >= 0.75:
        if levels[first - 1] == 0:
            _compute_factor(eigenvalues, levels, factors, exponent - 2)
        taken += math.ldexp(1.0, exponent - 2)
        for j in range(levels[LEVELS] + 1):
            amplitudes[j] = amplitudes[j] * factors[first, j] * factors[first - 1, j]
        return taken
    for j in range(levels[LEVELS] + 1):
        amplitudes[j] = amplitudes[j] * factors[first, j]
    return taken


@borrowing_kernel
def free_event(amplitudes, rates, n, event):
    """e, e', its evaluation scale and e'' of the forcing and the ``n`` undriven modes.

    ``rotor_event`` without the driven modes, on the rotor's arrays that it uses (see ``turn``).
    """
    const, sine_amp, forcing_frequency = event.const, event.sine_amp, event.forcing_frequency
    sine, cosine = amplitudes[n].imag, amplitudes[n].real  # the forcing's phasor
    sine_term, cosine_term = sine_amp.real * sine, sine_amp.imag * cosine
    # the undriven modes (weight 0 for the driven): q = Re z, w q' = Re(w lambda z), w q'' =
    # Re(w lambda^2 z); two partial sums of each, in a fixed order, so that the additions do
    # not each wait for the previous one
    v0 = v1 = s0 = s1 = d0 = d1 = a0 = a1 = 0.0
    for j in range(0, n - 1, 2):
        x, y = amplitudes[j].real, amplitudes[j].imag
        term = rates[0, j].real * x
        v0 += term
        s0 += abs(term)
        d0 += rates[1, j].real * x - rates[1, j].imag * y
        a0 += rates[2, j].real * x - rates[2, j].imag * y
        x, y = amplitudes[j + 1].real, amplitudes[j + 1].imag
        term = rates[0, j + 1].real * x
        v1 += term
        s1 += abs(term)
        d1 += rates[1, j + 1].real * x - rates[1, j + 1].imag * y
        a1 += rates[2, j + 1].real * x - rates[2, j + 1].imag * y
    if n % 2 == 1:
        x, y = amplitudes[n - 1].real, amplitudes[n - 1].imag
        term = rates[0, n - 1].real * x
        v0 += term
        s0 += abs(term)
        d0 += rates[1, n - 1].real * x - rates[1, n - 1].imag * y
        a0 += rates[2, n - 1].real * x - rates[2, n - 1].imag * y
    value = const + sine_term + cosine_term + (v0 + v1)
    scale = abs(const) + abs(sine_term) + abs(cosine_term) + (s0 + s1)
    slope = forcing_frequency * (sine_amp.real * cosine - sine_amp.imag * sine) + (d0 + d1)
    acceleration = -forcing_frequency**2 * (sine_term + cosine_term) + (a0 + a1)
    return value, slope, scale, acceleration


@borrowing_kernel
def rotor_event(rotor, q_s, v_s, t_s, t, oscillators, event):
    """e, e', its evaluation scale and e'' at time t (s), from the rotor.

    As ``events.evaluate`` and ``events.event_acceleration``, with the undriven modes taken from
    the rotor (``free_event``) and the driven ones propagated exactly from their state (q_s,
    v_s) at t_s (s).
    """
    forcing_frequency = event.forcing_frequency
    n = oscillators.frequencies.size
    value, slope, scale, acceleration = free_event(rotor.amplitudes, rotor.rates, n, event)
    sine, cosine = rotor.amplitudes[n].imag, rotor.amplitudes[n].real
    if rotor.levels[LEVELS + 1] == 0:
        return value, slope, scale, acceleration
    h = t - t_s
    phase_plus = complex(math.cos(forcing_frequency * t_s), math.sin(forcing_frequency * t_s))
    step_plus = complex(math.cos(forcing_frequency * h), math.sin(forcing_frequency * h))
    for j in range(n):
        if rotor.driven[j]:
            w, zeta, f = oscillators.frequencies[j], oscillators.zeta[j], oscillators.force[j]
            qj, vj = advance_mode(q_s[j], v_s[j], h, w, zeta, f, forcing_frequency, phase_plus,
                                  step_plus)
            term = event.weights[j] * qj
            value += term
            scale += abs(term)
            slope += event.weights[j] * vj
            acceleration += event.weights[j] * compiled_modal_acceleration(f, w, zeta, qj, vj,
                                                                           sine, cosine)
    return value, slope, scale, acceleration
