"""Brent's bracketing root finder, step for step as ``scipy.optimize.brentq``.

Why not SciPy's: importing ``scipy.optimize`` costs about 0.3 s on top of NumPy (it loads its
linear programming, global optimisers and ``scipy.linalg``), more than `impactbeams modes`
spends computing, and a first-impact map needs nothing else from SciPy. This is SciPy's C
routine (scipy/optimize/Zeros/brentq.c) with the same operations in the same order on
doubles, so its roots are bitwise SciPy's (tests/test_startup.py compares them).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

MAX_ITERATIONS = 100  # SciPy's default maxiter


def brentq(f: Callable[..., Any], a: float, b: float, args: tuple[Any, ...] = (),
           xtol: float = 2e-12, rtol: float = 8.881784197001252e-16) -> float:
    """A root of ``f(x, *args)`` in [a, b], where f(a) and f(b) have opposite signs.

    Converged when half the bracket is below (xtol + rtol |x|) / 2. Raises ValueError if f(a)
    and f(b) have the same sign or f is NaN, RuntimeError after `MAX_ITERATIONS` steps, as
    SciPy does.
    """
    x_pre, x_cur = float(a), float(b)
    f_pre, f_cur = _value(f, x_pre, args), _value(f, x_cur, args)
    if f_pre == 0:
        return x_pre
    if f_cur == 0:
        return x_cur
    if _negative(f_pre) == _negative(f_cur):
        raise ValueError("f(a) and f(b) must have different signs")
    x_blk = f_blk = s_pre = s_cur = 0.0
    for _ in range(MAX_ITERATIONS):
        done, x_pre, x_cur, x_blk, f_pre, f_blk, s_pre, s_cur = iteration(
            x_pre, x_cur, x_blk, f_pre, f_cur, f_blk, s_pre, s_cur, xtol, rtol)
        if done:
            return x_cur
        f_cur = _value(f, x_cur, args)
    raise RuntimeError(f"Failed to converge after {MAX_ITERATIONS} iterations.")


def iteration(x_pre: float, x_cur: float, x_blk: float, f_pre: float, f_cur: float,
              f_blk: float, s_pre: float, s_cur: float, xtol: float, rtol: float,
              ) -> tuple[bool, float, float, float, float, float, float, float]:
    """One step of Brent's method: (converged, x_pre, x_cur, x_blk, f_pre, f_blk, s_pre, s_cur).

    Converged: x_cur is the root. Else f(x_cur) is the caller's to evaluate for the next step:
    interpolated (secant or inverse quadratic) if short enough, else bisection. Self-contained
    arithmetic on floats, so that `impactbeams.kernels.extrema` compiles it into a kernel.
    """
    # C's signbit (true for -0.0 too)
    if f_pre != 0 and f_cur != 0 and (math.copysign(1.0, f_pre) < 0) != (
            math.copysign(1.0, f_cur) < 0):
        x_blk, f_blk = x_pre, f_pre
        s_pre = s_cur = x_cur - x_pre
    if abs(f_blk) < abs(f_cur):  # x_cur: the better estimate of the two ends
        x_pre, x_cur, x_blk = x_cur, x_blk, x_cur
        f_pre, f_cur, f_blk = f_cur, f_blk, f_cur
    delta = (xtol + rtol * abs(x_cur)) / 2
    s_bis = (x_blk - x_cur) / 2
    if f_cur == 0 or abs(s_bis) < delta:
        return True, x_pre, x_cur, x_blk, f_pre, f_blk, s_pre, s_cur
    step_pre, step = s_bis, s_bis  # bisection, unless interpolation is short enough
    if abs(s_pre) > delta and abs(f_cur) < abs(f_pre):
        if x_pre == x_blk:  # secant
            s_try = -f_cur * (x_cur - x_pre) / (f_cur - f_pre)
        else:  # inverse quadratic extrapolation
            d_pre = (f_pre - f_cur) / (x_pre - x_cur)
            d_blk = (f_blk - f_cur) / (x_blk - x_cur)
            s_try = -f_cur * (f_blk * d_blk - f_pre * d_pre) / (d_blk * d_pre * (f_blk - f_pre))
        bound = 3 * abs(s_bis) - delta
        if 2 * abs(s_try) < (abs(s_pre) if abs(s_pre) < bound else bound):  # C's MIN
            step_pre, step = s_cur, s_try
    s_pre, s_cur = step_pre, step
    x_pre, f_pre = x_cur, f_cur
    x_cur += s_cur if abs(s_cur) > delta else (delta if s_bis > 0 else -delta)
    return False, x_pre, x_cur, x_blk, f_pre, f_blk, s_pre, s_cur


def _value(f: Callable[..., Any], x: float, args: tuple[Any, ...]) -> float:
    """f(x, *args) as a float; NaN is a ValueError (SciPy's check since 1.11)."""
    value = float(f(x, *args))
    if math.isnan(value):
        raise ValueError(f"The function value at x={x} is NaN; solver cannot continue.")
    return value


def _negative(value: float) -> bool:
    """C's signbit: true for -0.0 and negative NaNs too."""
    return math.copysign(1.0, value) < 0
