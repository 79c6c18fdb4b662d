"""Periodic orbits of the spring law: the period map, shooting, Floquet multipliers.

`period_map`: the period map P^p with its exact Jacobian (`contacts_map`: several contacts');
`shooting`: periodic orbits by Newton (and Newton-Picard) on z = P^p(z);
`grazing`: the non-impacting orbit's smallest gap and grazing curves, in closed form;
`basin_map`: basins of attraction, the attractors runs settle on (cells: `basin_cells`).
"""

from impactbeams.orbits.basin_cells import Settling
from impactbeams.orbits.basin_map import basin_stability, basins
from impactbeams.orbits.contacts_map import ContactsPeriodMap
from impactbeams.orbits.grazing import (
    GRAZING_PARAMETERS,
    SteadyGap,
    grazing_curve,
    grazing_frequencies,
    steady_gap,
)
from impactbeams.orbits.period_map import PeriodMap, PeriodMapResult
from impactbeams.orbits.shooting import OrbitNotConverged, PeriodicOrbit, periodic_orbit

__all__ = ["GRAZING_PARAMETERS", "ContactsPeriodMap", "OrbitNotConverged", "PeriodMap",
           "PeriodMapResult", "PeriodicOrbit", "Settling", "SteadyGap", "basin_stability", "basins",
           "grazing_curve", "grazing_frequencies", "periodic_orbit", "steady_gap"]
