"""Overhead of the Dask path against the local path, per chunk size, on one machine.

Run ``python benchmarks/bench_distributed.py`` (``--help`` for options). The same grid (by
default the fig5a sweep) is computed locally (one process, all Numba threads) and on a
LocalCluster of ``--workers`` processes with one Dask thread each, for several chunk sizes;
each timing is the minimum of ``--repeats`` runs, local and distributed interleaved so both
see the same background load. Start-up is timed separately: cluster start, and the first
chunk on every worker (imports, sweep plan, kernel compile) with a cold and a warm Numba disk
cache. Writes docs/benchmarks/distributed.json and docs/benchmarks/distributed.md.
"""

import argparse
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# A fresh Numba cache for this run, set before numba is imported, so that the first cluster's
# warm-up really compiles. Workers inherit it; they also re-import this file (spawn), hence
# the guard.
if "IMPACTBEAMS_BENCH_CACHE" not in os.environ:
    os.environ["IMPACTBEAMS_BENCH_CACHE"] = tempfile.mkdtemp(prefix="impactbeams-bench-numba-")
    os.environ["NUMBA_CACHE_DIR"] = os.environ["IMPACTBEAMS_BENCH_CACHE"]

import dask  # noqa: E402
import numba  # noqa: E402
import numpy as np  # noqa: E402

from impactbeams import __version__  # noqa: E402
from impactbeams.sweep import (  # noqa: E402
    Chunking,
    compute_chunk,
    default_chunk_cells,
    load_sweep,
    run_sweep,
    sweep_from_mapping,
)
from impactbeams.sweep.dask_runner import dask_client, dask_runner  # noqa: E402

THRESHOLD = 0.10  # the chunk size reported is the smallest with overhead below this


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sweep", default=str(ROOT / "sweeps" / "fig5a-omega-force.toml"))
    parser.add_argument("--num", type=int, help="reduce every axis to NUM points (quick runs)")
    parser.add_argument("--chunk-cells", type=int, nargs="+",
                        default=[256, 1024, 2048, 4096, 8192, 16384, 65536])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--output-dir", default=str(ROOT / "docs" / "benchmarks"))
    return parser.parse_args()


def load(path, num):
    sweep = load_sweep(path)
    if num is None:
        return sweep
    definition = sweep.definition()
    for axis in definition["axes"].values():
        axis["num"] = num
    return sweep_from_mapping(definition, source=f"{sweep.source} (axes reduced to {num})")


def timed(function, *args, **kwargs):
    start = time.perf_counter()
    result = function(*args, **kwargs)
    return time.perf_counter() - start, result


def warm_up(client, sweep):
    """First chunk on every worker: imports, plan and kernel compile (or cache load)."""
    seconds, _ = timed(client.run, compute_chunk, sweep, 0, 1, False)
    return seconds


def task_cost(client, sweep, repeats, tasks=1000):
    """Seconds per task of the Dask path alone: chunks of zero cells (minimum over repeats)."""
    empty = [(k, 0, 0) for k in range(tasks)]
    return min(timed(list, dask_runner(client)(sweep, empty))[0] for _ in range(repeats)) / tasks


def measure(sweep, client, chunk_sizes, repeats):
    """Minimum wall times: local and distributed per chunk size, local default, local serial."""
    default = default_chunk_cells(sweep)
    local = {c: [] for c in {*chunk_sizes, default}}
    remote = {c: [] for c in chunk_sizes}
    serial = []  # one process, serial kernel: serial / workers is the ideal distributed time
    for repeat in range(repeats):
        for cells in chunk_sizes:
            local[cells].append(timed(run_sweep, sweep, progress=False, chunk_cells=cells)[0])
            seconds, _ = timed(run_sweep, sweep, progress=False, chunk_cells=cells,
                               runner=dask_runner(client))
            remote[cells].append(seconds)
            print(f"  repeat {repeat + 1}: {cells:6d} cells/chunk  local {local[cells][-1]:7.3f}"
                  f" s  distributed {seconds:7.3f} s", file=sys.stderr)
        if default not in chunk_sizes:
            local[default].append(timed(run_sweep, sweep, progress=False)[0])
        serial.append(timed(run_sweep, sweep, progress=False, parallel=False)[0])
    return (default, {c: min(t) for c, t in local.items()}, {c: min(t) for c, t in remote.items()},
            min(serial))


def check_equal(sweep, client):
    a = run_sweep(sweep, progress=False)
    b = run_sweep(sweep, progress=False, runner=dask_runner(client))
    return bool(np.array_equal(a.first_impact_time, b.first_impact_time, equal_nan=True))


def report(args, sweep, startup, task_s, timings, equal, load_before):
    default, local, remote, serial = timings
    baseline, ideal = local[default], serial / args.workers
    rows = [{"chunk_cells": c, "chunks": Chunking.at_most(sweep.shape, c).count,
             "local_s": local[c], "distributed_s": remote[c], "overhead": remote[c] / baseline - 1,
             "overhead_same_chunks": remote[c] / local[c] - 1,
             "overhead_vs_ideal": remote[c] / ideal - 1} for c in sorted(remote)]
    below = [r["chunk_cells"] for r in rows if r["overhead"] < THRESHOLD]
    return {
        "sweep": sweep.source.replace(f"{ROOT}{os.sep}", ""), "shape": list(sweep.shape),
        "cells": sweep.size,
        "t_max_s": sweep.t_max, "n_modes": sweep.n_modes,
        "workers": args.workers, "threads_per_worker": 1, "repeats": args.repeats,
        "local_default_chunk_cells": default, "local_default_s": baseline,
        "local_serial_s": serial,
        "rows": rows, "smallest_chunk_cells_below_10_percent": min(below, default=None),
        "distributed_equals_local_bitwise": equal, "startup_s": startup,
        "seconds_per_empty_task": task_s,
        "machine": {"cpu_count": os.cpu_count(), "numba_threads": numba.config.NUMBA_NUM_THREADS,
                    "platform": platform.platform(), "python": platform.python_version(),
                    "load_average_before": load_before, "load_average_after": os.getloadavg()},
        "versions": {"impactbeams": __version__, "numba": numba.__version__,
                     "dask": dask.__version__, "numpy": np.__version__},
        "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
    }


def markdown(result):
    return "\n".join([*_header(result), *_table(result), *_footer(result)])


def _header(result):
    machine = result["machine"]
    return [
        "# Distributed path overhead (generated by benchmarks/bench_distributed.py)",
        "",
        f"Grid: {result['sweep']}, {' x '.join(map(str, result['shape']))} = "
        f"{result['cells']} cells, t_max = {result['t_max_s']} s, {result['n_modes']} modes. "
        f"Machine: {machine['cpu_count']} cores, load average "
        f"{machine['load_average_before'][0]:.2f} before and "
        f"{machine['load_average_after'][0]:.2f} after (other work on the machine makes "
        f"every number noisy); {result['date']}.",
        "",
        f"Local: one process, {machine['numba_threads']} Numba threads, default chunking "
        f"({result['local_default_chunk_cells']} cells): **{result['local_default_s']:.3f} s**"
        f"; with the serial kernel: {result['local_serial_s']:.3f} s. Distributed: "
        f"LocalCluster of {result['workers']} workers x 1 thread, one Numba thread per task. "
        f"Minimum of {result['repeats']} runs each; start-up not included (below).",
        "",
        "Overhead = distributed / local default - 1. Also shown: against a local run with the "
        "same chunks, and against the ideal split of the serial run over the workers "
        "(serial / workers), which does not depend on how well Numba's parallel kernel "
        "scales on a loaded machine.",
        "",
    ]


def _table(result):
    lines = ["| cells per chunk | chunks | local, same chunks (s) | distributed (s) | overhead "
             "| vs same chunks | vs ideal |", "|---:|---:|---:|---:|---:|---:|---:|"]
    for r in result["rows"]:
        lines.append(f"| {r['chunk_cells']} | {r['chunks']} | {r['local_s']:.3f} | "
                     f"{r['distributed_s']:.3f} | {100 * r['overhead']:+.1f}% | "
                     f"{100 * r['overhead_same_chunks']:+.1f}% | "
                     f"{100 * r['overhead_vs_ideal']:+.1f}% |")
    return lines


def _footer(result):
    s, best = result["startup_s"], result["smallest_chunk_cells_below_10_percent"]
    return [
        "",
        "Smallest chunk size with overhead below 10%: "
        f"{f'**{best} cells**' if best else 'none of the sizes tried'}. "
        "Distributed map bitwise equal to local: "
        f"{result['distributed_equals_local_bitwise']}.",
        "",
        f"Fixed cost of the Dask path per task (chunks of zero cells): "
        f"{1e3 * result['seconds_per_empty_task']:.1f} ms; overhead stays below 10% when a "
        "chunk computes for more than about ten times that.",
        "",
        "Start-up, paid once per run (not in the table):",
        "",
        f"- LocalCluster start: {s['cluster_start_cold']:.2f} s (first), "
        f"{s['cluster_start_warm']:.2f} s (second)",
        f"- first chunk on every worker (imports, plan, kernels), cold Numba cache (compile): "
        f"{s['worker_warm_up_cold_cache']:.2f} s; warm disk cache: "
        f"{s['worker_warm_up_warm_cache']:.2f} s",
        f"- local process, first chunk with the parallel kernel (its callees already in the "
        f"disk cache): {s['local_warm_up']:.2f} s",
        "",
    ]


def main():
    args = parse_args()
    load_before = os.getloadavg()
    sweep = load(args.sweep, args.num)
    print(f"{sweep.source}: {sweep.size} cells", file=sys.stderr)
    startup = {}
    start = time.perf_counter()
    with dask_client(local_workers=args.workers) as client:  # cold Numba cache: compiles
        startup["cluster_start_cold"] = time.perf_counter() - start
        startup["worker_warm_up_cold_cache"] = warm_up(client, sweep)
    start = time.perf_counter()
    with dask_client(local_workers=args.workers) as client:
        startup["cluster_start_warm"] = time.perf_counter() - start
        startup["worker_warm_up_warm_cache"] = warm_up(client, sweep)
        startup["local_warm_up"] = timed(compute_chunk, sweep, 0, 1)[0]
        equal = check_equal(sweep, client)
        task_s = task_cost(client, sweep, args.repeats)
        timings = measure(sweep, client, args.chunk_cells, args.repeats)
    result = report(args, sweep, startup, task_s, timings, equal, load_before)
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "distributed.json").write_text(json.dumps(result, indent=2) + "\n")
    (out / "distributed.md").write_text(markdown(result))
    print(markdown(result))
    shutil.rmtree(os.environ["IMPACTBEAMS_BENCH_CACHE"], ignore_errors=True)


if __name__ == "__main__":
    main()
