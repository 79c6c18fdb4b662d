"""Running a sweep: chunks handed to a runner, collected (and saved) as they finish.

A runner (`ChunkRunner`) computes a list of chunks and yields each result as it
finishes, in any order: `local_runner` in this process, or the Dask runner of
`impactbeams.sweep.dask_runner` on a cluster. `write_sweep` streams the results
into a netCDF file chunk by chunk (saving them for a resume); [`run_sweep`][] returns the
map as a Dataset.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import itertools
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.lock import output_lock
from impactbeams.params import (
    MAX_CHUNK_CELLS,
    is_integer,
    is_path,
    moving_stop,
    require,
    require_type,
)
from impactbeams.preflight import require_memory
from impactbeams.sweep.definition import (
    Sweep,
    as_sweep,
    default_chunk_cells,
    expected_memory,
    row_cells,
)
from impactbeams.sweep.output import cell_values, map_dataset, map_file
from impactbeams.sweep.plan import (
    Chunking,
    build_plan,
    check_contact_phases,
    compute_chunk,
    contact_resolution,
    reusing_geometries,
)
from impactbeams.sweep.progress import Progress, chunk_progress
from impactbeams.sweep.store import ChunkStore, finished_output, reporting_kept_chunks

if TYPE_CHECKING:
    import xarray as xr

Chunk = tuple[int, int, int]  # (chunk number, first flat cell, end flat cell)
ChunkRunner = Callable[[Sweep, list[Chunk]], Iterator[tuple[int, dict[str, np.ndarray]]]]
Keep = Callable[[int, int, int, Mapping[str, np.ndarray]], None]  # (chunk, start, stop, values)


@contextlib.contextmanager
def numba_threads(threads: int | None) -> Iterator[None]:
    """Run the body on ``threads`` Numba threads (None: leave them), then restore the count."""
    if threads is None:
        yield
        return
    import numba

    limit = numba.config.NUMBA_NUM_THREADS
    require("threads", threads, is_integer(threads) and 1 <= threads <= limit,
            f"must be an integer from 1 to {limit}")
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        yield
    finally:
        numba.set_num_threads(previous)


def local_runner(parallel: bool = True) -> ChunkRunner:
    """Compute chunks in this process over all Numba threads.

    A chunk of long runs (seconds per cell, costs that differ by orders of magnitude between
    cells) goes to one thread, which runs its cells one after the other, while the other
    threads take the next chunks: no thread waits at the end of a chunk for another's last
    cell. Other chunks run one after the other, each over all threads.
    """
    def run(sweep: Sweep, chunks: list[Chunk]) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
        plan = build_plan(sweep) if chunks else None  # once per run, shared by its chunks
        if parallel and sweep.long_time is not None:
            yield from _chunk_per_thread(sweep, chunks, plan)
            return
        for chunk, start, stop in chunks:
            yield chunk, compute_chunk(sweep, start, stop, parallel, plan)

    return run


def _chunk_per_thread(sweep: Sweep, chunks: list[Chunk],
                      plan: Any) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
    """Each chunk computed serially on one of Numba's thread count of threads, as they free."""
    import numba

    workers = numba.get_num_threads()
    queue = iter(chunks)
    pool = concurrent.futures.ThreadPoolExecutor(workers)
    pending: dict[concurrent.futures.Future, int] = {}

    def submit() -> None:
        for chunk, start, stop in itertools.islice(queue, 1):
            pending[pool.submit(compute_chunk, sweep, start, stop, False, plan)] = chunk

    try:
        for _ in range(workers):
            submit()
        while pending:
            done, _ = concurrent.futures.wait(pending,
                                              return_when=concurrent.futures.FIRST_COMPLETED)
            for future in done:
                chunk = pending.pop(future)
                submit()
                yield chunk, future.result()
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def _chunking(sweep: Sweep, chunk_cells: int | None) -> Chunking:
    """The chunks of at most ``chunk_cells`` cells (default `default_chunk_cells`)."""
    require("chunk_cells", chunk_cells, chunk_cells is None or (
        isinstance(chunk_cells, int) and 1 <= chunk_cells <= MAX_CHUNK_CELLS),
        f"must be an integer from 1 to {MAX_CHUNK_CELLS}")
    if sweep.stepping is not None:
        rows = row_cells(sweep)
        require("chunk_cells", chunk_cells, chunk_cells is None or chunk_cells >= rows,
                f"a stepped sweep's chunk holds whole rows along {sweep.stepping.axis}: at "
                f"least {rows} cells")
    return Chunking.at_most(sweep.shape, chunk_cells or default_chunk_cells(sweep))


def _check_options(output: object, threads: object, callbacks: Mapping[str, object],
                   switches: Mapping[str, object]) -> None:
    """The types of run_sweep's and write_sweep's options.

    Their values are checked on use; chunk_cells, type and value, by `_chunking`.
    """
    require_type("output", output, output is None or is_path(output),
                 "None or the path of a netCDF file (str or pathlib.Path)")
    require_type("threads", threads, threads is None or is_integer(threads), "None or an integer")
    for name, value in callbacks.items():
        require_type(name, value, value is None or callable(value), "None or a function")
    for name, value in switches.items():
        require_type(name, value, isinstance(value, (bool, np.bool_)), "True or False")


def run_sweep(sweep: Sweep | str | Path, output: str | Path | None = None,
              threads: int | None = None, progress: bool = False, parallel: bool = True,
              chunk_cells: int | None = None, on_chunk: Callable[[int], None] | None = None,
              runner: ChunkRunner | None = None, discard_corrupt: bool = False) -> xr.Dataset:
    """Compute a sweep and return its Dataset; with ``output``, write it as netCDF first.

    Without ``output`` the map is computed in memory (a ParameterError if it would not fit).
    With it, see `write_sweep` (which takes the same arguments); the Dataset returned is
    then the file, opened lazily, so that a map larger than memory can be read in parts.
    ``sweep`` may be the path of a sweep TOML file (read by [`load_sweep`][]).
    """
    import xarray as xr

    sweep = as_sweep(sweep)
    _check_options(output, threads, {"on_chunk": on_chunk, "runner": runner},
                   {"progress": progress, "parallel": parallel,
                    "discard_corrupt": discard_corrupt})
    with reusing_geometries():  # the check's geometries are the plan's
        check_contact_phases(sweep)
        if output is not None:
            write_sweep(sweep, output, threads, progress, parallel, chunk_cells, on_chunk,
                        runner, discard_corrupt)
            return xr.open_dataset(output)  # as registered: written so, or checked if reused
        return _run_in_memory(sweep, threads, progress, parallel, chunk_cells, on_chunk,
                              runner)


def _run_in_memory(sweep: Sweep, threads: int | None, progress: bool, parallel: bool,
                   chunk_cells: int | None, on_chunk: Callable[[int], None] | None,
                   runner: ChunkRunner | None) -> xr.Dataset:
    """`run_sweep` without an output, once checked: the map computed in memory."""
    require_memory(f"a map of {sweep.size} cells held in memory ({sweep.source})",
                   expected_memory(sweep, threads, in_memory=True),
                   "give an output file, to which the map is written chunk by chunk")
    _warn_unresolved(sweep)
    _warn_moving_stop(sweep)
    chunking = _chunking(sweep, chunk_cells)
    # every cell is filled by its chunk
    results = {name: np.empty((sweep.size, *shape), dtype)
               for name, (dtype, shape) in cell_values(sweep).items()}

    def keep(_: int, start: int, stop: int, values: Mapping[str, np.ndarray]) -> None:
        for name, array in results.items():
            array[start:stop] = values[name]

    _compile_in_two_processes(sweep, runner, parallel)
    with numba_threads(threads):
        _compute(sweep, chunking, range(chunking.count), runner or local_runner(parallel),
                 chunk_progress(sweep, chunking, progress), on_chunk, keep)
    return map_dataset(sweep, results)


def write_sweep(sweep: Sweep | str | Path, output: str | Path, threads: int | None = None,
                progress: bool = False, parallel: bool = True, chunk_cells: int | None = None,
                on_chunk: Callable[[int], None] | None = None, runner: ChunkRunner | None = None,
                discard_corrupt: bool = False) -> bool:
    """Compute a sweep into the netCDF file ``output``, chunk by chunk; False if it was there.

    Nothing holds the whole map: each chunk is written into the file as it finishes, and
    saved under ``OUTPUT.partial/`` (but the last one, which completes the file) until the
    file is complete and renamed into place, so an interrupted run loses no finished chunk and
    the same call resumes it. An existing
    ``output`` of this sweep and code is kept as it is (returns False); any other existing
    file is an error. Damaged saved chunks are an error naming them; ``discard_corrupt``
    deletes such chunks and computes them again.

    ``threads``: Numba threads during the run (default: as set; restored afterwards).
    ``progress``: draw a progress bar on stderr. ``chunk_cells``: the most cells per chunk
    (default `default_chunk_cells`), rounded down to whole lines of the last axes (a
    resumed run keeps its chunks). ``on_chunk`` is called with each computed chunk number
    (for tests and monitoring). ``runner`` computes the chunks (default `local_runner`;
    see `impactbeams.sweep.dask_runner` for a Dask cluster); they may finish in any order.
    ``sweep`` may be the path of a sweep TOML file (read by [`load_sweep`][]).

    One writer per output: the run holds the lock of `impactbeams.lock` from its
    start to its end; while another run holds it, this one raises
    [`OutputInUse`][impactbeams.lock.OutputInUse] (a ParameterError) naming that run. A file
    that cannot be written (a full disk, a removed or read-only folder, a quota) raises
    [`WriteError`][impactbeams.io.WriteError] (an OSError), one line naming the file, its cause and
    the chunks kept: the same call resumes from them once the cause is fixed.
    """
    sweep = as_sweep(sweep)
    require_type("output", output, is_path(output), "the path of a netCDF file (str or "
                 "pathlib.Path)")
    _check_options(output, threads, {"on_chunk": on_chunk, "runner": runner},
                   {"progress": progress, "parallel": parallel,
                    "discard_corrupt": discard_corrupt})
    output = Path(output)
    with reusing_geometries():  # the check's geometries are the plan's
        check_contact_phases(sweep)
        with reporting_kept_chunks(output), output_lock(output):
            return _write_sweep(sweep, output, threads, progress, parallel, chunk_cells,
                                on_chunk, runner, discard_corrupt)


def _write_sweep(sweep: Sweep, output: Path, threads: int | None, progress: bool,
                 parallel: bool, chunk_cells: int | None,
                 on_chunk: Callable[[int], None] | None, runner: ChunkRunner | None,
                 discard_corrupt: bool) -> bool:
    """`write_sweep` under the output's lock."""
    if finished_output(output, sweep):
        return False
    _warn_unresolved(sweep)
    _warn_moving_stop(sweep)
    store = ChunkStore(output, sweep, _chunking(sweep, chunk_cells), chunk_cells)
    chunking = store.chunking
    bar = chunk_progress(sweep, chunking, progress)
    with numba_threads(threads), map_file(sweep, output, store.building, chunking) as write:
        pending = []
        for chunk in range(chunking.count):  # the saved chunks first: damaged ones stop the run
            start, stop = chunking.bounds(chunk)
            saved = store.load(chunk, stop - start, discard_corrupt)
            if saved is None:
                pending.append(chunk)
                continue
            write(start, stop, saved)
            bar.update(stop - start, computed=False, part=chunk)
        store.refuse_damaged()

        unsaved = len(pending)

        def keep(chunk: int, start: int, stop: int, values: Mapping[str, np.ndarray]) -> None:
            nonlocal unsaved
            unsaved -= 1
            if unsaved:  # first: once saved, an interrupt cannot lose it. The last chunk
                store.save(chunk, values)  # completes the file: nothing would resume from it
            write(start, stop, values)

        _compile_in_two_processes(sweep, runner, parallel)
        with _one_behind(keep) as keep_behind:
            _compute(sweep, chunking, pending, runner or local_runner(parallel), bar,
                     on_chunk, keep_behind)
        if unsaved:  # a runner that stopped early: the file must not be moved into place
            raise RuntimeError(f"the chunk runner returned {len(pending) - unsaved} of "
                               f"{len(pending)} chunks: {output} was not written")
    store.remove()
    return True


@contextlib.contextmanager
def _one_behind(keep: Keep) -> Iterator[Keep]:
    """``keep`` run on a background thread, one chunk behind the computation.

    Chunk k is saved and compressed into the file while chunk k + 1 computes: on two cores this
    hides about half of that cost (both release the GIL). One call at most is in flight, so
    two chunks at most are in memory; a call's error is raised by the next call. On exit, by
    an error or an interrupt too, every call has finished: no computed chunk goes unsaved.
    """
    with concurrent.futures.ThreadPoolExecutor(1, "impactbeams-writer") as writer:
        previous: concurrent.futures.Future | None = None

        def submit(*arguments: Any) -> None:
            nonlocal previous
            if previous is not None:
                previous.result()
            previous = writer.submit(keep, *arguments)

        yield submit
        if previous is not None:
            previous.result()


def _warn_moving_stop(sweep: Sweep) -> None:
    """Warn once (not per cell) if ``sweep`` moves a stop with a shaker left to its default.

    (The counterpart and the shaker are not swept: the base parameters' hold for every cell.)
    """
    axes = {axis.name: axis.values for axis in sweep.axes}
    base = sweep.base
    note = moving_stop(not base.partner.has_beam2,
                       float(np.max(axes.get("base_amplitude", base.base_amplitude))) > 0.0,
                       base.shaker_named)
    if note:
        warnings.warn(f"{sweep.source}: {note}", UserWarning, stacklevel=3)


def _warn_unresolved(sweep: Sweep) -> None:
    """Warn if the spring contact of a dynamics sweep needs more modes than it has."""
    resolution = contact_resolution(sweep)
    if resolution is not None and sweep.n_modes < resolution:
        warnings.warn(f"n_modes = {sweep.n_modes} does not resolve the spring contact of "
                      f"{sweep.source}: use n_modes >= {resolution} (docs/model.md, "
                      "Resolution)", RuntimeWarning, stacklevel=3)


def _compile_in_two_processes(sweep: Sweep, runner: ChunkRunner | None,
                              parallel: bool) -> None:
    """A local run that will compile shares the compile with a helper process (not Dask's)."""
    if runner is None:
        from impactbeams.compilation import compile_in_two_processes
        from impactbeams.sweep.definition import run_kind
        from impactbeams.sweep.plan import first_impact_kernel

        compile_in_two_processes(run_kind(sweep), first_impact_kernel(sweep, parallel))


def _compute(sweep: Sweep, chunking: Chunking, chunks: Iterable[int], runner: ChunkRunner,
             bar: Progress, on_chunk: Callable[[int], None] | None,
             keep: Keep) -> None:
    """Compute ``chunks`` with ``runner``; pass each to ``keep(chunk, start, stop, values)``."""
    bounds = {chunk: chunking.bounds(chunk) for chunk in chunks}
    for chunk, values in runner(sweep, [(chunk, *cells) for chunk, cells in bounds.items()]):
        start, stop = bounds[chunk]
        keep(chunk, start, stop, values)
        bar.update(stop - start, part=chunk)
        if on_chunk:
            on_chunk(chunk)
