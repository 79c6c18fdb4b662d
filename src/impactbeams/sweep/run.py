"""Running a sweep: chunks handed to a runner, collected (and saved) as they finish.

A runner (:data:`ChunkRunner`) computes a list of chunks and yields each result as it
finishes, in any order: :func:`local_runner` in this process, or the Dask runner of
:mod:`impactbeams.sweep.dask_runner` on a cluster.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import xarray as xr

from impactbeams.io import write_netcdf
from impactbeams.params import require
from impactbeams.sweep.definition import Sweep
from impactbeams.sweep.output import map_dataset
from impactbeams.sweep.plan import build_plan, compute_chunk, contact_resolution
from impactbeams.sweep.progress import Progress
from impactbeams.sweep.store import ChunkStore, finished_output

Chunk = tuple[int, int, int]  # (chunk number, first flat cell, end flat cell)
ChunkRunner = Callable[[Sweep, list[Chunk]], Iterator[tuple[int, dict[str, np.ndarray]]]]


@contextlib.contextmanager
def numba_threads(threads: int | None) -> Iterator[None]:
    """Run the body on ``threads`` Numba threads (None: leave them), then restore the count."""
    if threads is None:
        yield
        return
    import numba

    limit = numba.config.NUMBA_NUM_THREADS
    require("threads", threads, isinstance(threads, int) and 1 <= threads <= limit,
            f"must be an integer from 1 to {limit}")
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        yield
    finally:
        numba.set_num_threads(previous)


def local_runner(parallel: bool = True) -> ChunkRunner:
    """Compute chunks one after the other in this process, each over all Numba threads."""
    def run(sweep: Sweep, chunks: list[Chunk]) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
        plan = build_plan(sweep) if chunks else None  # once per run, shared by its chunks
        for chunk, start, stop in chunks:
            yield chunk, compute_chunk(sweep, start, stop, parallel, plan)

    return run


def chunk_bounds(size: int, chunk_cells: int) -> list[tuple[int, int]]:
    """Split ``size`` flat cells into consecutive chunks of at most ``chunk_cells``."""
    return [(start, min(start + chunk_cells, size)) for start in range(0, size, chunk_cells)]


def default_chunk_cells(size: int, long_runs: bool = False) -> int:
    """About 100 chunks, each between 4096 and 65536 cells (a second or less of work).

    ``long_runs``: cells of long-time observables take seconds each: chunks of 16 to 256
    cells, so that progress shows and an interrupted run loses little.
    """
    if long_runs:
        return int(min(max(size // 100, 16), 256))
    return int(min(max(size // 100, 4096), 65536))


def run_sweep(sweep: Sweep, output: str | Path | None = None, threads: int | None = None,
              progress: bool = False, parallel: bool = True, chunk_cells: int | None = None,
              on_chunk: Callable[[int], None] | None = None,
              runner: ChunkRunner | None = None) -> xr.Dataset:
    """Compute a sweep and return its Dataset; with ``output``, also write it as netCDF.

    ``threads``: Numba threads during the run (default: as set; restored afterwards). With
    ``output``, finished chunks are kept under ``OUTPUT.partial/`` until the file is
    complete, and a re-run resumes from them. ``progress``: draw a progress bar on stderr.
    ``on_chunk`` is called with each finished chunk number (for tests and monitoring).
    ``runner`` computes the chunks (default: :func:`local_runner`; see
    :mod:`impactbeams.sweep.dask_runner` for a Dask cluster); chunks may finish in any order.
    """
    resolution = contact_resolution(sweep)
    if resolution is not None and sweep.n_modes < resolution:
        warnings.warn(f"n_modes = {sweep.n_modes} does not resolve the spring contact of "
                      f"{sweep.source}: use n_modes >= {resolution} (docs/model.md, "
                      "Resolution)", RuntimeWarning, stacklevel=2)
    with numba_threads(threads):
        store = None
        if output is not None:
            output = Path(output)
            finished = finished_output(output, sweep)
            if finished is not None:
                return finished
            store = ChunkStore(output, sweep.fingerprint(), chunk_cells,
                               default_chunk_cells(sweep.size, sweep.long_time is not None))
            chunk_cells = store.chunk_cells
        bounds = chunk_bounds(sweep.size, chunk_cells or default_chunk_cells(
            sweep.size, sweep.long_time is not None))
        results = _collect(sweep, bounds, store, runner or local_runner(parallel),
                           Progress(sweep.size, enabled=progress), on_chunk)
    dataset = map_dataset(sweep, results)
    if store is not None:
        write_netcdf(dataset, output)
        store.remove()
    return dataset


def _collect(sweep: Sweep, bounds: list[tuple[int, int]], store: ChunkStore | None,
             runner: ChunkRunner, bar: Progress,
             on_chunk: Callable[[int], None] | None) -> dict[str, np.ndarray]:
    """Flat results of every cell: saved chunks loaded, the others computed by ``runner``."""
    results = {name: np.full((sweep.size, *sweep.value_shape(name)), np.nan)
               for name in sweep.stored}
    pending = []
    for chunk, (start, stop) in enumerate(bounds):
        saved = store.load(chunk) if store else None
        if saved is None:
            pending.append((chunk, start, stop))
            continue
        for name in results:
            results[name][start:stop] = saved[name]
        bar.update(stop - start, computed=False)
    for chunk, values in runner(sweep, pending):
        if store:
            store.save(chunk, values)
        start, stop = bounds[chunk]
        for name in results:
            results[name][start:stop] = values[name]
        bar.update(stop - start)
        if on_chunk:
            on_chunk(chunk)
    return results
