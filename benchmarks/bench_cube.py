"""Benchmark: an (Omega, clearance, F0) first-impact cube streamed into netCDF (issue 13).

    python benchmarks/bench_cube.py --num 100 200       # 10^6 and 8 10^6 cells: about a minute
    python benchmarks/bench_cube.py --num 1000          # the 10^9-cell cube itself
    python benchmarks/bench_cube.py --compression       # zlib level, shuffle, float32

Each cube (``num`` points per axis, t_max = 1 s, 5 modes per beam) runs through
:func:`impactbeams.sweep.write_sweep`, as ``impactbeams run`` does, on ``--threads`` Numba threads
after a warm-up: wall and CPU time, time per cell, peak memory (RSS of this process), the file's
size, and the costs of one chunk of the middle of the cube measured apart (building its cell
rows, the kernel, saving its ``.npz``, compressing it into the file). The 10^9-cell time is
extrapolated from each size as (wall time per cell) x 10^9. Results go to
docs/benchmarks/cube.json and cube.md; a size measured again replaces its earlier result, so the
long run can be made alone. --compression writes compression.json instead: sizes and write
times of the Fig. 5a map and of a plane of the cube for several HDF5 filters (the numbers
behind ``impactbeams.io.COMPRESSION``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

from impactbeams import __version__
from impactbeams.io import write_npz
from impactbeams.sweep import (
    Chunking,
    build_plan,
    compute_chunk,
    default_chunk_cells,
    load_sweep,
    sweep_from_mapping,
    write_sweep,
)
from impactbeams.sweep.output import map_file
from impactbeams.sweep.plan import chunk_cells

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "benchmarks"
CUBE = {  # the Fig. 5a ranges of Omega and F0, and two decades of clearance around Fig. 5a's
    "t_max": 1.0, "n_modes": 5,
    "axes": {"omega": {"min": 10.0, "max": 400.0},
             "clearance": {"min": 1e-6, "max": 1e-4, "scale": "log"},
             "force_amplitude": {"min": 1e-6, "max": 1e-3, "scale": "log"}},
}


def cube(num: int):
    """The benchmark cube with ``num`` points per axis."""
    axes = {name: {**axis, "num": num} for name, axis in CUBE["axes"].items()}
    return sweep_from_mapping({**CUBE, "axes": axes}, source=f"benchmark cube {num}^3")


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far (MB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def cpu_seconds() -> float:
    """User + system CPU time of this process so far, all threads (s)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def timed(function, *args, repeats: int = 1, **kwargs) -> float:
    """Best wall time (s) of ``repeats`` calls."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function(*args, **kwargs)
        best = min(best, time.perf_counter() - start)
    return best


def chunk_costs(sweep, directory: Path) -> dict[str, float]:
    """Seconds of each step for the middle chunk of ``sweep``, each measured apart."""
    chunking = Chunking.at_most(sweep.shape, default_chunk_cells(sweep))
    start, stop = chunking.bounds(chunking.count // 2)
    plan = build_plan(sweep)
    costs = {"cells": stop - start,
             "cell_rows_s": timed(chunk_cells, sweep, plan, start, stop, repeats=3)}
    compute = timed(compute_chunk, sweep, start, stop, plan=plan, repeats=2)
    values = compute_chunk(sweep, start, stop, plan=plan)
    costs["kernel_s"] = compute - costs["cell_rows_s"]
    costs["save_npz_s"] = timed(write_npz, directory / "chunk.npz", values, repeats=3)

    def netcdf_block() -> None:  # HDF5 compresses a block when it leaves its cache: on close
        with map_file(sweep, directory / "chunk.nc", directory / "building.nc",
                      chunking) as write:
            write(start, stop, values)

    costs["netcdf_block_s"] = timed(netcdf_block, repeats=3)
    costs["impacted_fraction"] = float(np.isfinite(values["first_impact_time"]).mean())
    return costs


def run_cube(num: int, threads: int, directory: Path) -> dict:
    """One streamed run of the ``num``^3 cube: time, memory, size, and one chunk's costs."""
    sweep = cube(num)
    path = directory / f"cube{num}.nc"
    path.unlink(missing_ok=True)
    costs = chunk_costs(sweep, directory)
    rss_before, cpu_before = peak_rss_mb(), cpu_seconds()
    wall = timed(write_sweep, sweep, path, threads=threads, progress=sys.stderr.isatty())
    cpu = cpu_seconds() - cpu_before
    result = {"num": num, "cells": sweep.size, "threads": threads, "wall_s": wall, "cpu_s": cpu,
              "seconds_per_cell": wall / sweep.size,
              "extrapolated_1e9_cells_s": wall / sweep.size * 1e9,
              # what the same work takes when the threads have the cores to themselves
              "extrapolated_1e9_cells_cpu_per_thread_s": cpu / threads / sweep.size * 1e9,
              "chunks": Chunking.at_most(sweep.shape, default_chunk_cells(sweep)).count,
              "peak_rss_mb": peak_rss_mb(), "peak_rss_before_mb": rss_before,
              "file_mb": path.stat().st_size / 1e6,
              "raw_mb": sweep.size * 9 / 1e6,  # float64 first_impact_time + int8 impacted
              "chunk": costs, "load_average": os.getloadavg()[0]}
    path.unlink()
    print(json.dumps(result), file=sys.stderr)
    return result


def _filter_rows(data: np.ndarray, directory: Path) -> list[dict]:
    """Size and write time of the 2-D float array ``data`` as netCDF for several filters."""
    import netCDF4

    rows = []
    for dtype in ("f8", "f4"):
        for level, shuffle in [(0, False), (1, False), (1, True), (4, False), (4, True),
                               (6, True), (9, True)]:
            path = directory / "plane.nc"
            start = time.perf_counter()
            with netCDF4.Dataset(path, "w") as nc:
                nc.createDimension("a", data.shape[0])
                nc.createDimension("b", data.shape[1])
                options = {"zlib": True, "complevel": level, "shuffle": shuffle} if level else {}
                variable = nc.createVariable("t", dtype, ("a", "b"), fill_value=np.nan,
                                             chunksizes=data.shape, **options)
                variable[:] = data
            rows.append({"dtype": dtype, "level": level, "shuffle": shuffle,
                         "seconds_per_million_cells": (time.perf_counter() - start)
                         / data.size * 1e6,
                         "bytes_per_cell": path.stat().st_size / data.size})
    return rows


def compression_study(num: int, directory: Path) -> dict:
    """HDF5 filters on the Fig. 5a map and on the middle (Delta, F0) plane of the cube.

    The cube's plane is special: with no uplifts t* depends on Delta / F0 alone, and on these
    log axes of equal steps it repeats along diagonals, which zlib finds. The map is typical.
    """
    fig5a = load_sweep(ROOT / "sweeps" / "fig5a-omega-force.toml")
    maps = {"fig5a map": compute_chunk(fig5a, 0, fig5a.size)["first_impact_time"]
            .reshape(fig5a.shape)}
    sweep = cube(num)
    plane = compute_chunk(sweep, (num // 2) * num * num, (num // 2 + 1) * num * num)
    maps[f"cube plane, Omega = {sweep.axes[0].values[num // 2]:.1f} rad/s"] = (
        plane["first_impact_time"].reshape(num, num))
    return {name: {"cells": data.size, "impacted_fraction": float(np.isfinite(data).mean()),
                   "float32_max_relative_error": float(np.nanmax(
                       np.abs(data.astype(np.float32) - data) / data)),
                   "rows": _filter_rows(data, directory)} for name, data in maps.items()}


def markdown(report: dict) -> str:
    """The cube results as a table, with the 10^9-cell extrapolation."""
    lines = ["| cube | cells | chunks | wall (s) | CPU (s) | wall per cell (us) | 10^9 cells "
             "at this wall time per cell (s) | 10^9 cells at CPU / threads (s) | peak RSS (MB) "
             "| file (MB) / raw (MB) | load average |", "|---" * 11 + "|"]
    for r in report["runs"]:
        lines.append(f"| {r['num']}^3 | {r['cells']:,} | {r['chunks']} | {r['wall_s']:.1f} | "
                     f"{r['cpu_s']:.1f} | {r['seconds_per_cell'] * 1e6:.2f} | "
                     f"{r['extrapolated_1e9_cells_s']:.0f} | "
                     f"{r['extrapolated_1e9_cells_cpu_per_thread_s']:.0f} | "
                     f"{r['peak_rss_mb']:.0f} | {r['file_mb']:.1f} / {r['raw_mb']:.0f} | "
                     f"{r['load_average']:.1f} |")
    chunk = ["| cube | cells per chunk | cell rows (ms) | kernel (ms) | .npz save (ms) | "
             "netCDF block (ms) |", "|---|---|---|---|---|---|"]
    for r in report["runs"]:
        c = r["chunk"]
        chunk.append(f"| {r['num']}^3 | {c['cells']:,} | {c['cell_rows_s'] * 1e3:.1f} | "
                     f"{c['kernel_s'] * 1e3:.1f} | {c['save_npz_s'] * 1e3:.1f} | "
                     f"{c['netcdf_block_s'] * 1e3:.1f} |")
    return (f"(Omega, clearance, F0) cube, t_max = 1 s, 5 modes per beam, streamed into "
            f"netCDF by `write_sweep` on {report['runs'][0]['threads']} threads "
            f"({report['machine']}, {report['date']}; load average at the start of each run in "
            "cube.json):\n\n" + "\n".join(lines) + "\n\nOne chunk from the middle of the cube, "
            "each step timed apart (the run saves and compresses chunk k on a second thread "
            "while chunk k + 1 computes):\n\n" + "\n".join(chunk) + "\n")


def _saved_runs(path: Path) -> list[dict]:
    """The runs already in ``path`` (cube.json), so that sizes can be measured separately."""
    return json.loads(path.read_text())["runs"] if path.exists() else []


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--num", type=int, nargs="+", default=[100, 200],
                        help="points per axis of each cube (1000: the 10^9-cell cube)")
    parser.add_argument("--threads", type=int, default=min(2, numba.config.NUMBA_NUM_THREADS))
    parser.add_argument("--compression", action="store_true",
                        help="compare HDF5 filters on the Fig. 5a map and a plane of a --num "
                        "cube instead")
    parser.add_argument("--dir", help="folder for the cube files (default: a temporary one)")
    parser.add_argument("--out", default=str(OUT))
    args = parser.parse_args()
    compute_chunk(cube(10), 0, 16)  # warm-up: kernels loaded or compiled
    out = Path(args.out)
    about = {"machine": f"{platform.machine()}, {os.cpu_count()} cores",
             "impactbeams": __version__, "numba": numba.__version__,
             "date": time.strftime("%Y-%m-%d %H:%M")}
    with tempfile.TemporaryDirectory(dir=args.dir) as directory:
        if args.compression:
            report = {**compression_study(args.num[0], Path(directory)), **about}
            (out / "compression.json").write_text(json.dumps(report, indent=1) + "\n")
            print(json.dumps(report, indent=1))
            return
        runs = {(r["num"], r["threads"]): r for r in _saved_runs(out / "cube.json")}
        for num in args.num:  # a size run again replaces its earlier result
            run = run_cube(num, args.threads, Path(directory))
            runs[num, args.threads] = {**run, "date": about["date"]}
    report = {"runs": [runs[key] for key in sorted(runs)], **about}
    (out / "cube.json").write_text(json.dumps(report, indent=1) + "\n")
    (out / "cube.md").write_text(markdown(report))
    print(markdown(report))


if __name__ == "__main__":
    main()
