"""Independent checks of located folds and grazings of the beams' branches.

Fold: the branch parametrised by one state component c (the fold's largest tangent
component), each point solved by Newton with finite-difference Jacobians of the nonlinear
period map (no tangent kernel, no monodromy); the fold is the vertex of p(c), from a parabola
through three points. Grazing: the orbit without contact is the linear steady state, a pure
harmonic y1(l1, t) = Im(G e^(i Omega t)) at the tip (its quasi-static part included): against a
stop it grazes where |G(Omega)| = Delta, found by Brent's method on the closed-form steady
start (``start = "steady"``) of `simulate`.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

import impactbeams as ib
from impactbeams.orbits import PeriodMap

FD_STEP = 1e-7  # relative to the state's norm: central differences, error ~ 1e-13 of the map


def period_map_at(params, parameter, p, n_modes):
    return PeriodMap(params.replace(**{parameter: p}), n_modes=n_modes)


def solve_at_component(params, parameter, n_modes, z, p, k, c, iterations=12):
    """(z, p) with z[k] = c and P(z, p) = z, by Newton with finite-difference Jacobians."""
    z = z.copy()
    z[k] = c
    free = [j for j in range(z.size) if j != k]
    for _ in range(iterations):
        period_map = period_map_at(params, parameter, p, n_modes)
        residual = period_map(z, measures=False).state - z
        h = FD_STEP * np.linalg.norm(z)
        columns = []
        for j in free:
            e = np.zeros(z.size)
            e[j] = h
            columns.append((period_map(z + e, measures=False).state
                            - period_map(z - e, measures=False).state) / (2 * h) - e / h)
        hp = 1e-7 * abs(p)
        columns.append((period_map_at(params, parameter, p + hp, n_modes)(z, measures=False).state
                        - period_map_at(params, parameter, p - hp, n_modes)(z, measures=False)
                        .state) / (2 * hp))
        delta = np.linalg.solve(np.array(columns).T, -residual)
        z[free] += delta[:-1]
        p += delta[-1]
        if np.max(np.abs(delta[:-1])) < 1e-13 * np.linalg.norm(z) and abs(delta[-1]) < 1e-13 * p:
            return z, p
    raise AssertionError("the reference Newton did not converge")


def fold_vertex(params, parameter, n_modes, z, p, k, h):
    """The largest (or smallest) p along the branch near (z, p), parametrised by z[k]."""
    values = [solve_at_component(params, parameter, n_modes, z, p, k, z[k] + s * h)[1]
              for s in (-1.0, 0.0, 1.0)]
    a, b, c = values
    curvature = a - 2 * b + c
    return b - (c - a) ** 2 / (8 * curvature)


def steady_amplitude(params, omega, n_modes):
    """|G| of the no-contact steady tip response y1(l1, t) at omega (m)."""
    run = ib.simulate(params.replace(omega=omega, start="steady"), 1e-6, n_modes=n_modes,
                      times=[0.0])
    y, v = float(run.tip_deflection_1[0]), float(run.tip_velocity_1[0])
    return float(np.hypot(y, v / omega))


def stop_grazing(params, n_modes, low, high):
    """The omega in [low, high] where the steady tip amplitude reaches the clearance."""
    return brentq(lambda omega: steady_amplitude(params, omega, n_modes) - params.clearance,
                  low, high, xtol=1e-13, rtol=4 * np.finfo(float).eps)
