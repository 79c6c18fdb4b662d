"""Benchmark: time per point of a bifurcation curve in two parameters (issue 34).

Three curves, each from the event a one-parameter branch located (`continue_curve`): the
soft stop's upper fold (the shipped continuation example's model, `sweeps/
continuation-stop-fold.toml`) followed in the tip force from 1e-4 to 2e-4 N at 3 and 5 modes
per beam (2 N = 6, 10: the fold's augmented system differences the full monodromy in each
coordinate, so a point costs about 2 N + 2 monodromies per corrector iteration), and the grazing
of the two-beam small model (the continuation tests' model, 3 modes, 2 N = 12) in the tip
force from 3e-5 to 4e-5 N. Beside each, the one-parameter branch it started from, per point:
what the second parameter costs. A point's time is the wall (and the process's CPU) time
between the first and the last point the progress reports, over the points between; warm (a
first curve compiles). BLAS on one thread. Writes docs/benchmarks/two_parameter.json and .md.

    python benchmarks/bench_two_parameter.py
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import json  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import impactbeams as ib  # noqa: E402
from impactbeams.continuation import (  # noqa: E402
    BifurcationCurve,
    Continuation,
    continue_curve,
    continue_orbits,
)

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "benchmarks"
STOP = ib.Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                 force_amplitude=1e-4)
SMALL = ib.Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5,
                  clearance=1.1e-5)
# (name, params, branch range and options, the curve's kind, second parameter and range)
CASES = (
    ("stop fold, 3 modes", STOP, (195.0, 330.0, {"n_modes": 3, "subspace": 4}), "fold",
     ("force_amplitude", 1e-4, 2e-4)),
    ("stop fold, 5 modes", STOP, (195.0, 330.0, {"n_modes": 5}), "fold",
     ("force_amplitude", 1e-4, 2e-4)),
    ("two beams grazing, 3 modes", SMALL, (225.0, 240.0, {"n_modes": 3, "max_points": 20}),
     "grazing", ("force_amplitude", 3e-5, 4e-5)),
)


def timed(run) -> tuple[object, dict]:
    """``run(progress)``'s result and its seconds per point between the first and last."""
    stamps: list[tuple[float, float]] = []
    result = run(lambda *_: stamps.append((time.perf_counter(), time.process_time())))
    wall, cpu = (np.diff(np.array(stamps)[[0, -1]], axis=0)[0] / (len(stamps) - 1)).tolist()
    return result, {"seconds_per_point": wall, "cpu_seconds_per_point": cpu,
                    "points": len(stamps)}


def case(params, span, kind, second) -> dict:
    low, high, options = span
    continuation = Continuation(params, "omega", low, high, max_branches=1, **options)
    branch, along = timed(lambda progress: continue_orbits(continuation, progress))
    curve = BifurcationCurve.from_branch(continuation, branch, kind, *second)
    dataset, cost = timed(lambda progress: continue_curve(curve, progress))
    return {"state_size": int(dataset.state.size), "branch": along, "curve": cost,
            "newton_iterations": float(dataset.newton_iterations.values[1:].mean()),
            "curve_ending": dataset.attrs["curve_ending"]}


def main() -> None:
    case(*CASES[0][1:])  # compiled, warm
    results = {name: case(params, span, kind, second)
               for name, params, span, kind, second in CASES}
    report = {"date": time.strftime("%Y-%m-%d %H:%M"), "load_average": os.getloadavg()[0],
              "machine": f"{platform.machine()}, {os.cpu_count()} cores",
              "python": sys.version.split()[0], "impactbeams": ib.__version__,
              "cases": results}
    (OUT / "two_parameter.json").write_text(json.dumps(report, indent=1) + "\n")
    (OUT / "two_parameter.md").write_text(page(report))
    print(json.dumps(report, indent=1))


def page(report: dict) -> str:
    """The markdown page of ``report`` (every number from it)."""
    lines = ["# Two-parameter continuation: time per curve point", "",
             f"`python benchmarks/bench_two_parameter.py`; {report['machine']}, Python "
             f"{report['python']}, impactbeams {report['impactbeams']}, {report['date']}, load "
             f"average {report['load_average']:.1f} on 2 cores (a shared machine: the CPU "
             "time, in brackets, is what one free core would take). Each curve starts at the "
             "event its one-parameter branch in Omega located (`continue_curve`); in ms per "
             "point.", "",
             "| case | 2N | curve | Newton iterations | its branch | curve / branch | "
             "points (curve, branch) |",
             "|---|---|---|---|---|---|---|"]
    for name, row in report["cases"].items():
        curve, branch = row["curve"], row["branch"]
        lines.append(
            f"| {name} | {row['state_size']} | {1e3 * curve['seconds_per_point']:.0f} "
            f"({1e3 * curve['cpu_seconds_per_point']:.0f}) | {row['newton_iterations']:.1f} | "
            f"{1e3 * branch['seconds_per_point']:.0f} "
            f"({1e3 * branch['cpu_seconds_per_point']:.0f}) | "
            f"{curve['cpu_seconds_per_point'] / branch['cpu_seconds_per_point']:.1f} | "
            f"{curve['points']}, {branch['points']} |")
    lines += ["", "A curve's corrector differences its condition in every coordinate of the "
              "state and in the first parameter (one run each; a fold's or period doubling's "
              "test function also the monodromy at each), so a point costs about 2 N + 2 "
              "period maps per iteration against the branch's one: the ratio grows with the "
              "modes. A branch's points also carry its located events' searches.", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
