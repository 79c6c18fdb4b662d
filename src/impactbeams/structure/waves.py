"""Bending waves on one uniform segment at a frequency: bases, dynamic stiffness, counts.

On a segment of length h the deflection at frequency omega solves y'''' = y in xi = k x,
``k = (omega^2 rhoA / EI)^(1/4)``, ``b = k h``. Two bases span the solutions, each bounded on
[0, b] with all its digits:

* short segments (b <= ``SHORT``): the Krylov functions S, T, U, V (S = (cosh + cos) / 2,
  T = (sinh + sin) / 2, U = (cosh - cos) / 2, V = (sinh - sin) / 2), summed as power series,
  which hold their relative accuracy as b -> 0 (the closed forms cancel like 1 / b^3);
* long segments: e^-xi, e^(xi - b), cos xi, sin xi (the growing exponential referred to the
  segment's far end, as in Goncalves, Brennan & Elliott, J. Sound Vib. 2007).

The dynamic stiffness (end forces against end displacements) is written with the same split:
series for short segments, every hyperbolic function divided by cosh b for long ones, so that
its entries stay finite at any b away from its poles.

``quadrature``: the composite Gauss rule that resolves the products of such waves (the
projections of fields on a beam's modes, uniform or in pieces).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.polynomial.legendre import leggauss

SHORT = 2.0  # b at or below which a segment uses the Krylov series
_TERMS = 12  # series terms: the 12th of S at b = 2 is 16^11 / 44! < 1e-40
_INVERSE_FACTORIALS = np.array([1.0 / math.factorial(n) for n in range(4 * _TERMS)])
_GAUSS_ORDER = 12


def wave_number(omega: float, EI: np.ndarray, rhoA: np.ndarray) -> np.ndarray:
    """The wave number k = (omega^2 rhoA / EI)^(1/4) (1/m) at ``omega`` (rad/s)."""
    return np.sqrt(omega * np.sqrt(rhoA / EI))


def krylov(xi: np.ndarray) -> np.ndarray:
    """(S - 1, T, U, V) at ``xi`` (0 <= xi <= ``SHORT``), last axis; S - 1 without cancellation."""
    xi = np.asarray(xi, dtype=float)
    x4 = xi**4
    sums = []
    for offset in range(4):
        coefficients = _INVERSE_FACTORIALS[offset::4]
        total = np.zeros_like(xi)
        for c in coefficients[:0:-1]:  # Horner in xi^4, without the n = 0 term
            total = (total + c) * x4
        sums.append(total + coefficients[0] * (offset > 0))
    s1, t, u, v = sums
    return np.stack([s1, xi * t, xi**2 * u, xi**3 * v], axis=-1)


def short_basis(xi: np.ndarray, derivative: int) -> np.ndarray:
    """d^p/dxi^p of (S, T, U, V) at ``xi``, last axis: each derivative shifts S<-T<-U<-V<-S."""
    s1, t, u, v = np.moveaxis(krylov(xi), -1, 0)
    functions = [s1 + 1.0, t, u, v]
    return np.stack([functions[(i - derivative) % 4] for i in range(4)], axis=-1)


def long_basis(xi: np.ndarray, b: np.ndarray, derivative: int) -> np.ndarray:
    """d^p/dxi^p of (e^-xi, e^(xi - b), cos xi, sin xi) at ``xi`` (0 <= xi <= b), last axis."""
    xi, b = np.broadcast_arrays(np.asarray(xi, dtype=float), np.asarray(b, dtype=float))
    phase = xi + derivative * np.pi / 2
    return np.stack([(-1.0) ** derivative * np.exp(-xi), np.exp(xi - b), np.cos(phase),
                     np.sin(phase)], axis=-1)


def basis(xi: np.ndarray, b: float, short: bool, derivative: int) -> np.ndarray:
    """The segment's basis (short or long) at ``xi``, differentiated ``derivative`` times."""
    return short_basis(xi, derivative) if short else long_basis(xi, b, derivative)


def end_values(b: np.ndarray, short: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each piece's basis and its first three xi-derivatives at xi = 0 and xi = b.

    Two arrays (pieces, derivative 0..3, basis function 0..3); ``short`` picks the basis.
    """
    b = np.asarray(b, dtype=float)
    start, end = np.empty((2, len(b), 4, 4))
    for derivative in range(4):
        start[:, derivative] = long_basis(np.zeros_like(b), b, derivative)
        end[:, derivative] = long_basis(b, b, derivative)
    if short.any():
        start[short] = np.eye(4)  # (S, T, U, V) and their derivatives at 0
        for derivative in range(4):
            end[short, derivative] = short_basis(b[short], derivative)
    return start, end


def _numerators(b: float) -> tuple[float, ...]:
    """(D, D_free, n11, n12, n13, n14, n22, n24) of the dynamic stiffness, scaled alike.

    Unscaled: D = 1 - cos cosh (zero at clamped-clamped frequencies), D_free = 1 + cos cosh
    (zero at clamped-free ones), n11 = cos sinh + sin cosh, n12 = sin sinh, n13 = sinh + sin,
    n14 = cosh - cos, n22 = sin cosh - cos sinh, n24 = sinh - sin, all at b. Short segments:
    from the Krylov series; long ones: all divided by cosh b (signs unchanged).
    """
    if b <= SHORT:
        s1, t, u, v = krylov(b)
        s = s1 + 1.0
        return (u * u - s1 * (s + 1.0), 2.0 + s1 * (s + 1.0) - u * u, 2.0 * (s * t - u * v),
                t * t - v * v, 2.0 * t, 2.0 * u, 2.0 * (t * u - s * v), 2.0 * v)
    e = math.exp(-b)
    sech, tanh = 2.0 * e / (1.0 + e * e), (1.0 - e * e) / (1.0 + e * e)
    c, s = math.cos(b), math.sin(b)
    return (sech - c, sech + c, c * tanh + s, s * tanh, tanh + s * sech, 1.0 - c * sech,
            s - c * tanh, tanh - s * sech)


def dynamic_stiffness(EI: float, k: float, b: float) -> np.ndarray:
    """4x4 dynamic stiffness of a segment on (w_a, theta_a, w_b, theta_b), FE signs (N/m ...).

    At omega -> 0 it tends to the static stiffness of a Hermite beam element.
    """
    d, _, n11, n12, n13, n14, n22, n24 = _numerators(b)
    k2, k3 = k * k, k**3
    return EI / d * np.array([
        [k3 * n11, k2 * n12, -k3 * n13, k2 * n14],
        [k2 * n12, k * n22, -k2 * n14, k * n24],
        [-k3 * n13, -k2 * n14, k3 * n11, -k2 * n12],
        [k2 * n14, k * n24, -k2 * n12, k * n22]])


def free_end_stiffness(EI: float, k: float, b: float) -> np.ndarray:
    """2x2 dynamic stiffness on (w_a, theta_a) of a segment whose far end is free."""
    _, d_free, n11, n12, _, _, n22, _ = _numerators(b)
    return -EI / d_free * np.array([[k**3 * n11, k * k * n12], [k * k * n12, k * n22]])


def clamped_count(b: float) -> int:
    """Natural frequencies of the segment clamped at both ends below b (roots of cos cosh = 1).

    One root in each (j pi, (j + 1) pi), j >= 1 (Wittrick & Williams 1971).
    """
    j = math.floor(b / math.pi)
    return j - 1 + int((-1) ** j * _numerators(b)[0] > 0)


def free_count(b: float) -> int:
    """Natural frequencies of the segment clamped at its near end, free at its far one, below b.

    Roots of cos cosh = -1: one in each ((j - 1) pi, j pi), j >= 1.
    """
    j = math.floor(b / math.pi)
    return j + int((-1) ** j * _numerators(b)[1] < 0)


def quadrature(length: float, max_wavenumber: float) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss-Legendre nodes (m) and weights on [0, length].

    Two panels per half-wave of the product of two shapes with wave numbers up to
    ``max_wavenumber`` (1/m).
    """
    n_panels = max(16, int(np.ceil(4 * max_wavenumber * length / np.pi)))
    nodes, weights = leggauss(_GAUSS_ORDER)
    edges = np.linspace(0.0, length, n_panels + 1)
    a, b = edges[:-1, None], edges[1:, None]
    return ((a + b) / 2 + (b - a) / 2 * nodes).ravel(), ((b - a) / 2 * weights).ravel()
