"""A periodic orbit as an xarray Dataset: one period of its run, with its multipliers."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from impactbeams.trajectory.simulation import simulate
from impactbeams.variables import attributes, validate

if TYPE_CHECKING:
    from impactbeams.orbits.shooting import PeriodicOrbit


def orbit_dataset(orbit: PeriodicOrbit, samples_per_period: int) -> xr.Dataset:
    """`simulate` over [0, p T] from the orbit's section state, with its multipliers."""
    # the orbit's state replaces the run's start (uplifts and start="steady" belong to a guess)
    params = orbit.params.replace(start="rest", uplift1=0.0, uplift2=0.0)
    times = np.linspace(0.0, orbit.duration, samples_per_period * orbit.period + 1)
    dataset = simulate(params, orbit.duration, orbit.n_modes, times=times,
                       initial_state=orbit.state)
    dataset = dataset.assign_coords(multiplier=("multiplier",
                                                np.arange(orbit.multipliers.size),
                                                attributes("multiplier")))
    for name, values in (("floquet_multiplier_real", orbit.multipliers.real),
                         ("floquet_multiplier_imag", orbit.multipliers.imag),
                         ("floquet_exponent", orbit.exponents)):
        dataset[name] = ("multiplier", values, attributes(name))
    dataset.attrs.update({"orbit_period": orbit.period, "orbit_stable": int(orbit.stable),
                          "orbit_residual": orbit.residual,
                          "orbit_iterations": orbit.iterations, "orbit_method": orbit.method,
                          "orbit_contacts": orbit.contacts, "orbit_episodes": orbit.episodes})
    validate(dataset)
    return dataset
