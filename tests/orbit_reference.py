"""An independent periodic-orbit solver for the shooting tests: its own propagation and Jacobians.

The period map is integrated by solve_ivp (DOP853) on the modal spring-contact equations of
tests/spring_modal_reference.py (`SpringModal`: only the free modes' data come from
impactbeams), with event location at the onsets and releases; the contact phase at the
start is decided by the same rule (tips overlapping and the spring pushing). Newton's method
runs on z = P(z) with central finite-difference Jacobians of that map, whose eigenvalues
are the Floquet multipliers. No tangent dynamics, no saltation, no package kernel.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from impactbeams.kernels.layout import FREE, ROW_FREQUENCY
from spring_modal_reference import SpringModal


def _terminal(fun, direction):
    def event(t, y, contact):
        return fun(t, y)

    event.terminal, event.direction = True, direction
    return event


def reference_map(model: SpringModal, z: np.ndarray, t_end: float, rtol: float = 1e-13,
                  ) -> np.ndarray:
    """The state (q, q') at t_end (s) of the run from the section state z at t = 0."""
    n = model.omega.size
    scale = np.abs(z) + 1e-30
    atol = 1e-16 * np.concatenate([np.full(n, np.max(scale[:n])), np.full(n, np.max(scale[n:]))])
    t, y = 0.0, z.copy()
    gap, rate = model.gap(0.0, y[:n], y[n:])
    contact = gap < 0 and -model.k_eff * gap - model.c * rate > 0

    def rhs(t, y, contact):
        q, v = y[:n], y[n:]
        return np.concatenate([v, model.acceleration(t, q, v, model.force(t, q, v)
                                                     if contact else 0.0)])

    while t < t_end:
        event = ((lambda t, y: model.force(t, y[:n], y[n:])) if contact else
                 (lambda t, y: model.gap(t, y[:n], y[n:])[0]))
        solution = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol,
                             events=[_terminal(event, -1)], args=(contact,))
        assert solution.success, solution.message
        if solution.status != 1:
            return solution.y[:, -1].copy()
        # the event as located on DOP853's interpolant is off by ~1e-9 relative: Newton on
        # the event function, integrating afresh from the last step before it
        t_step, y_step = solution.t[-2], solution.y[:, -2]
        t = solution.t[-1]
        for _ in range(4):
            y = y_step if t == t_step else solve_ivp(
                rhs, (t_step, t), y_step, method="DOP853", rtol=rtol, atol=atol,
                args=(contact,)).y[:, -1]
            value = event(t, y)
            rate = (event(t + 1e-9 * (t_end), y + 1e-9 * t_end * rhs(t, y, contact))
                    - value) / (1e-9 * t_end)
            t -= value / rate
        y = solve_ivp(rhs, (t_step, t), y_step, method="DOP853", rtol=rtol, atol=atol,
                      args=(contact,)).y[:, -1].copy()
        contact = not contact
    return y


def energy_scale(model: SpringModal) -> np.ndarray:
    return np.concatenate([model.omega, np.ones(model.omega.size)])


def map_energy_scale(period_map) -> np.ndarray:
    """D with D z = (omega q, q') of a period map's free modes: the energy norm's coordinates."""
    omega = period_map.packed.tables[FREE, ROW_FREQUENCY]
    return np.concatenate([omega, np.ones(omega.size)])


def settled(period_map, periods: int = 60) -> np.ndarray:
    """The section state after ``periods`` maps from the run's start."""
    z = period_map.rest_state()
    for _ in range(periods):
        z = period_map(z, measures=False).state
    return z


def central_jacobian(function, z: np.ndarray, scale: np.ndarray, step: float) -> np.ndarray:
    """d function / dz by central differences: steps ``step`` |D z| / D_j (D = ``scale``)."""
    size = step * np.linalg.norm(scale * z)
    columns = []
    for j in range(z.size):
        e = np.zeros(z.size)
        e[j] = size / scale[j]
        columns.append((function(z + e) - function(z - e)) / (2 * e[j]))
    return np.array(columns).T


def reference_jacobian(model: SpringModal, z: np.ndarray, t_end: float, step: float,
                       ) -> np.ndarray:
    """dP/dz by central differences, step ``step`` relative to |z| in the energy norm."""
    return central_jacobian(lambda x: reference_map(model, x, t_end), z, energy_scale(model),
                            step)


def reference_orbit(model: SpringModal, z: np.ndarray, t_end: float, tolerance: float = 1e-13,
                    step: float = 1e-5, iterations: int = 8,
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Chord-Newton on z = P(z) from z with its finite-difference Jacobian (converging
    linearly, at the rate of the Jacobian's change over the correction): (state, multipliers
    by decreasing modulus, the Jacobian's eigenvalues at the start)."""
    scale = energy_scale(model)
    jacobian = reference_jacobian(model, z, t_end, step)
    for _ in range(iterations):
        residual = reference_map(model, z, t_end) - z
        if np.linalg.norm(scale * residual) <= tolerance * np.linalg.norm(scale * z):
            multipliers = np.linalg.eigvals(jacobian)
            return z, multipliers[np.argsort(-np.abs(multipliers), kind="stable")]
        z = z + np.linalg.solve(np.eye(z.size) - jacobian, residual)
    raise AssertionError("the reference Newton did not converge")
