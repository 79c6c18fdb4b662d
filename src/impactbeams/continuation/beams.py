"""The beams' periodic orbits as a continuation problem: r(z, p) = P^p(z) - z.

``P^p`` is the exact period map of the spring law (`impactbeams.orbits.PeriodMap`) at the
parameters with the continued one set to p; dr/dz is its monodromy minus the identity, carried
by the tangent kernel with saltation. The grazing value is signed: the smallest local minimum of
the gap in free flight (> 0) or minus the overlap of the shallowest contact, its peak force
over the contact stiffness (< 0), whichever is nearer 0: it passes through 0 where a contact
appears or vanishes (a free-flight minimum that touches becomes a contact with a small
overlap).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from impactbeams.continuation.problem import Evaluation
from impactbeams.kernels.layout import FREE, ROW_FREQUENCY, TIP_Y1
from impactbeams.orbits import ContactsPeriodMap, PeriodMap, PeriodMapResult
from impactbeams.orbits.contacts_map import make_period_map
from impactbeams.orbits.period_map import CELL_ONLY
from impactbeams.orbits.shooting import (
    by_modulus,
    checked_method,
    checked_subspace,
    leading,
    orthonormal,
)
from impactbeams.params import Params, parameter_value, with_parameter

# the round-off of a gap read from a run (m, per metre of clearance): a gap is the clearance
# less the tips' deflections, each to a few eps of itself (measured: 1e-19 m at 5e-4 m)
GAP_ROUND_OFF = 1e3 * np.finfo(float).eps
CACHED_MAPS = 8  # period maps kept by parameter value (a corrector asks for 3 values a step)


class BeamOrbits:
    """Periodic orbits of ``period`` forcing periods of ``params`` with ``parameter`` = p.

    ``method``: how dr/dz is formed, as `periodic_orbit`'s: "newton" (the full monodromy,
    2 N tangent columns), "newton-picard" (M exactly on a carried basis V of ``subspace``
    directions and on the residual's component outside it, 0 on the rest: m + 1 columns) or
    "auto" (Newton up to `shooting.AUTO_NEWTON_DIMENSION` coordinates). With Newton-Picard the
    multipliers are the leading Ritz values of V^T M V (the bifurcations' test functions only
    need those near the unit circle) and V takes one subspace iteration per evaluation, from
    point to point along the branch.
    """

    def __init__(self, params: Params, parameter: str, n_modes: int, period: int = 1,
                 method: str = "auto", subspace: int | None = None) -> None:
        self.params, self.parameter, self.n_modes, self.period = (
            params, parameter, n_modes, period)
        self._maps: dict[float, PeriodMap | ContactsPeriodMap] = {}
        self._last: tuple[float, bytes, PeriodMapResult] | None = None
        # the other maps of a cell's parameter are built on its geometry (`PeriodMap.at`)
        self._origin = make_period_map(params, n_modes=n_modes, periods=period)
        dimension = self._origin.dimension
        self.method = checked_method(method, dimension)
        self.subspace = checked_subspace(subspace, dimension)
        self.basis: np.ndarray | None = None  # V: orthonormal in the energy coordinates
        self._warned = False

    @property
    def gap_round_off(self) -> float:
        """How well a gap (the grazing or interval value) is known (m): below it, round-off."""
        return GAP_ROUND_OFF * max(run.clearance for run in self.params.each_contact())

    @property
    def approximate(self) -> bool:
        """Whether dr/dz is Newton-Picard's approximation (the engine then keeps dr/dp)."""
        return self.method == "newton-picard"

    def period_map(self, p: float) -> PeriodMap | ContactsPeriodMap:
        """The period map at parameter value ``p`` (ParameterError if not allowed)."""
        if p not in self._maps:
            if len(self._maps) >= CACHED_MAPS:
                self._maps.pop(next(iter(self._maps)))
            params = with_parameter(self.params, self.parameter, p)
            self._maps[p] = (self._origin.at(params) if self.parameter in CELL_ONLY
                             else make_period_map(params, self.n_modes, self.period))
        return self._maps[p]

    def evaluate(self, z: np.ndarray, p: float, jacobian: bool = True,
                 grazing: bool = True) -> Evaluation:
        """r(z, p), the contacts, and what is asked.

        With dr/dz and the multipliers if ``jacobian``; with the orbit's grazing value if
        ``grazing``.
        """
        period_map = self.period_map(p)
        result = self._run(period_map, z, p, grazing)
        residual = result.state - z
        value = grazing_value(period_map, result) if grazing else math.nan
        interval = result.interval_gap if grazing else math.nan
        if not jacobian:
            return Evaluation(residual, np.empty((0, 0)), np.empty(0), value, result.contacts,
                              result.episodes, interval=interval)
        if self.method == "newton":
            # the multipliers are the corrector's to compute, at the point it finds only
            drz, multipliers = period_map.jacobian(result, "all") - np.eye(len(z)), None
        else:
            drz, multipliers = self._subspace_jacobian(period_map, result, residual)
        return Evaluation(residual, drz, multipliers, value, result.contacts, result.episodes,
                          interval=interval)

    def measures(self, z: np.ndarray, p: float) -> dict[str, float | np.ndarray]:
        """The orbit's named measures (`orbit_measures`) at (z, p)."""
        period_map = self.period_map(p)
        result = period_map.measured(self._run(period_map, z, p, True))
        self._last = (p, z.tobytes(), result)
        return orbit_measures(period_map, result)

    def _run(self, period_map: PeriodMap, z: np.ndarray, p: float,
             grazing: bool) -> PeriodMapResult:
        """The map's run from z, the last one again if it is the same (a point's measures).

        What a grazing value needs (`PeriodMap.approach`) is read from the run if asked; of
        the last run, without running it again.
        """
        key = z.tobytes()
        if self._last is not None and self._last[:2] == (p, key):
            result = self._last[2]
        else:
            result = period_map(z, measures=False)
        if grazing:
            result = period_map.approach(result)
        self._last = (p, key, result)
        return result

    def _subspace_jacobian(self, period_map: PeriodMap, result: PeriodMapResult,
                           residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Newton-Picard's dr/dz and the leading Ritz values; V advanced one iteration.

        M is applied exactly to V and to the residual's direction outside span V (so that the
        corrector is Newton on that span and Picard, M ~ 0, on the contracting rest).
        """
        w = self.state_weights()
        v = self._current_basis(len(residual))
        r = w * residual
        outside = r - v @ (v.T @ r)
        size = np.linalg.norm(outside)
        columns = v if size <= 1e-14 * max(np.linalg.norm(r), 1e-300) else np.column_stack(
            [v, outside / size])
        images = w[:, None] * period_map.jacobian(result, columns / w[:, None])
        m = v.shape[1]
        ritz = by_modulus(np.linalg.eigvals(v.T @ images[:, :m]))
        self._check_complement(ritz)
        self.basis = orthonormal(images[:, :m])
        drz = (images @ columns.T) / w[:, None] * w[None, :] - np.eye(len(residual))
        return drz, ritz[:leading(ritz)]

    def _current_basis(self, size: int) -> np.ndarray:
        if self.basis is None or self.basis.shape != (size, self.subspace):
            # fixed pseudo-random directions: the same branch on every machine
            self.basis = orthonormal(np.random.default_rng(0).standard_normal(
                (size, self.subspace)))
        return self.basis

    def _check_complement(self, ritz: np.ndarray) -> None:
        """Warn when span V may leave a multiplier on or outside the unit circle out.

        Subspace iteration converges to the m dominant multipliers' space, so the complement's
        are at most |mu_m|, the smallest Ritz value's modulus: below 1, none of them can
        cross the unit circle and the subspace's multipliers decide every bifurcation.
        """
        if abs(ritz[-1]) >= 1.0 and not self._warned:
            self._warned = True
            warnings.warn(f"newton-picard: the smallest of the {ritz.size} Ritz values has "
                          f"modulus {abs(ritz[-1]):.3g} >= 1: a multiplier outside the "
                          "subspace may cross the unit circle unseen (raise subspace, or use "
                          "method='newton')", RuntimeWarning, stacklevel=2)

    def start_basis(self, basis: np.ndarray | None) -> None:
        """Carry a periodic orbit's Newton-Picard basis (free coordinates) as V."""
        if basis is not None and basis.shape[1] == self.subspace:
            self.basis = orthonormal(self.state_weights()[:, None] * basis)

    def iterated(self, times: int) -> BeamOrbits:
        """The orbits of ``times`` times the period."""
        return BeamOrbits(self.params, self.parameter, self.n_modes, self.period * times,
                          self.method, self.subspace)

    def state_weights(self) -> np.ndarray:
        """D with D z = (omega q, q'): the energy norm's coordinates (one per component)."""
        packed = self.period_map(parameter_value(self.params, self.parameter)).packed
        omega = packed.tables[FREE, ROW_FREQUENCY]
        return np.concatenate([omega, np.ones(omega.size)])


def grazing_value(period_map: PeriodMap | ContactsPeriodMap, result: PeriodMapResult,
                  ) -> float:
    """The signed grazing value (m): see the module's docstring; NaN if neither exists."""
    return period_map.grazing_value(result)


def orbit_measures(period_map: PeriodMap, result: PeriodMapResult,
                   ) -> dict[str, float | np.ndarray]:
    """The amplitude measures of the registry (impactbeams.variables) of one orbit.

    ``section_deflection_1``: the orbit's p stroboscopic samples of y1, at t = k T, k < p.
    What a shaker's user reads: beam 1's tip amplitude absolute (``tip_amplitude_1``) and
    relative to its clamp (``tip_relative_amplitude_1``), the absolute one over the base
    amplitude (``transmissibility``, NaN without base motion), the largest closing speed of
    the gap at a contact's onset (``max_impact_velocity``, 0 without contact) and the largest
    contact force (``peak_contact_force``); the contacts per orbit are the evaluation's own.
    """
    # the tips on the sections by the period map's own sampling of its run
    sections = period_map.forcing_period * np.arange(period_map.periods)
    section = period_map.tip_motions(result, sections)[:, TIP_Y1]
    base = period_map.params.base_amplitude
    return {"tip_amplitude_1": result.max_tip1, "tip_amplitude_2": result.max_tip2,
            "tip_relative_amplitude_1": result.max_relative_tip1,
            "transmissibility": result.max_tip1 / base if base > 0 else math.nan,
            "max_impact_velocity": float(np.max(-result.impact_velocities, initial=0.0)),
            "peak_contact_force": result.peak_force,
            "contact_impulse": result.impulse / period_map.periods,
            "section_deflection_1": section}
