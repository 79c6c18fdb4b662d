"""The map Dataset of a sweep: one array per observable over the swept axes."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from impactbeams.params import MATERIAL_KEYS
from impactbeams.sweep.definition import FIRST_IMPACT, LONG_TIME_KEYS, Sweep
from impactbeams.sweep.plan import contact_resolution
from impactbeams.variables import attributes, global_attributes, parameter_attributes

_INTEGER_TYPES = {"dynamics_status": np.int8, "impact_count": np.int32,  # codes and counts
                  "response_period": np.int32}


def map_dataset(sweep: Sweep, results: dict[str, np.ndarray]) -> xr.Dataset:
    """The Dataset of ``sweep`` from its flat ``results`` (one array of all cells each)."""
    dims = [axis.name for axis in sweep.axes]
    coords = {axis.name: (axis.name, axis.values,
                          {**parameter_attributes(axis.name), "scale": axis.scale})
              for axis in sweep.axes}
    extra = {name: sweep.value_shape(name) for name in results}
    data_vars = {name: ([*dims, *(["period"] if extra[name] else [])],
                        values.astype(_INTEGER_TYPES.get(name, values.dtype))
                        .reshape(sweep.shape + extra[name]), attributes(name))
                 for name, values in results.items()}
    if FIRST_IMPACT in results:
        impacted = np.isfinite(results[FIRST_IMPACT]).astype(np.int8).reshape(sweep.shape)
        data_vars["impacted"] = (dims, impacted, attributes("impacted"))
    run = {"t_max": sweep.t_max, "t_max_units": "s", "n_modes": sweep.n_modes,
           "observables": " ".join(sweep.observables), "swept_parameters": " ".join(dims),
           "sweep_definition": json.dumps(sweep.definition(), sort_keys=True),
           "sweep_fingerprint": sweep.fingerprint()}
    if sweep.long_time is not None:
        long_time = sweep.long_time
        run.update({key: getattr(long_time, key) for key in LONG_TIME_KEYS},
                   transient_periods=sweep.transient_periods)
        if any(extra.values()):
            coords["period"] = ("period", long_time.period_numbers(sweep.transient_periods),
                                attributes("period"))
    resolution = contact_resolution(sweep)
    if resolution is not None:
        run.update(contact_resolved=int(sweep.n_modes >= resolution),
                   contact_resolution_modes=resolution)
    attrs = global_attributes("impactbeams parameter sweep", f"run {sweep.source}",
                              _fixed_parameters(sweep), **run)
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _fixed_parameters(sweep: Sweep) -> dict[str, float]:
    """The parameters no axis changes (a swept material key makes EI_i and rhoA_i vary)."""
    swept = {axis.name for axis in sweep.axes}
    for i in ("1", "2"):
        if any(k + i in swept for k in MATERIAL_KEYS):
            swept |= {"EI" + i, "rhoA" + i}
    return {name: value for name, value in sweep.base.as_dict().items() if name not in swept}
