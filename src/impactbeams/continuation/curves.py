"""Bifurcations in two parameters as zeros of augmented systems, for the same arclength engine.

A bifurcation of the periodic orbits of one parameter p1 (a grazing, a fold, a period doubling, a
Neimark-Sacker point) persists along a curve in the plane (p1, p2). On that curve the orbit's
section state z, p1 and p2 solve

    P(z; p1, p2) - z = 0,     c(z; p1, p2) = 0,

with c the bifurcation's condition (`Grazing`, `Multiplier`, `UnitPair`): n + 1 equations in n + 2
unknowns, a curve. [`CurveProblem`][] presents it to the one-parameter engine
(`impactbeams.continuation.arclength`) as a family in p2 whose "state" is y = (z, p1): the
engine's pseudo-arclength corrector, tangents, step control and root location then follow the
curve unchanged, with p1 as free as z and p2 its continued parameter.

The Jacobian of the orbit's equations in z is the exact monodromy minus the identity
(`BeamOrbits`); the columns in p1 and the condition's row are forward differences from the
evaluation at y (their error steers Newton only: a converged point solves the equations to
the tolerance whatever it is, as dr/dp in `problem.parameter_derivative`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from impactbeams.continuation.beams import BeamOrbits, grazing_value
from impactbeams.continuation.problem import PARAMETER_STEP, Evaluation, multipliers_of
from impactbeams.orbits import ContactsPeriodMap, PeriodMap, PeriodMapResult
from impactbeams.orbits.shooting import GUARD
from impactbeams.params import Params, parameter_value, with_parameter

SectionMaps = PeriodMap | ContactsPeriodMap  # one contact's, several contacts'
CACHED_PLANES = 4  # BeamOrbits kept by p2 value (the engine's dr/dp2 asks for a second one)


class Grazing:
    """The orbit's smallest gap over the period is zero (m): of one contact, ``contact``.

    The gap read from the free coordinates (`PeriodMap.least_gap`): in free flight the gap's
    smallest value (a certified search: samples refined by Brent's method on the gap's
    rate), in a contact the depth the tips would reach without it. With several contacts
    the gap of the one that grazes at the curve's start (`start`), read as if it were open
    (`ContactsPeriodMap.least_gap`): the others' grazings are other curves. Both sides have
    one slope at the grazing, where the signed grazing value of the one-parameter branches
    (`beams.grazing_value`: minus the overlap in a contact) changes it by 1 + the static
    compliance times the contact stiffness: Newton on the curve converges quadratically
    instead of linearly (measured on the small model's grazing curve in (Omega, F0): 3
    iterations a point instead of 6 to 8).
    """

    label = "grazing"
    needs_monodromy = False
    # the curve is where the contacts change: it goes on across them
    smooth_across_contacts = True

    def __init__(self) -> None:
        self.contact = 0

    def start(self, period_map: SectionMaps, result: PeriodMapResult) -> None:
        """Follow the contact whose gap is nearest 0 on the start's orbit ``result``."""
        self.contact = period_map.grazing_contact(result)

    def value(self, period_map: SectionMaps, result: PeriodMapResult,
              drz: np.ndarray | None = None) -> float:
        """The condition at an orbit's run (``drz`` unused)."""
        return period_map.least_gap(result, self.contact)

    def probe(self, period_map: SectionMaps, result: PeriodMapResult) -> float:
        """A quantity whose forward differences are the condition's (its value)."""
        return self.value(period_map, result)

    def border(self, drz: np.ndarray, weights: np.ndarray) -> None:
        """Nothing to adapt: the condition does not depend on where the curve is."""


class Multiplier:
    """A Floquet multiplier at ``sigma`` (+1: a fold; -1: a period doubling).

    The test function is the minimally augmented system's (Govaerts, Numerical Methods for
    Bifurcations of Dynamical Equilibria, 2000, ch. 3-4): with A = M - sigma I of the
    monodromy in the energy coordinates D z = (omega q, q'), D M D^-1, and borders b, c,

        [A  b] [v]   [0]        [A^T c] [w]   [0]
        [c' 0] [s] = [1],       [b'  0] [s] = [1],

    s is a smooth function with a simple zero where A is singular (a simple multiplier at
    sigma), of the order of A's smallest singular value nearby. Its gradient is
    ``-w' A_x v``: differences of A, no second derivatives of the map and no inverse of the
    singular A. The determinant det(M - sigma I) would be simpler to state but scales with
    the product of every other multiplier's distance from sigma (it changes by orders of
    magnitude along a curve as they move, and with the model's size), and its gradient is
    the adjugate's, which Newton would form from a nearly singular matrix. The borders are
    the singular vectors of A's smallest singular value at the last point of the curve
    (`border`), so that the bordered matrix stays well conditioned along it.
    """

    needs_monodromy = True
    # the monodromy jumps where the orbit's contacts change: the curve ends there
    smooth_across_contacts = False

    def __init__(self, sigma: float) -> None:
        self.sigma = sigma
        self.label = "fold" if sigma > 0 else "period_doubling"
        self.b: np.ndarray | None = None
        self.c: np.ndarray | None = None
        self._left = self._right = np.empty(0)  # w and v of the last solve

    def start(self, period_map: SectionMaps, result: PeriodMapResult) -> None:
        """Nothing to choose: the borders are set at the first point (`of`)."""

    def matrix(self, monodromy: np.ndarray) -> np.ndarray:
        """A of the monodromy in the energy coordinates, D M D^-1: M - sigma I."""
        return monodromy - self.sigma * np.eye(len(monodromy))

    def value(self, period_map: SectionMaps, result: PeriodMapResult,
              drz: np.ndarray | None = None) -> float:
        """The test function s at an orbit's run whose monodromy minus the identity is ``drz``."""
        return self.of(self._matrix_at(period_map, result, drz))

    def of(self, a: np.ndarray) -> float:
        """The test function s of A (bordered at A itself if no border is set yet)."""
        if self.b is None:
            self._set_borders(a)
        n = len(a)
        bordered = np.zeros((n + 1, n + 1))
        bordered[:n, :n], bordered[:n, n], bordered[n, :n] = a, self.b, self.c
        rhs = np.zeros(n + 1)
        rhs[n] = 1.0
        right = np.linalg.solve(bordered, rhs)
        self._right, self._left = right[:n], np.linalg.solve(bordered.T, rhs)[:n]
        return float(right[n])

    def probe(self, period_map: SectionMaps, result: PeriodMapResult) -> float:
        """-w' A v at a run, with the last solve's v and w: its differences are s's.

        M in full, then A and the products: the tangent propagation of v alone rounds
        otherwise than M's columns do (5e-7 relative, measured), which differences over 1e-8
        of the state would magnify; M's columns at two nearby runs round alike.
        """
        return -float(self._left @ self._matrix_at(period_map, result) @ self._right)

    def border(self, drz: np.ndarray, weights: np.ndarray) -> None:
        """New borders from A at a point of the curve (its smallest singular vectors)."""
        monodromy = drz + np.eye(weights.size)
        self._set_borders(self.matrix(weights[:, None] * monodromy / weights[None, :]))

    def _matrix_at(self, period_map: SectionMaps, result: PeriodMapResult,
                   drz: np.ndarray | None = None) -> np.ndarray:
        weights = state_weights(period_map)
        monodromy = (period_map.jacobian(result, "all") if drz is None
                     else drz + np.eye(weights.size))
        return self.matrix(weights[:, None] * monodromy / weights[None, :])

    def _set_borders(self, a: np.ndarray) -> None:
        u, _, vt = np.linalg.svd(a)
        self.b, self.c = u[:, -1].copy(), vt[-1].copy()


class UnitPair(Multiplier):
    """A pair of Floquet multipliers on the unit circle, e^(+-i theta): a Neimark-Sacker.

    A = M (.) M - I, with M (.) M the bialternate product (Kuznetsov, Elements of Applied
    Bifurcation Theory, 3rd ed., sec. 10.2), whose eigenvalues are the products mu_i mu_j,
    i < j, of M's: singular where two multipliers' product is 1, a pair on the circle (or two
    real ones mu, 1 / mu: a neutral saddle, which the curve's multipliers tell apart). The
    same minimally augmented test function as a single multiplier's, on a matrix of order
    N (2 N - 1).
    """

    def __init__(self) -> None:
        super().__init__(1.0)
        self.label = "neimark_sacker"

    def matrix(self, monodromy: np.ndarray) -> np.ndarray:
        """M (.) M - I: rows and columns the pairs (p, q), p > q, entries 2 x 2 minors of M."""
        p, q = np.tril_indices(len(monodromy), -1)
        product = (monodromy[p][:, p] * monodromy[q][:, q]
                   - monodromy[p][:, q] * monodromy[q][:, p])
        return product - np.eye(p.size)


# the strong resonances of a Neimark-Sacker pair e^(+-i theta), at cos theta = 1 (1:1), -1 (1:2),
# -1/2 (1:3) and 0 (1:4) (Kuznetsov, sec. 9.5 and 10.3); at 1:1 and 1:2 the pair meets on the
# real axis, at +1 (the fold curve) or -1 (the period-doubling curve): the Neimark-Sacker curve
# ends there (past them M (.) M - I stays singular on a neutral saddle, mu and 1 / mu real)
RESONANCES = {"resonance_1_1": 1.0, "resonance_1_2": -1.0, "resonance_1_3": -0.5,
              "resonance_1_4": 0.0}
PAIR_TURNS_REAL = ("resonance_1_1", "resonance_1_2")


def critical_pair(multipliers: np.ndarray) -> tuple[int, int]:
    """The indices of the two multipliers whose product is nearest 1 (a Neimark-Sacker's pair)."""
    i, j = np.triu_indices(multipliers.size, 1)
    k = int(np.argmin(np.abs(multipliers[i] * multipliers[j] - 1.0)))
    return int(i[k]), int(j[k])


def pair_cosine(multipliers: np.ndarray) -> float:
    """(mu + mu') / 2 of the critical pair: cos theta on the circle, beyond +-1 where real.

    Continuous through a strong resonance 1:1 or 1:2, where the pair meets on the real axis
    (the pair's own argument has a square-root branch there).
    """
    i, j = critical_pair(multipliers)
    return float(0.5 * (multipliers[i] + multipliers[j]).real)


def other_multipliers(multipliers: np.ndarray) -> np.ndarray:
    """The multipliers but the critical pair."""
    return np.delete(multipliers, critical_pair(multipliers))


CONDITIONS = {"grazing": Grazing, "fold": lambda: Multiplier(1.0),
              "period_doubling": lambda: Multiplier(-1.0), "neimark_sacker": UnitPair}
KINDS = tuple(CONDITIONS)


def state_weights(period_map: SectionMaps) -> np.ndarray:
    """D with D z = (omega q, q'), the energy norm's coordinates."""
    from impactbeams.kernels.layout import FREE, ROW_FREQUENCY

    omega = period_map.packed.tables[FREE, ROW_FREQUENCY]
    return np.concatenate([omega, np.ones(omega.size)])


class CurveProblem:
    """The curve of ``condition`` in (``first``, ``second``) as a family in the second.

    The engine's state is y = (z, p1) (n + 1 values), its parameter p2; the residual is the
    orbit's P^p(z) - z (``period`` forcing periods) and the condition. ``n_modes`` per beam,
    the full monodromy (Newton: the curves are for models small enough that M is cheap).
    ``first_box``: p1's box (low, high), its scale where the start's p1 is 0.
    The evaluation's ``grazing`` is the orbit's grazing value for a multiplier's curve (its
    sign change is a codimension-two point: the bifurcating orbit touches), NaN for a grazing
    curve (there it is the condition itself); its multipliers are the orbit's.
    """

    def __init__(self, params: Params, first: str, second: str, n_modes: int, period: int,
                 condition: Grazing | Multiplier, first_box: tuple[float, float]) -> None:
        self.params, self.first, self.second = params, first, second
        self.n_modes, self.period, self.condition = n_modes, period, condition
        # p1's scale for its differences: its start's size, or where that is 0 (a mass, a
        # damping continued from none) its box's width, as a branch's parameter its range's
        self.first_scale = abs(parameter_value(params, first)) or first_box[1] - first_box[0]
        self._planes: dict[float, BeamOrbits] = {}

    def start(self, z: np.ndarray, p1: float) -> None:
        """Fit the condition to the start's orbit ``z`` at p1 and p2 (params') (`Grazing`)."""
        period_map = self.orbits(parameter_value(self.params, self.second)).period_map(p1)
        self.condition.start(period_map, period_map(z, measures=False))

    @property
    def followed_contact(self) -> int | None:
        """With several contacts, the one whose grazing a grazing curve follows; else None."""
        return (self.condition.contact if self.params.several_contacts
                and isinstance(self.condition, Grazing) else None)

    def orbits(self, p2: float) -> BeamOrbits:
        """The orbits of p1 at p2 (ParameterError if p2 is not allowed)."""
        if p2 not in self._planes:
            if len(self._planes) >= CACHED_PLANES:
                self._planes.pop(next(iter(self._planes)))
            params = with_parameter(self.params, self.second, p2)
            # (Newton's full monodromy: the subspace is unused, the smallest allowed)
            self._planes[p2] = BeamOrbits(params, self.first, self.n_modes, self.period,
                                          method="newton", subspace=GUARD + 1)
        return self._planes[p2]

    @property
    def gap_round_off(self) -> float:
        """How well a gap is known (m), as `BeamOrbits.gap_round_off`."""
        return self.orbits(parameter_value(self.params, self.second)).gap_round_off

    def evaluate(self, y: np.ndarray, p: float, jacobian: bool = True,
                 grazing: bool = True) -> Evaluation:
        """The residual (orbit, condition) at y = (z, p1) and p2 = ``p``; dr/dy if asked."""
        z, p1 = y[:-1], float(y[-1])
        orbits = self.orbits(p)
        period_map = orbits.period_map(p1)
        result = period_map(z, directions="all" if self.condition.needs_monodromy else None,
                            measures=False)
        drz = None if result.jacobian is None else result.jacobian - np.eye(z.size)
        condition = self.condition.value(period_map, result, drz)
        residual = np.append(result.state - z, condition)
        orbit_grazing = (grazing_value(period_map, period_map.approach(result))
                         if grazing and not isinstance(self.condition, Grazing) else math.nan)
        multipliers = np.empty(0) if drz is None else multipliers_of(drz)
        if not jacobian:
            return Evaluation(residual, np.empty((0, 0)), multipliers, orbit_grazing,
                              result.contacts, result.episodes)
        if drz is None:
            drz = period_map.jacobian(result, "all") - np.eye(z.size)
            multipliers = multipliers_of(drz)
        full = np.zeros((z.size + 1, z.size + 1))
        full[:-1, :-1] = drz
        full[:-1, -1], full[-1] = self._differences(orbits, z, p1, result)
        return Evaluation(residual, full, multipliers, orbit_grazing, result.contacts,
                          result.episodes)

    def _differences(self, orbits: BeamOrbits, z: np.ndarray, p1: float,
                     result: PeriodMapResult) -> tuple[np.ndarray, np.ndarray]:
        """dP/dp1 and the condition's gradient in (z, p1), by forward differences.

        Steps of ``PARAMETER_STEP`` times the orbit's size in each coordinate (the energy
        norm's) and times max(|p1|, ``first_scale``) in p1, where truncation and round-off
        balance.
        """
        period_map = orbits.period_map(p1)
        weights = state_weights(period_map)
        base = self.condition.probe(period_map, result)
        size = max(float(np.linalg.norm(weights * z)), np.finfo(float).tiny)
        gradient = np.empty(z.size + 1)
        for j in range(z.size):
            h = PARAMETER_STEP * size / weights[j]
            shifted = z.copy()
            shifted[j] += h
            gradient[j] = (self.condition.probe(period_map, period_map(shifted, measures=False))
                           - base) / h
        h = PARAMETER_STEP * max(abs(p1), self.first_scale)
        moved = orbits.period_map(p1 + h)
        other = moved(z, measures=False)
        gradient[-1] = (self.condition.probe(moved, other) - base) / h
        return (other.state - result.state) / h, gradient

    @staticmethod
    def parameter_derivative(problem: CurveProblem, y: np.ndarray, p: float, scale: float,
                             at: Evaluation) -> np.ndarray:
        """dr/dp2 by a forward difference from ``at``, as `problem.parameter_derivative`.

        Without its narrowing where the contacts differ: a grazing curve's orbits touch at
        zero depth, so that a contact comes or goes with every difference (the grazing value
        is continuous there, its slope changes: the difference steers Newton only).
        """
        h = PARAMETER_STEP * max(abs(p), scale)
        return (problem.evaluate(y, p + h, jacobian=False, grazing=False).residual
                - at.residual) / h

    def border(self, y: np.ndarray, p: float, evaluation: Evaluation) -> None:
        """Adapt the condition to the curve's point (y, p) (a multiplier's borders)."""
        period_map = self.orbits(p).period_map(float(y[-1]))
        self.condition.border(evaluation.jacobian[:-1, :-1], state_weights(period_map))

    def multipliers(self, y: np.ndarray, p: float) -> np.ndarray:
        """The orbit's Floquet multipliers at y = (z, p1) and p2 = ``p``, largest first.

        The corrector's are its last iterate's, within Newton's last correction of the point:
        on a fold curve up to 1e-7 from +1 where the point's own are 1e-12 from it.
        """
        period_map = self.orbits(p).period_map(float(y[-1]))
        result = period_map(y[:-1], directions="all", measures=False)
        return multipliers_of(result.jacobian - np.eye(y.size - 1))

    def measures(self, y: np.ndarray, p: float) -> Mapping[str, float | np.ndarray]:
        """The orbit's named measures at (z, p1) and p2 = ``p``."""
        return self.orbits(p).measures(y[:-1], float(y[-1]))
