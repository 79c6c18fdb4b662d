"""Benchmark: the long-time bifurcation diagram (sweeps/bifurcation-omega.toml) and its profile.

The issue's target: a 400-point bifurcation diagram over Omega, 500 forcing periods of
transient and 200 sampled, spring law at a resolved n_modes, in under 20 s on 2 cores (issue 24;
issue 14's was 60 s).

* Cost per cell: every ``--stride``-th cell of the diagram (a uniform sample of its Omega
  axis) is run alone on one thread (serial kernel, after a compile warm-up); the whole
  diagram's cost on one core is ``stride`` times their sum, on 2 cores half of that at ideal
  scaling; times are the CPU time of the thread (load-proof). Per cell: run time, simulated
  time (the horizon), forcing periods, contact onsets per
  period in the sampled window.
* ``--full``: the whole diagram as one sweep on 2 threads, its wall time and the CPU time of
  this process (on a shared machine the CPU time says what two free cores would take).
* The same diagram with a softer contact (``--variant-stiffness``, default k = 1e4 N/m, at its
  own resolved n_modes): what the contact stiffness costs (modes and micro-contacts).
* Profile, at a few Omega: one event-driven run of ``PROFILE_PERIODS`` forcing periods, split
  into the event searches of free and contact phases (``find_switch`` replayed from every
  recorded segment start), the coordinate changes at the switches and one closed-form
  propagation per segment; and the stroboscopic sampling of 200 states. Best of 5 each.
* ``--previous FILE``: the previous code's ``longtime.json`` (this script run on that code,
  with ``PYTHONPATH`` at it and ``--out`` elsewhere): its figures beside this code's and, where
  both ran ``--full``, the number of cells whose response period is the same.

Idle BLAS threads sleep (``OPENBLAS_THREAD_TIMEOUT``, set here before NumPy and SciPy load),
as they do in the command line (`impactbeams.cli.BLAS_THREAD_TIMEOUT`), so that the figures
are the command's (since issue 32 the cells call no BLAS; a geometry's set-up holds it to one
thread).

Writes longtime.json and longtime.md to ``--out`` (default docs/benchmarks).

    python benchmarks/bench_longtime.py [--stride 10] [--full] [--previous F] [--out DIR]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", "4")  # as impactbeams.cli.BLAS_THREAD_TIMEOUT

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

from impactbeams import __version__  # noqa: E402
from impactbeams.kernels import contact  # noqa: E402
from impactbeams.kernels import dynamics as dyn  # noqa: E402
from impactbeams.kernels.layout import CONTACT, FREE  # noqa: E402
from impactbeams.kernels.rotor import rotor_arrays  # noqa: E402
from impactbeams.packing import pack_run  # noqa: E402
from impactbeams.sweep import (  # noqa: E402
    build_plan,
    compute_chunk,
    load_sweep,
    run_sweep,
    sweep_from_mapping,
)
from impactbeams.trajectory.phases import run, sample  # noqa: E402

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
TARGET_S = 20.0  # issue 24's target for the whole diagram on 2 cores (issue 14's was 60 s)
PROFILE_PERIODS = 50
PROFILE_OMEGA = (150.0, 300.0, 500.0, 800.0)


@dataclasses.dataclass
class CellCost:
    """One cell's serial run: Omega (rad/s), run time (s), horizon (s), onsets per period."""

    omega: float
    seconds: float
    horizon: float
    periods: int
    onsets_per_period: float
    response_period: int


def cell_costs(sweep, stride: int) -> list[CellCost]:
    """Serial run time of every ``stride``-th cell, after a warm-up (compile) on the last."""
    plan = build_plan(sweep)
    long_time = sweep.long_time
    compute_chunk(sweep, sweep.size - 1, sweep.size, parallel=False, plan=plan)
    costs = []
    for i in range(0, sweep.size, stride):
        start = time.thread_time()  # CPU time of this thread: what an idle core would take
        values = compute_chunk(sweep, i, i + 1, parallel=False, plan=plan)
        seconds = time.thread_time() - start
        omega = float(sweep.params_at(_point(sweep, i)).omega)
        period = float(long_time.forcing_period(omega))
        costs.append(CellCost(omega, seconds,
                              float(long_time.horizon(omega, sweep.transient_periods)),
                              sweep.transient_periods + long_time.sampled_periods,
                              float(values["steady_impact_rate"][0]) * period,
                              int(values["response_period"][0])))
        print(f"Omega {omega:7.1f}: {seconds:7.2f} s, {costs[-1].onsets_per_period:5.1f} "
              f"onsets/period, period {costs[-1].response_period}", flush=True)
    return costs


def _point(sweep, flat: int) -> dict[str, float]:
    """The swept parameters of flat cell ``flat``."""
    index = np.unravel_index(flat, sweep.shape)
    return {axis.name: axis.value(int(i)) for axis, i in zip(sweep.axes, index, strict=True)}


def map_estimate(sweep, stride: int) -> dict:
    """One-core cost (s) of a whole map, extrapolated from every ``stride``-th cell."""
    costs = cell_costs(sweep, stride)
    serial = sum(c.seconds for c in costs)
    return {"sweep": sweep.source, "cells": sweep.size, "stride": stride,
            "sampled_cells": len(costs), "one_core_s": stride * serial,
            "cell_s_mean": serial / len(costs)}


@numba.njit
def _replay_searches(tables, forces, scalars, seg_time, seg_phase, seg_q, seg_v, settings,
                     phase):
    """Repeat the switching search from the start of every recorded segment of ``phase``."""
    n = seg_q.shape[1]
    q, v = np.empty(n), np.empty(n)
    rotor = rotor_arrays(n)
    total = 0.0
    for k in range(seg_time.size):
        if seg_phase[k] == phase:
            total += dyn.find_switch(tables[phase], forces[phase], scalars[phase], seg_q[k],
                                     seg_v[k], seg_time[k], True, False, settings, q, v,
                                     rotor)
    return total


@numba.njit
def _replay_switches(seg_time, seg_phase, end_q, end_v, switching, settings):
    """Repeat the change of coordinates at every recorded switch."""
    n = end_q.shape[1]
    q, v = np.empty(n), np.empty(n)
    for k in range(seg_time.size - 1):
        contact.switch_state(end_q[k], end_v[k], seg_time[k + 1], 1 - seg_phase[k], switching,
                             settings, q, v)
    return q[0]


@numba.njit
def _replay_propagations(tables, forces, seg_time, seg_phase, seg_q, seg_v, settings):
    """One closed-form propagation per recorded segment, to its end."""
    n = seg_q.shape[1]
    q, v = np.empty(n), np.empty(n)
    for k in range(seg_time.size - 1):
        phase = seg_phase[k]
        dyn.propagate(tables[phase], forces[phase], seg_q[k], seg_v[k], seg_time[k],
                      seg_time[k + 1], settings, q, v)
    return q[0]


def _best(function, *args, repeats: int = 5) -> float:
    """Best wall time (s) of ``function(*args)`` over ``repeats`` calls (after one warm-up)."""
    function(*args)
    best = math.inf
    for _ in range(repeats):
        start = time.thread_time()
        function(*args)
        best = min(best, time.thread_time() - start)
    return best


def profile(sweep, omega: float) -> dict:
    """Where one event-driven run of PROFILE_PERIODS forcing periods spends its time."""
    params = sweep.base.replace(omega=omega)
    horizon = PROFILE_PERIODS * 2.0 * math.pi / omega
    packed = pack_run(params, sweep.n_modes, horizon, horizon)
    limit = 10**7
    total = _best(run, packed, limit)
    trajectory = run(packed, limit)
    arrays = (packed.tables, packed.forces, packed.phase_scalars, trajectory.time,
              trajectory.phase, trajectory.q, trajectory.v, packed.settings)
    searches = {name: _best(_replay_searches, *arrays, phase)
                for name, phase in (("free", FREE), ("contact", CONTACT))}
    switches = _best(_replay_switches, trajectory.time, trajectory.phase, trajectory.end_q,
                     trajectory.end_v, packed.switching, packed.settings)
    propagations = _best(_replay_propagations, packed.tables, packed.forces, trajectory.time,
                         trajectory.phase, trajectory.q, trajectory.v, packed.settings)
    times = np.linspace(0.0, horizon, 200)
    sampling = _best(sample, packed, trajectory, times)
    counts = {name: int(np.count_nonzero(trajectory.phase == phase))
              for name, phase in (("free", FREE), ("contact", CONTACT))}
    return {"omega": omega, "periods": PROFILE_PERIODS, "phases": int(trajectory.time.size),
            "phases_per_period": trajectory.time.size / PROFILE_PERIODS,
            "run_s": total, "run_us_per_phase": 1e6 * total / trajectory.time.size,
            "search_s": searches, "segments": counts,
            "search_us_per_segment": {k: 1e6 * searches[k] / max(1, counts[k])
                                      for k in searches},
            "switches_s": switches, "propagation_us_per_segment":
                1e6 * propagations / max(1, trajectory.time.size - 1),
            "sampling_200_states_s": sampling,
            "search_fraction": (searches["free"] + searches["contact"]) / total}


def _summary_rows(study: dict) -> list[str]:
    """The summary table's rows of one diagram study."""
    one_core = study["diagram_one_core_s"]
    return [
        *_full_rows(study["full_run"]),
        *_previous_rows(study),
        f"| whole diagram, 1 core (extrapolated) | {one_core:,.0f} s |",
        f"| whole diagram, 2 cores at ideal scaling | {one_core / 2:,.0f} s "
        f"(target {TARGET_S:g} s: {one_core / 2 / TARGET_S:.1f}x) |",
        f"| cost per cell: median, max | {study['cell_s_median']:.2f} s, "
        f"{study['cell_s_max']:.1f} s |",
        f"| cost per simulated second: mean over the cells | "
        f"{study['s_per_simulated_s']:.3f} s |",
        f"| cost per forcing period: mean | {1e3 * study['s_per_period']:.2f} ms |",
        f"| contact onsets per forcing period (sampled window): mean, max | "
        f"{study['onsets_per_period_mean']:.1f}, {study['onsets_per_period_max']:.1f} |",
    ]


def _map_rows(estimate: dict | None) -> list[str]:
    """The period map's extrapolated cost, if it was estimated."""
    if estimate is None:
        return []
    return [f"| `{Path(estimate['sweep']).name}` ({estimate['cells']} cells), 1 core "
            f"(extrapolated from every {estimate['stride']}-th cell) | "
            f"{estimate['one_core_s']:,.0f} s ({estimate['cell_s_mean']:.2f} s per cell) |"]


def _full_rows(full: dict | None) -> list[str]:
    """The whole diagram's measured run, if it was run."""
    if full is None:
        return []
    return [f"| **whole diagram run as one sweep on 2 threads**: wall time, CPU time | "
            f"**{full['wall_s']:,.0f} s**, {full['cpu_s']:,.0f} s ({full['cores_used']:.2f} "
            f"cores on average; target {TARGET_S:g} s) |"]


def _previous_rows(study: dict) -> list[str]:
    """The previous code's figures (``--previous``), with its periods compared cell by cell."""
    previous = study.get("previous")
    if previous is None:
        return []
    full, cells = previous["full_run"], study["diagram_cells"]
    rows = [f"| previous code, run just before in the same environment: whole diagram on 2 "
            f"threads, wall (CPU); 1 core (extrapolated) | {full['wall_s']:,.0f} s "
            f"({full['cpu_s']:,.0f} s); {previous['diagram_one_core_s']:,.0f} s |" if full else
            "| previous code, run just before in the same environment: 1 core (extrapolated) | "
            f"{previous['diagram_one_core_s']:,.0f} s |"]
    if previous["same_periods"] is not None:
        rows.append(f"| cells whose response period equals the previous code's | "
                    f"{previous['same_periods']} of {cells} |")
    return rows


def _load(report: dict) -> str:
    """The machine's 1-minute load average during the run, if recorded."""
    if "load_average" not in report:
        return ""
    return ", load average {:.1f} at the start, {:.1f} at the end".format(*report["load_average"])


def markdown(report: dict) -> str:
    """The results as the Markdown page docs/benchmarks/longtime.md."""
    variant = report["variant"]
    lines = [
        "# Long-time dynamics: the bifurcation diagram's cost",
        "",
        f"`{report['sweep']}`: {report['diagram_cells']} values of Omega "
        f"({report['omega_range'][0]:g}..{report['omega_range'][1]:g} rad/s), "
        f"{report['transient_periods']} + {report['sampled_periods']} forcing periods each, "
        f"spring law (k = {report['contact_stiffness']:.3g} N/m) at {report['n_modes']} modes "
        f"per beam; {report['machine']}, {report['date']}, impactbeams {report['impactbeams']}"
        f"{_load(report)}. Regenerate with `python benchmarks/bench_longtime.py` (per-cell and "
        "profile times are the CPU time of the thread that ran them, so that another job's load "
        "does not count; the whole diagram's wall time is inflated by such a load, its CPU "
        "time less so).",
        "",
        f"Measured: every {report['stride']}-th cell ({len(report['cells'])} cells, a uniform "
        "sample of the Omega axis), each alone on one thread; the diagram's cost is "
        f"extrapolated from them ({report['stride']} times their sum).",
        "",
        "| quantity | value |",
        "|---|---|",
        *_summary_rows(report),
        *_map_rows(report["period_map"]),
        "",
        f"The same diagram with a softer contact, k = {variant['contact_stiffness']:g} N/m, at "
        f"its resolved {variant['n_modes']} modes per beam:",
        "",
        "| quantity | value |",
        "|---|---|",
        *_summary_rows(variant),
        "",
        f"Per cell at k = {report['contact_stiffness']:.3g} N/m (Omega in rad/s, run time in s "
        "on one thread):",
        "",
        "| Omega | run time | simulated time | onsets per period | ms per period | period |",
        "|---|---|---|---|---|---|",
    ]
    for c in report["cells"]:
        lines.append(f"| {c['omega']:.1f} | {c['seconds']:.2f} | {c['horizon']:.2f} s | "
                     f"{c['onsets_per_period']:.1f} | {1e3 * c['seconds'] / c['periods']:.2f} | "
                     f"{c['response_period']} |")
    if report["profile"]:
        lines += ["", f"## Profile of one run ({PROFILE_PERIODS} forcing periods from rest)", "",
                  "| Omega | phases per period | us per phase | event search, free "
                  "(us/segment) | event search, contact (us/segment) | search share | "
                  "switches share | propagation (us/segment) | 200 samples (ms) |",
                  "|---|---|---|---|---|---|---|---|---|"]
    for p in report["profile"]:
        lines.append(
            f"| {p['omega']:g} | {p['phases_per_period']:.1f} | {p['run_us_per_phase']:.0f} | "
            f"{p['search_us_per_segment']['free']:.0f} | "
            f"{p['search_us_per_segment']['contact']:.0f} | {p['search_fraction']:.0%} | "
            f"{p['switches_s'] / p['run_s']:.0%} | {p['propagation_us_per_segment']:.1f} | "
            f"{1e3 * p['sampling_200_states_s']:.1f} |")
    return "\n".join(lines) + "\n"


def headline(report: dict) -> str:
    """A paragraph for docs/benchmarks/README.md, pointing to longtime.md."""
    soft = report["variant"]

    def cost(study: dict) -> str:
        full = study["full_run"]
        measured = (f"{full['wall_s']:,.0f} s on 2 threads ({full['cpu_s']:,.0f} s of CPU), "
                    if full else "")
        return f"{measured}{study['diagram_one_core_s']:,.0f} s on one core (extrapolated)"

    return (f"## Long-time bifurcation diagram\n\n`{report['sweep']}` "
            f"({report['diagram_cells']} values of Omega, {report['transient_periods']} + "
            f"{report['sampled_periods']} forcing periods each, target {TARGET_S:g} s on 2 "
            f"cores): with the Hertz contact (k = {report['contact_stiffness']:.3g} N/m, "
            f"{report['n_modes']} modes per beam) {cost(report)}, "
            f"{1e3 * report['s_per_period']:.1f} ms per forcing period; with k = "
            f"{soft['contact_stiffness']:g} N/m ({soft['n_modes']} modes) {cost(soft)}. "
            "Details and profile: [longtime.md](longtime.md).\n")


def full_run(sweep) -> dict:
    """Wall and CPU time (s) of the whole diagram as one sweep on 2 threads, and each cell's
    response period (compared cell by cell with the previous code's)."""
    wall, cpu = time.perf_counter(), time.process_time()
    diagram = run_sweep(sweep, threads=min(2, numba.config.NUMBA_NUM_THREADS), progress=False)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {"wall_s": wall, "cpu_s": cpu, "cores_used": cpu / wall,
            "response_period": diagram.response_period.values.ravel().tolist()}


def against_previous(study: dict, previous: dict) -> dict:
    """The previous code's figures of the same study, and its periods against this code's."""
    mine, theirs = study["full_run"], previous["full_run"]
    same = None
    if mine and theirs and "response_period" in theirs:
        same = sum(a == b for a, b in zip(mine["response_period"], theirs["response_period"],
                                          strict=True))
    return {"full_run": None if theirs is None else {k: theirs[k] for k in ("wall_s", "cpu_s")},
            "diagram_one_core_s": previous["diagram_one_core_s"], "same_periods": same}


def diagram_study(sweep, source: str, stride: int, full: bool) -> dict:
    """Cost of one bifurcation diagram: per-cell serial times, extrapolation, a full run."""
    costs = cell_costs(sweep, stride)
    serial = sum(c.seconds for c in costs)
    seconds = np.array([c.seconds for c in costs])
    return {
        "sweep": source, "diagram_cells": sweep.size, "stride": stride,
        "omega_range": [sweep.axes[0].min, sweep.axes[0].max], "n_modes": sweep.n_modes,
        "contact_stiffness": sweep.base.contact_stiffness,
        "transient_periods": sweep.transient_periods,
        "sampled_periods": sweep.long_time.sampled_periods,
        "cells": [dataclasses.asdict(c) for c in costs],
        "diagram_one_core_s": stride * serial, "full_run": full_run(sweep) if full else None,
        "cell_s_median": float(np.median(seconds)), "cell_s_max": float(seconds.max()),
        "s_per_simulated_s": serial / sum(c.horizon for c in costs),
        "s_per_period": serial / sum(c.periods for c in costs),
        "onsets_per_period_mean": float(np.mean([c.onsets_per_period for c in costs])),
        "onsets_per_period_max": float(np.max([c.onsets_per_period for c in costs])),
    }


def soft_variant(sweep, stiffness: float):
    """The same diagram with contact stiffness ``stiffness`` (N/m) at its resolved n_modes."""
    from impactbeams.compliant import recommended_modes

    definition = sweep.definition()
    definition["params"] = {**definition["params"], "contact_stiffness": stiffness}
    definition["n_modes"] = recommended_modes(sweep.base.replace(contact_stiffness=stiffness))
    return sweep_from_mapping(definition, source=f"{sweep.source}, k = {stiffness:g} N/m")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sweep", default=str(ROOT / "sweeps" / "bifurcation-omega.toml"))
    parser.add_argument("--stride", type=int, default=10)
    parser.add_argument("--variant-stiffness", type=float, default=1e4)
    parser.add_argument("--no-profile", action="store_true")
    parser.add_argument("--full", action="store_true", help="also run the whole diagram")
    parser.add_argument("--map", default=str(ROOT / "sweeps" / "period-map-omega-force.toml"))
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--previous", type=Path,
                        help="the previous code's longtime.json, run with --full too")
    parser.add_argument("--map-stride", type=int, default=46,
                        help="estimate the period map from every N-th cell (0: skip)")
    args = parser.parse_args()
    load_before = os.getloadavg()[0]
    sweep = load_sweep(args.sweep)
    name = Path(args.sweep).name
    report = diagram_study(sweep, name, args.stride, args.full)
    variant = soft_variant(sweep, args.variant_stiffness)
    report["variant"] = diagram_study(variant, f"{name} with k = {args.variant_stiffness:g} N/m",
                                      args.stride, args.full)
    report.update({
        "period_map": (map_estimate(load_sweep(args.map), args.map_stride)
                       if args.map_stride else None),
        "profile": [] if args.no_profile else [profile(sweep, w) for w in PROFILE_OMEGA],
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "impactbeams": __version__, "numba": numba.__version__,
        "date": time.strftime("%Y-%m-%d"),
        "load_average": [load_before, os.getloadavg()[0]],  # 1-min load at start and end
    })
    if args.previous:
        previous = json.loads(args.previous.read_text())
        for study, before in ((report, previous), (report["variant"], previous["variant"])):
            study["previous"] = against_previous(study, before)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "longtime.json").write_text(json.dumps(report, indent=1) + "\n")
    (args.out / "longtime.md").write_text(markdown(report))
    print(markdown(report))


if __name__ == "__main__":
    main()
