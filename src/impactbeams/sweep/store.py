"""Finished chunks on disk, so that an interrupted sweep resumes where it stopped.

Each finished chunk is saved at once, atomically, under ``OUT.nc.partial/``, next to the netCDF
file being built there; a run that is interrupted (Ctrl-C or a killed process) loses no
finished chunk, and the same command resumes: it rebuilds the file from the saved chunks and
computes the others. A run is identified by the sweep's fingerprint and the digest of the code
that computes it (`code_digest`): chunks or finished files of
another sweep or of other code are never reused.
"""

from __future__ import annotations

import json
import shutil
import warnings
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import BinaryIO

import numpy as np

from impactbeams.io import write_npz, write_text
from impactbeams.params import ParameterError
from impactbeams.sweep.definition import Sweep
from impactbeams.sweep.plan import Chunking, code_digest

RECORD = "run.json"  # what the saved chunks belong to
# what reading a damaged .npz raises (truncated, overwritten, bits flipped, arrays missing)
_DAMAGE = (OSError, EOFError, ValueError, KeyError, zipfile.BadZipFile, zlib.error)


class ChunkStore:
    """Finished chunks of one run, saved one ``.npz`` file each, atomically, next to the output.

    ``run.json`` records the sweep's fingerprint, the code digest and the chunking. A resumed
    run must have the same sweep and code, and adopts the recorded chunking (chunk ``k`` must
    cover the same cells), unless ``chunk_cells`` (the caller's choice that gave ``chunking``)
    asks for another one: that is an error rather than ignored.
    """

    def __init__(self, output: Path, sweep: Sweep, chunking: Chunking,
                 chunk_cells: int | None) -> None:
        self.directory = output.with_name(output.name + ".partial")
        self.building = self.directory / output.name  # the netCDF file until it is complete
        identity = {"sweep": sweep.fingerprint(), "code": code_digest()}
        record = self.directory / RECORD
        if not self.directory.exists():
            self.directory.mkdir(parents=True)
            write_text(record, json.dumps({**identity, "chunk_axis": chunking.axis,
                                           "chunk_run": chunking.run}))
            self.chunking = chunking
            return
        saved, self.chunking = self._read(record, sweep.shape)
        if saved.get("sweep") != identity["sweep"]:
            raise ParameterError(f"{self.directory} holds a partial run of a different sweep: "
                                 "delete it or choose another output")
        if saved.get("code") != identity["code"]:
            raise ParameterError(
                f"{self.directory} holds a partial run computed by other impactbeams code (code "
                f"digest {saved.get('code')}, this code {identity['code']}): delete it to "
                "recompute with this code, or choose another output")
        if chunk_cells is not None and self.chunking != chunking:
            raise ParameterError(
                f"chunk_cells = {chunk_cells} is not allowed: the partial run in "
                f"{self.directory} was split into chunks of {self.chunking.cells} cells; "
                "resume with that size (or without choosing one)")

    def _read(self, record: Path, shape: tuple[int, ...]) -> tuple[dict, Chunking]:
        """The run record and its chunking; a ParameterError if this version cannot read it."""
        try:
            saved = json.loads(record.read_text())
            return saved, Chunking(shape, int(saved["chunk_axis"]), int(saved["chunk_run"]))
        except (OSError, ValueError, KeyError, TypeError):
            raise ParameterError(f"{self.directory} holds no partial run this impactbeams can "
                                 f"resume (no readable {RECORD}): delete it or choose another "
                                 "output") from None

    def _path(self, chunk: int) -> Path:
        return self.directory / f"chunk_{chunk:06d}.npz"

    def load(self, chunk: int, size: int, shapes: Mapping[str, tuple[int, ...]],
             discard_corrupt: bool = False) -> dict[str, np.ndarray] | None:
        """The saved arrays of a chunk of ``size`` cells, or None if it is not saved.

        ``shapes``: the arrays' names and the shape of one cell's value of each.

        A damaged file (truncated, not an ``.npz``, arrays missing or of the wrong size) is a
        ParameterError naming it; with ``discard_corrupt`` it is deleted instead (with a
        warning) and the chunk counts as not saved.
        """
        path = self._path(chunk)
        if not path.exists():
            return None
        try:
            with open(path, "rb") as stream:
                return _arrays(stream, size, shapes)
        except _DAMAGE as error:
            problem = f"{type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
            if not discard_corrupt:
                raise ParameterError(
                    f"saved chunk {path} is damaged ({problem}): run again with "
                    "--discard-corrupt (discard_corrupt=True) to recompute its cells, or delete "
                    f"{self.directory}") from None
            warnings.warn(f"discarded the damaged chunk {path} ({problem}); its cells are "
                          "computed again", RuntimeWarning, stacklevel=2)
            path.unlink()
            return None

    def save(self, chunk: int, values: dict[str, np.ndarray]) -> None:
        """Save a finished chunk atomically."""
        write_npz(self._path(chunk), values)

    def remove(self) -> None:
        """Delete the partial results once the final file is written."""
        shutil.rmtree(self.directory)


def _arrays(stream: BinaryIO, size: int,
            shapes: Mapping[str, tuple[int, ...]]) -> dict[str, np.ndarray]:
    """The float64 arrays of ``size`` cells in an open ``.npz`` file.

    Each cell has one value of ``shapes[name]`` in array ``name``.
    """
    archive = np.load(stream)
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise ValueError("an .npy array, not an .npz archive")
    with archive:
        values = {name: archive[name] for name in shapes}
    for name, array in values.items():
        expected = (size, *shapes[name])
        if array.shape != expected or array.dtype != np.float64:
            raise ValueError(f"{name} has {array.dtype} values of shape {array.shape}, "
                             f"expected float64 of shape {expected}")
    return values


def finished_output(output: Path, sweep: Sweep) -> bool:
    """Whether ``output`` already holds this sweep's result from this code (nothing to do).

    False if there is no file; a ParameterError if it holds anything else (another sweep, the
    same sweep from other code, not netCDF): an existing file is never silently reused or
    overwritten.
    """
    if not output.exists():
        return False
    import netCDF4

    if output.is_dir():
        raise ParameterError(f"output {output} is a folder: give a file name ending in .nc")
    try:
        with netCDF4.Dataset(output) as nc:
            found = {key: nc.getncattr(key) if key in nc.ncattrs() else None
                     for key in ("sweep_fingerprint", "code_digest")}
    except OSError as error:
        raise ParameterError(f"{output} exists and is not a netCDF file ({error}): delete it "
                             "or choose another output") from None
    if found["sweep_fingerprint"] != sweep.fingerprint():
        raise ParameterError(f"{output} exists and holds a different result: delete it or "
                             "choose another output")
    if found["code_digest"] != code_digest():
        raise ParameterError(
            f"{output} holds this sweep's result computed by other impactbeams code (code "
            f"digest {found['code_digest']}, this code {code_digest()}): delete it to recompute "
            "with this code, or choose another output")
    return True
