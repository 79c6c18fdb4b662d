"""Extrema within a recorded run, each refined by Brent's method on its rate in one call.

A continuation reads a grazing value at every corrected point: the gap's smallest minimum in
free flight, and its highest rise between contacts, each refined at the root of the gap's rate
between two samples; at the points it keeps, the tips' largest deflections too. Brent's method
there takes some ten evaluations of the rate, each a closed-form state of the run; from Python
each was a kernel call of its own (some 120 us a refinement on the stiff stop, 6 % of its
continuation). Here the samples, the choice and the search are one call.

The gap is the one read from the free coordinates, as `impactbeams.orbits.PeriodMap` reads it:
g = const + S sin(Omega t) + C cos(Omega t) + w . q (``phase_scalars[FREE]``, w the free
phase's event row), in a contact phase too (its state observed in the free coordinates). The
tips are `stroboscope.tip_motion`'s.
"""

import math

import numpy as np

from impactbeams.kernels import contact
from impactbeams.kernels.bracketing import MAX_ITERATIONS, iteration
from impactbeams.kernels.drive import clamp_motion
from impactbeams.kernels.dynamics import propagate, sample_grid, sample_segments, segment_index
from impactbeams.kernels.jit import inlined_kernel, kernel
from impactbeams.kernels.layout import (
    CONTACT,
    FREE,
    ROW_EVENT,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
    TIP_V1,
    TIP_V2,
    TIP_Y1,
)
from impactbeams.kernels.stroboscope import tip_motion

_brent_iteration = inlined_kernel(iteration)
RTOL = 4.0 * np.finfo(np.float64).eps  # SciPy's brentq default, as `impactbeams.brent`'s


GAP, TIP = 0, 1  # the quantities whose extrema are sought: the gap, a tip's |deflection|


@kernel
def gap_extremum(tables, forces, phase_scalars, switching, settings, recorded, omega, lo,
                 hi, sign, xtol):
    """The gap's minimum (``sign`` 1) or maximum (-1) in (lo, hi): its time (s) and value (m).

    Brent's method on ``sign`` times the gap's rate from (lo, hi), as SciPy's ``brentq`` with
    ``xtol`` (s) steps: a simple root, found to round-off. (NaN, NaN) unless that rate is < 0
    at lo and > 0 at hi (no such extremum between them). ``omega``: the forcing frequency
    (rad/s).
    """
    return _extremum(GAP, sign, 0, 0.0, tables, forces, phase_scalars, switching,
                     settings, recorded, omega, lo, hi, xtol)


@kernel
def tip_maximum(tables, forces, phase_scalars, switching, settings, recorded, column,
                clamp, lo, hi, xtol):
    """The largest |tip ``column``| (``layout.TIP_Y1`` or ``TIP_Y2``) in (lo, hi): time, value.

    ``clamp`` 1: beam 1's deflection relative to its clamp (the clamp's motion subtracted), 0:
    absolute. As `gap_extremum`, on the rate of |tip|: (NaN, NaN) unless it is > 0 at lo and
    < 0 at hi.
    """
    return _extremum(TIP, -1.0, column, clamp, tables, forces, phase_scalars, switching,
                     settings, recorded, settings.forcing_frequency, lo, hi, xtol)


@kernel
def _extremum(what, sign, column, clamp, tables, forces, phase_scalars, switching,
              settings, recorded, omega, lo, hi, xtol):
    """Brent's method on ``sign`` times the rate of ``what`` (of its size for a tip)."""
    n_coords = recorded.q.shape[1]
    work = (np.empty(n_coords), np.empty(n_coords), np.empty(n_coords), np.empty(n_coords),
            np.empty(4))
    x_pre, x_cur = lo, hi
    _, f_pre = _value_rate(what, sign, column, clamp, tables, forces, phase_scalars, switching,
                           settings, recorded, omega, x_pre, work)
    _, f_cur = _value_rate(what, sign, column, clamp, tables, forces, phase_scalars, switching,
                           settings, recorded, omega, x_cur, work)
    if not f_pre < 0.0 < f_cur:
        return math.nan, math.nan
    x_blk = f_blk = s_pre = s_cur = 0.0
    for _ in range(MAX_ITERATIONS):
        done, x_pre, x_cur, x_blk, f_pre, f_blk, s_pre, s_cur = _brent_iteration(
            x_pre, x_cur, x_blk, f_pre, f_cur, f_blk, s_pre, s_cur, xtol, RTOL)
        value, f_cur = _value_rate(what, sign, column, clamp, tables, forces, phase_scalars,
                                   switching, settings, recorded, omega, x_cur, work)
        if done:
            return x_cur, value
    return math.nan, math.nan


@kernel
def _value_rate(what, sign, column, clamp, tables, forces, phase_scalars, switching,
                settings, recorded, omega, t, work):
    """``what``'s value at t (s), and ``sign`` times its rate (of |tip| for a tip).

    ``work``: (y, y', q, q', tips) arrays to sample into.
    """
    y, y_rate, q, v, tips = work
    phase = _state(tables, forces, switching, settings, recorded, t, y, y_rate, q, v)
    if what == GAP:
        scalars, weights = phase_scalars[FREE], tables[FREE, ROW_EVENT]
        return _gap(scalars, weights, omega, t, q), sign * _rate(scalars, weights, omega, t, v)
    tip_motion(tables, forces, phase_scalars, settings, contact.residual_flexibility2(
        tables[FREE], settings), phase, t, q, v, tips)
    moved, moved_rate, _ = clamp_motion(settings, t)
    value = tips[column] - clamp * settings.shaker1 * moved
    rate = tips[TIP_V1 if column == TIP_Y1 else TIP_V2] - clamp * settings.shaker1 * moved_rate
    return abs(value), sign * math.copysign(1.0, value) * rate


@kernel
def smallest_free_minimum(tables, forces, phase_scalars, switching, settings, recorded,
                          omega, times):
    """The gap's smallest interior minimum in free flight, sampled on ``times`` and refined.

    ``times``: an equally spaced grid over the run (s), sampled a step at a time
    (`dynamics.sample_grid`). The sample: the smallest gap of a free sample between two free
    samples not below it (the first if several). Refined by `gap_extremum` between the
    sample's neighbours. Returns (t, g) refined (NaN, NaN where the rate does not change sign
    there: the caller minimises the gap itself), then the sample's (t, g) and its neighbours'
    times (all NaN without such a sample).
    """
    n_coords, m = recorded.q.shape[1], times.size
    q, v = np.empty((m, n_coords)), np.empty((m, n_coords))
    phase = np.empty(m, dtype=np.int64)
    sample_grid(tables, forces, switching, settings, recorded, times, q, v, phase)
    scalars, weights = phase_scalars[FREE], tables[FREE, ROW_EVENT]
    gap = np.empty(m)
    for i in range(m):
        gap[i] = _gap(scalars, weights, omega, times[i], q[i])
    best = -1
    for i in range(1, m - 1):
        if (phase[i - 1] == FREE and phase[i] == FREE and phase[i + 1] == FREE
                and gap[i] <= gap[i - 1] and gap[i] <= gap[i + 1]
                and (best < 0 or gap[i] < gap[best])):
            best = i
    if best < 0:
        return math.nan, math.nan, math.nan, math.nan, math.nan, math.nan
    lo, hi = times[best - 1], times[best + 1]
    t, value = gap_extremum(tables, forces, phase_scalars, switching, settings, recorded,
                            omega, lo, hi, 1.0, 1e-14 * max(hi, 1.0))
    return t, value, times[best], gap[best], lo, hi


@kernel
def interval_gap(tables, forces, phase_scalars, switching, settings, recorded, ends, omega,
                 count):
    """The gap's local maximum nearest 0 between contacts (m); NaN if there is none.

    Each segment (ending at ``ends``, s) sampled ``count`` times a step at a time
    (`dynamics.sample_segments`). The candidates, in order: each lasting contact's interior
    sample maxima (above the sample before, not below the one after), then each free interval
    between two contacts' highest sample (the period's ends joined: a free interval across
    them is its last and first segments) if inside its segment. The first nearest 0 is
    sampled exactly and refined by `gap_extremum` between its neighbours.
    """
    segments, n_coords = recorded.time.size, recorded.q.shape[1]
    contact = recorded.phase == CONTACT
    if not contact.any():
        return math.nan
    q, v = np.empty((segments * count, n_coords)), np.empty((segments * count, n_coords))
    sample_segments(tables, forces, switching, settings, recorded, ends, count, q, v)
    scalars, weights = phase_scalars[FREE], tables[FREE, ROW_EVENT]
    times, gap = np.empty((segments, count)), np.empty((segments, count))
    for k in range(segments):
        step = (ends[k] - recorded.time[k]) / (count - 1)
        for i in range(count):  # as np.linspace: the last sample at the segment's end
            times[k, i] = ends[k] if i == count - 1 else i * step + recorded.time[k]
            gap[k, i] = _gap(scalars, weights, omega, times[k, i], q[k * count + i])
    best_k, best_i = -1, -1
    for k in range(segments):
        if contact[k] and ends[k] > recorded.time[k]:  # a contact of zero duration: no interior
            for i in range(1, count - 1):
                if gap[k, i] > gap[k, i - 1] and gap[k, i] >= gap[k, i + 1]:
                    best_k, best_i = _nearer_zero(gap, best_k, best_i, k, i)
    for k in range(segments):
        if contact[k] or (segments > 1 and k == segments - 1 and not contact[0]):
            continue  # (the period's first segment goes on from its last: taken with it)
        last = segments - 1 if k == 0 and segments > 1 and not contact[segments - 1] else k
        if contact[(last - 1) % segments] and contact[(k + 1) % segments]:
            highest = last if np.max(gap[last]) > np.max(gap[k]) else k
            at = int(np.argmax(gap[highest]))
            if 0 < at < count - 1:
                best_k, best_i = _nearer_zero(gap, best_k, best_i, highest, at)
    if best_k < 0:
        return math.nan
    y, y_rate, q_t, v_t = (np.empty(n_coords), np.empty(n_coords), np.empty(n_coords),
                           np.empty(n_coords))
    t = times[best_k, best_i]
    _state(tables, forces, switching, settings, recorded, t, y, y_rate, q_t, v_t)
    value = _gap(scalars, weights, omega, t, q_t)
    lo, hi = times[best_k, best_i - 1], times[best_k, best_i + 1]
    _, rise = gap_extremum(tables, forces, phase_scalars, switching, settings, recorded,
                           omega, lo, hi, -1.0, 1e-14 * max(hi, 1.0))
    return value if math.isnan(rise) else max(value, rise)


@kernel
def _nearer_zero(gap, best_k, best_i, k, i):
    """(k, i) if its sample is nearer 0 than the best's so far (or there is none), else the best."""
    if best_k < 0 or abs(gap[k, i]) < abs(gap[best_k, best_i]):
        return k, i
    return best_k, best_i


@kernel
def _state(tables, forces, switching, settings, recorded, t, y, y_rate, q, v):
    """The run's state at t (s), observed in the free coordinates, into (q, v); its phase."""
    k = segment_index(recorded.time, recorded.time.size, t, 0)
    phase = recorded.phase[k]
    propagate(tables[phase], forces[phase], recorded.q[k], recorded.v[k], recorded.time[k], t,
              settings, y, y_rate)
    contact.observed_state(phase, y, y_rate, t, switching, settings, q, v)
    return phase


@kernel
def _gap(scalars, weights, omega, t, q):
    """The gap g (m) at t from the free coordinates q."""
    return (scalars[SCALAR_CONST] + scalars[SCALAR_SINE] * math.sin(omega * t)
            + scalars[SCALAR_COSINE] * math.cos(omega * t) + _dot(q, weights))


@kernel
def _rate(scalars, weights, omega, t, v):
    """dg/dt (m/s) at t from the free coordinates' rates v."""
    return (omega * (scalars[SCALAR_SINE] * math.cos(omega * t)
                     - scalars[SCALAR_COSINE] * math.sin(omega * t)) + _dot(v, weights))


@kernel
def _dot(a, b):
    """The sum of a_j b_j: a loop, not np.dot, whose BLAS call costs a cold compile 0.2 s."""
    total = 0.0
    for j in range(a.size):
        total += a[j] * b[j]
    return total
