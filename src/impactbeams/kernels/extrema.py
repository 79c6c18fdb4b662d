"""The gap's extrema within a recorded run: Brent's method on the gap's rate, in one call.

A continuation reads a grazing value at every corrected point: the gap's smallest minimum in
free flight, and its highest rise between contacts, each refined at the root of the gap's rate
between two samples. Brent's method there takes some ten evaluations of the rate, each a
closed-form state of the run; from Python each was a kernel call of its own (some 120 us a
refinement on the stiff stop, 6 % of its continuation). Here the whole search is one call.

The gap is the one read from the free coordinates, as `impactbeams.orbits.PeriodMap` reads it:
g = const + S sin(Omega t) + C cos(Omega t) + w . q (``phase_scalars[FREE]``, w the free
phase's event row), in a contact phase too (its state observed in the free coordinates).
"""

import math

import numpy as np

from impactbeams.brent import MAX_ITERATIONS, iteration
from impactbeams.kernels import contact
from impactbeams.kernels.dynamics import propagate, segment_index
from impactbeams.kernels.jit import inlined_kernel, kernel
from impactbeams.kernels.layout import FREE, ROW_EVENT, SCALAR_CONST, SCALAR_COSINE, SCALAR_SINE

_brent_iteration = inlined_kernel(iteration)
RTOL = 4.0 * np.finfo(np.float64).eps  # SciPy's brentq default, as `impactbeams.brent`'s


@kernel
def gap_extremum(tables, forces, scalars, spring, drives, settings, recorded, omega, lo, hi,
                 sign, xtol):
    """The gap's minimum (``sign`` 1) or maximum (-1) in (lo, hi): its time (s) and value (m).

    Brent's method on ``sign`` times the gap's rate from (lo, hi), as SciPy's ``brentq`` with
    ``xtol`` (s) steps: a simple root, found to round-off. (NaN, NaN) unless that rate is < 0
    at lo and > 0 at hi (no such extremum between them). ``scalars``: the free phase's
    (``phase_scalars[FREE]``); ``omega``: the forcing frequency (rad/s).
    """
    n_coords = recorded.q.shape[1]
    y, y_rate = np.empty(n_coords), np.empty(n_coords)
    q, v = np.empty(n_coords), np.empty(n_coords)
    weights = tables[FREE, ROW_EVENT]
    x_pre, x_cur = lo, hi
    _state(tables, forces, spring, drives, settings, recorded, x_pre, y, y_rate, q, v)
    f_pre = sign * _rate(scalars, weights, omega, x_pre, v)
    _state(tables, forces, spring, drives, settings, recorded, x_cur, y, y_rate, q, v)
    f_cur = sign * _rate(scalars, weights, omega, x_cur, v)
    if not f_pre < 0.0 < f_cur:
        return math.nan, math.nan
    x_blk = f_blk = s_pre = s_cur = 0.0
    for _ in range(MAX_ITERATIONS):
        done, x_pre, x_cur, x_blk, f_pre, f_blk, s_pre, s_cur = _brent_iteration(
            x_pre, x_cur, x_blk, f_pre, f_cur, f_blk, s_pre, s_cur, xtol, RTOL)
        _state(tables, forces, spring, drives, settings, recorded, x_cur, y, y_rate, q, v)
        if done:
            return x_cur, _gap(scalars, weights, omega, x_cur, q)
        f_cur = sign * _rate(scalars, weights, omega, x_cur, v)
    return math.nan, math.nan


@kernel
def _state(tables, forces, spring, drives, settings, recorded, t, y, y_rate, q, v):
    """The run's state at t (s), observed in the free coordinates, into (q, v)."""
    k = segment_index(recorded.time, recorded.time.size, t, 0)
    phase = recorded.phase[k]
    propagate(tables[phase], forces[phase], recorded.q[k], recorded.v[k], recorded.time[k], t,
              settings, y, y_rate)
    contact.observed_state(phase, y, y_rate, t, spring, drives, settings, q, v)


@kernel
def _gap(scalars, weights, omega, t, q):
    """G (m) at t from the free coordinates q."""
    return (scalars[SCALAR_CONST] + scalars[SCALAR_SINE] * math.sin(omega * t)
            + scalars[SCALAR_COSINE] * math.cos(omega * t) + _dot(q, weights))


@kernel
def _rate(scalars, weights, omega, t, v):
    """dg/dt (m/s) at t from the free coordinates' rates v."""
    return (omega * (scalars[SCALAR_SINE] * math.cos(omega * t)
                     - scalars[SCALAR_COSINE] * math.sin(omega * t)) + _dot(v, weights))


@kernel
def _dot(a, b):
    """A . b: a loop, not np.dot, whose BLAS call costs a cold compile 0.2 s."""
    total = 0.0
    for j in range(a.size):
        total += a[j] * b[j]
    return total
