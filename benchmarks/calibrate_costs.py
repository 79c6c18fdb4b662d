"""Measure the constants of the cost model (impactbeams.costs) on this machine.

    python benchmarks/calibrate_costs.py [--output docs/benchmarks/costs.json] [--skip-compile]
                                         [--only-compile]

Compute costs on one thread in this process (warm kernels; the first call of each kind is
discarded), per cell (first-impact maps) or per cycle of an impacting cell (full dynamics,
fitted as a n^p over n modes per beam, per kind of run and contact law); the 2-thread speed-up;
the start-up of a command and the cold compile of each kind of run (subprocesses with an empty
NUMBA_CACHE_DIR, minus the same run with the cache filled). Writes the JSON (with the load
average before and after) and rewrites the constants blocks of src/impactbeams/costs.py and
configuration.py (each contact law's costs per impacting cycle).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from impactbeams.configuration import LAWS

ROOT = Path(__file__).resolve().parents[1]
MODES = (5, 12, 32)
# an impacting grid (most cells impact: checked), moderate modal damping
IMPACTING = {"omega": (150.0, 900.0), "force_amplitude": (3e-3, 1e-2)}


def sweep_mapping(n_modes, t_max, observables, law, axes, num=3, **extra):
    from impactbeams.sweep.definition import sweep_from_mapping

    data = {"t_max": t_max, "n_modes": n_modes, "observables": observables,
            "params": {"clearance": 1.1e-5, "contact_law": law,
                       "damping_ratio": extra.pop("damping_ratio", 0.01),
                       **({"force_amplitude": extra.pop("force_amplitude")}
                          if "force_amplitude" in extra else {})},
            "axes": {name: {"min": lo, "max": hi, "num": num if lo != hi else 1,
                            "scale": "log" if name == "force_amplitude" else "linear"}
                     for name, (lo, hi) in axes.items()}, **extra}
    return sweep_from_mapping(data, source="calibration")


def timed(function, repeat=2):
    """Best wall time of ``repeat`` calls (s)."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def impacting_cycles(sweep, horizon_of):
    """Cycles of the sweep's cells that the model says impact, and that fraction."""
    from impactbeams import costs
    from impactbeams.sweep.estimate import sample_points

    points = sample_points(sweep, limit=sweep.size)
    values = {name: np.array([p.numeric()[name] for p in points]) for name in points[0].numeric()}
    horizon = horizon_of(values)
    hit = costs.impacts(values, sweep.n_modes, horizon)
    return float(np.sum(costs.cycles(values, horizon) * hit)), float(hit.mean())


def fit_power(modes, per_cycle):
    """(a, p) of per_cycle = a n^p, least squares in logs."""
    power, log_scale = np.polyfit(np.log(modes), np.log(per_cycle), 1)
    return float(np.exp(log_scale)), float(power)


def first_impact_costs(log):
    from impactbeams.sweep.run import run_sweep

    axes = {"omega": (10.0, 400.0), "force_amplitude": (1e-6, 1e-3)}
    per_cell = []
    for n in (5, 20, 40):
        sweep = sweep_mapping(n, 1.0, ["first_impact_time"], "spring", axes, num=200,
                              damping_ratio=0.0)
        run_sweep(sweep, threads=1)
        per_cell.append(timed(lambda: run_sweep(sweep, threads=1), 3) / sweep.size)  # noqa: B023
        log(f"first impact, {n} modes: {per_cell[-1] * 1e6:.3f} us per cell")
    slope, intercept = np.polyfit((5, 20, 40), per_cell, 1)
    return {"modes": [5, 20, 40], "seconds_per_cell": per_cell}, (float(intercept),
                                                                  float(slope))


def cell_search_costs(log):
    """First-impact cells searched alone (a map along omega): s per mode of an impacting cell,
    and per cycle and mode of a cell without impact (its whole horizon walked)."""
    from impactbeams.sweep.run import run_sweep

    alone, walk = [], []
    for n in (5, 20):
        for force, found in ((1e-2, alone), (1e-8, walk)):
            sweep = sweep_mapping(n, 1.0, ["first_impact_time"], "spring",
                                  {"omega": (300.0, 600.0)}, num=400, force_amplitude=force)
            cycles, share = impacting_cycles(sweep, lambda v, sweep=sweep: sweep.t_max)
            assert share == (1.0 if force > 1e-4 else 0.0)
            seconds = timed(lambda sweep=sweep: run_sweep(sweep, threads=1))
            if share:
                found.append(seconds / sweep.size / n)
            else:
                from impactbeams import costs
                from impactbeams.sweep.estimate import sample_points

                points = sample_points(sweep, limit=sweep.size)
                values = {k: np.array([p.numeric()[k] for p in points])
                          for k in points[0].numeric()}
                found.append(seconds / float(np.sum(costs.cycles(values, 1.0))) / n)
        log(f"first impact alone, {n} modes: {alone[-1] * 1e6:.2f} us per impacting cell "
            f"and mode, {walk[-1] * 1e9:.1f} ns per cycle and mode without impact")
    return float(np.mean(alone)), float(np.mean(walk))


def dynamics_costs(kind, law, log):
    """Seconds per impacting cycle at MODES, and the fit, of one kind of run."""
    from impactbeams.sweep.run import run_sweep
    from impactbeams.trajectory import simulate

    per_cycle = []
    for n in MODES:
        if kind == "simulate":
            from impactbeams import Params, costs

            params = Params(contact_law=law, omega=400.0, force_amplitude=5e-3,
                            damping_ratio=0.01)
            t_max = 0.3
            values = params.numeric()
            cycles = float(costs.cycles(values, t_max))
            assert costs.impacts(values, n, t_max)
            simulate(params, 0.01, n_modes=n)
            seconds = timed(lambda: simulate(params, t_max, n_modes=n,  # noqa: B023
                                             dt_output=1e-3), 3)
        else:
            observables, extra, t_max = {
                "dynamics": (["impact_count"], {}, 0.3),
                "lyapunov": (["lyapunov_exponent"], {}, 0.3),
                # the shipped long-time sweeps' periods and damping
                "long_time": (["response_period"], {"transient_periods": 500,
                                                    "sampled_periods": 200,
                                                    "damping_ratio": 0.03}, 1.0),
            }[kind]
            sweep = sweep_mapping(n, t_max, observables, law, IMPACTING, **extra)
            if kind == "long_time":
                horizon = lambda v, sweep=sweep: sweep.long_time.horizon(  # noqa: E731
                    v["omega"], sweep.transient_periods)
                cycles, share = impacting_cycles(sweep, horizon)
            else:
                cycles, share = impacting_cycles(sweep, lambda v, sweep=sweep: sweep.t_max)
            assert share >= 0.5, f"calibration grid of {kind}: {share:.0%} impacting"
            seconds = timed(lambda sweep=sweep: run_sweep(sweep, threads=1))  # the first compiles
        per_cycle.append(seconds / cycles)
        log(f"{kind}, {law}, {n} modes: {per_cycle[-1] * 1e6:.1f} us per impacting cycle")
    return {"modes": list(MODES), "seconds_per_cycle": per_cycle}, fit_power(MODES, per_cycle)


def free_cost(log, observable="impact_count"):
    """Seconds per cycle and mode of cells that never impact (tiny force)."""
    from impactbeams import costs
    from impactbeams.sweep.run import run_sweep

    axes = {"omega": (150.0, 900.0), "force_amplitude": (1e-8, 1e-7)}
    per_mode_cycle = []
    for n in (5, 20):
        sweep = sweep_mapping(n, 10.0, [observable], "spring", axes, num=4)
        points_cycles = impacting_cycles(sweep, lambda v, sweep=sweep: sweep.t_max)
        assert points_cycles[1] == 0.0
        from impactbeams.sweep.estimate import sample_points

        points = sample_points(sweep, limit=sweep.size)
        values = {k: np.array([p.numeric()[k] for p in points]) for k in points[0].numeric()}
        total = float(np.sum(costs.cycles(values, sweep.t_max)))
        per_mode_cycle.append(timed(lambda sweep=sweep: run_sweep(sweep, threads=1)) / total / n)
        log(f"free, {observable}, {n} modes: {per_mode_cycle[-1] * 1e9:.1f} ns per cycle and "
            "mode")
    return float(np.mean(per_mode_cycle))


def sampling_cost(log):
    """Seconds per output time and mode of simulate (fine grid minus coarse grid)."""
    from impactbeams import Params
    from impactbeams.trajectory import simulate

    params, n = Params(contact_law="spring", omega=400.0, damping_ratio=0.01), 12
    coarse = timed(lambda: simulate(params, 0.2, n_modes=n, dt_output=1e-3))
    fine = timed(lambda: simulate(params, 0.2, n_modes=n, dt_output=2e-6))
    per = max(fine - coarse, 0.0) / (0.2 / 2e-6) / n
    log(f"sampling: {per * 1e9:.1f} ns per output time and mode")
    return per


def energy_cost(log):
    """Seconds per node of the energy quadrature and mode (with the balance minus without)."""
    from impactbeams import Params, costs
    from impactbeams.preflight import highest_frequency
    from impactbeams.trajectory import simulate

    params, n, t_max, dt = Params(contact_law="spring", damping_ratio=0.01), 32, 0.1, 1e-3
    without = timed(lambda: simulate(params, t_max, n_modes=n, dt_output=dt))
    balance = timed(lambda: simulate(params, t_max, n_modes=n, dt_output=dt,
                                     energy_balance=True))
    per_node = costs.energy_seconds(float(highest_frequency(params.numeric(), n)), n, t_max,
                              round(t_max / dt) + 1) / costs.ENERGY_NODE
    per = max(balance - without, 0.0) / per_node
    log(f"energy balance: {per * 1e9:.1f} ns per quadrature node and mode")
    return per


def geometry_cost(log):
    from impactbeams.sweep.plan import build_plan

    n = 16
    sweep = sweep_mapping(n, 0.01, ["impact_count"], "spring", {"l1": (0.09, 0.11)}, num=10)
    build_plan(sweep)
    per = timed(lambda: build_plan(sweep)) / 10 / n**2
    log(f"geometry: {per * 1e6:.2f} us per geometry and mode^2")
    return per


def thread_speedup(log):
    from impactbeams.sweep.run import run_sweep

    sweep = sweep_mapping(12, 0.3, ["impact_count"], "spring", IMPACTING, num=4)
    one = timed(lambda sweep=sweep: run_sweep(sweep, threads=1))
    two = timed(lambda: run_sweep(sweep, threads=2))
    log(f"2 threads: {one / two:.2f}x")
    return one / two


# the shipped continuation's model at these modes (2 N = 2 n coordinates: a stop), this many
# points from where its orbit impacts (past the grazing at 202 rad/s)
CONTINUATION_MODES, CONTINUATION_POINTS, CONTINUATION_START = (5, 20, 50, 200), 20, 210.0


def continuation_costs(log):
    """CPU seconds per branch point of the shipped continuation, fitted as a (2 N)^p.

    Between the first and the last point `continue_orbits` reports (the located events
    among them): the corrector, its dr/dp, the test functions and the measures.
    """
    from impactbeams.continuation import continue_orbits, load_continuation

    shipped = load_continuation(ROOT / "sweeps" / "continuation-stop-fold.toml")
    per_point = []
    for n in CONTINUATION_MODES:
        continuation = dataclasses.replace(shipped, n_modes=n, max_points=CONTINUATION_POINTS,
                                           max_branches=1, start=CONTINUATION_START)
        continue_orbits(dataclasses.replace(continuation, max_points=3))  # warm
        stamps = []
        continue_orbits(continuation, lambda *_, stamps=stamps: stamps.append(time.process_time()))
        per_point.append((stamps[-1] - stamps[0]) / (len(stamps) - 1))
        log(f"continuation, {n} modes: {per_point[-1] * 1e3:.1f} ms CPU per point")
    coordinates = 2 * np.array(CONTINUATION_MODES)
    return dict(zip(map(str, CONTINUATION_MODES), per_point, strict=True)), fit_power(
        coordinates, per_point)


# tiny runs of each kind, through the command line (compile and start-up)
TINY = {
    "first_impact": "t_max = 0.1\nn_modes = 5\n[axes.omega]\nmin = 100.0\nmax = 300.0\nnum = 4\n",
    # more than one block of cells: the map's parallel twin (`sweep.plan.first_impact_kernel`)
    "first_impact_parallel": ("t_max = 0.1\nn_modes = 5\n[axes.omega]\nmin = 100.0\n"
                              "max = 300.0\nnum = 300\n"),
    "dynamics": ('t_max = 0.01\nn_modes = 5\nobservables = ["impact_count"]\n[params]\n'
                 "force_amplitude = 1e-2\n[axes.omega]\nmin = 100.0\nmax = 300.0\nnum = 2\n"),
    "lyapunov": ('t_max = 0.05\nn_modes = 5\nobservables = ["lyapunov_exponent"]\n[params]\n'
                 "force_amplitude = 1e-2\n[axes.omega]\nmin = 300.0\nmax = 400.0\nnum = 2\n"),
    "long_time": ('n_modes = 5\nobservables = ["response_period"]\nsampled_periods = 4\n'
                  "[params]\nforce_amplitude = 1e-2\n[axes.omega]\nmin = 300.0\nmax = 400.0\n"
                  "num = 2\n"),
}


def command(kind, folder):
    """The CLI command of the tiny run of ``kind`` (writing into ``folder``)."""
    if kind == "simulate":
        return ["simulate", "--t-max", "0.01", "--n-modes", "5", "-o",
                str(Path(folder) / "simulate.nc")]
    sweep = Path(folder) / f"{kind}.toml"
    sweep.write_text(TINY[kind])
    return ["run", str(sweep), "-o", str(Path(folder) / f"{kind}.nc"), "--quiet"]


def cli_seconds(arguments, cache, folder):
    """Wall time (s) of ``impactbeams ARGUMENTS`` with NUMBA_CACHE_DIR=cache, output removed."""
    for output in Path(folder).glob("*.nc"):
        output.unlink()
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONWARNINGS": "ignore"}
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "impactbeams.cli", *arguments], env=env, check=True,
                   capture_output=True)
    return time.perf_counter() - start


def compile_costs(log):
    """Cold compile (s) of each kind, and the start-up of a warm command (s)."""
    compile_seconds, warm = {}, {}
    with tempfile.TemporaryDirectory() as folder:
        for kind in ("first_impact", "first_impact_parallel", "dynamics", "lyapunov",
                     "long_time", "simulate"):
            cache = Path(folder) / f"cache-{kind}"
            arguments = command(kind, folder)
            cold = cli_seconds(arguments, cache, folder)
            warm[kind] = min(cli_seconds(arguments, cache, folder) for _ in range(2))
            compile_seconds[kind] = cold - warm[kind]
            log(f"compile {kind}: {compile_seconds[kind]:.1f} s (cold {cold:.1f} s, warm "
                f"{warm[kind]:.2f} s)")
    return compile_seconds, warm


# several contacts (issue 33): beam 1 against stops under its tip (one), under mid-span and the
# tip (two), a two-sided stop at each (four), as benchmarks/bench_contacts.py's; an impacting
# grid over Omega
CONTACT_CASES = {
    1: {"clearance": 6e-6},
    2: {"contacts": [{"position1": 0.05, "clearance": 2e-6}, {"clearance": 6e-6}]},
    4: {"contacts": [{"position1": 0.05, "clearance": 2e-6},
                     {"position1": 0.05, "side": "above", "clearance": 3e-6},
                     {"clearance": 6e-6}, {"side": "above", "clearance": 8e-6}]},
}
CONTACT_MODES = (8, 16)


def contacts_sweep(count, n_modes):
    from impactbeams.sweep.definition import sweep_from_mapping

    return sweep_from_mapping({
        "t_max": 0.2, "n_modes": n_modes, "observables": ["impact_count"],
        "params": {"counterpart": "stop", "force_amplitude": 1e-3, "contact_stiffness": 1e4,
                   "damping_ratio": 0.01, **CONTACT_CASES[count]},
        "axes": {"omega": {"min": 300.0, "max": 500.0, "num": 24}}}, source="calibration")


def contacts_costs(log):
    """CONTACT_CELL, and each case's seconds per cell, measured against estimated.

    A cell of several contacts costs its contacts' runs' events (the single contact's model
    of each, `sweep.estimate.cell_seconds`) and CONTACT_CELL per contact: the mean over the
    cases of two and four contacts of (measured - those runs) / contacts. One thread, a
    sweep each (its set-up included), best of 3.
    """
    from impactbeams import costs
    from impactbeams.sweep.estimate import _run_seconds, cell_seconds, sample_points
    from impactbeams.sweep.run import run_sweep

    cases, shares = [], []
    for n in CONTACT_MODES:
        for count in CONTACT_CASES:
            sweep = contacts_sweep(count, n)
            run_sweep(sweep, threads=1)  # the first compiles
            seconds = timed(lambda sweep=sweep: run_sweep(sweep, threads=1), 3) / sweep.size
            points = sample_points(sweep, limit=sweep.size)
            events = float(np.mean([np.sum(_run_seconds(sweep, point.each_contact()))
                                    for point in points]))
            if count > 1:
                shares.append((seconds - events) / count)
            cases.append({"contacts": count, "n_modes": n, "measured_s_per_cell": seconds,
                          "events_model_s_per_cell": events})
            log(f"{count} contacts, {n} modes: {seconds * 1e3:.2f} ms per cell (events' model "
                f"{events * 1e3:.2f} ms)")
    fitted = round_constants(float(np.mean(shares)))  # as costs.py will hold it
    previous, costs.CONTACT_CELL = costs.CONTACT_CELL, fitted
    for case in cases:
        sweep = contacts_sweep(case["contacts"], case["n_modes"])
        case["estimated_s_per_cell"] = float(np.mean(cell_seconds(
            sweep, sample_points(sweep, limit=sweep.size))))
        case["measured_over_estimated"] = case["measured_s_per_cell"] / case[
            "estimated_s_per_cell"]
    costs.CONTACT_CELL = previous
    log(f"several contacts: {fitted * 1e3:.2f} ms per contact and cell beyond the events")
    return cases, fitted


def round_constants(constants):
    """Two significant digits (floats), recursively."""
    if isinstance(constants, dict):
        return {key: round_constants(value) for key, value in constants.items()}
    if isinstance(constants, (list, tuple)):
        return [round_constants(value) for value in constants]
    return float(f"{constants:.2g}")


def module_blocks(constants):
    """The text of each constants block, by the module that holds it.

    src/impactbeams/costs.py holds every constant but the costs per impacting cycle
    (``IMPACT_CYCLE``: by kind of run, then by contact law), which each law holds
    (`ContactLaw.impact_cycle`): ``<LAW>_CYCLE``, by kind, in src/impactbeams/configuration.py.
    """
    def text(value):
        if isinstance(value, dict):
            return "{" + ", ".join(f"{text(key)}: {text(v)}" for key, v in value.items()) + "}"
        if isinstance(value, list):
            return "(" + ", ".join(text(v) for v in value) + ")"
        return json.dumps(value) if isinstance(value, str) else repr(value)

    def block(named):
        lines = []
        for name, value in named.items():
            line = f"{name} = {text(value)}"
            if len(line) > 99 and isinstance(value, dict):  # one entry per line
                line = "\n".join([f"{name} = {{", *(f"    {text(key)}: {text(v)}," for key, v
                                                     in value.items()), "}"])
            lines.append(line)
        return "\n".join(lines) + "\n"

    cycle = constants["IMPACT_CYCLE"]
    rest = {name: value for name, value in constants.items() if name != "IMPACT_CYCLE"}
    rest["THREAD_SPEEDUP"] = {int(k): v for k, v in rest["THREAD_SPEEDUP"].items()}
    laws = {f"{law.upper()}_CYCLE": {kind: by_law[law] for kind, by_law in cycle.items()
                                     if law in by_law} for law in LAWS}
    source = ROOT / "src" / "impactbeams"
    return {source / "costs.py": block(rest), source / "configuration.py": block(laws)}


# a constants block: its header line, its lines, its closing rule
CONSTANTS_BLOCK = re.compile(
    r"(# --- [^\n]* from docs/benchmarks/costs\.json[^\n]*\n)(.*?)(# ---+\n)", re.S)


def write_module(constants):
    """Rewrite the constants blocks (`module_blocks`) from ``constants``."""
    for path, lines in module_blocks(constants).items():
        path.write_text(CONSTANTS_BLOCK.sub(lambda m, lines=lines: m.group(1) + lines
                                            + m.group(3), path.read_text(), count=1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", type=Path, default=ROOT / "docs" / "benchmarks" / "costs.json")
    parser.add_argument("--skip-compile", action="store_true",
                        help="keep the compile and start-up figures of the existing output")
    parser.add_argument("--only-continuation", action="store_true",
                        help="measure CONTINUATION_POINT only, keep the other constants")
    parser.add_argument("--only-contacts", action="store_true",
                        help="measure CONTACT_CELL only, keep the other constants")
    parser.add_argument("--only-compile", action="store_true",
                        help="measure COMPILE and START_UP only, keep the other constants")
    args = parser.parse_args()
    if args.only_compile:
        compile_only(args.output)
        return
    if args.only_continuation:
        continuation_only(args.output)
        return
    if args.only_contacts:
        contacts_only(args.output)
        return
    warnings.simplefilter("ignore")
    log = lambda text: print(text, flush=True)  # noqa: E731
    load_before = os.getloadavg()
    started = time.time()
    measured, constants = {}, {}
    measured["first_impact"], (cell, mode) = first_impact_costs(log)
    constants["FIRST_IMPACT_CELL"], constants["FIRST_IMPACT_MODE"] = cell, mode
    constants["FIRST_IMPACT_ALONE"], constants["FIRST_IMPACT_WALK"] = cell_search_costs(log)
    cycle = {}
    for kind in ("dynamics", "lyapunov", "long_time", "simulate"):
        cycle[kind] = {}
        # Lyapunov exponents need a flow with tangent dynamics (`ContactLaw.tangent_flow`)
        for law in (law for law in LAWS.values() if kind != "lyapunov" or law.tangent_flow):
            measured[f"{kind}_{law.name}"], cycle[kind][law.name] = dynamics_costs(
                kind, law.name, log)
    constants["IMPACT_CYCLE"] = cycle
    constants["FREE_CYCLE"] = free_cost(log)
    constants["LYAPUNOV_FREE_CYCLE"] = free_cost(log, "lyapunov_exponent")
    constants["SAMPLING"] = sampling_cost(log)
    constants["ENERGY_NODE"] = energy_cost(log)
    constants["GEOMETRY"] = geometry_cost(log)
    constants["THREAD_SPEEDUP"] = {1: 1.0, 2: thread_speedup(log)}
    measured["continuation"], constants["CONTINUATION_POINT"] = continuation_costs(log)
    measured["contacts"], constants["CONTACT_CELL"] = contacts_costs(log)
    if args.skip_compile:
        previous = json.loads(args.output.read_text())
        constants["START_UP"] = previous["constants"]["START_UP"]
        constants["COMPILE"] = previous["constants"]["COMPILE"]
        measured["warm_command"] = previous["measured"]["warm_command"]
    else:
        constants["COMPILE"], measured["warm_command"] = compile_costs(log)
        constants["START_UP"] = min(measured["warm_command"].values())
    # the load (last minute) and cores the compile times were measured at, last: the compile
    # scales from them to a machine's load (`costs.compile_estimate`)
    load_after = os.getloadavg()
    constants["COMPILE_LOAD"] = (previous["constants"]["COMPILE_LOAD"] if args.skip_compile
                                 else load_after[0])
    constants["COMPILE_CORES"] = os.cpu_count()
    constants = round_constants(constants)
    constants["COMPILE_CORES"] = int(constants["COMPILE_CORES"])
    result = {"constants": constants, "measured": measured,
              "load_average_before": list(load_before), "load_average_after":
              list(load_after), "cpu_count": os.cpu_count(),
              "started_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime(started)),
              "seconds": round(time.time() - started, 1)}
    args.output.write_text(json.dumps(result, indent=1) + "\n")
    write_module(constants)
    log(f"wrote {args.output} and the constants of costs.py and configuration.py")


def continuation_only(output):
    """Measure CONTINUATION_POINT alone into ``output`` and the module (the rest kept)."""
    result = json.loads(output.read_text())
    measured, fitted = continuation_costs(lambda text: print(text, flush=True))
    constants = result["constants"]
    constants["CONTINUATION_POINT"] = round_constants(fitted)
    result["measured"]["continuation"] = measured
    result["continuation_measured_utc"] = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    result["continuation_load_average"] = list(os.getloadavg())
    output.write_text(json.dumps(result, indent=1) + "\n")
    write_module(constants)


def contacts_only(output):
    """Measure CONTACT_CELL alone into ``output`` and the module (the rest kept)."""
    warnings.simplefilter("ignore")
    result = json.loads(output.read_text())
    measured, fitted = contacts_costs(lambda text: print(text, flush=True))
    constants = result["constants"]
    constants["CONTACT_CELL"] = fitted
    result["measured"]["contacts"] = measured
    result["contacts_measured_utc"] = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    result["contacts_load_average"] = list(os.getloadavg())
    output.write_text(json.dumps(result, indent=1) + "\n")
    write_module(constants)


def compile_only(output):
    """Measure COMPILE, START_UP and COMPILE_LOAD alone into ``output`` and the module."""
    warnings.simplefilter("ignore")
    result = json.loads(output.read_text())
    constants = result["constants"]
    compile_seconds, result["measured"]["warm_command"] = compile_costs(
        lambda text: print(text, flush=True))
    load_after = os.getloadavg()  # the load the compile times were measured at, as in main
    constants.update(round_constants({
        "COMPILE": compile_seconds, "COMPILE_LOAD": load_after[0],
        "START_UP": min(result["measured"]["warm_command"].values())}))
    constants["COMPILE_CORES"] = os.cpu_count()
    result["compile_measured_utc"] = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    result["compile_load_average"] = list(load_after)
    output.write_text(json.dumps(result, indent=1) + "\n")
    write_module(constants)


if __name__ == "__main__":
    main()
