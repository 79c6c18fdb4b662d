"""Run sweeps on a Dask cluster (``dask.distributed``): one task per chunk, saved as it arrives.

`dask_runner` is a `ChunkRunner` for
[`run_sweep`][impactbeams.sweep.run_sweep]: the sweep's plan (the modes of every geometry) is built
once, as a task whose result stays on the cluster, and every pending chunk becomes one task
computing `compute_chunk` with it on a worker; results come back in
the order they finish. The client saves each one at once under ``OUT.nc.partial/`` (as a
local run does), so an interrupted client loses no finished chunk and the same command
resumes. A task whose worker dies is rerun elsewhere by the scheduler (up to
``distributed.scheduler.allowed-failures`` times); each task is yielded once, and saving a
chunk again would write the same bytes.

Threads: a task runs ``threads_per_task`` Numba threads (restored when it ends), by default
``max(1, cores // dask_threads)`` per host (smallest over hosts), so Dask threads times Numba
threads equals the cores and nothing is oversubscribed. With one Numba thread a task runs the
serial kernel, which gives the same bits as the parallel one.

Dask is optional (``pip install impactbeams[distributed]``) and imported only here, lazily.
See docs/distributed.md.
"""

from __future__ import annotations

import contextlib
import socket
import uuid
from collections.abc import Iterator
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from impactbeams import __version__
from impactbeams.params import ParameterError, require
from impactbeams.sweep.definition import Sweep
from impactbeams.sweep.plan import Plan, build_plan, code_digest, compute_chunk
from impactbeams.sweep.run import Chunk, ChunkRunner, numba_threads

if TYPE_CHECKING:
    from distributed import Client, Future

INSTALL_HINT = "pip install 'impactbeams[distributed]'"
WINDOW_PER_THREAD = 4  # tasks in flight per Dask thread: workers stay busy, memory stays bounded


def require_dask() -> ModuleType:
    """The ``distributed`` module, or an ImportError that says how to install it."""
    try:
        import distributed
    except ImportError as error:
        raise ImportError(f"running a sweep on a Dask cluster needs dask.distributed, which is "
                          f"not installed: {INSTALL_HINT}") from error
    return distributed


@contextlib.contextmanager
def dask_client(scheduler: str | None = None,
                local_workers: int | None = None) -> Iterator[Client]:
    """A client of the cluster at ``scheduler`` (e.g. ``tcp://host:8786``), or of a new local one.

    With ``local_workers``, start a LocalCluster of that many worker processes with one Dask
    thread each, on loopback (dashboard on a free port); it is shut down on exit.
    """
    require("scheduler / local_workers", (scheduler, local_workers),
            (scheduler is None) != (local_workers is None), "give exactly one of the two")
    distributed = require_dask()
    if scheduler is not None:
        try:
            client = distributed.Client(scheduler)
        except OSError as error:
            raise ParameterError(f"scheduler = {scheduler!r}: cannot connect ({error})") from None
        with client:
            yield client
        return
    require("local_workers", local_workers, local_workers >= 1, "must be >= 1")
    with (distributed.LocalCluster(n_workers=local_workers, threads_per_worker=1,
                                   processes=True, host="127.0.0.1",
                                   dashboard_address=":0") as cluster,
          distributed.Client(cluster) as client):
        yield client


def _release() -> str:
    """The impactbeams version and the digest of its numerical code in this process."""
    return f"{__version__} (code {code_digest()})"


def _worker_info() -> tuple[str, int, str]:
    """(host name, Numba's thread limit, `_release`) of the calling worker process."""
    import numba

    return socket.gethostname(), int(numba.config.NUMBA_NUM_THREADS), _release()


def _workers(client: Client) -> dict[str, tuple[str, int, str]]:
    """`_worker_info` of every connected worker; all must run this client's code.

    The version alone is not enough: an edited kernel without a version bump would compute
    other numbers on the workers than here.
    """
    info = client.run(_worker_info)
    other = sorted({release for _, _, release in info.values()} - {_release()})
    if other:
        raise RuntimeError(f"workers run impactbeams {', '.join(other)}, this client "
                           f"{_release()}: install the same version on every worker")
    return info


def default_threads_per_task(client: Client) -> int:
    """Numba threads per task so that Dask threads x Numba threads = cores on every host.

    Per host: ``max(1, cores // sum of the Dask threads of its workers)``; the smallest over
    hosts. 1 when no worker is connected yet.
    """
    return _threads_rule(_workers(client), client.nthreads())


def _threads_rule(workers: dict[str, tuple[str, int, str]], nthreads: dict[str, int]) -> int:
    hosts: dict[str, list[int]] = {}  # host -> [cores, Dask threads]
    for address, (host, cores, _) in workers.items():
        entry = hosts.setdefault(host, [cores, 0])
        entry[0] = max(entry[0], cores)
        entry[1] += nthreads.get(address, 1)
    return min((max(1, cores // threads) for cores, threads in hosts.values()), default=1)


def _chunk_task(sweep: Sweep, plan: Plan, start: int, stop: int,
                threads: int) -> dict[str, np.ndarray]:
    """Run on a worker: one chunk over ``threads`` Numba threads (the serial kernel for 1)."""
    if threads == 1:
        return compute_chunk(sweep, start, stop, parallel=False, plan=plan)
    import numba

    with numba_threads(min(threads, numba.config.NUMBA_NUM_THREADS)):
        return compute_chunk(sweep, start, stop, parallel=True, plan=plan)


def dask_runner(client: Client, threads_per_task: int | None = None,
                window: int | None = None) -> ChunkRunner:
    """A chunk runner that computes chunks as tasks on the cluster of ``client``.

    ``threads_per_task``: Numba threads per task (default `default_threads_per_task`).
    ``window``: most tasks in flight (default 4 per Dask thread); more are submitted as
    results come in, so a grid of thousands of chunks holds only a window in memory.
    """
    distributed = require_dask()
    for name, value in (("threads_per_task", threads_per_task), ("window", window)):
        require(name, value, value is None or (isinstance(value, int) and value >= 1),
                "must be an integer >= 1")

    def run(sweep: Sweep, chunks: list[Chunk]) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
        if not chunks:
            return
        workers, nthreads = _workers(client), client.nthreads()
        threads = threads_per_task or _threads_rule(workers, nthreads)
        limit = window or WINDOW_PER_THREAD * max(1, sum(nthreads.values()))
        token = uuid.uuid4().hex[:8]  # unique keys: a rerun never reuses an old result
        # one plan per run, kept on the cluster while chunks need it (rebuilt if its worker dies)
        plan = client.submit(build_plan, sweep, key=f"impactbeams-plan-{token}")
        todo = iter(chunks)
        in_flight: dict[str, tuple[int, Future]] = {}
        finished = distributed.as_completed(with_results=True)

        def submit_next() -> None:
            chunk = next(todo, None)
            if chunk is not None:
                number, start, stop = chunk
                future = client.submit(_chunk_task, sweep, plan, start, stop, threads,
                                       key=f"impactbeams-chunk-{number}-{token}")
                in_flight[future.key] = (number, future)
                finished.add(future)

        for _ in range(limit):
            submit_next()
        try:
            for future, values in finished:
                number, _ = in_flight.pop(future.key)
                submit_next()
                yield number, values
        finally:  # the consumer stopped early: do not leave work running on the cluster
            finished.clear()
            if in_flight:
                client.cancel([future for _, future in in_flight.values()])
            plan.release()

    return run
