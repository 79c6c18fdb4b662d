"""The largest contact force of a contact phase, certified by branch and bound.

In a contact phase the contact force is the phase's event function (`impactbeams.kernels.events`),

    R(t) = const + Im(S e^(i Omega t)) + sum_j w_j x_j(t),

with the steady states of the modes away from resonance moved into the sinusoid
(``events.split_steady_states``): x_j is then a free transient, whose modulus
``A_j = |(x_j, (x_j' + sigma_j x_j) / omega_dj)|`` bounds |x_j| and, times omega_j^2, |x_j''|
from then on, decaying like ``e^(-sigma_j t)``; a mode near resonance keeps its drive and
`events.phase_bounds`' growth bounds over the contact. On an interval [a, b] of length h,
split the modes into a slow group, which together with the sinusoid has
``|R_slow''| <= C_slow``, and a fast group, ``|R_fast| <= band``. R_slow lies below its chord
plus C_slow h^2 / 8, and each end's R_slow is R there within ``band``, so

    max R on [a, b] <= max(R(a), R(b)) + 2 band + C_slow h^2 / 8,

and the best split puts mode j in the slow group when omega_j h < 4 (its share
``|w_j| A_j min(omega_j^2 h^2 / 8, 2)`` is then the smaller). A fast mode costs only its
amplitude, however fast it is, so a long contact is cut in pieces on the time scale of the
motion that carries R, not on the fastest mode's: an interval whose bound is below the best
value found is dropped, the others are bisected (depth first, the more promising half first).
The search ends when every interval is dropped: it has the largest R of the split form to within
``PEAK_TOLERANCE`` eps of R's evaluation scale (its own rounding), at a time located to that
level, and no peak can have been skipped between samples (the bound holds between them). The
value returned is R there from the unsplit state, as the dynamics evaluate it: the two forms
round differently, by a few eps of the scale. Each evaluation is one propagation of the split
modes from the contact's start.
"""

import math

import numpy as np

from impactbeams.kernels.events import (
    evaluate,
    phase_bounds,
    phase_event_function,
    phase_oscillators,
    split_steady_states,
)
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.propagation import advance_to
from impactbeams.kernels.records import EventFunction, Oscillators

_EPS = np.finfo(np.float64).eps
PEAK_TOLERANCE = 4.0  # eps of R's evaluation scale: the search's resolution, R's own rounding


@kernel
def _mode_bounds(q, v, t_s, span, oscillators, event):
    """Per mode over [t_s, t_s + span]: ``(coherent, reach, curvature, decay)``.

    ``coherent``: the steady states `events.phase_bounds` splits off the driven modes, summed
    (complex, N); per mode, ``reach`` bounds |w_j x_j| and ``curvature`` |w_j x_j''| (N/s^2)
    of the rest, which decays at least like e^(-decay_j (t - t_s)) (decay_j = sigma_j for an
    undriven mode, 0 for a driven one: its bounds hold as they are). ``oscillators``,
    ``event``: the `records` of the phase with its steady states split off.
    """
    omega = oscillators.forcing_frequency
    n = oscillators.frequencies.size
    reach, curvature, decay = np.empty(n), np.empty(n), np.zeros(n)
    coherent = 0j
    for j in range(n):
        mode = Oscillators(oscillators.frequencies[j:j + 1], oscillators.zeta[j:j + 1],
                           oscillators.force[j:j + 1], omega)
        weight = EventFunction(event.weights[j:j + 1], 0.0, 0j, omega)
        steady, band, bend, _, _ = phase_bounds(q[j:j + 1], v[j:j + 1], t_s, span, mode, weight)
        coherent += steady
        reach[j], curvature[j] = band, bend  # bend counts the steady part's too: an upper bound
        if oscillators.force[j] == 0:
            decay[j] = oscillators.zeta[j] * oscillators.frequencies[j]
    return coherent, reach, curvature, decay


@kernel
def _slack(a, h, t_s, frequencies, reach, curvature, decay, sine_curvature):
    """``max R - max(R(a), R(a + h))`` on [a, a + h] is at most this (N): the module's bound."""
    slack = sine_curvature * h * h / 8.0
    for j in range(frequencies.size):
        fade = math.exp(-decay[j] * (a - t_s)) if decay[j] > 0.0 else 1.0
        slack += fade * min(curvature[j] * h * h / 8.0, 2.0 * reach[j])
    return slack


@kernel
def peak_force(table, force, scalars, settings, q_s, v_s, t_s, t_e):
    """Largest contact force (N) over the contact segment [t_s, t_e] and its time (s).

    Certified branch and bound (the module's docstring): the maximum of R over the segment to
    within R's rounding (``PEAK_TOLERANCE`` eps of its evaluation scale, plus the difference of
    the split and unsplit forms); the value returned is R at the returned time, as the phase's
    event function gives it from (q_s, v_s) at t_s.
    """
    omega = settings.forcing_frequency
    x_s, u_s = q_s.copy(), v_s.copy()
    split_modes = phase_oscillators(table, force.copy(), omega)
    split = split_steady_states(x_s, u_s, t_s, split_modes, phase_event_function(table, scalars,
                                                                                 omega))
    coherent, reach, curvature, decay = _mode_bounds(x_s, u_s, t_s, t_e - t_s, split_modes,
                                                     split)
    sine_curvature = omega * omega * abs(split.sine_amp + coherent)
    q, v = np.empty(q_s.size), np.empty(q_s.size)
    start = (x_s, u_s, t_s)
    r_s, scale_s = _force_at(split_modes, split, start, t_s, q, v)
    r_e, scale_e = _force_at(split_modes, split, start, t_e, q, v)
    best, best_t = (r_s, t_s) if r_s >= r_e else (r_e, t_e)
    tolerance = PEAK_TOLERANCE * _EPS * max(scale_s, scale_e)
    # depth-first, the more promising half first: intervals (a, b, R(a), R(b))
    # a bisection stops at intervals of 4 eps: a pop pushes two halves, so the stack holds at
    # most one interval per halving, plus one
    halvings = math.log2(max(t_e - t_s, _EPS) / (4.0 * _EPS))
    stack = np.empty((int(halvings) + 8, 4))  # a margin for midpoints rounded at the last ulps
    size = _push(stack, 0, t_s, t_e, r_s, r_e)
    while size > 0:
        size -= 1
        a, b, r_a, r_b = stack[size]
        h = b - a
        if (max(r_a, r_b) + _slack(a, h, t_s, split_modes.frequencies, reach, curvature,
                                   decay, sine_curvature) <= best + tolerance
                or h <= 4.0 * _EPS * max(abs(b), 1.0)):
            continue
        middle = a + 0.5 * h
        r_m, scale = _force_at(split_modes, split, start, middle, q, v)
        tolerance = max(tolerance, PEAK_TOLERANCE * _EPS * scale)
        if r_m > best:
            best, best_t = r_m, middle
        if r_a >= r_b:  # the left half on top
            size = _push(stack, _push(stack, size, middle, b, r_m, r_b), a, middle, r_a, r_m)
        else:
            size = _push(stack, _push(stack, size, a, middle, r_a, r_m), middle, b, r_m, r_b)
    # the unsplit phase's R, by the same compiled code as the search's (one propagation site)
    value, _ = _force_at(phase_oscillators(table, force, omega),
                         phase_event_function(table, scalars, omega), (q_s, v_s, t_s), best_t,
                         q, v)
    return value, best_t


@kernel
def least_peak_force(table, force, scalars, settings, q, v, starts, ends):
    """The smallest of the peak forces (N) of the contact segments [starts[i], ends[i]] (s).

    ``q``, ``v``: each contact's state at its start (rows). ``peak_force`` of each contact in
    the order of R at its middle, a lower bound of its peak (a grazing reads only the least
    peak, and all but one contact are far above it): a contact whose bound exceeds the least
    peak so far by more than R's rounding there cannot be lower and is not searched. The value
    is the one ``peak_force`` gives that contact; inf without contacts.
    """
    omega = settings.forcing_frequency
    oscillators = phase_oscillators(table, force, omega)
    event = phase_event_function(table, scalars, omega)
    x, u = np.empty(q.shape[1]), np.empty(q.shape[1])
    below = np.empty(starts.size)
    for i in range(starts.size):
        value, scale = _force_at(oscillators, event, (q[i], v[i], starts[i]),
                                 0.5 * (starts[i] + ends[i]), x, u)
        below[i] = value - 2.0 * PEAK_TOLERANCE * _EPS * scale
    least = np.inf
    for i in np.argsort(below):
        if below[i] >= least:
            break
        least = min(least, peak_force(table, force, scalars, settings, q[i], v[i], starts[i],
                                      ends[i])[0])
    return least


@kernel
def _push(stack, size, a, b, r_a, r_b):
    """Put the interval (a, b, R(a), R(b)) on ``stack`` above its ``size`` entries; the new size.

    Element by element: assigning a tuple to a row compiles Numba's string formatting for its
    shape-mismatch message (1.6 s of a cold compile).
    """
    stack[size, 0], stack[size, 1], stack[size, 2], stack[size, 3] = a, b, r_a, r_b
    return size + 1


@kernel
def _force_at(oscillators, event, start, t, q, v):
    """R (N) and its evaluation scale at t (s) of the phase's ``oscillators`` and ``event``.

    ``start``: their state (q_s, v_s, t_s).
    """
    q_s, v_s, t_s = start
    advance_to(oscillators, q_s, v_s, t_s, t, q, v)
    value, _, scale = evaluate(q, v, t, event)
    return value, scale
