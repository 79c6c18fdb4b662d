"""Static flexibility of a cantilever with springs: its Green's function, in closed form.

A unit load at y conjugate to d = 0 (a force, on the deflection) or d = 1 (a couple, on the
slope) bends the section at s < y with the moment m_d(y, s) = y - s or 1. By the unit-load
method the deflection (d = 0) or slope (d = 1) at x under the load at y is

    G0 = int_0^min(x, y) m_d(x, s) m_e(y, s) / EI(s) ds + m_d(x, 0) m_e(y, 0) / kr_clamp,

exact for any piecewise-uniform EI; the last term is the compliant clamp's rotation (none for
a rigid clamp). Springs to ground at points P then enter by the Woodbury identity,
G = G0 - G0(., P) (I + K G0(P, P))^-1 K G0(P, .), K = diag of their stiffnesses; point masses
do not change a static deflection.
"""

from __future__ import annotations

import numpy as np


def _piece_integral(x: np.ndarray, d: int, y: np.ndarray, e: int, start: float, end: float,
                    EI: float) -> np.ndarray:
    """The integral over [start, end] clipped to [0, min(x, y)] of m_d(x, s) m_e(y, s) / EI ds.

    Written in distances to the nearer point (t = near - s >= 0) so that every term is a
    difference of powers of positive numbers: no cancellation beyond a factor of order 1.
    """
    x, y = np.broadcast_arrays(x, y)
    top = np.clip(np.minimum(x, y), start, end)
    if d == e == 1:
        return (top - start) / EI
    if d + e == 1:  # one arm is x - s (or y - s), the other 1
        arm = x if d == 0 else y
        return ((arm - start) ** 2 - (arm - top) ** 2) / (2.0 * EI)
    near, far = np.minimum(x, y), np.maximum(x, y)
    t_low, t_high = near - top, near - start  # t = near - s on [start, top]
    squares, cubes = t_high**2 - t_low**2, t_high**3 - t_low**3
    return ((far - near) * squares / 2.0 + cubes / 3.0) / EI


def clamped_flexibility(x: np.ndarray, d: int, y: np.ndarray, e: int, starts: np.ndarray,
                        ends: np.ndarray, EI: np.ndarray, clamp_stiffness: float) -> np.ndarray:
    """G0 between points ``x`` (derivative d) and ``y`` (load e), broadcast: m/N, 1/N, 1/(N m).

    No springs but the clamp's (``clamp_stiffness`` N m/rad, inf for a rigid clamp).
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    total = sum(_piece_integral(x, d, y, e, s0, s1, ei)
                for s0, s1, ei in zip(starts, ends, EI, strict=True))
    arm_x = x if d == 0 else np.ones_like(x)
    arm_y = y if e == 0 else np.ones_like(y)
    return total + arm_x * arm_y / clamp_stiffness


def spring_flexibility(x: np.ndarray, y: np.ndarray, starts: np.ndarray, ends: np.ndarray,
                       EI: np.ndarray, clamp_stiffness: float, ports: list[tuple[float, int]],
                       stiffness: np.ndarray, derivative: int = 0) -> np.ndarray:
    """Deflection (m/N) at each ``x`` under a unit force at each ``y``, with springs to ground.

    ``derivative`` 1: the slope there (1/N).

    ``ports``: (position m, 0 deflection | 1 slope) of each spring, ``stiffness`` its value
    (N/m or N m/rad). Shape (len(x), len(y)).
    """
    x, y = np.atleast_1d(x).astype(float), np.atleast_1d(y).astype(float)
    args = (starts, ends, EI, clamp_stiffness)
    flexibility = clamped_flexibility(x[:, None], derivative, y[None, :], 0, *args)
    if not ports:
        return flexibility
    at_x = np.stack([clamped_flexibility(x, derivative, p, e, *args) for p, e in ports], axis=1)
    at_y = np.stack([clamped_flexibility(p, d, y, 0, *args) for p, d in ports], axis=0)
    between = np.array([[clamped_flexibility(p, d, q, e, *args) for q, e in ports]
                        for p, d in ports])
    system = np.eye(len(ports)) + stiffness[:, None] * between
    return flexibility - at_x @ np.linalg.solve(system, stiffness[:, None] * at_y)
