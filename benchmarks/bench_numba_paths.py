"""Benchmark: the fast path against plain Numba kernels (kernels/jit.py, issue 35).

Compile: the first runs of ``bench_compile.py`` (a 10 x 10 first map and a 0.01 s simulate,
each in a fresh process with an empty Numba cache, then warm), on each path. Run: in a
fresh process per path and round, kernels loaded (a first call compiles or loads them), the
best of ``--repeats`` of the Fig. 5a map (1000 x 1000 cells), 8 cells of the long-time
diagram (sweeps/bifurcation-omega.toml: the Hertz law's long runs, where the fast path's
borrowing kernels count no references) on one thread, and a simulate of each contact law,
whose results (every variable's bytes) are compared between the paths. The
paths alternate, back to back, so that a shared machine's load hits both alike; the load
average is recorded. Writes docs/benchmarks/numba_paths.json.

    python benchmarks/bench_numba_paths.py [--rounds 2] [--repeats 5]
"""

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numba

from bench_compile import commands, first_run
from impactbeams import __version__
from impactbeams.kernels.jit import PLAIN_NUMBA

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
PATHS = {"fast": "", "plain": "1"}  # IMPACTBEAMS_PLAIN_NUMBA of each path
LONG_TIME_CELLS = 8  # of the long-time diagram's 400 frequencies
# runs each case once to load its kernels, then times it; prints the best times and a digest
# of each case's results
_CHILD = """
import hashlib, json, sys, time
from impactbeams import Params, simulate
from impactbeams.sweep import load_sweep, run_sweep, sweep_from_mapping
from impactbeams.sweep.definition import read_toml

repeats, cells = int(sys.argv[1]), int(sys.argv[2])
diagram = read_toml("sweeps/bifurcation-omega.toml")
diagram["axes"]["omega"]["num"] = cells
fig5a, long_time = load_sweep("sweeps/fig5a-omega-force.toml"), sweep_from_mapping(diagram)
cases = {
    "Fig. 5a map, 1000 x 1000 cells, 1 thread": lambda: run_sweep(fig5a, threads=1),
    f"long-time diagram (Hertz, 32 modes), {cells} cells, 1 thread":
        lambda: run_sweep(long_time, threads=1),
    "simulate, tied law, 20 s (output every ms)":
        lambda: simulate(Params(contact_law="tied"), 20.0, dt_output=1e-3),
    "simulate, spring law, 3 s (output every ms)":
        lambda: simulate(Params(contact_law="spring"), 3.0, dt_output=1e-3),
}
best, digests = {}, {}
for case, run in cases.items():
    dataset = run()
    digests[case] = hashlib.sha256(b"".join(
        dataset[name].values.tobytes() for name in sorted(dataset.variables))).hexdigest()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    best[case] = min(times)
print(json.dumps({"best_s": best, "digests": digests}))
"""


def _environment(path: str, cache: Path) -> dict[str, str]:
    env = {key: value for key, value in os.environ.items() if key != PLAIN_NUMBA}
    env.update({"NUMBA_CACHE_DIR": str(cache), "PYTHONWARNINGS": "ignore"})
    if PATHS[path]:
        env[PLAIN_NUMBA] = PATHS[path]
    return env


def compile_times(rounds: int, scratch: Path) -> dict[str, dict[str, list[dict]]]:
    """Each path's first runs (bench_compile's cases), cold then warm, ``rounds`` times."""
    runs: dict[str, dict[str, list[dict]]] = {path: {} for path in PATHS}
    for round_ in range(rounds):
        for kind, argv in commands(scratch).items():
            for path in PATHS:
                cache = scratch / f"cache-{path}-{kind}-{round_}"
                for state in ("cold", "warm"):
                    record = first_run(argv, cache, None, scratch,
                                       env={PLAIN_NUMBA: PATHS[path]})
                    runs[path].setdefault(f"{kind}, {state}", []).append(record)
    return runs


def run_times(rounds: int, repeats: int, scratch: Path) -> dict[str, list[dict]]:
    """Each path's best run times, one process per round (its own warm cache per path)."""
    best: dict[str, list[dict]] = {path: [] for path in PATHS}
    for _ in range(rounds):
        for path in PATHS:
            done = subprocess.run(
                [sys.executable, "-c", _CHILD, str(repeats), str(LONG_TIME_CELLS)], cwd=ROOT,
                env=_environment(path, scratch / f"cache-run-{path}"), check=True,
                capture_output=True, text=True)
            best[path].append(json.loads(done.stdout))
    return best


def report(compiles: dict, runs: dict, rounds: int, repeats: int, load: tuple) -> dict:
    """The results file: medians over the rounds of each path's cases."""
    return {
        "rounds": rounds, "repeats": repeats,
        "compile": {path: {case: {key: statistics.median(r[key] for r in records)
                                  for key in ("wall_s", "cpu_s")}
                           for case, records in cases.items()}
                    for path, cases in compiles.items()},
        "run_best_s": {path: {case: statistics.median(r["best_s"][case] for r in records)
                              for case in records[0]["best_s"]}
                       for path, records in runs.items()},
        "same_results": len({json.dumps(r["digests"], sort_keys=True)
                             for records in runs.values() for r in records}) == 1,
        "load_average": {"before": load[0], "after": os.getloadavg()[0]},
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
        "impactbeams": __version__,
        "numba": numba.__version__,
        "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    load = os.getloadavg()
    with tempfile.TemporaryDirectory() as scratch:
        compiles = compile_times(args.rounds, Path(scratch))
        runs = run_times(args.rounds, args.repeats, Path(scratch))
    result = report(compiles, runs, args.rounds, args.repeats, load)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "numba_paths.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
