"""The spring law with several contacts: one exact contact phase per active set.

With contacts j = 1..n (``Params.contacts``), each with its gap weights b_j (the free
coordinates' share of its gap, `impactbeams.contact.free.FreePhase.gap_weights` of its own
run), stiffness k_j and dashpot c_j, the contacts closed at a time form the active set S. Their
forces R_S push the structure by B_S R_S (B_S the columns b_j, j in S); the flexibility the
truncated modes miss between the contact points (signs included),

    R_N[j, l] = s_j s_l (G_1(x_j, x_l) + G_2(x'_j, x'_l)) - sum_n b_jn b_ln / omega_n^2,

is in series with the springs, so that the modal gaps g_S give R_S = -K_eff g_S - C_eff g_S'
with the static correction in matrix form (docs/model.md, "Several contacts"):

    K_eff = (K^-1 + R_N)^-1 = (I + K R_N)^-1 K,   C_eff = (I + K R_N)^-1 C (I + R_N K)^-1,

K = diag(k_S), C = diag(c_S), R_N restricted to S (for one contact k / (1 + k r_N) and
c / (1 + k r_N)^2). The phase's modal stiffness diag(omega^2) + B_S K_eff B_S^T is
diagonalised exactly as the single contact's rank-one update is (`rank_one_modes`), one rank-one
update per eigenvector of K_eff (it is symmetric positive definite), and its complex modes
follow with damping as the single contact's do (`complex_modes`). One active contact gives
`spring_contact`'s own contact phase, bit for bit (it is built by it).

Which sets can occur: every subset of the contacts except those holding both contacts of a
two-sided stop (one point of each beam, opposite sides: their gaps add up to the two
clearances, so they are never both closed): 2^n sets for n contacts, 3^p 2^(n - 2p) with p
two-sided stops among them (3 for a two-sided stop, 4 for two contacts that can close
together).

An inactive contact i's physical gap is its modal gap plus the static deflection the active
forces give it through what the modes miss, ``g_i + R_N[i, S] R_S``: it is 0 exactly when
contact i, added to S with R_i = 0, leaves the other forces where they were.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from impactbeams.contact.free import FreePhase, build_free_phase
from impactbeams.contact.spring import (
    complex_modes,
    rank_one_modes,
    real_modes,
    residual_flexibilities,
    spring_contact,
)
from impactbeams.modes import beam
from impactbeams.params import ParameterError, Params

__all__ = ["ActiveSet", "SeveralContacts", "possible_sets", "several_contacts"]


@dataclasses.dataclass(frozen=True)
class ActiveSet:
    """The contact phase of one active set (SI units; M free coordinates).

    Attributes:
        members: the indices (in ``Params.contacts``) of the closed contacts, ascending.
        effective_stiffness, effective_damping: K_eff (N/m) and C_eff (N s/m), |S| x |S|.
        eigenvalues: lambda_j (1/s), Im > 0; right (2 M, M): x = (q, q') = 2 Re(right z);
            left (M, 2 M): z = left x (as `impactbeams.contact.SpringContact`'s).
        force_weights: (|S|, M) complex: the active forces' modal part,
            -K_eff B^T q - C_eff B^T q' = 2 Re(force_weights z).
    """

    members: tuple[int, ...]
    effective_stiffness: np.ndarray
    effective_damping: np.ndarray
    eigenvalues: np.ndarray
    right: np.ndarray
    left: np.ndarray
    force_weights: np.ndarray

    @property
    def frequencies(self) -> np.ndarray:
        """Natural frequencies |lambda_j| of the phase's modes (rad/s)."""
        return np.abs(self.eigenvalues)


@dataclasses.dataclass(frozen=True)
class SeveralContacts:
    """Every active set's contact phase of a run's contacts (SI units).

    Attributes:
        frees: each contact's free phase (the same modes; each its own gap weights).
        stiffness, damping: k_j (N/m), c_j (N s/m) of each contact.
        residual: R_N (m/N), n x n, between the contact points (signs included).
        sets: the `ActiveSet` of each set that can occur, by its members (the empty set too).
    """

    frees: tuple[FreePhase, ...]
    stiffness: np.ndarray
    damping: np.ndarray
    residual: np.ndarray
    sets: dict[tuple[int, ...], ActiveSet]

    @property
    def gap_weights(self) -> np.ndarray:
        """b_j of each contact (rows), m per unit coordinate."""
        return np.array([free.gap_weights for free in self.frees])


def _never_together(runs: tuple[Params, ...]) -> set[tuple[int, int]]:
    """The pairs of contacts that cannot both be closed: the two sides of a two-sided stop."""
    return {(a, b) for a, b in itertools.combinations(range(len(runs)), 2)
            if runs[a].contact_point == runs[b].contact_point
            and runs[a].side.sign == -runs[b].side.sign}


def possible_sets(params: Params) -> list[tuple[int, ...]]:
    """Every active set of ``params``' contacts that can occur, the empty one first."""
    runs = params.each_contact()
    excluded = _never_together(runs)
    return [members for size in range(len(runs) + 1)
            for members in itertools.combinations(range(len(runs)), size)
            if not any(pair in excluded for pair in itertools.combinations(members, 2))]


def residual_matrix(runs: tuple[Params, ...], frees: tuple[FreePhase, ...]) -> np.ndarray:
    """R_N (m/N) between the contact points of ``runs``, signs included.

    Its diagonal is each contact's own r_N, as `spring_contact` sums it (the same bits).
    """
    n = len(runs)
    out = np.empty((n, n))
    for a, b in itertools.product(range(n), repeat=2):
        if a == b:
            out[a, a] = sum(residual_flexibilities(frees[a], frees[a].point_compliance))
            continue
        (x1, x2), (y1, y2) = runs[a].contact_point, runs[b].contact_point
        static = beam(runs[a], 1).flexibility(x1, y1)
        if runs[a].partner.has_beam2:
            static += beam(runs[a], 2).flexibility(x2, y2)
        modal = np.sum(frees[a].gap_weights * frees[b].gap_weights / frees[a].frequencies**2)
        out[a, b] = frees[a].side * frees[b].side * static - modal
    return out


def _static_correction(stiffness: np.ndarray, damping: np.ndarray, residual: np.ndarray,
                       ) -> tuple[np.ndarray, np.ndarray]:
    """K_eff = (I + K R_N)^-1 K and C_eff = A C A^T, A = (I + K R_N)^-1 (R_N, K symmetric)."""
    inverse = np.linalg.inv(np.eye(stiffness.size) + stiffness[:, None] * residual)
    k_eff = inverse * stiffness[None, :]
    c_eff = inverse @ np.diag(damping) @ inverse.T
    return 0.5 * (k_eff + k_eff.T), 0.5 * (c_eff + c_eff.T)


def _updated_modes(frequencies: np.ndarray, weights: np.ndarray, k_eff: np.ndarray,
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies and modes of diag(frequencies^2) + W K_eff W^T, one rank-one update at a time.

    K_eff = U diag(kappa) U^T: each kappa_l (W u_l)(W u_l)^T is added in the modes so far.
    """
    kappa, axes = np.linalg.eigh(k_eff)
    vectors = np.eye(frequencies.size)
    for value, axis in zip(kappa, axes.T, strict=True):
        frequencies, rotation = rank_one_modes(frequencies, value, vectors.T @ (weights @ axis))
        vectors = vectors @ rotation
    return frequencies, vectors


def active_set(contacts: tuple, members: tuple[int, ...],
               damping_ratio: float) -> ActiveSet:
    """The contact phase of active set ``members`` (``contacts``: frees, k, c, R_N)."""
    frees, stiffness, damping, residual = contacts
    if len(members) == 1:  # the single contact's own phase
        (j,) = members
        one = spring_contact(frees[j], frees[j].point_compliance, damping_ratio,
                             float(stiffness[j]), float(damping[j]))
        return ActiveSet(members, np.array([[one.effective_stiffness]]),
                         np.array([[one.effective_damping]]), one.eigenvalues, one.right,
                         one.left, (one.phase * one.force_weights)[None, :])
    index = list(members)
    omega = frees[0].frequencies
    weights = np.array([frees[j].gap_weights for j in index]).reshape(-1, omega.size).T
    k_eff, c_eff = _static_correction(stiffness[index], damping[index],
                                      residual[np.ix_(index, index)])
    frequencies, vectors = _updated_modes(omega, weights, k_eff)
    zeta = frees[0].damping_ratios(damping_ratio)
    if not np.any(zeta) and not np.any(damping[index]):
        eigenvalues, right, left = real_modes(frequencies, vectors)
    else:
        damped = complex_modes(frequencies, vectors,
                               np.diag(2.0 * zeta * omega) + weights @ c_eff @ weights.T)
        if damped is None:
            raise ParameterError(
                f"contact_damping = {damping[index].tolist()!r} is not allowed with "
                f"{frees[0].damping_named(damping_ratio)}: with contacts {members} closed "
                "together the contact phase has overdamped modes (real eigenvalues): lower either")
        eigenvalues, right, left = damped
    m = omega.size
    force_weights = -(k_eff @ weights.T @ right[:m] + c_eff @ weights.T @ right[m:])
    return ActiveSet(members, k_eff, c_eff, eigenvalues, right, left, force_weights)


def several_contacts(params: Params, n_modes: int) -> SeveralContacts:
    """Every possible active set's contact phase of ``params``' contacts, ``n_modes`` per beam.

    The spring law (each contact's own stiffness and dashpot). Built once per set
    (`possible_sets`): 4 for two contacts that can close together, 3 for a two-sided stop.
    """
    runs = params.each_contact()
    frees = tuple(build_free_phase(run, n_modes) for run in runs)
    stiffness = np.array([run.contact_stiffness for run in runs], dtype=float)
    damping = np.array([run.contact_damping for run in runs], dtype=float)
    residual = residual_matrix(runs, frees)
    parts = (frees, stiffness, damping, residual)
    sets = {members: active_set(parts, members, params.damping_ratio)
            for members in possible_sets(params)}
    return SeveralContacts(frees, stiffness, damping, residual, sets)
