"""Finished chunks on disk, so that an interrupted sweep resumes where it stopped.

Each finished chunk is saved at once, atomically, under ``OUT.nc.partial/``; a run that is
interrupted (Ctrl-C or a killed process) loses no finished work, and the same command resumes
it. The final netCDF is written atomically too (:mod:`impactbeams.io`).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import xarray as xr

from impactbeams.io import write_npz, write_text
from impactbeams.params import ParameterError
from impactbeams.sweep.definition import Sweep


class ChunkStore:
    """Finished chunks of one sweep, saved one file each, atomically, next to the output.

    The store records the sweep's fingerprint and the chunk size: chunks are numbered, so a
    resumed run must split the grid the same way (it adopts the recorded size).
    """

    def __init__(self, output: Path, fingerprint: str, chunk_cells: int | None,
                 default_chunk_cells: int) -> None:
        self.directory = output.with_name(output.name + ".partial")
        stamp = self.directory / "fingerprint"
        if not self.directory.exists():
            self.directory.mkdir(parents=True)
            self.chunk_cells = chunk_cells or default_chunk_cells
            write_text(stamp, f"{fingerprint} {self.chunk_cells}")
            return
        found, _, size = (stamp.read_text().strip() if stamp.exists() else "(none)").partition(" ")
        if found != fingerprint or not size.isdigit():
            raise ParameterError(
                f"{self.directory} holds a partial run of a different sweep (fingerprint "
                f"{found}, this sweep {fingerprint}): delete it or choose another output")
        if chunk_cells is not None and chunk_cells != int(size):
            raise ParameterError(
                f"chunk_cells = {chunk_cells} is not allowed: the partial run in "
                f"{self.directory} was split into chunks of {size} cells; resume with that "
                "size (or without choosing one)")
        self.chunk_cells = int(size)

    def _path(self, chunk: int) -> Path:
        return self.directory / f"chunk_{chunk:06d}.npz"

    def load(self, chunk: int) -> dict[str, np.ndarray] | None:
        """The saved results of a chunk, or None if it is not finished."""
        path = self._path(chunk)
        if not path.exists():
            return None
        with np.load(path) as data:
            return {name: data[name] for name in data.files}

    def save(self, chunk: int, values: dict[str, np.ndarray]) -> None:
        """Save a finished chunk atomically."""
        write_npz(self._path(chunk), values)

    def remove(self) -> None:
        """Delete the partial results once the final file is written."""
        shutil.rmtree(self.directory)


def finished_output(output: Path, sweep: Sweep) -> xr.Dataset | None:
    """The existing result of this very sweep at ``output``, or None if there is none."""
    if not output.exists():
        return None
    with xr.open_dataset(output) as existing:
        if existing.attrs.get("sweep_fingerprint") == sweep.fingerprint():
            return existing.load()
    raise ParameterError(f"{output} exists and holds a different result: delete it or choose "
                         "another output")
