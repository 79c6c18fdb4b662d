"""One step of Brent's bracketing root finder, as SciPy's C routine (``brentq``) takes it.

Plain arithmetic on floats, with no Numba import: `impactbeams.brent` loops over it in Python
(a root of a Python function, without SciPy's import cost), `impactbeams.kernels.extrema`
compiles it into its kernels' loops (a root of a run's quantity in one call).
"""

import math

MAX_ITERATIONS = 100  # SciPy's default maxiter


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
