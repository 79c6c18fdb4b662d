"""Periodic orbits of the spring law: the period map, shooting, Floquet multipliers.

`period_map`: the period map P^p with its exact
Jacobian; `shooting`: periodic orbits by Newton (and Newton-Picard) on z = P^p(z).
"""

from impactbeams.orbits.period_map import PeriodMap, PeriodMapResult
from impactbeams.orbits.shooting import OrbitNotConverged, PeriodicOrbit, periodic_orbit

__all__ = ["OrbitNotConverged", "PeriodMap", "PeriodMapResult", "PeriodicOrbit",
           "periodic_orbit"]
