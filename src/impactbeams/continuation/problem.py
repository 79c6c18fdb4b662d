"""What the continuation engine continues: zeros of r(z, p) = P(z, p) - z, and what it reads.

The engine ([`impactbeams.continuation.arclength`][]) knows nothing of beams: it asks a
[`Problem`][] for [`Evaluation`][]s of the residual at a state ``z`` and a parameter ``p``.
The beams' periodic orbits are one problem (`impactbeams.continuation.beams`); the tests hold
small ones with exact answers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Protocol

import numpy as np

# Forward differences in the parameter from the evaluation at p, which the corrector has
# anyway: the truncation error ~ h |r''| and the round-off ~ eps |r| / h balance at h ~
# eps^(1/2) times the parameter's scale, where both are ~ eps^(1/2) ~ 1.5e-8 relative. dr/dp
# only steers the corrector and the tangent: a converged point solves r = 0 to the tolerance
# whatever the error of dr/dp, and a fold, where the tangent's parameter part vanishes, moves
# by the square of its error in the parameter (central differences, eps^(2/3), cost a second
# run per iterate: 40 % of a stiff continuation).
PARAMETER_STEP = np.finfo(float).eps ** 0.5
# ... but a difference across a change of the orbit's contacts (a grazing within ~1e-5 of the
# parameter) measures the jump of the map's slope, not its slope, and Newton then converges
# slowly however small the step: the step narrows by NARROWING, at most NARROWINGS times
NARROWING, NARROWINGS = 1e-3, 2


@dataclasses.dataclass(frozen=True, eq=False)
class Evaluation:
    """The residual at (z, p) and what is read along a branch there.

    ``jacobian``: dr/dz (n x n), for a map r = P - z the monodromy minus the identity.
    ``multipliers``: the Floquet multipliers, leading first: given by the problem (e.g. a
    Newton-Picard subspace's), or None for the eigenvalues of dr/dz + I, which a corrector
    computes at the point it finds only (`with_multipliers`). ``grazing``: a number
    whose sign change along the branch is a grazing (the orbit's smallest free-flight gap), NaN
    if the problem has none. ``interval``: a number whose sign change is a merge or split of
    two contacts (the gap's local maximum between contacts nearest 0), NaN if none or not
    known. ``contacts``, ``episodes``: contacts and impact episodes per orbit
    (their change between two points is a nonsmooth event). ``measures``: named amplitudes
    (a number, or one per section of the orbit's period: an array), empty until the point is
    kept on a branch (`Problem.measures`).
    """

    residual: np.ndarray
    jacobian: np.ndarray
    multipliers: np.ndarray | None
    grazing: float = math.nan
    contacts: int = 0
    episodes: int = 0
    measures: Mapping[str, float | np.ndarray] = dataclasses.field(default_factory=dict)
    interval: float = math.nan


    def with_multipliers(self) -> Evaluation:
        """The evaluation with its multipliers (those of dr/dz + I if not given)."""
        if self.multipliers is not None:
            return self
        return dataclasses.replace(self, multipliers=multipliers_of(self.jacobian))


class Problem(Protocol):
    """A family of fixed-point problems P(z, p) = z, one per value of the parameter p."""

    period: int  # forcing periods per orbit (1 for a plain fixed point)

    def evaluate(self, z: np.ndarray, p: float, jacobian: bool = True,
                 grazing: bool = True) -> Evaluation:
        """r(z, p) and the contacts (``measures`` left empty).

        With dr/dz and the multipliers if ``jacobian`` (else both are empty); with the grazing
        value (and the interval value, if the problem has one) if ``grazing`` (else NaN).
        """

    def measures(self, z: np.ndarray, p: float) -> Mapping[str, float | np.ndarray]:
        """The named measures at (z, p): read only for the points a branch keeps."""

    def iterated(self, times: int) -> Problem:
        """The same family for ``times`` times the period (P applied ``times`` times)."""


def multipliers_of(jacobian: np.ndarray) -> np.ndarray:
    """The eigenvalues of dr/dz + I (the monodromy of a map), largest modulus first."""
    values = np.linalg.eigvals(jacobian + np.eye(len(jacobian)))
    return values[np.argsort(-np.abs(values), kind="stable")]


def parameter_derivative(problem: Problem, z: np.ndarray, p: float, scale: float,
                         at: Evaluation) -> np.ndarray:
    """dr/dp by a forward difference from ``at``, the evaluation at (z, p).

    The step is ``PARAMETER_STEP * max(|p|, scale)`` upward (never below a parameter's
    smallest allowed value, e.g. 0 for a force amplitude). Where the two ends have other
    contacts per orbit the step is narrowed (``NARROWING``).
    """
    h = PARAMETER_STEP * max(abs(p), scale)
    other = problem.evaluate(z, p + h, jacobian=False, grazing=False)
    for _ in range(NARROWINGS):
        if other.contacts == at.contacts:
            break
        h *= NARROWING  # the difference straddles a change of the contacts: nearer
        other = problem.evaluate(z, p + h, jacobian=False, grazing=False)
    return (other.residual - at.residual) / h
