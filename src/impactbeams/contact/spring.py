"""The compliant (spring) tip contact: its contact phase as exactly solvable oscillators.

Law (docs/model.md, "Compliant contact"): while the tips overlap, a spring k (N/m) and a
dashpot c (N s/m) push them apart, R = -k g - c g' as long as that is > 0. The free-phase
coordinates q (n cantilever modes per beam) are kept in both phases: with the gap weights
w = (Y_1n(l1), -Y_2n(l2)) and g = clearance - c1 F(t) + w . q, contact adds the rank-one terms

    q'' + (C + c_e w w^T) q' + (K + k_e w w^T) q = h(t) - k_e clearance w
                                                   + c1 (k_e F + c_e F') w,

with K = diag(omega^2), C = diag(2 zeta omega) (modal damping of the free modes' whole
coordinates, as in the free phase) and h the free phase's modal drive. The truncated modes
miss the tip flexibility r_N = c1 + c2 - sum_n w_n^2 / omega_n^2: in series with the spring it
gives k_e = k / (1 + k r_N) and, for the dashpot (low-frequency limit of the series element),
c_e = c / (1 + k r_N)^2.

The contact phase is solved once per (geometry, n_modes, zeta, k, c) by the complex modes of
its first-order form (undamped: the real eigenproblem of K + k_e w w^T, exact). Each mode
pair j (eigenvalue lambda_j with Im > 0) becomes one real damped oscillator

    y_j = 2 Re(rho_j z_j) - y_eq_j,   y_j'' + 2 zeta_j |lambda_j| y_j' + |lambda_j|^2 y_j
                                      = Im(A_j e^(i Omega t)),

with rho_j the phase of the mode's contact-force weight, so that the contact force is
R(t) = const + Im(S e^(i Omega t)) + sum_j |r_j| y_j: the form the package's exact propagator
and certified event search already handle. The maps between (q, q') and (y, y') are affine,
with offsets harmonic in time; they are the identity on the physical state (no projection, no
loss at a switch).

Against a stop (``counterpart = "stop"``) the same holds with beam 1's coordinates only:
w = Y_1n(l1), c2 = 0 and r_N = r_1, beam 1's residual alone.

A contact elsewhere (``Params.contact_point`` x1, x2, from ``Params.side`` s) is the same law
with the gap weights w = s (Y_1n(x1) - Y_2n(x2)), the gap's quasi-static part -s G1(x1, l1) F
(`impactbeams.contact.free`) and the flexibility each beam's modes miss at its contact point,
r_i = G_i(x_i, x_i) - sum_n Y_in(x_i)^2 / omega_in^2 (G the static Green's function); the tips,
which the outputs report, move through what the modes miss between tip and contact point by
``s (G1(l1, x1) - sum_n Y_1n(l1) Y_1n(x1) / omega_n^2) R`` (beam 1) and minus its like (beam 2).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from impactbeams.blas import one_blas_thread
from impactbeams.contact.free import FreePhase
from impactbeams.modes import AttachedBeam, UniformBeam, beam, values_at
from impactbeams.params import MAX_MODES, ParameterError, Params

__all__ = ["SpringContact", "needed_modes", "rank_one_modes", "recommended_modes",
           "required_modes", "residual_flexibilities", "resolution_modes", "spring_contact"]

# frequencies of the two beams closer than this (relative) count as equal in the rank-one
# update: the error it makes in their pair is below it, far better than a dense solver's
_DEFLATE = 1e-13
# A contact mode pair counts as underdamped while |Im lambda| exceeds this fraction of |lambda|
_OVERDAMPED = 1e-6
# n_modes per beam under the tied law when none is given: its first contacts converge in
# n_modes (docs/model.md), and 5 is the paper's resolution
TIED_MODES = 5


def residual_flexibilities(free: FreePhase, compliance: tuple[float, float],
                           ) -> tuple[float, float]:
    """r_i = c_i - sum_n Y_in(x_i)^2 / omega_in^2 (m/N): what each beam's modes miss there.

    ``compliance``: each beam's static flexibility at its contact point, (c1, c2) at the tips
    (``free.point_compliance``). Their sum is r_N, the flexibility the truncated modes miss
    between the contact points.
    """
    return (float(compliance[0] - np.sum(free.point1**2 / free.frequencies**2)),
            float(compliance[1] - np.sum(free.point2**2 / free.frequencies**2)))


def tip_shifts(free: FreePhase) -> tuple[float, float]:
    """How far each tip moves per unit contact force R through what the modes miss (m/N).

    Beam 1's: ``s (G1(l1, x1) - sum_n Y_1n(l1) Y_1n(x1) / omega_n^2)`` (R pushes it by s R);
    beam 2's the same of its own, its tip moving by minus that times R. Beam 2's is summed in
    order, as the kernels summed it when the contact sat at the tips (the same bits).
    """
    transfer1, transfer2 = free.tip_transfer
    shift1 = free.side * float(transfer1 - np.sum(free.tip1 * free.point1 / free.frequencies**2))
    missed = transfer2
    for tip, point, frequency in zip(free.tip2, free.point2, free.frequencies, strict=True):
        missed -= float(tip) * float(point) / (float(frequency) * float(frequency))
    return shift1, free.side * float(missed)


def resolution_modes(free: FreePhase, stiffness: float) -> int:
    """n* of each beam, the larger: modes whose modal tip stiffness omega^2 / Y(l)^2 < k.

    A contact is resolved when the modes reach well past the contact frequency; the
    recommended n_modes is at least 4 n* (docs/model.md, "Resolution").
    """
    n = free.modes_per_beam[0]
    weights = free.gap_weights
    with np.errstate(divide="ignore"):  # a mode with a node at the contact point never counts
        below = free.frequencies**2 / weights**2 < stiffness
    return int(max(np.sum(below[:n]), np.sum(below[n:])))


@dataclasses.dataclass(frozen=True)
class SpringContact:
    """The spring law's contact phase for one geometry (SI units).

    Attributes:
        stiffness, damping: k (N/m) and c (N s/m) of the law.
        effective_stiffness, effective_damping: k_e, c_e after the static correction.
        residual: r_N (m/N); residual1, residual2: each beam's share (c_i minus its modes',
            at its contact point).
        tip_shift1, tip_shift2: each tip's static response to R through what the modes miss
            (m/N, `tip_shifts`): beam 1's tip moves by tip_shift1 R, beam 2's by -tip_shift2 R.
        eigenvalues: lambda_j (1/s) of the contact phase's first-order form, Im > 0.
        right: (2 M, M) complex, x = (q, q') = 2 Re(right z).
        left: (M, 2 M) complex, z = left x.
        phase: rho_j (unit modulus); force_weights: |r_j| (N per unit y_j), with
            R_modal = -k_e w . q - c_e w . q' = sum_j 2 Re(r_j z_j).
    """

    stiffness: float
    damping: float
    effective_stiffness: float
    effective_damping: float
    residual: float
    residual1: float
    residual2: float
    tip_shift1: float
    tip_shift2: float
    eigenvalues: np.ndarray
    right: np.ndarray
    left: np.ndarray
    phase: np.ndarray
    force_weights: np.ndarray

    @property
    def frequencies(self) -> np.ndarray:
        """Natural frequencies |lambda_j| of the contact oscillators (rad/s)."""
        return np.abs(self.eigenvalues)

    @property
    def damping_ratios(self) -> np.ndarray:
        """Damping ratios -Re(lambda_j) / |lambda_j| of the contact oscillators."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)


def rank_one_modes(omega: np.ndarray, stiffness: float, weights: np.ndarray,
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies and orthonormal modes of diag(omega^2) + stiffness w w^T, to full accuracy.

    The low contact frequencies must be exact to their last digits, not to eps times the
    largest (as a dense solver gives): the secular equation of the rank-one update is solved
    per root by LAPACK's dlasd4, and the modes are built from the Loewner-corrected weights
    (Gu & Eisenstat), which makes them orthogonal. (Nearly) equal frequencies of the two beams
    are first deflated by rotations: one mode of each such pair keeps its frequency.
    Returns ``(frequencies, modes)``, the modes as columns, frequencies ascending.
    """
    order = np.argsort(omega)
    d, z = omega[order].astype(float), np.sqrt(stiffness) * weights[order]
    m = d.size
    basis = np.eye(m)
    deflated = np.zeros(m, dtype=bool)
    # an entry this small moves its root by a relative (8 eps d_max / d_j)^2 / 2: below
    # round-off, and the secular iteration would underflow on it (a k of 1e-300 N/m)
    tiny = max(np.finfo(float).eps * np.linalg.norm(z), 8.0 * np.finfo(float).eps * d[-1])
    last = -1
    for j in range(m):
        if abs(z[j]) <= tiny:
            deflated[j], z[j] = True, 0.0
        elif last >= 0 and d[j] - d[last] <= _DEFLATE * d[j]:  # rotate z onto the earlier one
            r = math.hypot(z[last], z[j])
            c, s = z[last] / r, z[j] / r
            basis[:, [last, j]] = basis[:, [last, j]] @ np.array([[c, -s], [s, c]])
            z[last], z[j], deflated[j] = r, 0.0, True
            d[j] = d[last]
        else:
            last = j
    active = np.flatnonzero(~deflated)
    da, za = d[active], z[active]
    n = active.size
    sigma, gap = np.empty(n), np.empty((n, n))  # gap[i, j] = d_j^2 - sigma_i^2
    for i in range(n):
        sigma[i], gap[i] = _secular_root(i, da, za)
    # Loewner: the weights for which the computed roots are exact
    corrected = np.empty(n)
    for j in range(n):  # d_i^2 - d_j^2 as a product: no cancellation for close frequencies
        below = -gap[:j, j] / ((da[:j] - da[j]) * (da[:j] + da[j]))
        above = -gap[j:n - 1, j] / ((da[j + 1:] - da[j]) * (da[j + 1:] + da[j]))
        corrected[j] = math.copysign(math.sqrt(-gap[n - 1, j] * np.prod(below) * np.prod(above)),
                                     za[j])
    vectors = corrected[None, :] / gap
    vectors /= np.linalg.norm(vectors, axis=1)[:, None]
    frequencies = np.concatenate([sigma, d[deflated]])
    modes = np.zeros((m, m))
    modes[active, :n] = vectors.T
    modes[np.flatnonzero(deflated), n + np.arange(np.count_nonzero(deflated))] = 1.0
    modes = basis @ modes
    arrange = np.argsort(frequencies)
    full = np.empty((m, m))
    full[order] = modes[:, arrange]
    return frequencies[arrange], full


def _secular_root(i: int, d: np.ndarray, z: np.ndarray) -> tuple[float, np.ndarray]:
    """Root ``i`` of the rank-one update's secular equation (LAPACK's dlasd4).

    Returns sigma_i and d_j^2 - sigma_i^2 for every j.
    A root that does not converge is solved again on the problem scaled to d <= 1 (the
    iteration's stopping test has an absolute part: seen for the last root of a stiff contact
    on a beam whose modes reach 4e11 rad/s); roots that converge are left exactly as they are.
    """
    if d.size == 1:  # dlasd4 returns sigma alone here (delta = work = 1), not the difference
        return math.hypot(d[0], z[0]), np.array([-z[0] ** 2])
    import scipy.linalg.lapack  # here, not at the top: a first-impact map needs no SciPy

    delta, sigma, work, info = scipy.linalg.lapack.dlasd4(i, d, z, 1.0)
    if info != 0:
        scale = d[-1]
        delta, sigma, work, info = scipy.linalg.lapack.dlasd4(i, d / scale, z / scale, 1.0)
        delta, sigma, work = delta * scale, sigma * scale, work * scale
    if info != 0:
        raise ArithmeticError(f"dlasd4 failed (info {info}) on contact mode {i}")
    return sigma, delta * work


def _undamped_modes(omega: np.ndarray, stiffness: float, weights: np.ndarray,
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Undamped: lambda = i omega, right = (V; i V Omega), left = (V^T, -i V^T / omega) / 2."""
    return real_modes(*rank_one_modes(omega, stiffness, weights))


def real_modes(frequencies: np.ndarray, vectors: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``_undamped_modes``' first-order form of modes ``vectors`` at ``frequencies`` (rad/s)."""
    right = np.vstack([vectors, 1j * vectors * frequencies]).astype(complex)
    left = 0.5 * np.hstack([vectors.T, -1j * vectors.T / frequencies[:, None]])
    return 1j * frequencies, right, left


def _damped_modes(omega: np.ndarray, stiffness: float, weights: np.ndarray,
                  damping_matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Complex modes of (q, q')' = [[0, I], [-K, -C]] (q, q'), balanced.

    None if a mode pair is overdamped (real eigenvalues), or the damping overflows.

    Solved in the undamped modes p = V^T q with the scaled state s = (Omega p, p'), where the
    first-order matrix [[0, Omega], [-Omega, -V^T C V]] has entries of one size.
    """
    return complex_modes(*rank_one_modes(omega, stiffness, weights), damping_matrix)


def complex_modes(omega: np.ndarray, vectors: np.ndarray, damping_matrix: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``_damped_modes`` given the undamped modes ``vectors`` at ``omega`` (rad/s)."""
    m = omega.size
    with np.errstate(over="ignore", invalid="ignore"):
        block = np.block([[np.zeros((m, m)), np.diag(omega)],
                          [-np.diag(omega), -vectors.T @ damping_matrix @ vectors]])
    if not np.all(np.isfinite(block)):  # damping beyond float range: no oscillation left
        return None
    import scipy.linalg  # here, not at the top: a first-impact map needs no SciPy

    values, modes = scipy.linalg.eig(block)
    rising = np.abs(values.imag) > _OVERDAMPED * np.abs(values)
    if np.count_nonzero(rising) != 2 * m:
        return None
    keep = np.flatnonzero(values.imag > 0)
    keep = keep[np.argsort(np.abs(values[keep]))]
    inverse = np.linalg.inv(modes)[keep]
    # x = (q, q') = T s with T = blockdiag(V Omega^-1, V); s = T^-1 x = (Omega V^T q, V^T q')
    right = np.vstack([vectors @ (modes[:m, keep] / omega[:, None]), vectors @ modes[m:, keep]])
    left = np.hstack([inverse[:, :m] @ (omega[:, None] * vectors.T), inverse[:, m:] @ vectors.T])
    return values[keep], right, left


@one_blas_thread
def spring_contact(free: FreePhase, compliance: tuple[float, float], damping_ratio: float,
                   stiffness: float, damping: float = 0.0) -> SpringContact:
    """The contact phase of the spring law (k = ``stiffness`` N/m, c = ``damping`` N s/m).

    ``compliance``: each beam's static flexibility at its contact point (m/N),
    ``free.point_compliance`` (the tip compliances for a contact at the tips); the free modes
    damped by ``free.damping_ratios(damping_ratio)`` (their own, or the run's ratio).
    """
    zeta = free.damping_ratios(damping_ratio)
    residual1, residual2 = residual_flexibilities(free, compliance)
    residual = residual1 + residual2
    k_e = stiffness / (1.0 + stiffness * residual)
    c_e = damping / (1.0 + stiffness * residual) ** 2
    w = free.gap_weights
    if not np.any(zeta) and damping == 0.0:
        eigenvalues, right, left = _undamped_modes(free.frequencies, k_e, w)
    else:
        def modes(contact_damping: float) -> tuple[np.ndarray, ...] | None:
            c_e = contact_damping / (1.0 + stiffness * residual) ** 2
            with np.errstate(over="ignore"):  # a dashpot beyond float range: overdamped
                matrix = np.diag(2.0 * zeta * free.frequencies) + c_e * np.outer(w, w)
            return _damped_modes(free.frequencies, k_e, w, matrix)

        damped = modes(damping)
        if damped is None:
            raise _overdamped(modes, damping, free.damping_named(damping_ratio), stiffness)
        eigenvalues, right, left = damped
    m = w.size
    # R_modal = -k_e w.q - c_e w.q' = sum_j 2 Re(r_j z_j)
    phase, magnitude = polar(-(k_e * w @ right[:m] + c_e * w @ right[m:]))
    return SpringContact(float(stiffness), float(damping), float(k_e), float(c_e), residual,
                         residual1, residual2, *tip_shifts(free), eigenvalues, right, left,
                         phase, magnitude)


def polar(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Complex mode weights as (phase rho_j, |r_j|): the oscillators' phases and weights."""
    magnitude = np.abs(weights)
    # a subnormal weight (a vanishing k) would overflow the division: its phase from its angle
    normal = magnitude >= np.finfo(float).tiny
    phase = np.where(normal, weights / np.where(normal, magnitude, 1.0),
                     np.exp(1j * np.angle(weights)))
    return phase, magnitude


def _overdamped(modes: Callable[[float], object], damping: float, modal_damping: str,
                stiffness: float) -> ParameterError:
    """The refusal of an overdamped contact phase, naming the largest contact damping allowed.

    ``modes(c)``: the contact modes with contact damping c, None if overdamped; the
    overdamped c form one range above a threshold (seen on every beam pair tried), found to
    3 digits by decades, then bisection in log c. ``modal_damping``: the free modes' damping
    as the refusal names it (`FreePhase.damping_named`).
    """
    law = f"with contact_stiffness = {stiffness:g} N/m and {modal_damping}"
    if modes(0.0) is None:
        return ParameterError(f"{modal_damping} is not allowed: with contact_stiffness = "
                              f"{stiffness:g} N/m, the contact phase has overdamped modes (real "
                              "eigenvalues) even without contact damping: lower it")
    low = damping
    while low > 1e-300 and modes(low) is None:
        low /= 10.0
    high = 10.0 * low
    while high > 1.001 * low:
        middle = math.sqrt(low * high)
        low, high = (middle, high) if modes(middle) is not None else (low, middle)
    return ParameterError(f"contact_damping = {damping!r} is not allowed: {law}, it overdamps "
                          "the contact phase (a mode pair with real eigenvalues); at most "
                          f"about {low:.3g} N s/m keeps every contact mode oscillating")


def required_modes(params: Params) -> int:
    """n_modes per beam that resolves the spring contact of ``params``: 4 n*, at least 5.

    n* is `resolution_modes` of ``MAX_MODES`` modes per beam, counted on as few of them as
    decide it (`_softer_modes`). May exceed the package's limit of ``MAX_MODES`` for a very
    stiff contact.
    """
    p, k = params, params.contact_stiffness
    x1, x2 = p.contact_point
    counts = [_softer_modes(beam(p, 1), k, x1)]
    if p.partner.has_beam2:
        counts.append(_softer_modes(beam(p, 2), k, x2))
    return int(max(5, 4 * max(counts)))


def _softer_modes(cantilever: UniformBeam | AttachedBeam, stiffness: float,
                  position: float) -> int:
    """How many of a cantilever's first ``MAX_MODES`` modes are softer than k (N/m) at a point.

    ``position``: the contact point (m from the clamp), the tip by default; the count stops as
    at the tip (whose modal stiffness is the lowest of the span's on a uniform beam: its
    |Y_n| is the largest), the modes softer at the point are counted.

    On a uniform beam mode n's modal tip stiffness omega_n^2 / Y_n(l)^2 is EI b_n^4 / (4 l^3)
    (mass-normalised cantilever modes all have Y_n(l)^2 = 4 / (rhoA l)): it rises with n, so
    the soft modes come first and the count is settled by the first stiff one. The modes are
    built as `build_free_phase` builds them (each mode's values do not depend on how many are
    built), from a few past b* = (4 k l^3 / EI)^(1/4) = (12 k c)^(1/4) (b_n is about
    (n - 1/2) pi, c the tip compliance), more if all of those are soft: the same count as
    `resolution_modes` of ``MAX_MODES`` modes, bit for bit. A beam with attachments is counted
    the same way, on its own modes, up to the first stiff one; a user structure too, on at
    most the modes it has (the guess b* only sets where the count starts).
    """
    b_soft = (12.0 * stiffness * cantilever.tip_compliance) ** 0.25
    limit = cantilever.mode_limit  # MAX_MODES, or fewer: the modes a user structure has
    n = min(limit, int(b_soft / math.pi) + 3)
    while True:
        modes = cantilever.free_modes(n)
        soft = modes.frequencies**2 / modes.shapes.tip()**2 < stiffness
        if not soft[-1] or n == limit:
            with np.errstate(divide="ignore"):  # a node at the point: infinitely stiff there
                at_point = modes.frequencies**2 / values_at(modes.shapes, position,
                                                            cantilever.length)**2 < stiffness
            return int(np.sum(at_point))
        n = min(2 * n, limit)


def needed_modes(params: Params) -> int:
    """n_modes per beam that resolves the contact of ``params`` (may exceed a run's limit).

    `required_modes` under a compliant law, ``TIED_MODES`` under the tied law.
    """
    return required_modes(params) if params.law.compliant else TIED_MODES


def recommended_modes(params: Params) -> int:
    """The n_modes per beam a run takes when none is given.

    `needed_modes`, within ``MAX_MODES`` and the modes beam 1's structure has: the one
    answer to "how many modes does this need" of simulate, period maps, basins, continuation
    and the CLI's contact frequencies.
    """
    return min(MAX_MODES, beam(params, 1).mode_limit, needed_modes(params))
