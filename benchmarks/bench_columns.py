"""Benchmark: first-impact maps by columns, Fig. 5a and issue 24's other maps, in-process.

The map's compute alone (no I/O, kernels loaded), on 1 and 2 threads, best of ``--repeats``,
alternating maps and thread counts so that a shared machine's load hits all alike:

* Fig. 5a (sweeps/fig5a-omega-force.toml, 1000 x 1000 cells) by columns along F0 (as
  ``compute_chunk`` runs it) and cell by cell (each cell searched on its own from t = 0, the
  algorithm before columns), whose classification and times the columns must reproduce;
* the maps in benchmarks/maps/ (``MAPS``): uplifts on both beams, along the clearance, along
  the base amplitude with a shaker, a beam against a stop, and the shipped (Omega, clearance)
  map (400 x 400 cells); each reported per impacting cell against Fig. 5a's in the same
  process.

``--reference DIR`` compares every map with ``DIR/<map>.npy`` (the same classification in
every cell, the largest difference in t*), and stores the maps not there yet: run it once
on the previous code (with ``PYTHONPATH`` at that code and ``--out`` elsewhere) to store its
maps, then on this code. ``--previous FILE`` adds that run's results file to the report.
Writes columns.json and columns.md to ``--out`` (default docs/benchmarks).

    python benchmarks/bench_columns.py [--repeats 5] [--reference /tmp/maps] [--previous F]
"""

import argparse
import json
import os
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
FIG5A = ROOT / "sweeps" / "fig5a-omega-force.toml"
MAPS = {  # issue 24's maps: what each varies from Fig. 5a
    "uplift-omega-force": "uplifts on both beams (3 um each)",
    "force-clearance": "(F0, clearance), columns along the clearance",
    "shaker-omega-amplitude": "(Omega, U0), shaker on beam 1's clamp, spring law",
    "stop-omega-force": "beam 1 against a stop, Fig. 5a's plane",
    "omega-clearance": "(Omega, clearance) to 2000 rad/s, undamped: the shipped 400 x 400 map",
}
THREADS = (1, 2)


def _inputs(path: Path) -> dict:
    """A map's sweep, kernel inputs and variants ``{name: (bounds, key)}``."""
    sweep = load_sweep(path)
    plan = build_plan(sweep)
    columns = first_impact_columns(sweep, 0, sweep.size)
    return {"sweep": sweep, "plan": plan, "cells": chunk_cells(sweep, plan, 0, sweep.size),
            "columns": columns, "variants": {"columns": (columns.bounds, columns.key)}}


def _run(case: dict, variant: str, out: np.ndarray,
         cells: slice = slice(None)) -> tuple[float, float]:
    """Wall and CPU time (s) of one map variant on the current threads, into ``out``."""
    bounds, key = case["variants"][variant]
    if cells != slice(None):
        bounds = bounds[:2]
    sweep, plan = case["sweep"], case["plan"]
    start, cpu = time.perf_counter(), time.process_time()
    first_impact.first_impact_map_parallel(case["cells"][cells], bounds, key, plan.tables,
                                           plan.geometry, sweep.t_max, out[cells])
    return time.perf_counter() - start, time.process_time() - cpu


def _compare(new: np.ndarray, old: np.ndarray) -> dict:
    """Classification and largest t* difference of map ``new`` against map ``old``."""
    hit = ~np.isnan(old) & ~np.isnan(new)
    difference = np.abs(new - old)[hit]
    return {"same_classification": bool(np.array_equal(np.isnan(new), np.isnan(old))),
            "max_time_difference_s": float(difference.max()) if difference.size else 0.0,
            "max_relative_difference": float((difference / old[hit]).max())
            if difference.size else 0.0}


def measure(cases: dict[str, dict], repeats: int) -> tuple[dict, dict]:
    """Best wall times ``{(map, variant, threads): s}`` (and ``(map, variant, "cpu")``: the
    best CPU time on 1 thread, which a loaded machine inflates less) and the maps
    ``{(map, variant): out}``."""
    fig5a = cases["fig5a-omega-force"]
    fig5a["variants"]["cells"] = (np.arange(fig5a["sweep"].size + 1), CELL_F0)
    maps = {(name, variant): np.empty(case["sweep"].size)
            for name, case in cases.items() for variant in case["variants"]}
    for (name, variant), out in maps.items():  # load the kernels
        _run(cases[name], variant, out, slice(0, 1000))
    best = {(name, variant, threads): np.inf for name, variant in maps
            for threads in (*THREADS, "cpu")}
    for _ in range(repeats):
        for threads in THREADS:
            numba.set_num_threads(threads)
            for (name, variant), out in maps.items():
                seconds, cpu = _run(cases[name], variant, out)
                best[name, variant, threads] = min(best[name, variant, threads], seconds)
                if threads == 1:
                    best[name, variant, "cpu"] = min(best[name, variant, "cpu"], cpu)
    return best, maps


def report_of(cases: dict, best: dict, maps: dict, reference: Path | None,
              repeats: int) -> dict:
    """The results file's content: Fig. 5a's keys as before, and ``maps``, one per map."""
    fig5a = "fig5a-omega-force"
    columns, cells = maps[fig5a, "columns"], maps[fig5a, "cells"]
    check = _compare(columns, cells)
    hit = ~np.isnan(cells)
    entries = []
    for name in (fig5a, *MAPS):
        out, sweep = maps[name, "columns"], cases[name]["sweep"]
        impacting = int(np.count_nonzero(~np.isnan(out)))
        entry = {"map": name, "what": MAPS.get(name, "Fig. 5a"), "cells": sweep.size,
                 "t_max_s": sweep.t_max, "impacted_fraction": impacting / sweep.size,
                 "best_s": {str(t): best[name, "columns", t] for t in THREADS},
                 "best_cpu_1_thread_s": best[name, "columns", "cpu"],
                 "ns_per_impacting_cell": {str(t): 1e9 * best[name, "columns", t] / impacting
                                           for t in THREADS},
                 "speedup_2_threads": best[name, "columns", 1] / best[name, "columns", 2]}
        if reference is not None:
            stored = reference / f"{name}.npy"
            if stored.exists():
                entry["against_reference"] = _compare(out, np.load(stored))
            else:
                reference.mkdir(parents=True, exist_ok=True)
                np.save(stored, out)
        entries.append(entry)
    per_cell = entries[0]["ns_per_impacting_cell"]
    for entry in entries:
        entry["per_impacting_cell_over_fig5a"] = {
            t: entry["ns_per_impacting_cell"][t] / per_cell[t] for t in per_cell}
    sweep = cases[fig5a]["sweep"]
    return {
        "sweep": FIG5A.name, "cells": sweep.size, "t_max_s": sweep.t_max,
        "n_modes": sweep.n_modes, "columns": int(cases[fig5a]["columns"].bounds.size - 1),
        "impacted_fraction": float(hit.mean()), **check,
        "best_s": {f"{variant}, {t} thread(s)": best[fig5a, variant, t]
                   for variant in ("columns", "cells") for t in THREADS},
        "speedup_columns_over_cells": {str(t): best[fig5a, "cells", t] / best[fig5a, "columns", t]
                                       for t in THREADS},
        "speedup_2_threads": {variant: best[fig5a, variant, 1] / best[fig5a, variant, 2]
                              for variant in ("columns", "cells")},
        "maps": entries, "repeats": repeats, "load_average": os.getloadavg()[0], **machine(),
    }


def markdown(report: dict, previous: dict | None) -> str:
    """columns.md: Fig. 5a's variants, then every map per impacting cell."""
    best = report["best_s"]
    rows = "\n".join(f"| {variant} | {best[f'{variant}, 1 thread(s)']:.3f} s | "
                     f"{best[f'{variant}, 2 thread(s)']:.3f} s | "
                     f"{report['speedup_2_threads'][variant]:.2f}x |"
                     for variant in ("columns", "cells"))
    before = {entry["map"]: entry for entry in (previous or {}).get("maps", [])}
    if previous and "maps" not in previous:  # a results file from before the other maps
        before = {"fig5a-omega-force": {"best_s": {
            str(t): previous["best_s"][f"columns, {t} thread(s)"] for t in THREADS}}}
    lines = []
    for entry in report["maps"]:
        seconds, per_cell = entry["best_s"], entry["ns_per_impacting_cell"]
        ratio = entry["per_impacting_cell_over_fig5a"]
        old = before.get(entry["map"], {}).get("best_s")
        check = entry.get("against_reference")
        lines.append(
            f"| `{entry['map']}` | {entry['impacted_fraction']:.0%} of {entry['cells']:,} | "
            f"{seconds['1']:.3f} s (CPU {entry['best_cpu_1_thread_s']:.3f} s) | "
            f"{seconds['2']:.3f} s | {entry['speedup_2_threads']:.2f}x | "
            f"{per_cell['1']:.0f} / {per_cell['2']:.0f} | {ratio['1']:.2f} / {ratio['2']:.2f} | "
            + (f"{old['1']:.3f} / {old['2']:.3f} s" if old else "-") + " | "
            + (f"{check['same_classification']}, {check['max_time_difference_s']:.1e} s"
               if check else "-") + " |")
    return ("# First-impact maps by columns\n\n"
            f"Compute only, kernels loaded, best of {report['repeats']} "
            f"(`benchmarks/bench_columns.py`, load average {report['load_average']:.1f} at the "
            "end).\n\n## Fig. 5a\n\n"
            "| variant | 1 thread | 2 threads | 2-thread speed-up |\n|---|---|---|---|\n"
            f"{rows}\n\nColumns over cells: {report['speedup_columns_over_cells']['1']:.2f}x "
            f"on 1 thread, {report['speedup_columns_over_cells']['2']:.2f}x on 2; same "
            f"classification in every cell: {report['same_classification']}; largest "
            f"difference in t*: {report['max_time_difference_s']:.1e} s.\n\n"
            "## Every map (`sweeps/fig5a-omega-force.toml`, `benchmarks/maps/*.toml`)\n\n"
            "Per impacting cell (ns, 1 / 2 threads) and over Fig. 5a's in the same run; the "
            "previous code's times (`--previous`) and the check against its maps "
            "(`--reference`: same classification in every cell, largest difference in t*).\n\n"
            "| map | impacting | 1 thread | 2 threads | speed-up | ns per impacting cell | "
            "over Fig. 5a | previous code | against previous maps |\n"
            "|---|---|---|---|---|---|---|---|---|\n" + "\n".join(lines) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--reference", type=Path, help="folder of stored maps to compare with")
    parser.add_argument("--previous", type=Path, help="the previous code's columns.json")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    names = {"fig5a-omega-force": FIG5A,
             **{name: ROOT / "benchmarks" / "maps" / f"{name}.toml" for name in MAPS}}
    cases = {name: _inputs(path) for name, path in names.items()}
    best, maps = measure(cases, args.repeats)
    report = report_of(cases, best, maps, args.reference, args.repeats)
    previous = json.loads(args.previous.read_text()) if args.previous else None
    if previous is not None:
        report["previous"] = previous
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "columns.json").write_text(json.dumps(report, indent=2) + "\n")
    (args.out / "columns.md").write_text(markdown(report, previous))
    print(markdown(report, previous))


if __name__ == "__main__":
    main()
