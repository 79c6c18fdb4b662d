"""Independent reference computations used by several test modules (numpy/scipy only)."""

import numpy as np
from numpy.polynomial.legendre import leggauss


def gauss_rule(length: float, panels: int = 800, order: int = 16):
    """A quadrature independent of the package's (finer, higher order) on [0, length]."""
    x, w = leggauss(order)
    edges = np.linspace(0.0, length, panels + 1)
    a, b = edges[:-1, None], edges[1:, None]
    return ((a + b) / 2 + (b - a) / 2 * x).ravel(), ((b - a) / 2 * w).ravel()


def free_tip_gap(free, compliance, clearance, force_amplitude, omega, uplift1=0.0, uplift2=0.0,
                 dtype=np.longdouble):
    """The free-phase gap g(t) from the textbook undamped solution, in extended precision.

    q_n = q0 cos(w t) + v0 / w sin(w t) + f D(t), with the driven response from rest
    D = (sin(Omega t) - Omega / w sin(w t)) / (w^2 - Omega^2) rewritten by sum-to-product as
    -(t cos((w + Omega) t / 2) sinc((Omega - w) t / 2) - sin(w t) / w) / (w + Omega), exact at
    and near resonance. Real trigonometry in long double (``dtype``): a different formula and
    precision from the package's complex exponential-integrator form.
    """
    ld = dtype
    w = free.frequencies.astype(ld)
    weights = (free.tip1 - free.tip2).astype(ld)
    b = free.drive.astype(ld)
    Om, F0 = ld(omega), ld(force_amplitude)
    f = -Om**2 * F0 * b
    q0 = ld(uplift1) * free.unit1.astype(ld) + ld(uplift2) * free.unit2.astype(ld)
    v0 = F0 * Om * b

    def gap(t):
        t = np.asarray(t, dtype=ld)[..., None]
        half = (Om - w) * t / 2
        sinc = np.where(half == 0, ld(1), np.sin(half) / np.where(half == 0, ld(1), half))
        driven = -(t * np.cos((w + Om) * t / 2) * sinc - np.sin(w * t) / w) / (w + Om)
        q = q0 * np.cos(w * t) + v0 / w * np.sin(w * t) + f * driven
        return ld(clearance) - ld(compliance) * F0 * np.sin(Om * t[..., 0]) + (q * weights).sum(-1)

    return gap


def bisect_root(gap, lo, hi):
    """Root of gap on [lo, hi] with gap(lo) > 0 >= gap(hi), bisected to the last double ulp."""
    lo, hi = float(lo), float(hi)
    while True:
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            return hi
        if gap(mid) > 0:
            lo = mid
        else:
            hi = mid


def left_bracket(gap, t_below, step):
    """A time before t_below where gap > 0, walking left with doubling steps."""
    lo = t_below - step
    while gap(lo) <= 0:
        step *= 2
        lo = t_below - step
    return lo


def reference_first_impact(gap, t_max, omega_max, samples_per_period=16, scan=None):
    """First root of gap in (0, t_max] by dense sampling and bisection, NaN if none seen.

    ``scan`` (default ``gap``) is a cheaper version of gap used for the dense sampling only.
    """
    n = int(np.ceil(t_max * omega_max / (2 * np.pi) * samples_per_period)) + 1
    t = np.linspace(0.0, t_max, n)
    values = (scan or gap)(t)
    below = np.nonzero(values <= 0)[0]
    if below.size == 0:
        return np.nan
    k = below[0]
    return bisect_root(gap, t[k - 1], t[k])


def damped_modal_gap(free, compliance, clearance, force_amplitude, omega, zeta, uplift1=0.0,
                     uplift2=0.0, dtype=np.longdouble):
    """The free-phase gap g(t) with modal damping, without the quasi-static split.

    Each mode's whole coordinate eta_n = <y, Y_n> obeys
    eta'' + 2 zeta w eta' + w^2 eta = -F(t) Y_n(l1) (tip force F0 sin(Omega t), downward),
    from rest in the uplift shape: eta(0) = <u, Y_n>, eta'(0) = 0. Closed form per mode
    (steady state Im(G e^(i Omega t)), G = -F0 Y_n(l1) / (w^2 - Omega^2 + 2 i zeta w Omega),
    plus the decaying free response), in real long-double trigonometry. The modes beyond the
    truncation respond quasi-statically to F: the tip flexibility they carry,
    c1 - sum_n Y_n(l1)^2 / w^2, is added as a static term, which makes this the same model as
    the package's split form through a different formulation.
    """
    ld = dtype
    w = free.frequencies.astype(ld)
    tip1 = free.tip1.astype(ld)
    weights = (free.tip1 - free.tip2).astype(ld)
    Om, F0, z = ld(omega), ld(force_amplitude), ld(zeta)
    sigma, wd = z * w, w * np.sqrt(1 - z * z)
    d_re, d_im = w**2 - Om**2, 2 * z * w * Om
    norm = d_re**2 + d_im**2
    g_re, g_im = -F0 * tip1 * d_re / norm, F0 * tip1 * d_im / norm  # G = -F0 Y(l1) / D
    eta0 = ld(uplift1) * free.unit1.astype(ld) + ld(uplift2) * free.unit2.astype(ld)
    a = eta0 - g_im  # eta_p(0) = Im G, eta_p'(0) = Omega Re G
    b = (-Om * g_re + sigma * a) / wd
    residual = ld(compliance) - np.sum(tip1**2 / w**2)

    def gap(t):
        t = np.asarray(t, dtype=ld)[..., None]
        steady = g_re * np.sin(Om * t) + g_im * np.cos(Om * t)
        free_part = np.exp(-sigma * t) * (a * np.cos(wd * t) + b * np.sin(wd * t))
        force = F0 * np.sin(Om * t[..., 0])
        return ld(clearance) - residual * force + ((steady + free_part) * weights).sum(-1)

    return gap


def tip_mass_secular(beta, mu, eta):
    """The cantilever with a tip mass and rotary inertia, divided by cosh(beta).

    Clamped shape w = A (cosh - cos) + B (sinh - sin) in xi = k x; at the tip, in beta = k L,
    mu = m / (rhoA L), eta = J / (rhoA L^3) and omega^2 = EI k^4 / rhoA, the moment balances
    the inertia couple, w'' = eta beta^3 w', and the shear the inertia force,
    w''' = -mu beta w. The 2x2 determinant in (A, B) is twice
    1 + cos cosh + mu beta (cos sinh - sin cosh) - eta beta^3 (sin cosh + cos sinh)
      + mu eta beta^4 (1 - cos cosh).
    """
    e = np.exp(-beta)
    sech, tanh = 2 * e / (1 + e * e), (1 - e * e) / (1 + e * e)
    c, s = np.cos(beta), np.sin(beta)
    return (sech + c + mu * beta * (c * tanh - s) - eta * beta**3 * (s + c * tanh)
            + mu * eta * beta**4 * (sech - c))


def tip_mass_roots(mu, eta, count):
    """The first ``count`` roots beta = k L of `tip_mass_secular` (brentq on a sign scan)."""
    from scipy.optimize import brentq

    grid = np.linspace(0.01, 40.0, 40000)  # roots lie ~pi apart: a sign scan isolates them
    values = tip_mass_secular(grid, mu, eta)
    starts = np.nonzero(np.sign(values[1:]) != np.sign(values[:-1]))[0][:count]
    return np.array([brentq(tip_mass_secular, grid[i], grid[i + 1], args=(mu, eta),
                            xtol=1e-300, rtol=1e-15) for i in starts])
