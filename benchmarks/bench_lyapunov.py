"""Benchmark: the cost of Lyapunov exponents relative to the plain run, measured side by side.

Two paths, each timed against the plain run of the same cell in the same process (medians of
``--repeats`` interleaved rounds, after a warm-up round that compiles):

* ``simulate(..., lyapunov=k)``: the tangent kernel on the recorded segments
  (``recorded_run_sums``) against the event kernel's run (``trajectory.run``), for k = 1
  (largest exponent), a few, and all 4 n_modes exponents;
* a sweep cell: the windowed run with the tangent (``kernels.lyapunov.cell_exponent``, one
  ``run_events`` call per forcing period) against the same plain run, and against a
  dynamics-map cell (``kernels.observables.cell_observables``: the run and its reductions,
  whose peak-force searches cost more than the run itself).

Cases: the paper's Fig. 4 case (spring law, Hertz k, 32 modes per beam; chaotic, ~1300 phases
per simulated second) and a periodic one (k = 1e4 N/m, zeta = 0.05, 12 modes). Writes
docs/benchmarks/lyapunov.json and docs/benchmarks/lyapunov.md.

    python benchmarks/bench_lyapunov.py [--repeats 5] [--t-max 5]
"""

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from impactbeams import __version__
from impactbeams.compliant import recommended_modes
from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.layout import OUT_COLUMNS
from impactbeams.kernels.lyapunov import cell_exponent
from impactbeams.kernels.observables import cell_observables
from impactbeams.kernels.records import segments
from impactbeams.kernels.tangent import recorded_run_sums
from impactbeams.packing import cell_rows, pack_run
from impactbeams.params import Params
from impactbeams.sweep import MAX_SEGMENTS
from impactbeams.trajectory import run

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
PAPER = Params()
CASES = {"fig4": (PAPER, recommended_modes(PAPER)),
         "periodic": (Params(contact_stiffness=1e4, damping_ratio=0.05), 12)}


def median_times(functions: dict, repeats: int) -> dict[str, float]:
    """Median wall time (s) of each function, all called in turn ``repeats`` times.

    One warm-up round first (compilation). Calls of one round run under about the same load,
    so ratios of the medians hold on a shared machine where absolute times drift.
    """
    for function in functions.values():
        function()
    times = {name: [] for name in functions}
    for _ in range(repeats):
        for name, function in functions.items():
            start = time.perf_counter()
            function()
            times[name].append(time.perf_counter() - start)
    return {name: float(np.median(values)) for name, values in times.items()}


def single_pass(packed, capacity: int):
    """The event kernel over [0, t_max] in one call, with room for ``capacity`` phases.

    (``trajectory.run`` starts with 4096 and reruns from t = 0 with twice as many when they
    run out: the baseline here is the run alone.)
    """
    n = packed.q0.size
    return dyn.run_events(packed.tables, packed.forces, packed.phase_scalars,
                          packed.switching, packed.settings, packed.q0, packed.v0,
                          segments(capacity, n))


def costs(params: Params, n_modes: int, t_max: float, repeats: int) -> dict:
    """The plain run against the tangent on its segments (k exponents) and the sweep cells."""
    packed = pack_run(params, n_modes, t_max, t_max)
    trajectory = run(packed, 10**8)
    d = packed.dynamics
    cell = cell_rows({**params.as_dict(), "geometry": 0.0}, 1)[0]
    out = np.empty(len(OUT_COLUMNS))

    def tangent(count: int):
        return recorded_run_sums(
            packed.tables, packed.phase_scalars, packed.switching, packed.settings,
            trajectory.segments, trajectory.t_end, count, 0, 16)

    def map_cell():
        cell_observables(cell, d.tables, d.switching, d.geometry, t_max, MAX_SEGMENTS, out)

    def exponent_cell():
        return cell_exponent(cell, d.tables, d.switching, d.geometry, t_max, 0, MAX_SEGMENTS)

    def plain():
        return single_pass(packed, trajectory.time.size + 1)

    times = median_times({"run": plain, "tangent_1": lambda: tangent(1),
                          "tangent_4": lambda: tangent(4), "map_cell": map_cell,
                          "exponent_cell": exponent_cell}, repeats)
    spectrum = median_times({"run": plain, "all": lambda: tangent(4 * n_modes)}, 1)
    value, status = exponent_cell()
    run_s = times["run"]
    return {
        "n_modes": n_modes, "phases": int(trajectory.time.size), "run_s": run_s,
        "tangent_ratio_to_run": {"1": times["tangent_1"] / run_s,
                                 "4": times["tangent_4"] / run_s,
                                 str(4 * n_modes): spectrum["all"] / spectrum["run"]},
        "run_per_simulated_s": run_s / t_max,
        "exponent_cell_per_simulated_s": times["exponent_cell"] / t_max,
        "exponent_cell_ratio_to_run": times["exponent_cell"] / run_s,
        "exponent_cell_ratio_to_map_cell": times["exponent_cell"] / times["map_cell"],
        "exponent": float(value), "status": int(status)}


def markdown(report: dict) -> str:
    """The report as a short Markdown page."""
    lines = ["# Cost of the Lyapunov exponent", "",
             f"`python benchmarks/bench_lyapunov.py`; {report['machine']}, impactbeams "
             f"{report['version']}, {report['date']}. t_max = {report['t_max_s']} s; medians "
             f"of {report['repeats']} interleaved rounds (the full spectrum: one), ratios "
             "measured in the same process. The machine may have been shared: absolute "
             "timings are noisy, ratios less so.", "",
             "simulate()'s path, the tangent on the recorded segments, over the plain run "
             "(the event kernel alone, one pass):", "",
             "| case | n_modes | phases | plain run (s) | + largest exponent | + 4 | + all 4 n |",
             "|---|---|---|---|---|---|---|"]
    for name, case in report["cases"].items():
        ratios = [f"{v:.3f}x" for v in case["tangent_ratio_to_run"].values()]
        lines.append(f"| {name} | {case['n_modes']} | {case['phases']} | {case['run_s']:.3f} | "
                     + " | ".join(ratios) + " |")
    lines += ["", "A sweep cell with the exponent (windowed run: one `run_events` call per "
              "forcing period, memory bounded by the phases of one period, plus the tangent):",
              "", "| case | plain run (s per simulated s) | cell with exponent (s per "
              "simulated s) | ratio to the run | ratio to a dynamics-map cell | exponent "
              "(1/s, no transient) |", "|---|---|---|---|---|---|"]
    for name, case in report["cases"].items():
        lines.append(f"| {name} | {case['run_per_simulated_s']:.4f} | "
                     f"{case['exponent_cell_per_simulated_s']:.4f} | "
                     f"{case['exponent_cell_ratio_to_run']:.2f}x | "
                     f"{case['exponent_cell_ratio_to_map_cell']:.2f}x | "
                     f"{case['exponent']:.2f} |")
    lines += ["", "A dynamics-map cell (`impact_count`, `max_contact_force`, ...) costs more "
              "than the run: its peak-force searches sample every contact finely."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--t-max", type=float, default=5.0, help="horizon of each run (s)")
    args = parser.parse_args()
    report = {"version": __version__, "date": time.strftime("%Y-%m-%d %H:%M"),
              "machine": f"{platform.machine()}, Python {platform.python_version()}",
              "t_max_s": args.t_max, "repeats": args.repeats, "cases": {}}
    for name, (params, n_modes) in CASES.items():
        report["cases"][name] = costs(params, n_modes, args.t_max, args.repeats)
        print(name, json.dumps(report["cases"][name]), flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "lyapunov.json").write_text(json.dumps(report, indent=1) + "\n")
    (OUT / "lyapunov.md").write_text(markdown(report))


if __name__ == "__main__":
    main()
