"""Benchmark: the first run on a fresh install, which compiles the kernels (issue 24).

Each case runs a command as a user runs it (``main(argv)`` of impactbeams.cli), in a fresh
process with its own temporary NUMBA_CACHE_DIR: the first-impact map of 10 x 10 cells over
(Omega, F0) (Fig. 5a's parameters) with an empty cache ("cold") and again with the cache that
run left ("warm"), and ``simulate`` (spring law, 0.01 s) cold and warm. For each: wall and CPU
time of the process, and every compile Numba reports (its ``numba:compile`` events: kernel,
the kernel whose compile asked for it, and its own time without the kernels it compiled in
turn, CPU and wall). A cold run may compile part of its kernels in a helper process
(`impactbeams.compilation.compile_in_two_processes`): its CPU time counts in the run's, its
compiles are not listed. ``--baseline SRC`` (the ``src`` folder of another checkout, e.g. the
previous release) runs each case of that code right before this code's, in each round: on a
loaded machine only such back-to-back ratios compare. The load average is recorded. Writes
docs/benchmarks/compile.json and compile.md.

    python benchmarks/bench_compile.py [--repeats 2] [--baseline ../old/src]
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
from collections import defaultdict
from pathlib import Path

import numba
import numpy as np

from impactbeams import __version__
from run_all import SMALL_SWEEP

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
FIRST_MAP = SMALL_SWEEP.replace("num = 100", "num = 10")  # 10 x 10 cells of Fig. 5a's plane
# issue 24's "before" (main 4467146, 2 cores, machine partly loaded): wall seconds
ISSUE_BEFORE = {"first map, cold": 35.8, "simulate, cold": 56.0}
# runs one command in this process and writes what it compiled to the file argv[1]
_CHILD = """
import json, os, sys, time, threading
start, cpu = time.perf_counter(), time.process_time()
from numba.core import event

class Recorder(event.Listener):
    def __init__(self):
        self.stack, self.rows = [], []
    def on_start(self, e):
        self.stack.append([e.data["dispatcher"], time.perf_counter(), time.thread_time(), 0.0, 0.0])
    def on_end(self, e):
        dispatcher, wall, cpu, child_wall, child_cpu = self.stack.pop()
        wall, cpu = time.perf_counter() - wall, time.thread_time() - cpu
        if self.stack:
            self.stack[-1][3] += wall
            self.stack[-1][4] += cpu
        caller = self.stack[-1][0] if self.stack else None
        self.rows.append({"kernel": name(dispatcher), "caller": caller and name(caller),
                          "wall_s": wall - child_wall, "cpu_s": cpu - child_cpu})

def name(dispatcher):
    module = dispatcher.py_func.__module__.removeprefix("impactbeams.kernels.")
    return f"{module}.{dispatcher.py_func.__name__}"

recorder = Recorder()
with event.install_listener("numba:compile", recorder):
    from impactbeams.cli import main
    code = main(sys.argv[2:])
from impactbeams import compilation
for helper in getattr(compilation, "_helpers", {}).values():  # CPU of a compile helper too
    helper.wait()
children = os.times().children_user + os.times().children_system
with open(sys.argv[1], "w") as out:
    json.dump({"exit": code, "wall_s": time.perf_counter() - start,
               "cpu_s": time.process_time() - cpu + children, "compiles": recorder.rows}, out)
"""


def commands(folder: Path) -> dict[str, list[str]]:
    """Each kind of first run's arguments (writing into ``folder``)."""
    sweep = folder / "first-map.toml"
    sweep.write_text(FIRST_MAP)
    return {"first map": ["run", str(sweep), "-o", str(folder / "map.nc"), "--quiet"],
            "simulate": ["simulate", "--t-max", "0.01", "-o", str(folder / "run.nc")]}


def first_run(argv: list[str], cache: Path, source: Path | None, folder: Path,
              env: dict[str, str] | None = None) -> dict:
    """One command in a fresh process with NUMBA_CACHE_DIR=cache: its times and compiles.

    ``env``: more environment variables (``IMPACTBEAMS_PLAIN_NUMBA``: bench_numba_paths.py).
    """
    for output in folder.glob("*.nc"):
        output.unlink()
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONWARNINGS": "ignore",
           **(env or {})}
    if source is not None:
        env["PYTHONPATH"] = str(source)
    record = folder / "record.json"
    subprocess.run([sys.executable, "-c", _CHILD, str(record), *argv], env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.loads(record.read_text())


def rounds(codes: dict[str, Path | None], repeats: int) -> dict[str, dict[str, list[dict]]]:
    """Every case of each code, ``repeats`` rounds, the codes back to back in each."""
    runs: dict[str, dict[str, list[dict]]] = {code: defaultdict(list) for code in codes}
    with tempfile.TemporaryDirectory() as scratch:
        for round_ in range(repeats):
            for kind, argv in commands(Path(scratch)).items():
                for code, source in codes.items():
                    cache = Path(scratch, f"cache-{code}-{kind}-{round_}")
                    for state in ("cold", "warm"):  # the warm run reuses the cold one's cache
                        runs[code][f"{kind}, {state}"].append(
                            first_run(argv, cache, source, Path(scratch)))
    return runs


def kernel_table(records: list[dict]) -> list[dict]:
    """Per kernel over the cold runs of one case: compiles per run, mean own time, callers."""
    table: dict[str, dict] = {}
    for record in records:
        for row in record["compiles"]:
            entry = table.setdefault(row["kernel"], {"kernel": row["kernel"], "compiles": 0,
                                                     "cpu_s": 0.0, "wall_s": 0.0,
                                                     "callers": set()})
            entry["compiles"] += 1
            entry["cpu_s"] += row["cpu_s"]
            entry["wall_s"] += row["wall_s"]
            entry["callers"].add(row["caller"] or "(Python)")
    for entry in table.values():
        for key in ("compiles", "cpu_s", "wall_s"):
            entry[key] /= len(records)
        entry["callers"] = sorted(entry["callers"])
    return sorted(table.values(), key=lambda entry: -entry["cpu_s"])


def summary(runs: dict[str, list[dict]]) -> dict[str, dict]:
    """Median wall and CPU time and compile count of each case."""
    return {case: {"wall_s": statistics.median(r["wall_s"] for r in records),
                   "cpu_s": statistics.median(r["cpu_s"] for r in records),
                   "compiles": statistics.median(len(r["compiles"]) for r in records)}
            for case, records in runs.items()}


def markdown(report: dict) -> str:
    """compile.md: the cases against the baseline, and the costliest kernels of each."""
    base = report.get("baseline", {}).get("cases", {})
    lines = ["# First run: compiling the kernels", "",
             f"`benchmarks/bench_compile.py` ({report['date']}; {report['machine']}; load "
             f"average {report['load_average']['before']:.1f} before, "
             f"{report['load_average']['after']:.1f} after; median of {report['repeats']}). "
             "Each case is a fresh process with its own Numba cache folder: empty (cold) or "
             "left by the cold run (warm); its CPU time includes a compile helper process's, "
             "whose kernels are not counted. The first map: 10 x 10 cells of Fig. 5a's plane; "
             "simulate: the spring law over 0.01 s.", "",
             "| case | wall | CPU | kernels compiled | previous code (wall, CPU) | issue 24 |",
             "|---|---|---|---|---|---|"]
    for case, row in report["cases"].items():
        before = base.get(case)
        previous = f"{before['wall_s']:.1f} s, {before['cpu_s']:.1f} s" if before else "-"
        issue = f"{ISSUE_BEFORE[case]:.1f} s" if case in ISSUE_BEFORE else "-"
        lines.append(f"| {case} | {row['wall_s']:.1f} s | {row['cpu_s']:.1f} s | "
                     f"{row['compiles']:.0f} | {previous} | {issue} |")
    for case, table in report["kernels"].items():
        lines += ["", f"## {case}: the costliest compiles", "",
                  "Own time of each kernel's compile (without the kernels it compiled in "
                  "turn), mean over the cold runs; `numba.*` are Numba's own implementations.",
                  "", "| kernel | compiles per run | CPU | wall | called from |",
                  "|---|---|---|---|---|"]
        for entry in table[:15]:
            lines.append(f"| `{entry['kernel']}` | {entry['compiles']:g} | "
                         f"{entry['cpu_s']:.2f} s | {entry['wall_s']:.2f} s | "
                         f"{', '.join(entry['callers'][:4])} |")
        rest = table[15:]
        lines.append(f"| {len(rest)} others | {sum(e['compiles'] for e in rest):g} | "
                     f"{sum(e['cpu_s'] for e in rest):.2f} s | "
                     f"{sum(e['wall_s'] for e in rest):.2f} s | |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--baseline", type=Path, help="src folder of the code to compare with")
    args = parser.parse_args()
    load_before = os.getloadavg()
    codes = {"this": None}
    if args.baseline:
        codes["baseline"] = args.baseline.resolve()
    runs = rounds(codes, args.repeats)
    report = {
        "repeats": args.repeats,
        "cases": summary(runs["this"]),
        "kernels": {case: kernel_table(records) for case, records in runs["this"].items()
                    if case.endswith("cold")},
        "issue_before_s": ISSUE_BEFORE,
        "load_average": {"before": load_before[0], "after": os.getloadavg()[0]},
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
        "impactbeams": __version__,
        "numba": numba.__version__,
        "numpy": np.__version__,
        "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
    }
    if args.baseline:
        report["baseline"] = {"source": str(args.baseline), "cases": summary(runs["baseline"]),
                              "kernels": {case: kernel_table(records)
                                          for case, records in runs["baseline"].items()
                                          if case.endswith("cold")}}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "compile.json").write_text(json.dumps(report, indent=1) + "\n")
    (OUT / "compile.md").write_text(markdown(report))
    print(json.dumps({"cases": report["cases"],
                      "baseline": report.get("baseline", {}).get("cases")}, indent=1))


if __name__ == "__main__":
    main()
