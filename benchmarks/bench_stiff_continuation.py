"""Benchmark: a frequency response on a stiff stop driven by a shaker, end to end.

The case of issue 31, as a new user writes it: a steel cantilever 200 x 20 x 1 mm against a
rigid stop 0.5 mm below its tip, its clamp on a shaker (base amplitude 0.1 mm, no tip force),
zeta = 0.01, Omega over 0.5 to 2 omega_1 (65.6 to 262.5 rad/s), up and down, at the default
(Hertz) contact and at contact_stiffness = 1e4 N/m, each at its default modes and settings
but ``MAX_POINTS`` (every change of the contacts located). Per run: the wall and CPU time,
the points and branches, each branch's covered interval and ending, the events located. A run is
stopped after ``--cap`` seconds (it then reports how far it got). ``--baseline TREE`` runs
the same cases by an earlier version (its source tree) in a child process, right after each
of this version's. Writes docs/benchmarks/stiff_continuation.json and .md.

    python benchmarks/bench_stiff_continuation.py [--cap 900] [--baseline TREE]
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import signal  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import impactbeams as ib  # noqa: E402
from bench_orbits import report_header, write_report  # noqa: E402
from impactbeams.continuation import Continuation, ContinuationInterrupted, continue_orbits  # noqa: E402
from impactbeams.variables import BIFURCATIONS  # noqa: E402

SHAKER = {"l1": 0.2, "width1": 0.02, "thickness1": 0.001, "counterpart": "stop",
          "clearance": 5e-4, "shaker": "beam1", "base_amplitude": 1e-4, "force_amplitude": 0.0,
          "damping_ratio": 0.01}
LOW, HIGH = 65.6, 262.5  # rad/s: 0.5 to 2 omega_1
STIFFNESSES = (None, 1e4)  # N/m; None: the default Hertz contact
DIRECTIONS = ("up", "down")
MAX_POINTS = 10_000  # the Hertz case's branch takes about 6000 points


def params(stiffness: float | None) -> ib.Params:
    extra = {} if stiffness is None else {"contact_stiffness": stiffness}
    return ib.Params.from_mapping({**SHAKER, **extra})


class Cap(Exception):
    pass


def run(stiffness: float | None, direction: str, cap: float) -> dict:
    """One continuation of the case; stopped (and reported as far as it got) after ``cap`` s."""
    continuation = Continuation(params(stiffness), "omega", LOW, HIGH, direction=direction,
                                max_points=MAX_POINTS)
    signal.signal(signal.SIGALRM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt))
    signal.alarm(int(cap))
    wall, cpu = time.perf_counter(), time.process_time()
    try:
        dataset, capped = continue_orbits(continuation), False
    except ContinuationInterrupted as interrupted:
        dataset, capped = interrupted.dataset, True
    finally:
        signal.alarm(0)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    codes = dataset.bifurcation.values
    covered = dataset.attrs.get("branch_covered")
    if covered is None:  # an earlier version: from the points
        omega, branch = dataset.omega.values, dataset.branch.values
        covered = " ".join(f"{float(omega[branch == b].min())!r}:"
                           f"{float(omega[branch == b].max())!r}"
                           for b in range(int(branch.max()) + 1))
    return {"stiffness": stiffness, "direction": direction, "n_modes": int(dataset.n_modes),
            "seconds": wall, "cpu_seconds": cpu, "capped": capped,
            "points": int(dataset.branch_point.size),
            "branches": int(dataset.branch.max()) + 1,
            "covered": covered.split(), "endings": dataset.attrs["branch_endings"].split(),
            "events": {name: int((codes == code).sum())
                       for code, name in enumerate(BIFURCATIONS) if code and (codes == code).any()}}


def baseline(tree: Path, stiffness: float | None, direction: str, cap: float) -> dict:
    """``run`` by the version in ``tree`` in a child process (its own Numba cache)."""
    env = {**os.environ, "PYTHONPATH": f"{tree / 'src'}{os.pathsep}{Path(__file__).parent}",
           "NUMBA_CACHE_DIR": str(tree / ".numba-cache"), "PYTHONDONTWRITEBYTECODE": "1"}
    code = (f"import json, bench_stiff_continuation as b; print(json.dumps(b.run("
            f"{stiffness!r}, {direction!r}, {cap!r})))")
    done = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                          capture_output=True, text=True, cwd=tree)
    return json.loads(done.stdout.splitlines()[-1])


def _commit(tree: Path) -> str:
    """The earlier version's commit (and its tree), as the report names it."""
    commit = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                            check=True, capture_output=True, text=True).stdout.strip()
    return f"{commit} ({tree})"


def label(stiffness: float | None) -> str:
    return "Hertz (default)" if stiffness is None else f"{stiffness:g} N/m"


def coverage(case: dict) -> str:
    """Branch 0's covered interval and each branch's ending."""
    low, high = (float(v) for v in case["covered"][0].split(":"))
    capped = f", stopped at the {case['cap']:.0f} s cap" if case["capped"] else ""
    return f"{low:.2f} to {high:.2f} ({', '.join(case['endings'])}{capped})"


def markdown(report: dict) -> str:
    lines = ["# Continuation on a stiff stop driven by a shaker", "",
             f"`python benchmarks/bench_stiff_continuation.py`; {report['machine']}, impactbeams "
             f"{report['version']}, {report['date']}, load average {report['load']:.1f} on "
             f"{report['cores']} cores (CPU time in brackets: what one free core would take). "
             "The case of issue 31: a 200 x 20 x 1 mm steel cantilever, a rigid stop 0.5 mm "
             "below its tip, its clamp on a shaker (0.1 mm), zeta = 0.01, Omega from "
             f"{LOW} to {HIGH} rad/s (0.5 to 2 omega_1), default settings but max_points "
             f"{MAX_POINTS}; "
             "each run is stopped at the cap if it has not ended.", "",
             "| contact | direction | modes | time, s | points (branches) | branch 0 covers, rad/s "
             "(endings) | grazings | events |" + (" before: time, s / covers |"
                                                    if report.get("baseline") else ""),
             "|---" * (9 if report.get("baseline") else 8) + "|"]
    for case in report["cases"]:
        events = ", ".join(f"{n} {name}" for name, n in case["events"].items())
        line = (f"| {label(case['stiffness'])} | {case['direction']} | {case['n_modes']} | "
                f"{case['seconds']:.0f} ({case['cpu_seconds']:.0f}) | {case['points']} "
                f"({case['branches']}) | {coverage(case)} | "
                f"{case['events'].get('grazing', 0)} | {events} |")
        if "before" in case:
            old = case["before"]
            line += f" {old['seconds']:.0f} ({old['cpu_seconds']:.0f}) / {coverage(old)} |"
        lines.append(line)
    if report.get("baseline"):
        lines += ["", f"\"before\": the same cases by {report['baseline']}, each right "
                  "after this version's."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cap", type=float, default=900.0, help="seconds per run at most")
    parser.add_argument("--baseline", type=Path, help="an earlier version's source tree")
    args = parser.parse_args()
    # warm-ups, not timed: the compiles (from an empty cache they take longer than a run)
    run(1e4, "up", args.cap)
    if args.baseline:
        baseline(args.baseline, 1e4, "up", args.cap)
    report = report_header(cap=args.cap, baseline=_commit(args.baseline) if args.baseline
                           else "", max_points=MAX_POINTS)
    for stiffness in STIFFNESSES:
        for direction in DIRECTIONS:
            case = {**run(stiffness, direction, args.cap), "cap": args.cap}
            if args.baseline:
                case["before"] = {**baseline(args.baseline, stiffness, direction, args.cap),
                                  "cap": args.cap}
            report["cases"].append(case)
            print(json.dumps(case), flush=True)
    write_report("stiff_continuation", report, markdown)


if __name__ == "__main__":
    main()
