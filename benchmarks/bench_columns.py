"""Benchmark: the Fig. 5a first-impact map by columns against cell by cell, in-process.

The same kernels, the same cells (1000 x 1000, t_max = 1 s, 5 modes per beam), the map's
compute alone (no I/O, kernels loaded): columns along F0 (one shared modal response per
column, as ``compute_chunk`` runs it) against columns of one cell (each cell searched on its
own from t = 0, the algorithm before columns), on 1 and 2 threads, best of ``--repeats``,
alternating the variants so that a shared machine's load hits both alike. Writes
docs/benchmarks/columns.json and docs/benchmarks/columns.md.

    python benchmarks/bench_columns.py [--repeats 5] [--sweep sweeps/fig5a-omega-force.toml]
"""

import argparse
import json
import time
from pathlib import Path

import numba
import numpy as np

from impactbeams.kernels import first_impact
from impactbeams.kernels.layout import CELL_F0
from impactbeams.sweep import load_sweep
from impactbeams.sweep.plan import build_plan, chunk_cells, first_impact_columns
from run_all import machine

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sweep", default=str(ROOT / "sweeps" / "fig5a-omega-force.toml"))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    sweep = load_sweep(args.sweep)
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, sweep.size)
    columns = first_impact_columns(sweep, 0, sweep.size)
    variants = {"columns": (columns.bounds, columns.key),
                "cells": (np.arange(sweep.size + 1), CELL_F0)}
    kernel = first_impact.first_impact_map_parallel
    maps = {name: np.empty(sweep.size) for name in variants}
    best = {(name, threads): np.inf for name in variants for threads in (1, 2)}
    for name, (bounds, key) in variants.items():  # load the kernels
        kernel(cells[:1000], bounds[:2], key, plan.tables, plan.geometry, sweep.t_max,
               maps[name][:1000])
    for _ in range(args.repeats):
        for threads in (1, 2):
            numba.set_num_threads(threads)
            for name, (bounds, key) in variants.items():
                start = time.perf_counter()
                kernel(cells, bounds, key, plan.tables, plan.geometry, sweep.t_max, maps[name])
                best[name, threads] = min(best[name, threads], time.perf_counter() - start)
    same = np.array_equal(np.isnan(maps["columns"]), np.isnan(maps["cells"]))
    hit = ~np.isnan(maps["cells"])
    report = {
        "sweep": Path(args.sweep).name, "cells": sweep.size, "t_max_s": sweep.t_max,
        "n_modes": sweep.n_modes, "columns": int(columns.bounds.size - 1),
        "impacted_fraction": float(hit.mean()), "same_classification": bool(same),
        "max_time_difference_s": float(np.abs(maps["columns"] - maps["cells"])[hit].max()),
        "best_s": {f"{name}, {threads} thread(s)": seconds
                   for (name, threads), seconds in best.items()},
        "speedup_columns_over_cells": {str(t): best["cells", t] / best["columns", t]
                                       for t in (1, 2)},
        "speedup_2_threads": {name: best[name, 1] / best[name, 2] for name in variants},
        "repeats": args.repeats,
        **machine(),
    }
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "columns.json").write_text(json.dumps(report, indent=2) + "\n")
    rows = "\n".join(f"| {name} | {best[name, 1]:.3f} s | {best[name, 2]:.3f} s | "
                     f"{best[name, 1] / best[name, 2]:.2f}x |" for name in variants)
    (OUT / "columns.md").write_text(
        f"# Fig. 5a map by columns ({sweep.size} cells, {report['columns']} columns)\n\n"
        "Compute only, kernels loaded, best of "
        f"{args.repeats} (`benchmarks/bench_columns.py`).\n\n"
        "| variant | 1 thread | 2 threads | 2-thread speed-up |\n|---|---|---|---|\n"
        f"{rows}\n\nColumns over cells: {report['speedup_columns_over_cells']['1']:.2f}x on 1 "
        f"thread, {report['speedup_columns_over_cells']['2']:.2f}x on 2; same classification "
        f"in every cell: {same}; largest difference in t*: "
        f"{report['max_time_difference_s']:.1e} s.\n")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
