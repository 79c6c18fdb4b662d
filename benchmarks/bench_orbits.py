"""Benchmark: periodic orbits by shooting, per Newton step, per orbit and per branch point.

The default Hertz contact (linearised, k = 2.2e5 N/m) with zeta = 0.05 (at the default zeta = 0
the Fig. 4 motion is chaotic: no periodic orbit to follow), Omega = 50 rad/s, a stable period-1
orbit, at 8, 16 and 32 modes per beam (2 N = 32, 64, 128 coordinates). Medians of
``--repeats`` interleaved rounds after a warm-up round (compilation), all in one process:

* the period map alone, with the Newton-Picard block (m + 1 = 9 tangent columns) and with the
  full monodromy (2 N columns);
* a Newton step (full monodromy and the linear solve) and a Newton-Picard step (the map, then
  9 tangent columns along its run);
* an orbit from the state 100 periods after rest, each method, without the amplitude measures;
* a branch point: the orbit at Omega + 0.1 rad/s from the orbit at Omega as the guess (and its
  Newton-Picard basis), as a continuation's corrector would, with and without the measures
  (the contacts' peak forces, the gap's minimum and the tips' maxima);
* the largest difference of the leading multipliers, Newton-Picard against Newton.

BLAS runs on one thread (``OPENBLAS_NUM_THREADS=1``, set here before NumPy loads): the
matrices are small, and on a shared machine its threads only contend. Writes
docs/benchmarks/orbits.json and docs/benchmarks/orbits.md.

    python benchmarks/bench_orbits.py [--repeats 5]
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from bench_lyapunov import median_times  # noqa: E402
from impactbeams import Params, __version__, periodic_orbit  # noqa: E402
from impactbeams.orbits import PeriodMap  # noqa: E402

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
PARAMS = Params(damping_ratio=0.05)
MODES = (8, 16, 32)
STEP = 0.1  # rad/s: the branch point's step in Omega
SUBSPACE = 8


def case(n_modes: int, repeats: int) -> dict:
    """Timings and agreement at ``n_modes`` per beam."""
    period_map = PeriodMap(PARAMS, n_modes)
    z = period_map.rest_state()
    for _ in range(100):
        z = period_map(z, measures=False).state
    block = np.eye(z.size)[:, :SUBSPACE + 1]
    newton = periodic_orbit(PARAMS, n_modes, guess=z, method="newton", measures=False)
    picard = periodic_orbit(PARAMS, n_modes, guess=z, method="newton-picard", measures=False)
    shifted = dataclasses.replace(PARAMS, omega=PARAMS.omega + STEP)

    def newton_step():
        result = period_map(z, directions="all", measures=False)
        np.linalg.solve(np.eye(z.size) - result.jacobian, result.state - z)

    def picard_step():  # one run; the 9 columns carried along it
        result = period_map(z, measures=False)
        period_map.jacobian(result, block)

    times = median_times({
        "map": lambda: period_map(z, measures=False),
        "map_block": lambda: period_map(z, directions=block, measures=False),
        "map_monodromy": lambda: period_map(z, directions="all", measures=False),
        "newton_step": newton_step,
        "picard_step": picard_step,
        "orbit_newton": lambda: periodic_orbit(PARAMS, n_modes, guess=z, method="newton",
                                               measures=False),
        "orbit_picard": lambda: periodic_orbit(PARAMS, n_modes, guess=z,
                                               method="newton-picard", measures=False),
        "branch_point_newton": lambda: periodic_orbit(shifted, n_modes, guess=newton,
                                                      method="newton", measures=False),
        "branch_point_picard": lambda: periodic_orbit(shifted, n_modes, guess=picard,
                                                      method="newton-picard", measures=False),
        "branch_point_picard_measures": lambda: periodic_orbit(
            shifted, n_modes, guess=picard, method="newton-picard"),
    }, repeats)
    point = periodic_orbit(shifted, n_modes, guess=picard, method="newton-picard",
                           measures=False)
    count = picard.multipliers.size
    return {"n_modes": n_modes, "coordinates": int(z.size), "contacts": newton.contacts,
            "seconds": times,
            "iterations": {"orbit_newton": newton.iterations, "orbit_picard": picard.iterations,
                           "branch_point_picard": point.iterations},
            "leading_multipliers_abs": np.abs(newton.multipliers[:count]).tolist(),
            "picard_multiplier_difference": float(
                np.abs(picard.multipliers - newton.multipliers[:count]).max()),
            "picard_state_difference": float(np.abs(picard.state - newton.state).max()
                                             / np.abs(newton.state).max())}


def markdown(report: dict) -> str:
    """The report as a short Markdown page."""
    lines = ["# Periodic orbits: cost of shooting", "",
             f"`python benchmarks/bench_orbits.py`; {report['machine']}, impactbeams "
             f"{report['version']}, {report['date']}, load average {report['load']:.1f} on "
             f"{report['cores']} cores (a shared machine: absolute times are noisy, ratios "
             f"less so). Default Hertz contact, zeta = {PARAMS.damping_ratio}, Omega = "
             f"{PARAMS.omega} rad/s; medians of {report['repeats']} rounds, in ms.", "",
             "| n_modes | 2N | map | map + 9 columns | map + monodromy | Newton step | "
             "Newton-Picard step | orbit (Newton) | orbit (N-P) | branch point (Newton) | "
             "branch point (N-P) | + measures |",
             "|---" * 12 + "|"]
    for row in report["cases"]:
        s = {name: 1e3 * value for name, value in row["seconds"].items()}
        lines.append(
            f"| {row['n_modes']} | {row['coordinates']} | {s['map']:.1f} | {s['map_block']:.1f} "
            f"| {s['map_monodromy']:.1f} | {s['newton_step']:.1f} | {s['picard_step']:.1f} | "
            f"{s['orbit_newton']:.1f} | {s['orbit_picard']:.1f} | "
            f"{s['branch_point_newton']:.1f} | {s['branch_point_picard']:.1f} | "
            f"{s['branch_point_picard_measures']:.1f} |")
    lines += ["", "A branch point: the orbit at Omega + 0.1 rad/s from the orbit at Omega (its "
              "state, and Newton-Picard's basis), converged to a relative residual of 1e-11 "
              "with the leading multipliers settled; \"+ measures\" adds the orbit's peak "
              "force, impulse, tip maxima and minimum gap. Newton-Picard against Newton: "
              "largest difference of the leading multipliers "
              + ", ".join(f"{row['picard_multiplier_difference']:.1e} ({row['n_modes']} modes)"
                          for row in report["cases"]) + "."]
    return "\n".join(lines) + "\n"


def report_header(**settings) -> dict:
    """The head of a benchmark's report: version, date, machine, the run's settings."""
    return {"version": __version__, "date": time.strftime("%Y-%m-%d %H:%M"),
            "machine": f"{platform.machine()}, Python {platform.python_version()}",
            "cores": os.cpu_count(), **settings, "cases": []}


def write_report(name: str, report: dict, markdown) -> None:
    """Write ``name``.json and ``name``.md under docs/benchmarks, with the load at the end."""
    report["load"] = os.getloadavg()[0]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"{name}.json").write_text(json.dumps(report, indent=1) + "\n")
    (OUT / f"{name}.md").write_text(markdown(report))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    report = report_header(repeats=args.repeats)
    for n_modes in MODES:
        report["cases"].append(case(n_modes, args.repeats))
        print(json.dumps(report["cases"][-1]), flush=True)
    write_report("orbits", report, markdown)


if __name__ == "__main__":
    main()
