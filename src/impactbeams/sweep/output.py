"""The map of a sweep: one array per observable over the swept axes, in memory or on disk.

`map_layout` is what both forms hold (coordinates, variables, attributes);
`map_dataset` builds the in-memory Dataset, `map_file` fills the netCDF file
chunk by chunk, never holding the whole map.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.io import Layout, build_netcdf, writing_netcdf
from impactbeams.params import (
    MATERIAL_KEYS,
    element_field,
    named_attributes,
    without_unused_law_keys,
)
from impactbeams.sweep.definition import (
    FIRST_IMPACT,
    LONG_TIME_KEYS,
    Sweep,
)
from impactbeams.sweep.plan import Chunking, code_digest, contact_resolution, flat_boxes
from impactbeams.variables import (
    VARIABLES,
    attributes,
    check_variables,
    global_attributes,
)

if TYPE_CHECKING:
    import xarray as xr

ChunkWriter = Callable[[int, int, Mapping[str, np.ndarray]], None]


def map_layout(sweep: Sweep, chunks: tuple[int, ...] | None = None) -> Layout:
    """The map's coordinates, variables and attributes; ``chunks``: its blocks on disk."""
    coords = {} if sweep.stepping is None else {
        "sweep_direction": (np.array(sweep.stepping.directions), attributes("sweep_direction"))}
    coords.update({axis.name: (axis.values, {**named_attributes(axis.name),
                                             "scale": axis.scale}) for axis in sweep.axes})
    grid = tuple(coords)
    variables = {name: (dtype, attributes(name), grid + VARIABLES[name].dims[1:])
                 for name, (dtype, _) in cell_values(sweep).items()}
    if FIRST_IMPACT in sweep.stored:
        variables["impacted"] = (_dtype("impacted"), attributes("impacted"), grid)
    run = {"t_max": sweep.t_max, "t_max_units": "s", "n_modes": sweep.n_modes,
           "observables": " ".join(sweep.observables), "swept_parameters": " ".join(coords),
           "sweep_definition": json.dumps(sweep.definition(), sort_keys=True),
           "sweep_fingerprint": sweep.fingerprint(), "code_digest": code_digest()}
    if sweep.long_time is not None:
        long_time = sweep.long_time
        run.update({key: getattr(long_time, key) for key in LONG_TIME_KEYS},
                   transient_periods=sweep.transient_periods)
        if sweep.stepping is not None:
            run.update(stepping=sweep.stepping.direction, stepped_axis=sweep.stepping.axis)
        if any("period" in dims for _, _, dims in variables.values()):
            coords["period"] = (long_time.period_numbers(sweep.transient_periods).astype(
                _dtype("period"), copy=False), attributes("period"))
        if any("coordinate" in dims for _, _, dims in variables.values()):
            coords["coordinate"] = (np.arange(sweep.free_coordinates, dtype=_dtype(
                "coordinate")), attributes("coordinate"))
    if any("contact" in dims for _, _, dims in variables.values()):
        coords["contact"] = (np.arange(sweep.value_shape("contact_max_force")[0],
                                       dtype=_dtype("contact")), attributes("contact"))
    resolution = contact_resolution(sweep)
    if resolution is not None:
        run.update(contact_resolved=int(sweep.n_modes >= resolution),
                   contact_resolution_modes=resolution)
    attrs = global_attributes("impactbeams parameter sweep", f"run {sweep.source}",
                              _fixed_parameters(sweep), **run)
    layout = Layout(coords, variables, attrs, chunks or sweep.shape)
    check_variables(layout.described())  # the map in memory and its file: as registered
    return layout


def cell_values(sweep: Sweep) -> dict[str, tuple[np.dtype, tuple[int, ...]]]:
    """Each array a chunk of ``sweep`` yields: its dtype and the shape of one cell's value.

    The dtype is the registered one (variables.VARIABLES): the map in memory, its file and the
    saved chunks all hold it.
    """
    return {name: (_dtype(name), sweep.value_shape(name)) for name in sweep.stored}


def _dtype(name: str) -> np.dtype:
    return np.dtype(VARIABLES[name].dtype)


def stored_arrays(sweep: Sweep, values: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The map's variables over some cells, from the computed values of those cells."""
    arrays = {name: values[name].astype(dtype, copy=False)
              for name, (dtype, _) in cell_values(sweep).items()}
    if FIRST_IMPACT in values:
        arrays["impacted"] = np.isfinite(values[FIRST_IMPACT]).astype(_dtype("impacted"))
    return arrays


def map_dataset(sweep: Sweep, results: Mapping[str, np.ndarray]) -> xr.Dataset:
    """The in-memory Dataset of ``sweep`` from its flat ``results`` (one array of all cells)."""
    import xarray as xr

    layout = map_layout(sweep)
    arrays = stored_arrays(sweep, results)
    data_vars = {name: (dims, arrays[name].reshape(sweep.shape + arrays[name].shape[1:]), attrs)
                 for name, (_, attrs, dims) in layout.variables.items()}
    coords = {name: (name, values, attrs) for name, (values, attrs) in layout.coords.items()}
    return xr.Dataset(data_vars, coords=coords, attrs=layout.attrs)


@contextlib.contextmanager
def map_file(sweep: Sweep, path: Path, building: Path,
             chunking: Chunking) -> Iterator[ChunkWriter]:
    """Build the netCDF file of ``sweep`` at ``building`` and yield ``write(start, stop, values)``.

    ``write`` stores the computed values of the flat cells start..stop; each chunk of
    ``chunking`` is one compressed block of the file. On a normal exit the file is renamed to
    ``path`` (see `impactbeams.io.build_netcdf`).
    """
    with build_netcdf(path, building, map_layout(sweep, chunking.box)) as nc:
        def write(start: int, stop: int, values: Mapping[str, np.ndarray]) -> None:
            arrays, offset = stored_arrays(sweep, values), 0
            for box in flat_boxes(start, stop, sweep.shape):
                shape = tuple(s.stop - s.start for s in box)
                size = math.prod(shape)
                for name, array in arrays.items():  # a sampled observable: all its samples
                    block = array[offset:offset + size].reshape(shape + array.shape[1:])
                    with writing_netcdf(building):
                        nc[name][box] = block
                offset += size

        yield write


def _fixed_parameters(sweep: Sweep) -> dict[str, float]:
    """The parameters no axis changes (a swept material key makes EI_i and rhoA_i vary).

    Beside several contacts, not the law keys every contact gives its own of (or sweeps); the
    contacts or parts with a swept field as given (a part's table without it).
    """
    swept = {axis.name for axis in sweep.axes}
    for i in ("1", "2"):
        if any(k + i in swept for k in MATERIAL_KEYS):
            swept |= {"EI" + i, "rhoA" + i}
    fixed = without_unused_law_keys(sweep.base.as_dict())
    for name in swept:  # as given: the swept fields' values are the coordinates, left out here
        field = element_field(name)
        if field is not None:
            fixed[field[0]] = tuple(sweep.fixed[field[0]])
    return {name: value for name, value in fixed.items() if name not in swept}
