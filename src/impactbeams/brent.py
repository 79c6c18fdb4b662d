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

from impactbeams.kernels.bracketing import MAX_ITERATIONS, iteration


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


def _value(f: Callable[..., Any], x: float, args: tuple[Any, ...]) -> float:
    """f(x, *args) as a float; NaN is a ValueError (SciPy's check since 1.11)."""
    value = float(f(x, *args))
    if math.isnan(value):
        raise ValueError(f"The function value at x={x} is NaN; solver cannot continue.")
    return value


def _negative(value: float) -> bool:
    """C's signbit: true for -0.0 and negative NaNs too."""
    return math.copysign(1.0, value) < 0
