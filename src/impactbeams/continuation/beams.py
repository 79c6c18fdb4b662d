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

import numpy as np

from impactbeams.continuation.problem import Evaluation, multipliers_of
from impactbeams.kernels.layout import FREE, ROW_FREQUENCY, TIP_Y1
from impactbeams.orbits import PeriodMap, PeriodMapResult
from impactbeams.params import Params
from impactbeams.trajectory.impacts import impact_table

CACHED_MAPS = 8  # period maps kept by parameter value (a corrector asks for 3 values a step)


class BeamOrbits:
    """Periodic orbits of ``period`` forcing periods of ``params`` with ``parameter`` = p."""

    def __init__(self, params: Params, parameter: str, n_modes: int, period: int = 1) -> None:
        self.params, self.parameter, self.n_modes, self.period = (
            params, parameter, n_modes, period)
        self._maps: dict[float, PeriodMap] = {}

    def period_map(self, p: float) -> PeriodMap:
        """The period map at parameter value ``p`` (ParameterError if not allowed)."""
        if p not in self._maps:
            if len(self._maps) >= CACHED_MAPS:
                self._maps.pop(next(iter(self._maps)))
            self._maps[p] = PeriodMap(self.params.replace(**{self.parameter: p}),
                                      n_modes=self.n_modes, periods=self.period)
        return self._maps[p]

    def evaluate(self, z: np.ndarray, p: float, jacobian: bool = True,
                 measures: bool = True) -> Evaluation:
        """r(z, p); with the monodromy if ``jacobian``, the orbit's measures if ``measures``."""
        period_map = self.period_map(p)
        result = period_map(z, directions="all" if jacobian else None, measures=measures)
        residual = result.state - z
        if not jacobian:
            return Evaluation(residual, np.empty((0, 0)), np.empty(0),
                              grazing_value(period_map, result) if measures else math.nan,
                              result.contacts)
        drz = result.jacobian - np.eye(len(z))
        return Evaluation(residual, drz, multipliers_of(drz),
                          grazing_value(period_map, result) if measures else math.nan,
                          result.contacts, orbit_measures(period_map, result))

    def iterated(self, times: int) -> BeamOrbits:
        """The orbits of ``times`` times the period."""
        return BeamOrbits(self.params, self.parameter, self.n_modes, self.period * times)

    def state_weights(self) -> np.ndarray:
        """D with D z = (omega q, q'): the energy norm's coordinates (one per component)."""
        packed = self.period_map(getattr(self.params, self.parameter)).packed
        omega = packed.tables[FREE, ROW_FREQUENCY]
        return np.concatenate([omega, np.ones(omega.size)])


def grazing_value(period_map: PeriodMap, result: PeriodMapResult) -> float:
    """The signed grazing value (m): see the module's docstring; NaN if neither exists."""
    candidates = [result.min_gap] if math.isfinite(result.min_gap) else []
    if result.contacts:
        peaks = impact_table(period_map.packed, result.trajectory)["impact_peak_force"]
        candidates.append(-float(np.min(peaks)) / period_map.params.contact_stiffness)
    return min(candidates, key=abs) if candidates else math.nan


def orbit_measures(period_map: PeriodMap, result: PeriodMapResult) -> dict[str, float]:
    """The amplitude measures of the registry (impactbeams.variables) of one orbit."""
    # the tips at t = 0 by the period map's own sampling of its run (the section's y1)
    section = period_map._tips(result.trajectory, np.zeros(1))[0, TIP_Y1]
    return {"tip_amplitude_1": result.max_tip1, "tip_amplitude_2": result.max_tip2,
            "peak_contact_force": result.peak_force,
            "contact_impulse": result.impulse / period_map.periods,
            "section_deflection_1": float(section)}
