"""Writing results: files that are never left half-written (netCDF, text, npz).

Every writer goes through `atomic_write` or `build_netcdf`: write a temporary
file, then rename it over the target, so a reader sees the old file or the whole new one.
netCDF variables of numbers are compressed (`COMPRESSION`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import netCDF4
    import xarray as xr

# zlib level 4 after the byte shuffle (HDF5 filters): the Fig. 5a map's 9.0 MB become 2.1 MB
# (2.06 bytes per float64 cell), at about 80 ms per million cells. Measured by
# benchmarks/bench_cube.py --compression (docs/benchmarks/compression.json): level 1 is 2 %
# larger on that map (19 % on a cube plane) and not clearly faster, level 9 1 % smaller in 2-3
# times the time, no shuffle 27 % larger. float32 would be 2.7 times smaller but rounds t* to
# 6e-8 of its value, where the kernels resolve it to a few ulps of float64: kept float64.
COMPRESSION = {"zlib": True, "complevel": 4, "shuffle": True}


@contextlib.contextmanager
def _temporary_for(path: Path) -> Iterator[Path]:
    """A temporary name next to ``path`` (hidden, never matching the target's pattern)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        yield temporary
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def atomic_write(path: str | Path, write: Callable[[Path], None]) -> None:
    """Call ``write(temporary)`` to fill a temporary file, then rename it to ``path``."""
    with _temporary_for(Path(path)) as temporary:
        write(temporary)


def _compressible(dtype: np.dtype) -> bool:
    """Whether HDF5 can compress a variable of ``dtype`` (numbers; not strings)."""
    return dtype.kind in "fiub"


def write_netcdf(dataset: xr.Dataset, path: str | Path) -> None:
    """Write ``dataset`` to netCDF4 atomically, its numeric data variables compressed.

    Coordinates get no ``_FillValue`` (CF: coordinate values are never missing).
    """
    encoding: dict[str, dict[str, Any]] = {name: {"_FillValue": None} for name in dataset.coords}
    encoding.update({name: dict(COMPRESSION) for name, variable in dataset.data_vars.items()
                     if variable.ndim and _compressible(variable.dtype)})
    atomic_write(path, lambda temporary: dataset.to_netcdf(
        temporary, engine="netcdf4", format="NETCDF4", encoding=encoding))


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    atomic_write(path, lambda temporary: temporary.write_text(text))


def write_npz(path: str | Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Write ``arrays`` to an uncompressed ``.npz`` file atomically."""
    def save(temporary: Path) -> None:
        with open(temporary, "wb") as stream:  # a file object: np.savez adds no suffix
            np.savez(stream, **arrays)

    atomic_write(path, save)


@dataclasses.dataclass(frozen=True)
class Layout:
    """What a gridded netCDF file holds before its data.

    ``coords``: one 1-D coordinate per dimension (values, attributes), the grid's dimensions
    first; ``variables``: (dtype, attributes, dimensions) of the data variables, stored
    compressed in blocks of ``chunks`` along the grid's dimensions (the first ``len(chunks)``)
    and whole along any other; ``attrs``: global attributes.
    Floating-point variables get ``_FillValue = NaN``, as xarray writes them.
    """

    coords: Mapping[str, tuple[np.ndarray, Mapping[str, Any]]]
    variables: Mapping[str, tuple[np.dtype, Mapping[str, Any], tuple[str, ...]]]
    attrs: Mapping[str, Any]
    chunks: tuple[int, ...]


@contextlib.contextmanager
def build_netcdf(path: str | Path, building: str | Path,
                 layout: Layout) -> Iterator[netCDF4.Dataset]:
    """Create the netCDF4 file ``building`` with ``layout`` and yield it to be filled.

    On a normal exit the file is closed and renamed to ``path``; on an error (or interrupt)
    it is deleted and ``path`` is left as it was. Fill it box by box (``nc[name][box] =
    values``) with boxes of ``layout.chunks``: each one is then compressed once.
    """
    import netCDF4

    building = Path(building)
    building.parent.mkdir(parents=True, exist_ok=True)
    nc = netCDF4.Dataset(building, "w", format="NETCDF4")
    try:
        _define(nc, layout)
        yield nc
        nc.close()
        os.replace(building, path)
    finally:
        if nc.isopen():
            nc.close()
        building.unlink(missing_ok=True)


def _define(nc: netCDF4.Dataset, layout: Layout) -> None:
    """The dimensions, coordinates, variables and attributes of ``layout`` in ``nc``."""
    for name, (values, attrs) in layout.coords.items():
        nc.createDimension(name, values.size)
        text = values.dtype.kind in "US"  # a categorical axis: variable-length strings
        coordinate = nc.createVariable(name, str if text else values.dtype, (name,))
        coordinate.setncatts(dict(attrs))
        coordinate[:] = values.astype(object) if text else values
    block = dict(zip(layout.coords, layout.chunks, strict=False))  # the grid: coords first
    for name, (dtype, attrs, dims) in layout.variables.items():
        fill = np.nan if np.dtype(dtype).kind == "f" else None
        chunks = tuple(block.get(dim, layout.coords[dim][0].size) for dim in dims)
        variable = nc.createVariable(name, dtype, dims, fill_value=fill, chunksizes=chunks,
                                     **COMPRESSION)
        variable.setncatts(dict(attrs))
    nc.setncatts(dict(layout.attrs))
