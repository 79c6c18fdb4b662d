"""Writing results: files that are never left half-written (netCDF, text, npz).

Every writer goes through :func:`atomic_write`: write a temporary file in the same folder,
then rename it over the target, so a reader sees the old file or the whole new one.
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import xarray as xr


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


def write_netcdf(dataset: xr.Dataset, path: str | Path) -> None:
    """Write ``dataset`` to netCDF4 atomically.

    Coordinates get no ``_FillValue`` (CF: coordinate values are never missing).
    """
    encoding = {name: {"_FillValue": None} for name in dataset.coords}
    atomic_write(path, lambda temporary: dataset.to_netcdf(
        temporary, engine="netcdf4", format="NETCDF4", encoding=encoding))


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    atomic_write(path, lambda temporary: temporary.write_text(text))


def write_npz(path: str | Path, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` to an uncompressed ``.npz`` file atomically."""
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    atomic_write(path, lambda temporary: temporary.write_bytes(buffer.getvalue()))
