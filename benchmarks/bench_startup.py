"""Benchmark: start-up of every command, and what each one imports (issue 24).

Each command runs as a user runs it, in a fresh process (``main()`` of impactbeams.cli with
the arguments in ``sys.argv``, as the console script calls it): ``--help``, ``modes`` (spring
and tied contact), ``run`` of the Fig. 5a map into a new file, ``run`` again onto that
finished file (reused), and ``plot`` of the map. Python's bytecode of every module is cached
(in a scratch ``PYTHONPYCACHEPREFIX``, written in the warm-up round), as in an installed
package, even where ``PYTHONDONTWRITEBYTECODE`` is set (which would compile the package's
sources in every process). Rounds interleave the commands, so that a load on the machine falls
on all of them alike, after one warm-up round (Numba's cache warm); each command's wall time
and CPU time (user + system, all threads) are the medians over the rounds. Also measured,
each in a fresh process: the bare interpreter, the heavy libraries each command imports, and
the import time of each such library on its own (``python -X importtime``, cumulative), and
the CPU time of each phase of ``plot`` (import, read, draw, save) inside its process. The
load average is recorded before and after. ``--baseline SRC`` (the ``src`` folder of another
checkout, e.g. the previous release) runs each command of that code too, right before this
code's in each round, and reports the ratios of the medians: on a loaded machine only such
back-to-back ratios compare, CPU times better than wall times. Writes
docs/benchmarks/startup.json.

    python benchmarks/bench_startup.py [--repeats 5] [--sweep sweeps/fig5a-omega-force.toml]
                                       [--baseline ../old/src]
"""

import argparse
import datetime
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

from impactbeams import __version__

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
# the libraries whose import is a visible part of a command's start-up
HEAVY = ("numpy", "scipy", "scipy.linalg", "scipy.optimize", "numba", "netCDF4", "pandas",
         "xarray", "dask", "matplotlib.figure", "matplotlib.backends.backend_agg",
         "matplotlib.pyplot")
_MAIN = "import sys\nfrom impactbeams.cli import main\nsys.exit(main())"
_LOADED = ("import sys\nfrom impactbeams.cli import main\ntry:\n    main()\n"
           "except SystemExit:\n    pass\nimport json\n"  # a module hidden as None: not loaded
           "print(json.dumps(sorted(name for name, module in sys.modules.items()\n"
           "                        if module is not None and name in {heavy!r})))")


def commands(sweep: str, folder: Path) -> dict[str, list[str]]:
    """Each command's arguments; ``run`` writes a new file (`fresh_output` removes it first)."""
    fresh, reused = str(folder / "fresh.nc"), str(folder / "map.nc")
    return {
        "--help": ["--help"],
        "modes": ["modes"],
        "modes --contact-law tied": ["modes", "--contact-law", "tied"],
        "run": ["run", sweep, "-o", fresh, "--quiet"],
        "run (output reused)": ["run", sweep, "-o", reused, "--quiet"],
        "plot": ["plot", reused, "-o", str(folder / "map.png")],
    }


def environment(bytecode: Path, source: Path | None = None) -> dict[str, str]:
    """The commands' environment: bytecode cached under ``bytecode``, ``source`` imported.

    ``source``: the package's folder to import (default: the one this process imports).
    """
    env = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(bytecode)
    if source is not None:
        env["PYTHONPATH"] = str(source)
    return env


def seconds(argv: list[str], env: dict[str, str], code: str = _MAIN) -> tuple[float, float]:
    """Wall and CPU time (user + system) of one command (``python -c code ARGV``) in a fresh
    process (output discarded)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, *argv], check=True, env=env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


# the plot command's phases, timed inside its process (CPU seconds): what ``plot MAP -o PNG``
# does, step by step (impactbeams.cli._plot)
_PLOT_PHASES = """
import json, sys, time
start = time.process_time()
from impactbeams.plotting import draw
from impactbeams.plotting.arrays import read_figure_data
from impactbeams.plotting.files import save_figure
from matplotlib.figure import Figure
imported = time.process_time()
dataset = read_figure_data(sys.argv[1], "input")
read = time.process_time()
figure = Figure(figsize=(7, 5), layout="constrained")
draw(figure.subplots(), dataset)
drawn = time.process_time()
save_figure(figure, sys.argv[2])
saved = time.process_time()
print(json.dumps({"import": imported - start, "read": read - imported, "draw": drawn - read,
                  "save": saved - drawn}))
"""


def plot_phases(folder: Path, env: dict[str, str], repeats: int) -> dict[str, float]:
    """Median CPU seconds of each phase of ``plot`` of the map in ``folder`` (import, read the
    file, draw the figure, save it: layout, rendering, PNG), each run in a fresh process."""
    runs = [json.loads(subprocess.run(
        [sys.executable, "-c", _PLOT_PHASES, str(folder / "map.nc"), str(folder / "phases.png")],
        check=True, capture_output=True, text=True, env=env).stdout) for _ in range(repeats)]
    return {phase: statistics.median(run[phase] for run in runs) for phase in runs[0]}


def heavy_imports(argv: list[str], env: dict[str, str]) -> list[str]:
    """The `HEAVY` libraries a fresh process has imported after the command."""
    result = subprocess.run([sys.executable, "-c", _LOADED.format(heavy=HEAVY), *argv],
                            check=True, capture_output=True, text=True, env=env)
    return json.loads(result.stdout.strip().splitlines()[-1])


def import_seconds(module: str, env: dict[str, str]) -> float:
    """Cumulative import time of ``module`` alone in a fresh interpreter (-X importtime)."""
    result = subprocess.run([sys.executable, "-X", "importtime", "-c", f"import {module}"],
                            check=True, capture_output=True, text=True, env=env)
    last = [line for line in result.stderr.splitlines() if line.startswith("import time:")][-1]
    return int(last.split("|")[1]) * 1e-6


Times = dict[str, dict[str, list[float]]]  # code: command: one time per round


def interleaved(codes: dict[str, tuple[dict[str, str], Path]], sweep: str,
                repeats: int) -> tuple[Times, Times]:
    """Wall and CPU times of every command of each code (its environment, its scratch
    folder), ``repeats`` rounds of one run each, after a warm-up round (Numba's cache, the
    reused map, the bytecode)."""
    walls: Times = {code: {} for code in codes}
    cpus: Times = {code: {} for code in codes}
    for round_ in range(repeats + 1):
        for name in [*commands(sweep, Path()), "python -c pass"]:
            for code, (env, folder) in codes.items():
                (folder / "fresh.nc").unlink(missing_ok=True)
                argv = commands(sweep, folder).get(name)
                if argv is None and code != "this":  # the bare interpreter: measured once
                    continue
                wall, cpu = seconds(argv, env) if argv else seconds([], env, code="pass")
                if round_:
                    walls[code].setdefault(name, []).append(wall)
                    cpus[code].setdefault(name, []).append(cpu)
    return walls, cpus


def medians(times: dict[str, list[float]]) -> dict[str, float]:
    """Each command's median time."""
    return {name: statistics.median(t) for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--sweep", default=str(ROOT / "sweeps" / "fig5a-omega-force.toml"))
    parser.add_argument("--baseline", type=Path, help="src folder of the code to compare with")
    args = parser.parse_args()
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as scratch:
        bytecode = Path(scratch, "bytecode")
        codes = {"this": (environment(bytecode), Path(scratch, "this"))}
        if args.baseline:
            codes["baseline"] = (environment(bytecode, args.baseline.resolve()),
                                 Path(scratch, "baseline"))
        for _, folder in codes.values():
            folder.mkdir()
        walls, cpus = interleaved(codes, args.sweep, args.repeats)
        env, folder = codes["this"]
        imports = {name: heavy_imports(argv, env)
                   for name, argv in commands(args.sweep, folder).items()}
        import_alone = {module: statistics.median(import_seconds(module, env)
                                                  for _ in range(args.repeats))
                        for module in HEAVY}
        phases = plot_phases(folder, env, args.repeats)
    median = medians(walls["this"])
    cpu = medians(cpus["this"])
    report = {
        "sweep": Path(args.sweep).name,
        "repeats": args.repeats,
        "median_s": median,
        "cpu_median_s": cpu,
        "runs_s": walls["this"],
        "cpu_runs_s": cpus["this"],
        "heavy_imports": imports,
        "import_alone_s": import_alone,
        "plot_phases_cpu_s": phases,
        "load_average": {"before": load_before[0], "after": os.getloadavg()[0]},
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
        "impactbeams": __version__,
        "numba": numba.__version__,
        "numpy": np.__version__,
        "date": datetime.date.today().isoformat(),
    }
    if args.baseline:
        baseline, baseline_cpu = medians(walls["baseline"]), medians(cpus["baseline"])
        report["baseline"] = {"source": str(args.baseline), "median_s": baseline,
                              "cpu_median_s": baseline_cpu, "runs_s": walls["baseline"],
                              "cpu_runs_s": cpus["baseline"],
                              "ratio_to_baseline": {name: median[name] / baseline[name]
                                                    for name in baseline},
                              "cpu_ratio_to_baseline": {name: cpu[name] / baseline_cpu[name]
                                                        for name in baseline_cpu}}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "startup.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps({key: report[key] for key in ("median_s", "cpu_median_s", "heavy_imports",
                                                  "plot_phases_cpu_s")},
                     indent=2))
    if args.baseline:
        print(json.dumps({key: report["baseline"][key] for key in
                          ("median_s", "cpu_median_s", "ratio_to_baseline",
                           "cpu_ratio_to_baseline")}, indent=2))


if __name__ == "__main__":
    main()
