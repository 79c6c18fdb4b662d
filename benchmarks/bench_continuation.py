"""Benchmark: time per branch point of the continuation, Newton-Picard against full Newton.

The default Hertz contact (linearised, k = 2.2e5 N/m) with zeta = 0.05, a period-1 impacting
branch in Omega from 50 rad/s up, at 8, 16 and 32 modes per beam (2 N = 32, 64, 128
coordinates), each with ``method="newton"`` (the full monodromy at every corrector iteration)
and ``method="newton-picard"`` (m = 8 carried directions plus the residual's, `BeamOrbits`).
A branch point's time is the wall time (and the process's CPU time: on a loaded machine, what
one free core would take) between the first and the last point reported by
`continue_orbits`' progress, over the points between: the corrector with its dr/dp and the
point's measures (grazing gap, peak force, impulse, tips). The measures alone (the contacts'
peak-force searches) are timed apart, at the start orbit. All in one process after a warm-up
branch (compilation); BLAS on one thread (``OPENBLAS_NUM_THREADS=1``, set before NumPy loads).
``--baseline TREE`` times an earlier version too (TREE: its source tree, e.g. ``git worktree
add TREE v0.1.0``): the same cases in a child process on TREE/src, run right after each mode
count's own (so both see the same load), with its own Numba cache. Writes
docs/benchmarks/continuation.json and docs/benchmarks/continuation.md.

    python benchmarks/bench_continuation.py [--points 12] [--baseline TREE]
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import inspect  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from bench_orbits import MODES, PARAMS, report_header, write_report  # noqa: E402  (the orbits' model)
from impactbeams.continuation import Continuation, continue_orbits  # noqa: E402
from impactbeams.orbits import PeriodMap  # noqa: E402

METHODS = ("newton", "newton-picard")
LOW, HIGH = 50.0, 60.0  # rad/s: the branch's range (it ends at max points well before HIGH)
TRANSIENT = 100  # forcing periods from rest to the start orbit's guess


def branch(n_modes: int, method: str, points: int) -> dict:
    """Seconds per branch point (between the first and the last) and what the branch read."""
    stamps: list[tuple[float, float]] = []
    # the chattering orbit's contacts merge every step or two (50 -> 44 over the first 12
    # points at 8 modes): summarised, as the previous release did not locate them, so that a
    # point costs its corrector and measures, not a located merge's ~36 corrections
    summarised = ({"micro_contacts": "summarise"}
                  if "micro_contacts" in inspect.signature(Continuation).parameters else {})
    continuation = Continuation(PARAMS, "omega", LOW, HIGH, n_modes=n_modes, method=method,
                                transient_periods=TRANSIENT, max_points=points,
                                max_branches=1, **summarised)
    dataset = continue_orbits(
        continuation, lambda *_: stamps.append((time.perf_counter(), time.process_time())))
    wall, cpu = (np.diff(np.array(stamps)[[0, -1]], axis=0)[0] / (len(stamps) - 1)).tolist()
    return {"seconds_per_point": wall, "cpu_seconds_per_point": cpu,
            "points": len(stamps), "omega_end": float(dataset.omega[-1]),
            "iterations": float(dataset.newton_iterations.mean()),
            "contacts": int(dataset.contacts_per_orbit[0]),
            "leading_multipliers_abs": dataset.multiplier_modulus[0, :4].values.tolist()}


def measures_seconds(n_modes: int, repeats: int = 3) -> float:
    """The measures of one orbit (minus the map's run): what every accepted point adds.

    CPU time (s), a median of ``repeats`` pairs with and without the measures.
    """
    period_map = PeriodMap(PARAMS, n_modes)
    z = period_map.rest_state()
    for _ in range(TRANSIENT):
        z = period_map(z, measures=False).state
    times = []
    for measures in (True, False) * repeats:
        start = time.process_time()
        period_map(z, measures=measures)
        times.append((time.process_time() - start) * (1 if measures else -1))
    return float(np.median(np.add(times[0::2], times[1::2])))


def case(n_modes: int, points: int) -> dict:
    """One mode count's row: the measures and a branch with each method."""
    row = {"n_modes": n_modes, "measures": measures_seconds(n_modes)}
    row.update({method: branch(n_modes, method, points) for method in METHODS})
    return row


def baseline_case(tree: Path, n_modes: int, points: int, cache: str) -> dict:
    """``case`` run by the version in ``tree`` (its src/ first on the path), in a child."""
    env = {**os.environ, "PYTHONPATH": str(tree / "src"), "NUMBA_CACHE_DIR": cache,
           "PYTHONDONTWRITEBYTECODE": "1"}
    done = subprocess.run([sys.executable, __file__, "--row", str(n_modes), "--points",
                           str(points)], env=env, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.splitlines()[-1])


def point_times(method: dict) -> str:
    """A method's wall time per point (ms) and, where measured, its CPU time in brackets."""
    wall = f"{1e3 * method['seconds_per_point']:.0f}"
    cpu = method.get("cpu_seconds_per_point")
    return wall if cpu is None else f"{wall} ({1e3 * cpu:.0f})"


def markdown(report: dict) -> str:
    """The report as a short Markdown page."""
    before = all("baseline" in row for row in report["cases"])
    lines = ["# Continuation: time per branch point", "",
             f"`python benchmarks/bench_continuation.py`; {report['machine']}, impactbeams "
             f"{report['version']}, {report['date']}, load average {report['load']:.1f} on "
             f"{report['cores']} cores (a shared machine: absolute times are noisy; the CPU "
             f"time, in brackets, is what one free core would take). Default "
             f"Hertz contact, zeta = {PARAMS.damping_ratio}, the period-1 impacting branch in "
             f"Omega from {LOW} rad/s, {report['points']} points, changes of the contacts "
             "within an episode summarised (`micro_contacts = \"summarise\"`: the orbit "
             "chatters, 50 contacts per orbit at 8 modes, and located, each merge costs about "
             "36 corrections); in ms per point.", "",
             "| n_modes | 2N | contacts | Newton | Newton-Picard | of which measures | "
             "iterations (N / N-P) |" + (" before: Newton / N-P / measures |" if before else ""),
             "|---" * (8 if before else 7) + "|"]
    for row in report["cases"]:
        newton, picard = row["newton"], row["newton-picard"]
        line = (f"| {row['n_modes']} | {4 * row['n_modes']} | {picard['contacts']} | "
                f"{point_times(newton)} | {point_times(picard)} | "
                f"{1e3 * row['measures']:.0f} | "
                f"{newton['iterations']:.1f} / {picard['iterations']:.1f} |")
        if before:
            old = row["baseline"]
            line += (f" {point_times(old['newton'])} / {point_times(old['newton-picard'])} / "
                     f"{1e3 * old['measures']:.0f} |")
        lines.append(line)
    lines += ["", "A point's time includes its measures (the contacts' peak-force searches, "
              "the gap's minimum and the tips' maxima, timed apart at the start orbit, in CPU "
              "time: \"of which measures\"), read once per accepted point; the corrector's "
              "iterations read none."]
    if before:
        lines += ["", f"\"before\": the same cases by {report['baseline']}, each run in a child "
                  "process right after this version's."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--points", type=int, default=12)
    parser.add_argument("--baseline", type=Path, help="an earlier version's source tree")
    parser.add_argument("--row", type=int, help=argparse.SUPPRESS)  # a child: one row, as JSON
    args = parser.parse_args()
    branch(MODES[0], METHODS[1], 3)  # warm-up: compilation
    if args.row is not None:
        print(json.dumps(case(args.row, args.points)), flush=True)
        return
    report = report_header(points=args.points)
    if args.baseline is not None:
        report["baseline"] = subprocess.run(
            ["git", "-C", str(args.baseline), "describe", "--always", "--dirty"],
            capture_output=True, text=True).stdout.strip() or args.baseline.name
    with tempfile.TemporaryDirectory() as cache:
        for n_modes in MODES:
            row = case(n_modes, args.points)
            if args.baseline is not None:
                row["baseline"] = baseline_case(args.baseline, n_modes, args.points, cache)
            report["cases"].append(row)
            print(json.dumps(row), flush=True)
    write_report("continuation", report, markdown)


if __name__ == "__main__":
    main()
