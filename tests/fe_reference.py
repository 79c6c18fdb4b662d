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
to round-off, and frequencies converge as O(h^4).

Time integration is exact for the FE system: in each phase M x'' + K x = p0 + p1 sin(Omega t)
is diagonalised by the phase's own mass-normalised eigenvectors, and every mode is propagated in
closed form (no mode dropped; the forced response is written so that it stays exact at
resonance). Events (impact onset g = 0, release R = 0) are found by sampling on a dense grid
and refining the first sign change with scipy.optimize.brentq to near machine precision.

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
# Evaluate dense grids in chunks so a phase that ends early costs little.
_CHUNK = 4096


# --------------------------------------------------------------------------------------------
# Beam matrices and frequencies
# --------------------------------------------------------------------------------------------


def steel_strip(a: float = 0.7, E: float = 210e9, rho: float = 7850.0, width: float = 5e-3):
    """Return (EI (N m^2), rhoA (kg/m)) of the default steel strip with a = sqrt(EI/rhoA).

    The thickness is h = a / sqrt(E / (12 rho)) (m), as in MODEL.md.
    """
    h = a / np.sqrt(E / (12.0 * rho))
    return E * width * h**3 / 12.0, rho * width * h


def _eig(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequencies (rad/s, ascending) and M-orthonormal mode shapes of (K, M)."""
    lam, phi = scipy.linalg.eigh(K, M)
    return np.sqrt(lam), phi


def tip_dof(n_elements: int) -> int:
    """Index of the tip displacement DOF in the matrices of `beam_matrices`.

    DOF ordering: nodes 1..n (node 0 is clamped and removed); node j has its deflection w_j at
    index 2 (j - 1) and its slope theta_j at 2 (j - 1) + 1. The tip is node n.
    """
    return 2 * n_elements - 2


def beam_matrices(
    EI: float, rhoA: float, length: float, n_elements: int
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness K (N/m, N, N m) and consistent mass M (kg, ...) of a uniform cantilever.

    Uniform mesh of `n_elements` Hermite-cubic elements; the clamped node is removed, so both
    matrices are (2 n, 2 n), symmetric positive definite, DOFs ordered as in `tip_dof`.
    """
    h = length / n_elements
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
    n_full = 2 * (n_elements + 1)
    K = np.zeros((n_full, n_full))
    M = np.zeros((n_full, n_full))
    for e in range(n_elements):
        idx = slice(2 * e, 2 * e + 4)
        K[idx, idx] += k_e
        M[idx, idx] += m_e
    # Clamp: drop w and theta of node 0.
    return K[2:, 2:], M[2:, 2:]


def static_tip_shape(K: np.ndarray, tip_deflection: float) -> np.ndarray:
    """Static FE deflection under a tip point load, scaled to the given tip deflection (m).

    Hermite cubics represent u(x) = delta (3 l x^2 - x^3) / (2 l^3) exactly, so this is the
    nodal interpolant of the MODEL.md initial uplift shape.
    """
    tip = K.shape[0] - 2
    unit = np.zeros(K.shape[0])
    unit[tip] = 1.0
    x = scipy.linalg.solve(K, unit, assume_a="pos")
    return x * (tip_deflection / x[tip])


def cantilever_frequencies(
    EI: float, rhoA: float, length: float, n_modes: int, n_elements: int
) -> np.ndarray:
    """Lowest `n_modes` FE natural frequencies (rad/s) of one cantilever, ascending."""
    return _eig(*beam_matrices(EI, rhoA, length, n_elements))[0][:n_modes]


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
    return _eig(*pair.tied_matrices())[0][:n_modes]


@dataclass(frozen=True)
class _Pair:
    """Both beams in one block-diagonal system x = [x1, x2] (beam 1's DOFs first).

    `T` maps the tied coordinates z (x without beam 2's tip deflection) to x: x = T z + x_off
    with x_off = clearance at beam 2's tip, i.e. y2(l2) = y1(l1) + clearance (g = 0).
    """

    K: np.ndarray
    M: np.ndarray
    n1: int  # number of beam 1's DOFs
    tip1: int
    tip2: int
    T: np.ndarray

    @classmethod
    def build(cls, EI1, rhoA1, l1, EI2, rhoA2, l2, n_elements: tuple[int, int]) -> _Pair:
        K1, M1 = beam_matrices(EI1, rhoA1, l1, n_elements[0])
        K2, M2 = beam_matrices(EI2, rhoA2, l2, n_elements[1])
        tip1 = tip_dof(n_elements[0])
        tip2 = K1.shape[0] + tip_dof(n_elements[1])
        n = K1.shape[0] + K2.shape[0]
        T = np.delete(np.eye(n), tip2, axis=1)
        T[tip2, tip1] = 1.0  # beam 2's tip follows beam 1's tip
        K, M = scipy.linalg.block_diag(K1, K2), scipy.linalg.block_diag(M1, M2)
        return cls(K, M, K1.shape[0], tip1, tip2, T)

    def free_modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (rad/s) and mass-normalised modes of the untied beams, beam by beam."""
        blocks = (slice(0, self.n1), slice(self.n1, None))
        modes = [_eig(self.K[b, b], self.M[b, b]) for b in blocks]
        return np.concatenate([w for w, _ in modes]), scipy.linalg.block_diag(
            *[p for _, p in modes]
        )

    def tied_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """Return (T^T K T, T^T M T) of the tied system."""
        return self.T.T @ self.K @ self.T, self.T.T @ self.M @ self.T

    def unit(self, index: int) -> np.ndarray:
        """Unit vector of DOF `index` in the x coordinates."""
        e = np.zeros(self.K.shape[0])
        e[index] = 1.0
        return e


# --------------------------------------------------------------------------------------------
# Exact modal propagation of M x'' + K x = p0 + p1 sin(Omega t)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Modal:
    """Modal form q_n'' + omega_n^2 q_n = a_n + b_n sin(Omega t) of one phase.

    phi: mass-normalised eigenvectors (columns) in the phase's own coordinates.
    """

    omega: np.ndarray
    phi: np.ndarray
    a: np.ndarray
    b: np.ndarray
    forcing_omega: float

    @classmethod
    def build(cls, omega, phi, p0, p1, forcing_omega: float) -> _Modal:
        """Modal form of M x'' + K x = p0 + p1 sin(Omega t) with modes (omega, phi) of (K, M)."""
        return cls(omega, phi, phi.T @ p0, phi.T @ p1, forcing_omega)

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
        static = self.a / w**2
        free = q0 - static
        q = static + free * cos_wt + (v0 / w) * sin_wt + c_cos * h_cos + c_sin * h_sin
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
        free = np.abs(q0 - self.a / w**2 - p0) + np.abs(v0 - dp0) / w
        return np.abs(weights) * free


@dataclass(frozen=True)
class _Output:
    """A scalar output c0 + c_sin sin(Omega t) + r . q(t) that is linear in the modal state."""

    c0: float
    c_sin: float
    r: np.ndarray

    def __call__(self, modal: _Modal, t, q) -> np.ndarray:
        return self.c0 + self.c_sin * np.sin(modal.forcing_omega * np.atleast_1d(t)) + q @ self.r


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
    if omega_max == 0.0:
        omega_max = modal.omega[0]
    return 2.0 * np.pi / (samples_per_period * omega_max)


def _first_negative(
    modal: _Modal, out: _Output, t0: float, q0, v0, t_end: float, dt: float, starts_at_zero: bool
) -> float | None:
    """First time in [t0, t_end] at which the output crosses from >= 0 to < 0, or None.

    If the output is already negative at t0, the event is at t0 itself. If starts_at_zero, the
    output is zero at t0 by construction (the gap right after a release) and only a later
    crossing counts; see `_leave_zero`.
    """

    def value(t: float) -> float:
        q, _ = modal.propagate(t0, q0, v0, [t])
        return float(out(modal, t, q)[0])

    if not starts_at_zero and value(t0) < 0.0:
        return t0
    n_steps = int(np.ceil((t_end - t0) / dt))
    for k0 in range(0, n_steps, _CHUNK):
        t = np.minimum(t0 + np.arange(k0, min(k0 + _CHUNK, n_steps) + 1) * dt, t_end)
        q, _ = modal.propagate(t0, q0, v0, t)
        g = out(modal, t, q)
        negative = np.flatnonzero(g[1:] < 0.0)
        if not negative.size:
            continue
        i = negative[0]
        if k0 == 0 and i == 0 and starts_at_zero:
            bracket = _leave_zero(value, t0, t[1], _noise(modal, out, q0))
            if bracket is None:
                return t0
            return brentq(value, *bracket, xtol=_XTOL, rtol=_RTOL, maxiter=200)
        if g[i] == 0.0:
            return t[i]
        return brentq(value, t[i], t[i + 1], xtol=_XTOL, rtol=_RTOL, maxiter=200)
    return None


def _noise(modal: _Modal, out: _Output, q0) -> float:
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
    p1 = -force_amplitude * pair.unit(pair.tip1)  # F positive downward on beam 1's tip
    free = _Modal.build(*pair.free_modes(), np.zeros(pair.K.shape[0]), p1, omega)
    return free, _Output(c0=clearance, c_sin=0.0, r=free.phi[pair.tip1] - free.phi[pair.tip2])


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
        x_off = gap.c0 * pair.unit(pair.tip2)  # tie: y2(l2) = y1(l1) + clearance
        p0 = -pair.T.T @ pair.K @ x_off  # the tie's prescribed offset acts as a static load
        p1 = -force_amplitude * pair.T.T @ pair.unit(pair.tip1)
        contact = _Modal.build(*_eig(*pair.tied_matrices()), p0, p1, free.forcing_omega)
        # R = -(K x + M x'')[tip2], x = T phi q + x_off, q'' = a + b sin(Omega t) - omega^2 q.
        k_row = (pair.K @ pair.T @ contact.phi)[pair.tip2]
        m_row = (pair.M @ pair.T @ contact.phi)[pair.tip2]
        force = _Output(
            c0=-(pair.K[pair.tip2] @ x_off + m_row @ contact.a),
            c_sin=-(m_row @ contact.b),
            r=-(k_row - m_row * contact.omega**2),
        )
        # M-orthogonal projections between the bases: q_c = phi_c^T T^T M (x - x_off).
        proj = contact.phi.T @ pair.T.T @ pair.M
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
            static_tip_shape(pair.K[:n1, :n1], uplifts[0]),
            static_tip_shape(pair.K[n1:, n1:], uplifts[1]),
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
    samples_per_period: float = 16.0,
    mode_rtol: float = 1e-9,
) -> float:
    """Time (s) of the first impact (g = 0 while closing), NaN if none by t_max (s).

    Free phase only: the beams move independently from rest in their uplift shapes (m). The
    FE response is exact in time; the gap is sampled with samples_per_period points per period
    of the fastest mode whose tip contribution exceeds mode_rtol of the total (all modes are
    kept in the evaluation), then the first sign change is refined by brentq to a few ulps.
    A dip below zero shorter than the sampling step can be missed (grazing).
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
        mode_rtol: modes below this share of the event output are not resolved by the grid.
        max_events: cap on onsets + releases (raises RuntimeError beyond; chattering).

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
        modal, out = (phases.contact, phases.force) if seg.in_contact else (phases.free, phases.gap)
        released = len(segments) > 1 and not seg.in_contact  # g(t_start) = 0 by construction
        dt = _grid_step(modal, out, seg.t_start, seg.q0, seg.v0, samples_per_period, mode_rtol)
        t_event = _first_negative(
            modal, out, seg.t_start, seg.q0, seg.v0, t_max, dt, starts_at_zero=released
        )
        if t_event is None:
            break
        _check_progress(segments, t_event)
        seg.t_end = t_event
        q, v = modal.propagate(seg.t_start, seg.q0, seg.v0, [t_event])
        q, v = q[0], v[0]
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


def _check_progress(segments: list[_Segment], t_event: float) -> None:
    """Refuse an endless loop of zero-length phases (grazing at g = 0 with R = 0)."""
    if len(segments) >= 2 and t_event == segments[-1].t_start == segments[-2].t_start:
        raise RuntimeError(f"stuck at a grazing contact at t = {t_event} s")


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
