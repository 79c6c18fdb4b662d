"""Writing results: netCDF files that are never left half-written."""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr


def write_netcdf(dataset: xr.Dataset, path: str | Path) -> None:
    """Write ``dataset`` to netCDF4 through a temporary file in the same folder, then rename.

    Coordinates get no ``_FillValue`` (CF: coordinate values are never missing).
    """
    path = Path(path)
    encoding = {name: {"_FillValue": None} for name in dataset.coords}
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        dataset.to_netcdf(temporary, engine="netcdf4", format="NETCDF4", encoding=encoding)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)
