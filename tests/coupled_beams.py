"""Exact natural frequencies of two continuous cantilevers whose tips are joined by a spring.

Independent reference for the contact phase of the compliant (spring) tip-contact law of
shared/MODEL.md, taken bilateral: the spring k (N/m) acts between the tips for any sign of the
gap. numpy/scipy only; nothing from impactbeams' kernels (the `params` argument only needs the
attributes EI1, rhoA1, l1, EI2, rhoA2, l2 of `impactbeams.params.Params`).

Method: the continuous boundary-value problem, not a modal truncation. The tip receptance of a
clamped-free Euler-Bernoulli beam (tip displacement per unit tip force in the same direction)
from EI y'''' = rhoA omega^2 y, y(0) = y'(0) = y''(l) = 0, EI y'''(l) = -P, is

    alpha(omega) = (sin kl cosh kl - cos kl sinh kl) / (EI k^3 (1 + cos kl cosh kl)),
    k^4 = omega^2 rhoA / EI,

which tends to the static compliance l^3 / (3 EI) as omega -> 0. With tip displacements u1, u2
and spring force f = k (u1 - u2) (pulling beam 1's tip toward beam 2's), u1 = -alpha1 f and
u2 = +alpha2 f, so a nonzero f needs

    1/k + alpha1(omega) + alpha2(omega) = 0          (receptances in series; > 0 at omega = 0).

As a function of lambda = omega^2 each alpha_i is a sum of partial fractions
sum_n Y_in(l_i)^2 / (omega_in^2 - lambda) and increases strictly between its poles (the
cantilever frequencies); so the sum has exactly one root strictly between consecutive distinct
poles of the union of both beams' cantilever spectra and none below the lowest pole. A pole
shared by both beams (equal beams) is itself a coupled frequency (the beams move together,
the spring is not stretched): a pole of total multiplicity m contributes m - 1 roots at it.

Cancellation-free evaluation: numerator and denominator are divided by cosh kl (no e^{kl}
growth for any kl), the numerator uses its Taylor series for small kl (it is ~ 2 (kl)^3 / 3),
and roots are found on the pole-free product form

    P = d1 d2 / k + n1 d2 + n2 d1,    alpha_i = n_i / d_i,
    n_i = sin x - cos x tanh x,  d_i = EI_i k_i^3 (cos x + sech x),  x = k_i l_i,

which is continuous, equals d1 d2 (1/k + alpha1 + alpha2), and changes sign exactly once between
consecutive distinct poles (d1 d2 has no zero inside). k = inf gives the tied law (MODEL.md eq. 9).

Units: SI (N/m, rad/s, m/N).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

# Below this kl the receptance numerator is summed from its Taylor series (converges fast; the
# closed form would lose ~ 2 log10(1/x) digits to cancellation).
_SERIES_BELOW = 1.0
# Poles closer than this (relative) are treated as one shared pole: P cannot be evaluated with
# a reliable sign so close to two poles, and the root between them is within the same distance.
_SHARED_POLE_RTOL = 1e-13


def _sech_tanh(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (sech x, tanh x) without overflow for large x >= 0."""
    e = np.exp(-2.0 * x)
    return 2.0 * np.exp(-x) / (1.0 + e), (1.0 - e) / (1.0 + e)


def _numerator(x: np.ndarray) -> np.ndarray:
    """(sin x cosh x - cos x sinh x) / cosh x, accurate for all x >= 0."""
    x = np.asarray(x, dtype=float)
    sech, tanh = _sech_tanh(x)
    closed = np.sin(x) - np.cos(x) * tanh
    # Series: sin x cosh x - cos x sinh x = sum_m (-1)^m 2^(2m+1) x^(4m+3) / (4m+3)! * 2 ...
    # written as sum_m (-4)^m * 4 x^(4m+3) / (4m+3)!  (first term 2 x^3 / 3).
    series = np.zeros_like(x)
    for m in range(12):  # x < 1: the terms fall by ~4 x^4 / (4m+4)^4, 12 terms is far beyond eps
        series += (-4.0) ** m * 4.0 * x ** (4 * m + 3) / math.factorial(4 * m + 3)
    return np.where(x < _SERIES_BELOW, series * sech, closed)


def _wavenumber(EI: float, rhoA: float, omega) -> np.ndarray:
    return np.sqrt(np.abs(np.asarray(omega, dtype=float))) * (rhoA / EI) ** 0.25


def tip_receptance(EI: float, rhoA: float, length: float, omega) -> np.ndarray:
    """Tip displacement per unit tip force (same direction) of a cantilever at omega (m/N).

    Exact for the continuous Euler-Bernoulli beam; l^3 / (3 EI) at omega = 0, infinite at the
    cantilever frequencies.
    """
    k = _wavenumber(EI, rhoA, omega)
    x = k * length
    sech = _sech_tanh(x)[0]
    num = _numerator(x)
    den = np.cos(x) + sech
    with np.errstate(divide="ignore", invalid="ignore"):
        # n / (EI k^3 d) with n ~ 2 x^3 / 3: written as (n / x^3) l^3 / (EI d) to be finite at 0.
        ratio = np.where(x > 0, num / np.where(x > 0, x, 1.0) ** 3, 2.0 / 3.0)
        return ratio * length**3 / (EI * den)


def cantilever_frequencies(EI: float, rhoA: float, length: float, n: int) -> np.ndarray:
    """First n natural frequencies (rad/s) of a clamped-free beam: cos x + sech x = 0."""
    a = math.sqrt(EI / rhoA)
    roots = []
    for j in range(1, n + 1):
        guess = (2 * j - 1) * math.pi / 2
        roots.append(brentq(lambda x: math.cos(x) + float(_sech_tanh(np.array(x))[0]),
                            guess - 0.5, guess + 0.5, xtol=1e-15, rtol=4 * np.finfo(float).eps))
    return a * (np.array(roots) / length) ** 2


def _beam(EI: float, rhoA: float, length: float, omega: float) -> tuple[float, float]:
    """(n_i, d_i) of the module docstring at omega."""
    k = float(_wavenumber(EI, rhoA, omega))
    x = k * length
    sech = float(_sech_tanh(np.array(x))[0])
    return float(_numerator(np.array(x))), EI * k**3 * (math.cos(x) + sech)


def characteristic(params, k: float, omega: float) -> float:
    """P(omega) = d1 d2 (1/k + alpha1 + alpha2): pole-free, zero at the coupled frequencies."""
    n1, d1 = _beam(params.EI1, params.rhoA1, params.l1, omega)
    n2, d2 = _beam(params.EI2, params.rhoA2, params.l2, omega)
    spring = 0.0 if np.isinf(k) else d1 * d2 / k
    return spring + n1 * d2 + n2 * d1


def coupled_frequencies(params, k: float, n: int) -> np.ndarray:
    """Lowest n natural frequencies (rad/s) of the two cantilevers coupled by a tip spring k.

    k (N/m) > 0; k = numpy.inf gives the tied tips of the rigid law. Exact for the continuous
    beams (to a few ulps, brentq on the pole-free characteristic function); equal beams
    (shared cantilever frequencies) are handled.
    """
    if not k > 0:
        raise ValueError("k must be > 0")
    poles = np.sort(np.concatenate([
        cantilever_frequencies(params.EI1, params.rhoA1, params.l1, n + 1),
        cantilever_frequencies(params.EI2, params.rhoA2, params.l2, n + 1),
    ]))
    roots = []
    for lo, hi in zip(poles[:-1], poles[1:], strict=True):
        if hi - lo <= _SHARED_POLE_RTOL * hi:
            roots.append(0.5 * (lo + hi))  # shared pole: the beams move together
            continue
        # Just inside (lo, hi), 1/k + alpha1 + alpha2 runs from -inf to +inf, so P has the sign
        # -s after lo and +s before hi, s = sign(d1 d2) on the interval (d1 d2 has no zero
        # inside; at a shared pole P itself is ~0 to round-off, so its end values are not used).
        mid = 0.5 * (lo + hi)
        s = math.copysign(1.0, _beam(params.EI1, params.rhoA1, params.l1, mid)[1]
                          * _beam(params.EI2, params.rhoA2, params.l2, mid)[1])

        def f(w, lo=lo, hi=hi, s=s):
            if w <= lo:
                return -1.0
            if w >= hi:
                return 1.0
            return s * characteristic(params, k, w)

        roots.append(brentq(f, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500))
        if len(roots) == n:
            break
    return np.array(roots)
