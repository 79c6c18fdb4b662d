"""Independent finite-element reference model of two impacting cantilevers.

Used only by the test suite, to check impactbeams against a different discretisation. It imports
numpy and scipy only, never impactbeams. The physics and signs are those of shared/MODEL.md:

- beam i (i = 1, 2) is an Euler-Bernoulli cantilever, clamped at x = 0, free tip at x = l_i,
  bending stiffness EI_i (N m^2), mass per length rhoA_i (kg/m); deflections upward positive (m);
- the tip force on beam 1, F(t) = F0 sin(Omega t) (N), is positive DOWNWARD;
- gap g(t) = clearance + y1(l1, t) - y2(l2, t) >= 0 (m);
- in contact the tips are tied, y2(l2) = y1(l1) + clearance, and the contact force R >= 0 (N)
  pushes beam 1 up and beam 2 down.

Discretisation: Hermite-cubic beam elements (nodal DOFs w, theta), consistent mass, the clamped
node removed. Cubics hold the static tip-load shape exactly, so static tip-load results are exact
to round-off, and frequencies converge as O(h^4). Eigenproblems are solved from the closed-form
flexibility K^-1 (see `beam_flexibility` and `_eig`) to keep the low modes exact to round-off.

Time integration is exact for the FE system: in each phase M x'' + K x = p0 + p1 sin(Omega t)
is diagonalised by the phase's own mass-normalised eigenvectors, and every mode is propagated in
closed form (no mode dropped; the forced response is written so that it stays exact at
resonance). Events (impact onset g = 0, release R = 0) are found by sampling on a dense grid,
with a cubic-Hermite check for dips between samples, and refining the first sign change with
scipy.optimize.brentq to a few ulps of the event time.

Public: steel_strip, tip_dof, beam_matrices, beam_flexibility, stepped_beam,
static_tip_shape,
cantilever_frequencies, contact_frequencies, first_impact_time, simulate_impacts.

Units: SI throughout (m, s, N, kg, rad/s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.optimize import brentq

# brentq tolerances: the root is located to a few ulps of the event time.
_XTOL = 1e-16
_RTOL = 4.0 * np.finfo(float).eps
# Dense grids are evaluated in chunks that start small and grow, as phases are often short
# (chattering) but may also last many periods.
_FIRST_CHUNK, _MAX_CHUNK = 32, 8192
# Cubic Hermite basis at s = 1/8 .. 7/8 of an interval (for end values and scaled slopes).
_S = np.arange(1, 8)[:, None] / 8.0
_HERMITE = np.hstack(
    [2 * _S**3 - 3 * _S**2 + 1, _S**3 - 2 * _S**2 + _S, 3 * _S**2 - 2 * _S**3, _S**3 - _S**2]
)


# --------------------------------------------------------------------------------------------
# Beam matrices and frequencies
# --------------------------------------------------------------------------------------------


def steel_strip(
    a: float = 0.7, E: float = 210e9, rho: float = 7850.0, width: float = 5e-3
) -> tuple[float, float]:
    """Return (EI (N m^2), rhoA (kg/m)) of the default steel strip with a = sqrt(EI/rhoA).

    The thickness is h = a / sqrt(E / (12 rho)) (m), as in MODEL.md.
    """
    h = a / np.sqrt(E / (12.0 * rho))
    return E * width * h**3 / 12.0, rho * width * h


def tip_dof(n_elements: int) -> int:
    """Index of the tip displacement DOF in the matrices of `beam_matrices`.

    DOF ordering: nodes 1..n (node 0 is clamped and removed); node j has its deflection w_j at
    index 2 (j - 1) and its slope theta_j = dw/dx at 2 (j - 1) + 1. The tip is node n.
    """
    return 2 * n_elements - 2


def _element(EI: float, rhoA: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass of one Hermite-cubic element of length h (m)."""
    k_e = (EI / h**3) * np.array(
        [
            [12.0, 6 * h, -12.0, 6 * h],
            [6 * h, 4 * h**2, -6 * h, 2 * h**2],
            [-12.0, -6 * h, 12.0, -6 * h],
            [6 * h, 2 * h**2, -6 * h, 4 * h**2],
        ]
    )
    m_e = (rhoA * h / 420.0) * np.array(
        [
            [156.0, 22 * h, 54.0, -13 * h],
            [22 * h, 4 * h**2, 13 * h, -3 * h**2],
            [54.0, 13 * h, 156.0, -22 * h],
            [-13 * h, -3 * h**2, -22 * h, 4 * h**2],
        ]
    )
    return k_e, m_e


def beam_matrices(
    EI: float, rhoA: float, length: float, n_elements: int
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness K and consistent mass M of a uniform cantilever (SI units, DOFs w and theta).

    Uniform mesh of `n_elements` Hermite-cubic elements; the clamped node is removed, so both
    matrices are (2 n, 2 n), symmetric positive definite, DOFs ordered as in `tip_dof`.
    """
    h = length / n_elements
    k_e, m_e = _element(EI, rhoA, h)
    n_full = 2 * (n_elements + 1)
    K = np.zeros((n_full, n_full))
    M = np.zeros((n_full, n_full))
    for e in range(n_elements):
        idx = slice(2 * e, 2 * e + 4)
        K[idx, idx] += k_e
        M[idx, idx] += m_e
    # Clamp: drop w and theta of node 0.
    return K[2:, 2:], M[2:, 2:]


def beam_flexibility(EI: float, length: float, n_elements: int) -> np.ndarray:
    """Flexibility F = K^-1 of `beam_matrices`, in closed form (m/N, 1/N, 1/(N m)).

    Under nodal forces and moments the exact cantilever deflection is piecewise cubic, which
    Hermite elements hold exactly, so K^-1 equals the exact nodal flexibility (Maxwell
    influence coefficients). Built from these formulas it carries no cancellation, unlike a
    solve with K (condition number ~ (l/h)^4): it is what keeps the low FE frequencies and the
    static responses accurate to round-off.
    """
    x = length * np.arange(1, n_elements + 1) / n_elements
    xi, xj = np.minimum.outer(x, x), np.maximum.outer(x, x)  # nearer and farther node
    F = np.empty((2 * n_elements, 2 * n_elements))
    F[0::2, 0::2] = xi**2 * (3 * xj - xi) / 6  # w due to a unit force
    F[1::2, 1::2] = xi  # theta due to a unit moment
    # w_i due to a unit moment at j: x_i^2 / 2 if x_i <= x_j, else x_j (2 x_i - x_j) / 2.
    xr, xc = x[:, None], x[None, :]
    F[0::2, 1::2] = np.where(xr <= xc, xr**2 / 2, xc * (2 * xr - xc) / 2)
    F[1::2, 0::2] = F[0::2, 1::2].T
    return F / EI


def stepped_beam(segments, n_elements: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K, M and the flexibility F = K^-1 of a stepped cantilever (DOFs as in `tip_dof`).

    ``segments``: (length, EI, rhoA) from the clamp out (m, N m^2, kg/m), each a whole number
    of the ``n_elements`` equal elements (so that every step is a node). F is the exact nodal
    flexibility by the unit-load method, F_IJ = int_0^L f_I(s) f_J(s) / EI(s) ds with f the
    moment of a unit load at DOF I (x_I - s for a force, 1 for a moment, 0 beyond x_I):
    Hermite elements hold it exactly for EI constant on each element. Simpson's rule is exact
    for these quadratics, and as F = Q Q^T with every entry of Q >= 0 it carries no
    cancellation (no solve with K).
    """
    lengths = np.array([s[0] for s in segments])
    length = float(np.sum(lengths))
    h = length / n_elements
    counts = np.rint(lengths / h).astype(int)
    assert counts.sum() == n_elements and np.allclose(counts * h, lengths, rtol=1e-12, atol=0)
    EI = np.repeat([s[1] for s in segments], counts)
    rhoA = np.repeat([s[2] for s in segments], counts)
    n_full = 2 * (n_elements + 1)
    K, M = np.zeros((n_full, n_full)), np.zeros((n_full, n_full))
    for e in range(n_elements):
        idx = slice(2 * e, 2 * e + 4)
        k_e, m_e = _element(EI[e], rhoA[e], h)
        K[idx, idx] += k_e
        M[idx, idx] += m_e
    x = h * np.arange(1, n_elements + 1)  # the nodes past the clamp
    starts = h * np.arange(n_elements)
    points = starts[:, None] + h * np.array([0.0, 0.5, 1.0])[None, :]  # (element, Simpson point)
    weights = np.sqrt(h * np.array([1.0, 4.0, 1.0])[None, :] / (6.0 * EI[:, None]))
    beyond = (x[:, None] > starts[None, :])[:, :, None]  # node i lies past element e's start
    Q = np.empty((2 * n_elements, n_elements, 3))
    Q[0::2] = np.where(beyond, (x[:, None, None] - points[None]) * weights[None], 0.0)
    Q[1::2] = np.where(beyond, weights[None], 0.0)
    Q = Q.reshape(2 * n_elements, -1)
    return K[2:, 2:], M[2:, 2:], Q @ Q.T


def static_tip_shape(F: np.ndarray, tip_deflection: float) -> np.ndarray:
    """Static FE deflection under a tip point load, scaled to the given tip deflection (m).

    F is the flexibility of `beam_flexibility`. Hermite cubics represent
    u(x) = delta (3 l x^2 - x^3) / (2 l^3) exactly, so this is the nodal interpolant of the
    MODEL.md initial uplift shape.
    """
    column = F[:, -2]  # response to a unit tip force
    return column * (tip_deflection / column[-2])


def _eig(F: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequencies (rad/s, ascending) and M-orthonormal modes from flexibility and mass.

    Solves F M phi = phi / omega^2 as the symmetric problem (L^T F L) psi = psi / omega^2 with
    M = L L^T and phi = L^-T psi. Eigenvalues come with absolute error ~ eps / omega_1^2, so the
    low modes, which carry nearly all of a tip response, are exact to round-off; mode n has a
    relative error ~ eps (omega_n / omega_1)^2. (eigh(K, M) is the other way round: its first
    frequency is off by ~1e-8 relative at 40 elements and ~1e-6 at 80.)
    """
    L = scipy.linalg.cholesky(M, lower=True)
    mu, psi = scipy.linalg.eigh(L.T @ F @ L)
    phi = scipy.linalg.solve_triangular(L, psi[:, ::-1], lower=True, trans="T")
    return 1.0 / np.sqrt(mu[::-1]), phi


def cantilever_frequencies(
    EI: float, rhoA: float, length: float, n_modes: int, n_elements: int
) -> np.ndarray:
    """Lowest `n_modes` FE natural frequencies (rad/s) of one cantilever, ascending."""
    M = beam_matrices(EI, rhoA, length, n_elements)[1]
    return _eig(beam_flexibility(EI, length, n_elements), M)[0][:n_modes]


def contact_frequencies(
    EI1: float,
    rhoA1: float,
    l1: float,
    EI2: float,
    rhoA2: float,
    l2: float,
    n_modes: int,
    n_elements1: int,
    n_elements2: int,
) -> np.ndarray:
    """Lowest `n_modes` FE natural frequencies (rad/s) of the two beams with tips tied.

    The clearance only shifts the static state of the tied system, not its frequencies.
    """
    pair = _Pair.build(EI1, rhoA1, l1, EI2, rhoA2, l2, (n_elements1, n_elements2))
    return _eig(pair.tied_flexibility(), pair.T.T @ pair.M @ pair.T)[0][:n_modes]


@dataclass(frozen=True)
class _Pair:
    """Both beams in one block-diagonal system x = [x1, x2] (beam 1's DOFs first).

    Tied coordinates z are x without beam 2's tip deflection; x = T z + x_off with x_off the
    clearance at beam 2's tip, i.e. y2(l2) = y1(l1) + clearance (g = 0).
    """

    K: np.ndarray
    M: np.ndarray
    F: np.ndarray
    n1: int  # number of beam 1's DOFs
    tip1: int
    tip2: int | None  # None: beam 1 alone, against a rigid stop (no beam 2)
    T: np.ndarray | None

    @classmethod
    def build(cls, EI1, rhoA1, l1, EI2, rhoA2, l2, n_elements: tuple[int, int]) -> _Pair:
        K1, M1 = beam_matrices(EI1, rhoA1, l1, n_elements[0])
        K2, M2 = beam_matrices(EI2, rhoA2, l2, n_elements[1])
        F1 = beam_flexibility(EI1, l1, n_elements[0])
        F2 = beam_flexibility(EI2, l2, n_elements[1])
        n1 = K1.shape[0]
        tip1, tip2 = tip_dof(n_elements[0]), n1 + tip_dof(n_elements[1])
        T = np.delete(np.eye(n1 + K2.shape[0]), tip2, axis=1)
        T[tip2, tip1] = 1.0  # beam 2's tip follows beam 1's tip
        blocks = scipy.linalg.block_diag
        return cls(blocks(K1, K2), blocks(M1, M2), blocks(F1, F2), n1, tip1, tip2, T)

    @classmethod
    def single(cls, EI1, rhoA1, l1, n_elements: int) -> _Pair:
        """Beam 1 alone, for a rigid stop: g = clearance + y1(l1) (the free and spring phases)."""
        K1, M1 = beam_matrices(EI1, rhoA1, l1, n_elements)
        return cls(K1, M1, beam_flexibility(EI1, l1, n_elements), K1.shape[0],
                   tip_dof(n_elements), None, None)

    @classmethod
    def of_beams(cls, beams: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> _Pair:
        """The pair of given beams' (K, M, F), as `build` does; one beam: as `single`."""
        n1 = beams[0][0].shape[0]
        blocks = [scipy.linalg.block_diag(*matrices) for matrices in zip(*beams, strict=True)]
        if len(beams) == 1:
            return cls(*blocks, n1, n1 - 2, None, None)
        tip2 = blocks[0].shape[0] - 2
        T = np.delete(np.eye(blocks[0].shape[0]), tip2, axis=1)
        T[tip2, n1 - 2] = 1.0  # beam 2's tip follows beam 1's tip
        return cls(*blocks, n1, n1 - 2, tip2, T)

    def gap_rows(self, matrix: np.ndarray) -> np.ndarray:
        """Rows of g - clearance = y1(l1) - y2(l2) (y1(l1) alone at a stop) of a DOF matrix."""
        return matrix[self.tip1] - (0.0 if self.tip2 is None else matrix[self.tip2])

    def unit(self, index: int) -> np.ndarray:
        """Unit vector of DOF `index` in the x coordinates."""
        e = np.zeros(self.K.shape[0])
        e[index] = 1.0
        return e

    def free_modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (rad/s) and mass-normalised modes of the untied beams, beam by beam."""
        if self.tip2 is None:
            return _eig(self.F, self.M)
        modes = [_eig(self.F[b, b], self.M[b, b]) for b in (slice(self.n1), slice(self.n1, None))]
        return np.concatenate([w for w, _ in modes]), scipy.linalg.block_diag(
            *[p for _, p in modes]
        )

    def tied_static(self, clearance: float) -> np.ndarray:
        """Static x (no load) of the tied beams, y2(l2) = y1(l1) + clearance.

        x = lambda F e with e = e_tip1 - e_tip2, the tie force lambda set by e^T x = -clearance.
        """
        e = self.unit(self.tip1) - self.unit(self.tip2)
        fe = self.F @ e
        return fe * (-clearance / (e @ fe))

    def tied_flexibility(self) -> np.ndarray:
        """Flexibility (T^T K T)^-1 of the tied system in z coordinates, without a solve with K.

        Tied nodal flexibility F - (F e)(F e)^T / (e^T F e) (x = F (f + lambda e) with the
        tie force lambda set by e^T x = 0); a load f_z in z is the nodal load with a zero at
        beam 2's tip, and z is x without that DOF.
        """
        e = self.unit(self.tip1) - self.unit(self.tip2)
        fe = self.F @ e
        tied = self.F - np.outer(fe, fe) / (e @ fe)
        return np.delete(np.delete(tied, self.tip2, axis=0), self.tip2, axis=1)


# --------------------------------------------------------------------------------------------
# Exact modal propagation of M x'' + K x = p0 + p1 sin(Omega t)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Modal:
    """Modal form q_n'' + omega_n^2 (q_n - static_n) = b_n sin(Omega t) of one phase.

    phi: mass-normalised eigenvectors (columns) in the phase's own coordinates; static: modal
    coordinates of the static state without forcing.
    """

    omega: np.ndarray
    phi: np.ndarray
    static: np.ndarray
    b: np.ndarray
    forcing_omega: float

    def propagate(self, t0: float, q0, v0, t) -> tuple[np.ndarray, np.ndarray]:
        """Modal displacements and velocities at times t (shape (len(t), n)) from state at t0.

        Zero-initial-condition responses to cos(Omega tau) and sin(Omega tau) are written with
        sinc((omega - Omega) tau / 2), so they are exact (no 0/0) at and near resonance:
        with s = omega + Omega, d = omega - Omega and S = tau sinc(d tau / 2),
        h_cos = sin(s tau/2) S / s and h_sin = -cos(s tau/2) S / s + sin(omega tau)/(omega s).
        """
        w, big_w = self.omega, self.forcing_omega
        tau = (np.atleast_1d(np.asarray(t, dtype=float)) - t0)[:, None]
        s, d = w + big_w, w - big_w
        sinc_term = tau * np.sinc(d * tau / (2.0 * np.pi))
        cos_wt, sin_wt = np.cos(w * tau), np.sin(w * tau)
        half_cos, half_sin = np.cos(0.5 * s * tau), np.sin(0.5 * s * tau)
        h_cos = half_sin * sinc_term / s
        h_sin = -half_cos * sinc_term / s + sin_wt / (w * s)
        dh_cos = w * half_cos * sinc_term / s + np.sin(big_w * tau) / s
        dh_sin = big_w * h_cos
        # sin(Omega (t0 + tau)) = sin(Omega t0) cos(Omega tau) + cos(Omega t0) sin(Omega tau)
        c_cos, c_sin = np.sin(big_w * t0) * self.b, np.cos(big_w * t0) * self.b
        free = q0 - self.static
        q = self.static + free * cos_wt + (v0 / w) * sin_wt + c_cos * h_cos + c_sin * h_sin
        v = -free * w * sin_wt + v0 * cos_wt + c_cos * dh_cos + c_sin * dh_sin
        return q, v

    def oscillation_bound(self, t0: float, q0, v0, weights) -> np.ndarray:
        """Bound per mode on the amplitude of weights_n q_n(t) at frequency omega_n.

        The steady response at Omega is left out (the grid resolves Omega anyway): what remains
        is the free oscillation that matches the state at t0, with the particular solution
        b sin(Omega t) / (omega^2 - Omega^2) (capped near resonance, where omega ~ Omega).
        """
        w, big_w = self.omega, self.forcing_omega
        detune = np.copysign(np.maximum(np.abs(w**2 - big_w**2), 1e-3 * w**2), w**2 - big_w**2)
        p0 = self.b * np.sin(big_w * t0) / detune
        dp0 = self.b * big_w * np.cos(big_w * t0) / detune
        free = np.abs(q0 - self.static - p0) + np.abs(v0 - dp0) / w
        return np.abs(weights) * free


@dataclass(frozen=True)
class _Output:
    """A scalar output c0 + c_sin sin(Omega t) + r . q(t) that is linear in the modal state."""

    c0: float
    c_sin: float
    r: np.ndarray

    def __call__(self, modal: _Modal, t, q) -> np.ndarray:
        return self.c0 + self.c_sin * np.sin(modal.forcing_omega * np.atleast_1d(t)) + q @ self.r

    def rate(self, modal: _Modal, t, v) -> np.ndarray:
        """Time derivative of the output, from the modal velocities v."""
        big_w = modal.forcing_omega
        return self.c_sin * big_w * np.cos(big_w * np.atleast_1d(t)) + v @ self.r


def _grid_step(
    modal: _Modal, out: _Output, t0: float, q0, v0, samples_per_period: float, mode_rtol: float
) -> float:
    """Sampling step (s) that resolves every mode that matters for the event output.

    A mode matters if its oscillation bound in the output exceeds mode_rtol times the sum of
    all bounds; the step is a fraction 1/samples_per_period of the shortest such period (and of
    the forcing period).
    """
    bound = modal.oscillation_bound(t0, q0, v0, out.r)
    significant = bound > mode_rtol * bound.sum()
    omega_max = max(modal.omega[significant].max(initial=0.0), modal.forcing_omega)
    if omega_max == 0.0:  # nothing moves (at rest, unforced): any step will do
        omega_max = modal.omega[0]
    return 2.0 * np.pi / (samples_per_period * omega_max)


def _first_negative(
    modal: _Modal, out: _Output, t0: float, q0, v0, t_end: float, dt: float, starts_at_zero: bool
) -> float | None:
    """First time in [t0, t_end] at which the output crosses from >= 0 to < 0, or None.

    If the output is already negative at t0, the event is at t0 itself. If starts_at_zero, the
    output is zero at t0 by construction (the gap right after a release) and only a later
    crossing counts; see `_leave_zero`. The output is sampled every dt, in growing chunks.
    """

    def sample(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q, v = modal.propagate(t0, q0, v0, t)
        return out(modal, t, q), out.rate(modal, t, v)

    def value(t: float) -> float:
        return float(sample(np.array([t]))[0][0])

    if not starts_at_zero and value(t0) < 0.0:
        return t0
    n_steps = int(np.ceil((t_end - t0) / dt))
    k0, chunk = 0, _FIRST_CHUNK
    while k0 < n_steps:
        k1 = min(k0 + chunk, n_steps)
        bracket = _find_bracket(sample, np.minimum(t0 + np.arange(k0, k1 + 1) * dt, t_end))
        if bracket is not None:
            a, b = bracket
            if a == t0 and starts_at_zero:
                bracket = _leave_zero(value, t0, b, _noise(out, q0))
                if bracket is None:
                    return t0
            elif value(a) == 0.0:
                return a
            return brentq(value, *bracket, xtol=_XTOL, rtol=_RTOL, maxiter=200)
        k0, chunk = k1, min(4 * chunk, _MAX_CHUNK)
    return None


def _find_bracket(sample, t: np.ndarray, depth: int = 2) -> tuple[float, float] | None:
    """First interval (a, b) of the grid t with output(b) < 0, or None.

    An interval whose ends are both >= 0 may still hide a short dip below zero: if the cubic
    Hermite interpolant of the end values and slopes dips below zero, the interval is
    resampled 16 times finer (`depth` levels deep) before moving on.
    """
    g, dg = sample(t)
    h = np.diff(t)
    cubic = _HERMITE @ np.vstack([g[:-1], h * dg[:-1], g[1:], h * dg[1:]])
    flagged = (g[1:] < 0.0) | (cubic.min(axis=0) < 0.0)
    for i in np.flatnonzero(flagged):
        if depth > 0:
            sub = _find_bracket(sample, np.linspace(t[i], t[i + 1], 17), depth - 1)
            if sub is not None:
                return sub
        elif g[i + 1] < 0.0:
            return t[i], t[i + 1]
    return None


def _noise(out: _Output, q0) -> float:
    """Round-off level (units of the output) below which its sign means nothing."""
    return 1e-13 * (abs(out.c0) + abs(out.c_sin) + np.abs(out.r) @ np.abs(q0))


def _leave_zero(value, t0: float, t1: float, noise: float) -> tuple[float, float] | None:
    """Bracket the first downward crossing in (t0, t1] of an output that is zero at t0.

    value(t1) < 0. Samples at t0 + (t1 - t0) 2^-j, j = 50..1, show how the output leaves zero
    (those below the noise level are skipped). If it leaves downward, return None: the event
    is at t0. Otherwise bracket the end of the first positive run.
    """
    t = t0 + (t1 - t0) * 0.5 ** np.arange(50, 0, -1)
    v = np.array([value(ti) for ti in t])
    t, v = np.append(t[np.abs(v) > noise], t1), np.append(v[np.abs(v) > noise], value(t1))
    if v[0] < 0.0:
        return None
    j = np.flatnonzero(v < 0.0)[0]
    return t[j - 1], t[j]


# --------------------------------------------------------------------------------------------
# Free and contact phases
# --------------------------------------------------------------------------------------------


def _free_phase(pair: _Pair, clearance: float, force_amplitude: float, omega: float):
    """Modal form of the untied beams and their gap output g = clearance + y1(l1) - y2(l2)."""
    omegas, phi = pair.free_modes()
    p1 = -force_amplitude * pair.unit(pair.tip1)  # F positive downward on beam 1's tip
    free = _Modal(omegas, phi, np.zeros_like(omegas), phi.T @ p1, omega)
    return free, _Output(c0=clearance, c_sin=0.0, r=pair.gap_rows(phi))


@dataclass(frozen=True)
class _Phases:
    """Modal forms of the free and contact phases and the maps between their states."""

    pair: _Pair
    free: _Modal
    gap: _Output
    contact: _Modal
    force: _Output
    x_off: np.ndarray
    to_contact: np.ndarray  # q_contact = to_contact @ q_free + to_contact_shift
    to_contact_shift: np.ndarray
    to_free_shift: np.ndarray  # q_free = to_contact.T @ q_contact + to_free_shift

    @classmethod
    def build(cls, pair: _Pair, free: _Modal, gap: _Output, force_amplitude: float) -> _Phases:
        clearance = gap.c0
        x_off = clearance * pair.unit(pair.tip2)  # tie: y2(l2) = y1(l1) + clearance
        M_c = pair.T.T @ pair.M @ pair.T
        omegas, phi = _eig(pair.tied_flexibility(), M_c)
        z_static = np.delete(pair.tied_static(clearance), pair.tip2)
        p1 = -force_amplitude * pair.unit(pair.tip1)
        b = phi.T @ pair.T.T @ p1
        contact = _Modal(omegas, phi, phi.T @ M_c @ z_static, b, free.forcing_omega)
        # R = -(K x + M x'')[tip2] with x = T phi q + x_off and
        # q'' = -omega^2 (q - static) + b sin(Omega t): linear in q.
        k_row = (pair.K @ pair.T @ phi)[pair.tip2]
        m_row = (pair.M @ pair.T @ phi)[pair.tip2]
        force = _Output(
            c0=-(pair.K[pair.tip2] @ x_off + m_row @ (omegas**2 * contact.static)),
            c_sin=-(m_row @ b),
            r=-(k_row - m_row * omegas**2),
        )
        # M-orthogonal projections between the bases: q_c = phi_c^T T^T M (x - x_off).
        proj = phi.T @ pair.T.T @ pair.M
        return cls(
            pair=pair,
            free=free,
            gap=gap,
            contact=contact,
            force=force,
            x_off=x_off,
            to_contact=proj @ free.phi,
            to_contact_shift=-proj @ x_off,
            to_free_shift=free.phi.T @ pair.M @ x_off,
        )

    def displacement(self, in_contact: bool, q: np.ndarray) -> np.ndarray:
        """Physical DOFs x (rows of q are time samples)."""
        if in_contact:
            return q @ (self.pair.T @ self.contact.phi).T + self.x_off
        return q @ self.free.phi.T

    def velocity(self, in_contact: bool, v: np.ndarray) -> np.ndarray:
        """Physical DOF velocities x' (rows of v are time samples)."""
        phi = self.pair.T @ self.contact.phi if in_contact else self.free.phi
        return v @ phi.T


def _setup(EI1, rhoA1, l1, EI2, rhoA2, l2, clearance, force_amplitude, omega, uplifts, n_el):
    """Validate the inputs; return the pair, free phase, gap output and initial modal state.

    Initial state: at rest in the static tip-load shapes with tip uplifts `uplifts` (m).
    """
    if clearance + uplifts[0] - uplifts[1] <= 0.0:
        raise ValueError("initial gap clearance + uplift1 - uplift2 must be > 0")
    if omega < 0.0:
        raise ValueError("forcing frequency omega must be >= 0")
    pair = _Pair.build(EI1, rhoA1, l1, EI2, rhoA2, l2, n_el)
    free, gap = _free_phase(pair, clearance, force_amplitude, omega)
    n1 = pair.n1
    x0 = np.concatenate(
        [
            static_tip_shape(pair.F[:n1, :n1], uplifts[0]),
            static_tip_shape(pair.F[n1:, n1:], uplifts[1]),
        ]
    )
    q0 = free.phi.T @ pair.M @ x0
    return pair, free, gap, q0, np.zeros_like(q0)


def first_impact_time(
    EI1: float,
    rhoA1: float,
    l1: float,
    EI2: float,
    rhoA2: float,
    l2: float,
    clearance: float,
    force_amplitude: float,
    omega: float,
    uplift1: float = 0.0,
    uplift2: float = 0.0,
    t_max: float = 1.0,
    n_elements: tuple[int, int] = (40, 40),
    samples_per_period: float = 8.0,
    mode_rtol: float = 1e-6,
) -> float:
    """Time (s) of the first impact (g = 0 while closing), NaN if none by t_max (s).

    Free phase only: the beams (N m^2, kg/m, m) move independently from rest in their uplift
    shapes (m), beam 1 forced by F0 sin(Omega t) (N, rad/s) downward at its tip. The FE
    response is exact in time, with all modes. The gap is sampled with samples_per_period
    points per period of the fastest mode whose share of the gap oscillation exceeds mode_rtol,
    intervals whose cubic interpolant dips below zero are resampled finer, and the first sign
    change is refined by brentq to a few ulps. The grid settings do not change the result,
    only the risk of missing a near-grazing dip.

    Discretisation error of t* (default case, from rest without uplift): O(h^4), about 1e-7
    relative with 20 elements per beam, 1e-8 with 40, 5e-10 with 80. With uplifts, the
    release excites every mode (tip amplitudes ~ n^-4) and the drifting FE phases of the high
    ones make t* converge only about as h^2, with an erratic sign: about 1e-6 relative with
    40 elements, 1e-7 with 240 (beam 1 released from 2e-5 m, no force).
    """
    _, free, gap, q0, v0 = _setup(
        EI1, rhoA1, l1, EI2, rhoA2, l2, clearance, force_amplitude, omega,
        (uplift1, uplift2), n_elements,
    )  # fmt: skip
    dt = _grid_step(free, gap, 0.0, q0, v0, samples_per_period, mode_rtol)
    t_hit = _first_negative(free, gap, 0.0, q0, v0, t_max, dt, starts_at_zero=False)
    return np.nan if t_hit is None else t_hit


@dataclass
class _Segment:
    """One phase of the trajectory: [t_start, t_end) with its initial modal state."""

    in_contact: bool
    t_start: float
    q0: np.ndarray
    v0: np.ndarray
    t_end: float = np.inf
    sticky: bool = False  # contact that began with a merged micro-bounce cascade


def simulate_impacts(
    EI1: float,
    rhoA1: float,
    l1: float,
    EI2: float,
    rhoA2: float,
    l2: float,
    clearance: float,
    force_amplitude: float,
    omega: float,
    uplift1: float = 0.0,
    uplift2: float = 0.0,
    t_max: float = 0.1,
    t_out: np.ndarray | None = None,
    n_elements: tuple[int, int] = (20, 20),
    samples_per_period: float = 8.0,
    mode_rtol: float = 1e-9,
    max_events: int = 10_000,
) -> dict[str, np.ndarray]:
    """Event-driven FE simulation of the impacting beams with the MODEL.md contact law.

    Free phase until g = 0 while closing; then the state is projected M-orthogonally onto the
    tied space (removes the relative tip velocity: the impact loss); tied phase until the
    contact force R (N) crosses zero downward; then free again with the state unchanged. If R
    is already negative right after an onset, the contact lasts zero time (release = onset).
    Each phase is propagated exactly in its own modes; events are found on a grid with
    samples_per_period points per period of the fastest mode that matters for g or R (which
    after an impact is usually the highest FE mode), refined by brentq to a few ulps.

    Args:
        EI1, rhoA1, l1, EI2, rhoA2, l2: beams (N m^2, kg/m, m).
        clearance: Delta (m). force_amplitude: F0 (N). omega: Omega (rad/s), >= 0.
        uplift1, uplift2: initial tip uplifts (m), at rest in the static tip-load shape.
        t_max: end time (s). t_out: output times (s) in [0, t_max]; default 2001 points.
        n_elements: elements per beam.
        samples_per_period: event grid points per period of the fastest relevant mode.
        mode_rtol: modes below this share of the event output are not resolved by the grid.
        max_events: cap on onsets + releases (raises RuntimeError beyond; chattering).

    Micro-bounces: if a zero-length contact is followed by a gap that recloses at once (its
    excursion below ~1e-13 of the gap scale), the cascade is merged into one contact during
    which R may stay slightly negative for at most one grid step before it turns positive.
    The FE model has the modal non-convergence of MODEL.md: impacts chatter, and the number
    of impacts, contact durations and peak forces depend on n_elements (e.g. 440, 1189 and
    ~2400 impacts in 0.1 s for 10, 20 and 40 elements, default case). Only the first onset
    converges; later events are also sensitive to round-off after some 100 events.

    Returns:
        dict with "onset_times", "release_times" (s; one fewer release if the run ends in
        contact; equal to the onset for zero-duration contacts), "impact_gap_rates" (dg/dt
        just before each onset, m/s, <= 0), and on the output grid "t" (s), "tip1" = y1(l1),
        "tip2" = y2(l2), "gap" (m), "contact_force" R (N, 0 when free), "in_contact" (bool),
        "energy" = x'^T M x' / 2 + x^T K x / 2 (J).
    """
    pair, free, gap, q, v = _setup(
        EI1, rhoA1, l1, EI2, rhoA2, l2, clearance, force_amplitude, omega,
        (uplift1, uplift2), n_elements,
    )  # fmt: skip
    phases = _Phases.build(pair, free, gap, force_amplitude)
    segments = [_Segment(False, 0.0, q, v)]
    onsets, releases, rates = [], [], []
    while len(onsets) + len(releases) < max_events:
        seg = segments[-1]
        t_event = _next_event(phases, seg, len(segments) > 1, t_max, samples_per_period, mode_rtol)
        if t_event is None:
            break
        if _rebounces_at_once(segments, t_event):
            # Contact of zero length, then the gap recloses within round-off: a cascade of
            # micro-bounces too small to resolve. Merge it into one contact that sticks.
            segments.pop()
            releases.pop()
            segments[-1].t_end, segments[-1].sticky = np.inf, True
            continue
        seg.t_end = t_event
        modal = phases.contact if seg.in_contact else phases.free
        q, v = (a[0] for a in modal.propagate(seg.t_start, seg.q0, seg.v0, [t_event]))
        if seg.in_contact:
            releases.append(t_event)
            q, v = phases.to_contact.T @ q + phases.to_free_shift, phases.to_contact.T @ v
        else:
            onsets.append(t_event)
            rates.append(v @ phases.gap.r)
            q, v = phases.to_contact @ q + phases.to_contact_shift, phases.to_contact @ v
        segments.append(_Segment(not seg.in_contact, t_event, q, v))
    else:
        raise RuntimeError(f"more than {max_events} events by t = {segments[-1].t_start} s")
    t_out = np.linspace(0.0, t_max, 2001) if t_out is None else np.asarray(t_out, dtype=float)
    result = _sample(phases, segments, t_out)
    result.update(
        onset_times=np.array(onsets),
        release_times=np.array(releases),
        impact_gap_rates=np.array(rates),
    )
    return result


def _next_event(
    phases: _Phases,
    seg: _Segment,
    after_release: bool,
    t_max: float,
    samples_per_period: float,
    mode_rtol: float,
) -> float | None:
    """End time (s) of the phase `seg` (onset if free, release if in contact), None if > t_max."""
    modal, out = (phases.contact, phases.force) if seg.in_contact else (phases.free, phases.gap)
    t0, q0, v0 = seg.t_start, seg.q0, seg.v0
    dt = _grid_step(modal, out, t0, q0, v0, samples_per_period, mode_rtol)
    if seg.sticky:
        # The contact force may start slightly negative: wait (one grid step at most) until
        # it is positive; only a later fall through zero is a release.
        t0 = _leave_negative(modal, out, t0, q0, v0, dt)
        q0, v0 = (a[0] for a in modal.propagate(seg.t_start, seg.q0, seg.v0, [t0]))
    starts_at_zero = after_release and not seg.in_contact  # g(t_start) = 0 by construction
    return _first_negative(modal, out, t0, q0, v0, t_max, dt, starts_at_zero)


def _leave_negative(modal: _Modal, out: _Output, t0: float, q0, v0, dt: float) -> float:
    """First of the times t0 + dt 2^-j (j = 50..0) at which the output is positive."""
    t = t0 + dt * 0.5 ** np.arange(50, -1, -1)
    q, _ = modal.propagate(t0, q0, v0, t)
    positive = np.flatnonzero(out(modal, t, q) > 0.0)
    if not positive.size:
        raise RuntimeError(f"contact force stays negative after a micro-bounce at t = {t0} s")
    return t[positive[0]]


def _rebounces_at_once(segments: list[_Segment], t_event: float) -> bool:
    """True if a free phase right after a zero-length contact ends where it began."""
    seg = segments[-1]
    return (
        not seg.in_contact and len(segments) > 2 and t_event == seg.t_start == segments[-2].t_start
    )


def _sample(phases: _Phases, segments: list[_Segment], t_out: np.ndarray) -> dict:
    """Tip histories, gap, contact force and energy of the trajectory at times t_out."""
    pair = phases.pair
    result = {
        "t": t_out,
        "tip1": np.empty_like(t_out),
        "tip2": np.empty_like(t_out),
        "contact_force": np.zeros_like(t_out),
        "in_contact": np.zeros(t_out.shape, dtype=bool),
        "energy": np.empty_like(t_out),
    }
    for seg in segments:
        mask = (t_out >= seg.t_start) & (t_out < seg.t_end)
        if not mask.any():
            continue
        modal = phases.contact if seg.in_contact else phases.free
        q, v = modal.propagate(seg.t_start, seg.q0, seg.v0, t_out[mask])
        x = phases.displacement(seg.in_contact, q)
        xd = phases.velocity(seg.in_contact, v)
        result["tip1"][mask] = x[:, pair.tip1]
        result["tip2"][mask] = x[:, pair.tip2]
        result["energy"][mask] = 0.5 * (
            np.einsum("ti,ij,tj->t", xd, pair.M, xd) + np.einsum("ti,ij,tj->t", x, pair.K, x)
        )
        if seg.in_contact:
            result["contact_force"][mask] = phases.force(modal, t_out[mask], q)
            result["in_contact"][mask] = True
    result["gap"] = phases.gap.c0 + result["tip1"] - result["tip2"]
    return result
