"""Run the whole benchmark suite; write JSON, PNG plots and a README into docs/benchmarks/.

    python benchmarks/run_all.py            # full size (tens of minutes on 2 cores)
    python benchmarks/run_all.py --quick    # small sizes, a couple of minutes
    python benchmarks/run_all.py --speed-only --baseline REVISION   # the speed targets only

Steps: ``bench_sweep.py`` (the Fig. 5a map: compile and run time, 1 and 2 threads, in process
and as a command), ``bench_cube.py`` (an (Omega, clearance, F0) cube streamed into netCDF), the
work-precision studies (``work_precision.py``: first-impact map, grazing cells, full dynamics;
``spring_precision.py``: full dynamics of the spring law against solve_ivp), the scaling
series (``scaling.py``), ``bench_distributed.py`` (Dask overhead, if installed),
``bench_continuation.py`` (the time per branch point of a continuation),
``bench_two_parameter.py`` (the time per point of a bifurcation curve),
``bench_contacts.py`` (several contacts against one, by contacts and modes), then the speed
targets' benchmarks: ``bench_columns.py`` (every benchmark map by columns), ``bench_longtime.py``
(the long-time bifurcation diagram, run whole on 2 threads), ``bench_compile.py`` (the first
run's compile, cold and warm), ``bench_startup.py`` (each command's start-up) and
``bench_numba_paths.py`` (compile and run times of the fast path and of plain Numba kernels).
``--baseline REVISION`` (a git revision, e.g. the previous release) checks that code out into a
temporary worktree and runs each speed benchmark on it too, right before this code's: the maps
(and this code's checked against them cell by cell), the long-time diagram (its periods
compared cell by cell), the first run and the start-up. Results go to
``work_precision.json``, ``dynamics.json``, ``spring.json``, ``scaling.json`` (plus
``sweep.json``/``sweep.md`` from bench_sweep, ``cube.json``/``cube.md`` from bench_cube,
``distributed.json``/``.md``, ``columns.json``/``.md``, ``longtime.json``/``.md``,
``continuation.json``/``.md``, ``two_parameter.json``/``.md``, ``contacts.json``,
``compile.json``/``.md``,
``startup.json``,
``numba_paths.json``); the plots are drawn
from those JSON files only; ``README.md`` holds the headline tables, the speed targets' first.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

import bench_contacts as contacts  # noqa: E402
import bench_harmonic_balance as harmonic_balance  # noqa: E402
import bench_longtime as longtime  # noqa: E402
import scaling  # noqa: E402
import spring_precision as spring  # noqa: E402
import work_precision as wp  # noqa: E402

SMALL_SWEEP = """t_max = 1.0
n_modes = 5
[params]
clearance = 1.1e-5
[axes.omega]
min = 10.0
max = 400.0
num = 100
[axes.force_amplitude]
min = 1e-6
max = 1e-3
num = 100
scale = "log"
"""

TARGETS = {"solve_ivp": 1000.0, "numpy": 10.0}


def log(message: str) -> None:
    """Progress on stderr, with a timestamp."""
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def machine() -> dict[str, str]:
    """Where and when the numbers were measured."""
    import numba
    import numpy
    import scipy

    from impactbeams import __version__

    return {"machine": f"{platform.machine()}, {os.cpu_count()} cores",
            "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__, "impactbeams": __version__,
            "date": time.strftime("%Y-%m-%d %H:%M")}


def run_bench_sweep(quick: bool) -> None:
    """The existing Fig. 5a benchmark (1e6 cells; 1e4 cells with --quick)."""
    command = [sys.executable, str(HERE / "bench_sweep.py")]
    with tempfile.TemporaryDirectory() as tmp:
        if quick:
            path = Path(tmp) / "small.toml"
            path.write_text(SMALL_SWEEP)
            command += ["--sweep", str(path), "--repeats", "1"]
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)


def run_bench_cube(quick: bool) -> None:
    """The streamed cube (10^6 and 8 10^6 cells, extrapolated to 10^9; 50^3 with --quick)."""
    sizes = ["50"] if quick else ["100", "200"]
    subprocess.run([sys.executable, str(HERE / "bench_cube.py"), "--num", *sizes], check=True,
                   stdout=subprocess.DEVNULL)


def _script(name: str, *arguments: str, src: Path | None = None) -> None:
    """Run benchmarks/NAME with ``arguments``, importing impactbeams from ``src`` if given."""
    env = {**os.environ, "PYTHONPATH": str(src)} if src else None
    subprocess.run([sys.executable, str(HERE / name), *arguments], check=True, env=env,
                   stdout=subprocess.DEVNULL)


@contextlib.contextmanager
def checkout(revision: str | None) -> Iterator[Path | None]:
    """The ``src`` folder of git ``revision`` in a temporary worktree (None without one)."""
    if revision is None:
        yield None
        return
    with tempfile.TemporaryDirectory() as scratch:
        tree = Path(scratch, "baseline")
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--quiet", "--detach",
                        str(tree), revision], check=True)
        try:
            yield tree / "src"
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)],
                           check=True)


def run_bench_columns(quick: bool, out: Path, baseline: Path | None) -> None:
    """Every benchmark map by columns, with the baseline's times and maps beside them."""
    repeats = ["--repeats", "1" if quick else "5"]
    with tempfile.TemporaryDirectory() as scratch:
        against: list[str] = []
        if baseline:
            maps = str(Path(scratch, "maps"))
            _script("bench_columns.py", *repeats, "--out", scratch, "--reference", maps,
                    src=baseline)
            against = ["--reference", maps, "--previous", str(Path(scratch, "columns.json"))]
        _script("bench_columns.py", *repeats, "--out", str(out), *against)


def run_bench_longtime(quick: bool, out: Path, baseline: Path | None) -> None:
    """The long-time bifurcation diagram's cost and profile (its own JSON and markdown), the
    whole diagram run on 2 threads, and the baseline's (periods compared cell by cell)."""
    size = ["--stride", "100", "--no-profile"] if quick else ["--full"]
    with tempfile.TemporaryDirectory() as scratch:
        against: list[str] = []
        if baseline:
            _script("bench_longtime.py", *size, "--no-profile", "--map-stride", "0", "--out",
                    scratch, src=baseline)
            against = ["--previous", str(Path(scratch, "longtime.json"))]
        _script("bench_longtime.py", *size, "--out", str(out), *against)


def run_bench_continuation(quick: bool) -> None:
    """The continuation's time per branch point (its own JSON and markdown)."""
    command = [sys.executable, str(HERE / "bench_continuation.py")]
    if quick:
        command += ["--points", "4"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)


def run_bench_two_parameter() -> None:
    """The time per point of a bifurcation curve in two parameters (its JSON and markdown)."""
    subprocess.run([sys.executable, str(HERE / "bench_two_parameter.py")], check=True,
                   stdout=subprocess.DEVNULL)


def run_bench_contacts(quick: bool) -> None:
    """Several contacts against one, by contacts and modes (contacts.json)."""
    _script("bench_contacts.py", "--repeats", "1" if quick else "7")


def run_bench_first_run(quick: bool, baseline: Path | None) -> None:
    """The first run's compile (cold and warm) and every command's start-up (their JSON),
    each case of the baseline run right before this code's; the fast path against plain
    Numba kernels."""
    against = ["--baseline", str(baseline)] if baseline else []
    for script in ("bench_compile.py", "bench_startup.py"):
        _script(script, "--repeats", "1" if quick else "3", *against)
    _script("bench_numba_paths.py", "--rounds", "1" if quick else "2")


def run_bench_distributed(quick: bool) -> None:
    """The Dask overhead benchmark (its own JSON and markdown), if Dask is installed."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        log("dask.distributed not installed: skipping bench_distributed.py")
        return
    command = [sys.executable, str(HERE / "bench_distributed.py")]
    if quick:
        command += ["--num", "100", "--repeats", "1"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)


# ---------------------------------------------------------------------------------------------
# Plots (from the saved JSON only)


def _floor(values, floor=1e-18):
    return [max(v, floor) for v in values]


def _wp_panel(ax, points, reference, title, key="max", time_key="seconds_per_cell",
              same_n=None):
    """One work-precision panel; with ``same_n``, only points with that many modes (a
    reference that solves the n-mode equations says nothing about other n)."""
    import matplotlib.pyplot as plt

    families = sorted({p["method"] for p in points if "ivp cells" not in p["method"]})
    colors = dict(zip(families, plt.rcParams["axes.prop_cycle"].by_key()["color"],
                      strict=False))
    for family in families:
        rows = [p for p in points if p["method"] == family
                and (same_n is None or p["n_modes"] == same_n)]
        errors = [p["errors"][reference] for p in rows]
        x = _floor([e[key] for e in errors])
        y = [p[time_key] for p in rows]
        ax.plot(x, y, "-", color=colors[family], alpha=0.5)
        for xi, yi, e, p in zip(x, y, errors, rows, strict=True):
            bad = e.get("missed", 0) + e.get("spurious", 0) + abs(e.get("count_diff", 0))
            ax.plot(xi, yi, "o", color=colors[family], mfc="none" if bad else colors[family])
            label = p["setting"].split("=")[1]
            ax.annotate(label + (f" [{bad}]" if bad else ""), (xi, yi), fontsize=6,
                        xytext=(3, 3), textcoords="offset points")
        ax.plot([], [], "o-", color=colors[family], label=family)
    ax.set(xscale="log", yscale="log", title=title)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7)


def plot_first_impact(results: dict, path: Path) -> None:
    """Run time per cell against max |t* error|, three panels (grid x 2 refs, grazing)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 5), constrained_layout=True)
    panels = [("grid", "many_modes", "map grid vs many-mode reference (truncation)"),
              ("grid", "exact_n", "map grid vs exact same-n solution (integration)"),
              ("grazing", "exact_n", "grazing cells vs exact same-n solution")]
    n = results["config"]["n_default"]
    for ax, (cells, ref, title) in zip(axes, panels, strict=True):
        _wp_panel(ax, results[cells]["points"], ref, title,
                  same_n=n if ref == "exact_n" else None)
        ax.set(xlabel="max |t* - t*_ref| (s) [hollow: missed/spurious impacts]",
               ylabel="run time per cell (s, 1 thread)")
    fig.suptitle("First impact: work-precision (labels: setting [missed + spurious])")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_dynamics(results: dict, path: Path) -> None:
    """Run time against max onset-time error of the impact sequence, two references."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), constrained_layout=True)
    for ax, ref, title in zip(axes, ("tight_ivp", "many_modes"),
                              ("vs tight DOP853, same modes", "vs many-mode simulate"),
                              strict=True):
        _wp_panel(ax, results["points"], ref, title, key="onset_max", time_key="seconds",
                  same_n=results["config"]["n_default"] if ref == "tight_ivp" else None)
        ax.set(xlabel="max onset-time error (s) [label: |impact-count difference|]",
               ylabel="run time (s)")
    fig.suptitle(f"Full dynamics, Fig. 3 case, t_max = {results['config']['t_max']} s")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_scaling(results: dict, path: Path) -> None:
    """Run time against grid size, t_max and modes; 1 vs 2 threads."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(18, 4.2), constrained_layout=True)
    for ax, key, label in zip(axes[:3], ("grid_size", "t_max", "n_modes"),
                              ("cells", "t_max (s)", "modes per beam"), strict=True):
        rows = results[key]
        x = [r["cells"] if key == "grid_size" else r[key] for r in rows]
        ax.loglog(x, [r["seconds"] for r in rows], "o-")
        ax.set(xlabel=label, ylabel="run time (s)", title=f"time vs {label}")
        ax.grid(True, alpha=0.3)
    threads = results["threads"]
    axes[3].bar([str(r["threads"]) for r in threads], [r["cells_per_second"] for r in threads])
    axes[3].set(xlabel="threads", ylabel="cells per second",
                title=f"{threads[0]['cells']:,} cells")
    compile_ = results["compile"]
    fig.suptitle(f"First-impact map scaling (compile apart: {compile_['cold_s']:.1f} s cold, "
                 f"{compile_['warm_cache_s']:.2f} s from cache)")
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------
# Headline table


def _speedups(first: dict) -> dict[str, dict]:
    """Matched-error speed-ups on the map grid, per baseline family and reference."""
    return {(m["baseline"], m["reference"]): m for m in first["grid"]["matched"]}


def _default_errors(cells: dict, n_default: int) -> dict:
    point = next(p for p in cells["points"] if p["method"] == "impactbeams"
                 and p["n_modes"] == n_default)
    return point["errors"]


def _baseline_misses(cells: dict) -> dict[str, int]:
    """Fewest missed + spurious impacts of each baseline family over its settings."""
    out = {}
    for p in cells["points"]:
        if p["method"].startswith("impactbeams"):
            continue
        e = p["errors"]["exact_n"]
        out.setdefault(p["method"], []).append(e["missed"] + e["spurious"])
    return {k: (min(v), max(v)) for k, v in out.items()}


def headline(first: dict, dynamics: dict, scale: dict, quick: bool) -> str:
    """The page's history section: the full suite's headline table and targets, as run then."""
    n = first["config"]["n_default"]
    speed = _speedups(first)
    grid_err, graze_err = (_default_errors(first[k], n) for k in ("grid", "grazing"))
    lines = ["| quantity | value |", "|---|---|"]
    for row in scale["threads"]:
        lines.append(f"| cells per second, {row['threads']} thread(s), {row['cells']:,}-cell "
                     f"map, t_max = 1 s, {n} modes (`scaling.json`) | "
                     f"{row['cells_per_second']:,.0f} |")
    verdicts = []
    for (family, ref), m in sorted(speed.items()):
        bound = ">= " if m["lower_bound"] else ""
        lines.append(f"| speed-up over {family} at matched error ({ref} reference; its "
                     f"{m['setting']}) | {bound}{m['speedup']:,.0f}x |")
        goal = TARGETS["solve_ivp" if family.startswith("solve_ivp") else "numpy"]
        verdicts.append(f"{family} ({ref}): {m['speedup']:,.0f}x vs target {goal:g}x: "
                        f"{'met' if m['speedup'] >= goal else 'NOT met'}")
    for name, errors in (("map grid", grid_err), ("grazing cells", graze_err)):
        for ref in ("exact_n", "many_modes"):
            e = errors[ref]
            lines.append(f"| worst t* error of impactbeams ({n} modes), {name}, vs {ref} | "
                         f"{e['max']:.2e} s; missed {e['missed']}, spurious {e['spurious']} |")
    misses = _baseline_misses(first["grazing"])
    counts = ", ".join(f"{k}: {a}..{b}" for k, (a, b) in misses.items())
    lines.append(f"| baselines' missed + spurious impacts on the grazing cells, exact_n "
                 f"(best..worst setting) | {counts} |")
    tight = next(p for p in dynamics["points"] if p["method"] == "impactbeams"
                 and p["n_modes"] == dynamics["config"]["n_default"])["errors"]["tight_ivp"]
    lines.append(f"| full dynamics ({dynamics['config']['t_max']} s, {n} modes): impactbeams vs "
                 f"tight DOP853 | onsets {tight['onset_max']:.1e} s, peak forces "
                 f"{tight['peak_rel_max']:.1e} rel., impact count diff {tight['count_diff']} |")
    lines.append(f"| compile time (apart from run time, `scaling.json`) | "
                 f"{scale['compile']['cold_s']:.1f} s cold, "
                 f"{scale['compile']['warm_cache_s']:.2f} s from the Numba cache |")
    size = "QUICK (small sizes: numbers indicative only)" if quick else "full size"
    run = {k: v for k, v in first["run"].items() if k != "quick"}
    return README.format(size=size, table="\n".join(lines),
                         verdicts="\n".join(f"- {v}" for v in verdicts), **run)


TITLE = """# Benchmarks: run time against error

Regenerate everything here (JSON, PNG and this file) with one command from the repository root:

    python benchmarks/run_all.py            # full size; add --quick for a small, fast run

Each section names its run's date, machine and load. The last, "History", is the full
suite's older run, kept as a record of the code of its date, not as a current figure.
"""

README = """## History: the full suite's run of {date}

Run time against error and the map's scaling, as measured then ({size}; {machine}, Python
{python}, NumPy {numpy}, SciPy {scipy}, Numba {numba}, impactbeams {impactbeams}) on the
code of that date: its times are not the current code's (the sections above are). The
machine may have been shared: timings are noisy.

{table}

Targets at matched error (first-impact map grid):

{verdicts}

### What is measured

* **impactbeams' accuracy knob is the number of modes only.** Its first-impact kernel has no
  tolerance: propagation is exact (closed form), steps are certified root-free, the root is
  resolved by Newton to a few ulps. Against the exact solution of the same n-mode equations
  (`exact_n`) its error is round-off; against a many-mode reference (`many_modes`) its error is
  the modal truncation of n modes, which every method on those equations shares.
* **Baselines** (`benchmarks/baselines.py`) solve the same modal equations independently:
  `solve_ivp` RK45 / DOP853 with a terminal gap event (direction -1) per cell, rtol as the
  knob; and vectorised NumPy (textbook closed form on a dense grid for a block of cells, first
  sign change, vectorised bisection), sampling density (samples per period of the fastest mode)
  as the knob. solve_ivp runs on a random subsample of cells (`ivp_cells` in the JSON); its
  cost per cell is the subsample mean and the map cost is extrapolated from it.
* **References**: `many_modes` = impactbeams with many modes (its distance from half as many
  modes is reported as `reference_self_distance`); `exact_n` = long-double textbook closed form
  (`tests/references.py`), earliest root found by a dense scan or by any method, each re-located
  by long-double bisection and kept only where the long-double gap closes.
* **Errors**: max / p95 / median of |t* - t*_ref| over cells where both impact; missed and
  spurious impacts counted apart. A baseline setting matches impactbeams' error when it has no
  more missed + spurious impacts and at most twice its max and median errors; otherwise the
  ratio against its most accurate setting is a lower bound (">=").
* **Grazing cells**: clearance set to the deepest dip of the response times 1 -+ depth, depth
  1e-9 .. 1e-2 (half just closing, half just open).
* **Full dynamics**: `simulate()` (model build included in its time) against `solve_ivp` on the
  same two-phase modal equations with event-driven switching and the projections of `model.py`;
  impacts matched by index. Against many modes the impact sequence does not converge (modal
  non-convergence, see `docs/modal_convergence.md` and `docs/limits.md`).

Files: `work_precision.json`, `dynamics.json`, `scaling.json`, `sweep.json` / `sweep.md`,
`cube.json` / `cube.md`, `compression.json` (`bench_cube.py --compression`);
plots `work_precision_first_impact.png`, `work_precision_dynamics.png`, `scaling.png`.
"""


def main() -> None:
    """Run the suite and write its results."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes (minutes)")
    parser.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    parser.add_argument("--baseline", metavar="REVISION",
                        help="git revision of the previous release, measured beside this code "
                             "by the speed benchmarks (maps, long-time, first run)")
    parser.add_argument("--speed-only", action="store_true",
                        help="only the speed targets' benchmarks (maps, long-time, first run)")
    parser.add_argument("--skip-bench-sweep", action="store_true")
    parser.add_argument("--skip-distributed", action="store_true")
    parser.add_argument("--skip-longtime", action="store_true")
    parser.add_argument("--skip-continuation", action="store_true")
    parser.add_argument("--skip-first-run", action="store_true",
                        help="keep compile.json and startup.json")
    parser.add_argument("--report-only", action="store_true",
                        help="redraw plots and README from the JSON already in --out")
    args = parser.parse_args()
    out = Path(args.out)
    if args.report_only:
        report(out)
        return
    out.mkdir(parents=True, exist_ok=True)
    with checkout(args.baseline) as baseline:
        if not args.speed_only:
            suite(args, out)
        log("bench_columns.py")
        run_bench_columns(args.quick, out, baseline)
        if not args.skip_longtime:
            log("bench_longtime.py")
            run_bench_longtime(args.quick, out, baseline)
        if not args.skip_first_run:
            log("bench_compile.py, bench_startup.py")
            run_bench_first_run(args.quick, baseline)
    report(out)


def suite(args: argparse.Namespace, out: Path) -> None:
    """Everything but the speed targets' benchmarks: accuracy against cost, scaling, peers."""
    if not args.skip_bench_sweep:
        log("bench_sweep.py")
        run_bench_sweep(args.quick)
        log("bench_cube.py")
        run_bench_cube(args.quick)
    log("work-precision: first impact")
    first = wp.first_impact_study(wp.QUICK if args.quick else wp.FirstImpactConfig(), log)
    log("work-precision: full dynamics")
    dynamics = wp.dynamics_study(wp.QUICK_DYNAMICS if args.quick else wp.DynamicsConfig(), log)
    log("work-precision: spring law")
    springs = spring.spring_study(spring.QUICK_SPRING if args.quick else spring.SpringConfig(),
                                  log)
    log("scaling")
    scale = scaling.scaling_study(scaling.QUICK if args.quick else scaling.ScalingConfig(), log)
    if not args.skip_distributed:
        log("bench_distributed.py")
        run_bench_distributed(args.quick)
    if not args.skip_continuation:
        log("bench_continuation.py")
        run_bench_continuation(args.quick)
        log("bench_two_parameter.py")
        run_bench_two_parameter()
    log("bench_contacts.py")
    run_bench_contacts(args.quick)
    about = {"quick": args.quick, **machine()}
    for name, data in (("work_precision", first), ("dynamics", dynamics), ("scaling", scale),
                       ("spring", springs)):
        (out / f"{name}.json").write_text(json.dumps({**data, "run": about}, indent=1) + "\n")


def _load(out: Path, name: str) -> dict:
    return json.loads((out / f"{name}.json").read_text())


def recorded(report: dict) -> tuple[str, str]:
    """(date, machine) of a results file, "not recorded" where an older writer left them out."""
    about = report.get("run", report)
    machine = about.get("machine", "not recorded")
    if isinstance(machine, dict):  # bench_distributed's record
        machine = f"{machine.get('cpu_count', '?')} cores, {machine.get('platform', '')}"
    return about.get("date", "not recorded"), machine


def results_files(out: Path) -> str:
    """A table of every results file in ``out``: when and where it was measured."""
    lines = ["## Results files", "",
             "Every number on this page is read from these files (the page is generated from "
             "them: `python benchmarks/run_all.py --report-only`); they were measured at "
             "different dates, by the script named in each file's section.", "",
             "| file | date | machine |", "|---|---|---|"]
    for path in sorted(out.glob("*.json")):
        date, machine = recorded(json.loads(path.read_text()))
        lines.append(f"| `{path.name}` | {date} | {machine} |")
    return "\n".join(lines) + "\n"


def page(out: Path) -> str:
    """The benchmarks page (README.md of ``out``), from its JSON files only."""
    first, dynamics, scale = (_load(out, name) for name in ("work_precision", "dynamics",
                                                             "scaling"))
    readme = TITLE + ("\n## Speed targets\n\nIssue 24's targets on 2 cores, each figure "
                      "against the previous release's measured beside it (`python "
                      "benchmarks/run_all.py --speed-only --baseline REVISION`); dates, "
                      "machines and loads in the sections below.\n\n" + speed_targets(out))
    if (out / "columns.json").exists():  # the map by columns, measured apart
        readme += "\n" + columns_section(_load(out, "columns"))
    if (out / "spring.json").exists():  # the spring law's section
        readme += "\n" + spring.markdown(_load(out, "spring"))
    if (out / "longtime.json").exists():  # the long-time diagram's cost, in brief
        readme += "\n" + longtime.headline(_load(out, "longtime"))
    if (out / "compile.json").exists() and (out / "startup.json").exists():
        readme += ("\n## First run and start-up\n\n`bench_compile.py` (a first map of 100 "
                   "cells and a first `simulate`, fresh processes, empty or warm Numba cache; "
                   "per-kernel compile times in [compile.md](compile.md)) and "
                   "`bench_startup.py` (each command's start-up, warm cache, bytecode "
                   "cached; medians of wall time and, in brackets, CPU time):\n\n"
                   + first_run_table(_load(out, "compile"), _load(out, "startup")))
    if (out / "numba_paths.json").exists():  # the fast path against plain Numba kernels
        readme += "\n" + numba_paths_section(_load(out, "numba_paths"))
    if (out / "harmonic_balance.json").exists():  # the harmonic-balance peer (pyHarm)
        readme += "\n" + harmonic_balance.section(_load(out, "harmonic_balance"))
    if (out / "contacts.json").exists():  # several contacts against one
        readme += "\n" + contacts.section(_load(out, "contacts"))
    readme += "\n" + headline(first, dynamics, scale, first["run"]["quick"])
    return readme + "\n" + results_files(out)


def columns_section(report: dict) -> str:
    """The Fig. 5a map by columns against cell by cell (``bench_columns.py``)."""
    date, machine = recorded(report)
    rows = [f"| {name} | {seconds:.3f} s |" for name, seconds in report["best_s"].items()]
    return ("## The Fig. 5a map by columns\n\n"
            f"`bench_columns.py` ({date}; {machine}): {report['cells']:,} cells, compute only, "
            f"kernels loaded, best of {report['repeats']}; same classification in every cell: "
            f"{report['same_classification']}, largest difference in t* "
            f"{report['max_time_difference_s']:.1e} s. The history section's table "
            "(`scaling.json`) is the full suite's older series. Details: "
            "[columns.md](columns.md).\n\n"
            "| kernel, threads | best time |\n|---|---|\n" + "\n".join(rows) + "\n"
            + ("\n" + maps_table(report) if "maps" in report else ""))


def maps_table(report: dict) -> str:
    """Every benchmark map of ``bench_columns.py`` per impacting cell, on 1 and 2 threads."""
    lines = [f"Load average {report['load_average']:.1f} at the end of the run (2 cores); CPU "
             "time on 1 thread beside the wall time, which the load inflates.\n",
             "| map | impacting | 1 thread | 2 threads | per impacting cell, 1 / 2 threads "
             "| over Fig. 5a |", "|---|---|---|---|---|---|"]
    for entry in report["maps"]:
        seconds, per_cell = entry["best_s"], entry["ns_per_impacting_cell"]
        ratio = entry["per_impacting_cell_over_fig5a"]
        lines.append(f"| `{entry['map']}` ({entry['what']}) | {entry['impacted_fraction']:.0%} | "
                     f"{seconds['1']:.3f} s (CPU {entry['best_cpu_1_thread_s']:.3f} s) | "
                     f"{seconds['2']:.3f} s | {per_cell['1']:.0f} / "
                     f"{per_cell['2']:.0f} ns | {ratio['1']:.2f} / {ratio['2']:.2f} |")
    return "\n".join(lines) + "\n"


def first_run_table(compile_report: dict, startup: dict) -> str:
    """First run (``compile.json``) and start-up of each command (``startup.json``), each
    against the previous code measured back to back, and issue 24's figures."""
    issue = compile_report["issue_before_s"]
    previous = compile_report.get("baseline", {}).get("cases", {})
    lines = ["| run | wall (CPU) | previous code | issue 24 (main 4467146) | measured |",
             "|---|---|---|---|---|"]
    load = compile_report["load_average"]
    when = (", ".join(dict.fromkeys(recorded(compile_report)))
            + f", load {load['before']:.1f} to {load['after']:.1f}")
    for case, row in compile_report["cases"].items():
        before = previous.get(case)
        lines.append(f"| {case} | {row['wall_s']:.1f} s ({row['cpu_s']:.1f} s) | "
                     + (f"{before['wall_s']:.1f} s ({before['cpu_s']:.1f} s)" if before else "-")
                     + f" | {f'{issue[case]:.1f} s' if case in issue else '-'} | {when} |")
    previous = startup.get("baseline", {})
    when = ", ".join(dict.fromkeys(recorded(startup)))
    if "load_average" in startup:
        load = startup["load_average"]
        when += f", load {load['before']:.1f} to {load['after']:.1f}"
    for command, seconds in startup["median_s"].items():
        if command in previous.get("median_s", {}):
            lines.append(f"| `impactbeams {command}`, warm (median) | "
                         f"{_with_cpu(seconds, startup, command)} | "
                         f"{_with_cpu(previous['median_s'][command], previous, command)} | - | "
                         f"{when} |")
    return "\n".join(lines) + "\n"


def numba_paths_section(report: dict) -> str:
    """Compile and run times of the fast path and of plain Numba kernels (numba_paths.json)."""
    load = report["load_average"]
    fast, plain = report["compile"]["fast"], report["compile"]["plain"]
    lines = ["## The fast path against plain Numba kernels", "",
             f"`bench_numba_paths.py` ({report['date']}; {report['machine']}; Numba "
             f"{report['numba']}; load average {load['before']:.1f} before, {load['after']:.1f} "
             f"after; medians of {report['rounds']} rounds, the paths back to back): every kernel "
             "a plain `numba.njit` kernel (`IMPACTBEAMS_PLAIN_NUMBA=1`, and what a Numba the fast "
             "path was not tested with gets) against the fast path "
             "([architecture](../architecture.md#two-paths-fast-and-plain)). First runs as in "
             "[compile.md](compile.md), fresh processes, wall (CPU):", "",
             "| first run | fast path | plain | plain / fast (wall) |", "|---|---|---|---|"]
    for case, row in fast.items():
        other = plain[case]
        lines.append(f"| {case} | {row['wall_s']:.1f} s ({row['cpu_s']:.1f} s) | "
                     f"{other['wall_s']:.1f} s ({other['cpu_s']:.1f} s) | "
                     f"{other['wall_s'] / row['wall_s']:.2f} |")
    same = "the same" if report["same_results"] else "DIFFERENT"
    lines += ["", f"Run time, kernels loaded, best of {report['repeats']} in each round's "
              f"process; results {same} on both paths (every variable's bytes):", "",
              "| run | fast path | plain | plain / fast |", "|---|---|---|---|"]
    for case, seconds in report["run_best_s"]["fast"].items():
        other = report["run_best_s"]["plain"][case]
        lines.append(f"| {case} | {seconds:.3f} s | {other:.3f} s | {other / seconds:.2f} |")
    return "\n".join(lines) + "\n"


def _worst_map(columns: dict) -> float | None:
    """The largest time per impacting cell over Fig. 5a's among the benchmark maps (1 or 2
    threads), None for a results file without them."""
    ratios = [max(entry["per_impacting_cell_over_fig5a"].values())
              for entry in columns.get("maps", [])]
    return max(ratios, default=None)


def _fig5a(columns: dict, threads: str) -> float | None:
    """Fig. 5a's best time (s) by columns on ``threads`` threads in a columns.json."""
    return columns.get("best_s", {}).get(f"columns, {threads} thread(s)")


class Target(NamedTuple):
    """One speed target: a time (s) or ratio (x) now and in the previous release (None where
    not measured), met at or under ``target``, or at or over it if ``at_least``."""

    quantity: str
    target: float
    unit: str
    now: float | None
    previous: float | None
    at_least: bool = False

    def shown(self, value: float | None) -> str:
        if value is None:
            return "-"
        return f"{value:.2f}x" if self.unit == "x" else f"{value:.3g} s"

    def row(self) -> str:
        met = self.now >= self.target if self.at_least else self.now <= self.target
        return (f"| {self.quantity} | {'>=' if self.at_least else '<='} "
                f"{self.shown(self.target)} | {self.shown(self.now)} | "
                f"{self.shown(self.previous)} | {'yes' if met else '**no**'} |")


def _targets(out: Path) -> list[Target]:
    """Every speed target measured in ``out``; "previous" is the baseline run beside it."""
    targets = []
    if (out / "columns.json").exists():
        now = _load(out, "columns")
        before = now.get("previous", {})
        targets += [
            Target("Fig. 5a map, 10^6 cells, 2 threads (compute)", 0.12, "s", _fig5a(now, "2"),
                   _fig5a(before, "2")),
            Target("Fig. 5a map, 2-thread speed-up", 1.8, "x",
                   now["speedup_2_threads"]["columns"],
                   before.get("speedup_2_threads", {}).get("columns"), at_least=True),
            Target("slowest benchmark map per impacting cell, over Fig. 5a", 1.5, "x",
                   _worst_map(now), _worst_map(before))]
    if (out / "compile.json").exists():
        now = _load(out, "compile")
        before = now.get("baseline", {}).get("cases", {})
        targets += [Target(f"{case} (wall)", limit, "s", now["cases"][case]["wall_s"],
                           before.get(case, {}).get("wall_s"))
                    for case, limit in (("first map, cold", 8.0), ("simulate, cold", 15.0))]
    if (out / "startup.json").exists():
        now = _load(out, "startup")
        before = now.get("baseline", {}).get("median_s", {})
        targets += [Target(f"`impactbeams {command}`, warm (median wall)", limit, "s",
                           now["median_s"][command], before.get(command))
                    for command, limit in (("run", 0.9), ("plot", 1.2))]
    now = _load(out, "longtime") if (out / "longtime.json").exists() else {}
    if now.get("full_run"):
        before = (now.get("previous") or {}).get("full_run") or {}
        targets.append(Target("long-time bifurcation diagram, 2 threads (wall)", 20.0, "s",
                              now["full_run"]["wall_s"], before.get("wall_s")))
    return targets


def speed_targets(out: Path) -> str:
    """Issue 24's speed targets: each figure now, the previous release's, whether met."""
    return "\n".join(["| quantity | target | now | previous release | met |",
                      "|---|---|---|---|---|", *(t.row() for t in _targets(out))]) + "\n"


def _with_cpu(wall: float, startup: dict, command: str) -> str:
    """``wall`` and, where bench_startup measured it, the command's median CPU time."""
    cpu = startup.get("cpu_median_s", {}).get(command)
    return f"{wall:.2f} s" + (f" ({cpu:.2f} s)" if cpu is not None else "")


def report(out: Path) -> None:
    """Plots and README from the saved JSON files in ``out`` (no computation)."""
    plot_first_impact(_load(out, "work_precision"), out / "work_precision_first_impact.png")
    plot_dynamics(_load(out, "dynamics"), out / "work_precision_dynamics.png")
    plot_scaling(_load(out, "scaling"), out / "scaling.png")
    if (out / "spring.json").exists():
        spring.plot_spring(_load(out, "spring"), out / "work_precision_spring.png")
    (out / "README.md").write_text(page(out))
    log(f"wrote {out}")


if __name__ == "__main__":
    main()
