"""Benchmark: cells per second of a basin map, against a direct simulation of the same cells.

Two cases, a cantilever against a stop at zeta = 0.02, F0 = 0.1 mN, Omega = 300 rad/s, each
with its resolved modes (`contact.spring.required_modes`) and two coexisting stable orbits:
docs/basins.md's soft stop (k = 100 N/m, 5 modes; the non-impacting orbit and one contact per
period) and the default contact stiffness (28 modes; the non-impacting orbit and a rattle of 11
contacts per period). A grid of ``--points`` x ``--points`` (the default contact: ``--points``
// 2 + 1 a side) of beam 1's initial tip deflection (+-40 um) and velocity (+-12 mm/s).

* The basin map (`impactbeams.basins`, default `Settling`) on 1 worker thread (CPU time of the
  process) and on 2 (wall time), after a warm-up map that compiles the kernels.
* The direct way to the same labels: `simulate` from each cell's state over a fixed horizon,
  the longest transient of the map plus the settling window (what a fixed-horizon run needs
  to label every cell), with its stroboscopic samples (`long_time`); CPU time, one thread,
  over every ``--stride``-th cell, scaled to the grid.

* Workers: the soft stop's map of ``--ratio-points`` x ``--ratio-points`` states (81: 6561)
  on 1 and on 2 worker threads, in turn ``--repeats`` times in this process; wall and CPU
  time of each, and the load average (1 min) before each pair, the machine being shared.

Writes basins.json (and prints it) to ``--out`` (default docs/benchmarks).

    python benchmarks/bench_basins.py [--points 21] [--stride 7] [--ratio-points 81]
        [--repeats 3] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

from impactbeams import LongTime, Params, __version__, basins, simulate
from impactbeams.contact.spring import required_modes
from impactbeams.orbits import Settling

SOFT = Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
              force_amplitude=1e-4, omega=300.0)
DEFAULT_CONTACT = Params(counterpart="stop", damping_ratio=0.02, force_amplitude=1e-4,
                         omega=300.0)
# name: (params, grid points divided by)
CASES = {"soft stop (k = 100 N/m)": (SOFT, 1), "default contact stiffness": (DEFAULT_CONTACT, 2)}
BOX = ((-4e-5, 4e-5), (-1.2e-2, 1.2e-2))  # m, m/s


def axes(points: int) -> tuple[np.ndarray, np.ndarray]:
    return tuple(np.linspace(low, high, points) for low, high in BOX)


def timed(call, clock) -> tuple[float, object]:
    start = clock()
    result = call()
    return clock() - start, result


def measure(params: Params, n_modes: int, points: int, stride: int) -> dict:
    """The basin map's and the direct runs' costs of one case."""
    basins(params, axes(3), n_modes=n_modes, workers=1)  # compiles
    cells = points ** 2
    cpu, dataset = timed(lambda: basins(params, axes(points), n_modes=n_modes, workers=1),
                         time.process_time)
    wall, _ = timed(lambda: basins(params, axes(points), n_modes=n_modes, workers=2),
                    time.perf_counter)
    horizon = int(dataset.settle_periods.max()) + Settling().window
    starts = np.concatenate([dataset.start_displacement.values, dataset.start_velocity.values],
                            axis=-1).reshape(cells, -1)
    period = 2 * math.pi / params.omega
    chosen = np.arange(0, cells, stride)

    def direct() -> None:
        for cell in chosen:
            simulate(params, horizon * period, n_modes, dt_output=period,
                     initial_state=starts[cell],
                     long_time=LongTime(sampled_periods=horizon, max_period=8))

    simulate(params, 10 * period, n_modes, dt_output=period,  # compiles
             long_time=LongTime(sampled_periods=10, max_period=5))
    direct_cpu, _ = timed(direct, time.process_time)
    direct_per_cell = direct_cpu / chosen.size
    return {
        "n_modes": n_modes, "cells": cells, "attractors": int(dataset.attractor.size),
        "contacts_per_orbit": dataset.attractor_contacts.values.tolist(),
        "settle_periods": {"min": int(dataset.settle_periods.min()),
                           "median": float(np.median(dataset.settle_periods)),
                           "max": int(dataset.settle_periods.max())},
        "basins_cpu_seconds_1_worker": cpu, "basins_cells_per_cpu_second": cells / cpu,
        "basins_wall_seconds_2_workers": wall, "basins_cells_per_second_2_workers": cells / wall,
        "direct_horizon_periods": horizon, "direct_cells_timed": int(chosen.size),
        "direct_cpu_seconds_per_cell": direct_per_cell,
        "direct_cells_per_cpu_second": 1.0 / direct_per_cell,
        "speedup_cpu": (cells / cpu) * direct_per_cell,
    }


def workers(params: Params, n_modes: int, points: int, repeats: int) -> dict:
    """The same map on 1 and on 2 worker threads, in turn ``repeats`` times: wall, CPU (s)."""
    basins(params, axes(3), n_modes=n_modes, workers=2)  # compiles
    runs: dict[str, list[float]] = {key: [] for key in (
        "load_1min", "wall_1_worker", "cpu_1_worker", "wall_2_workers", "cpu_2_workers")}
    for _ in range(repeats):
        runs["load_1min"].append(os.getloadavg()[0])
        for count, name in ((1, "1_worker"), (2, "2_workers")):
            wall, cpu = time.perf_counter(), time.process_time()
            basins(params, axes(points), n_modes=n_modes, workers=count)
            runs[f"cpu_{name}"].append(time.process_time() - cpu)
            runs[f"wall_{name}"].append(time.perf_counter() - wall)
    ratios = [one / two for one, two in zip(runs["wall_1_worker"], runs["wall_2_workers"],
                                            strict=True)]
    return {"n_modes": n_modes, "cells": points ** 2, **runs, "wall_ratio_1_to_2": ratios}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--points", type=int, default=21)
    parser.add_argument("--stride", type=int, default=7)
    parser.add_argument("--ratio-points", type=int, default=81)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path(__file__).parents[1] / "docs"
                        / "benchmarks")
    args = parser.parse_args()
    report = {"version": __version__, "date": time.strftime("%Y-%m-%d %H:%M"),
              "machine": f"{platform.machine()}, Python {platform.python_version()}",
              "case": "a cantilever against a stop, zeta = 0.02, F0 = 0.1 mN, Omega = 300 "
                      "rad/s; CPU times on one thread, wall time on 2 worker threads"}
    for name, (params, shrink) in CASES.items():
        points = args.points if shrink == 1 else args.points // 2 + 1
        report[name] = measure(params, required_modes(params), points,
                               max(1, args.stride // shrink))
    report["workers"] = workers(SOFT, required_modes(SOFT), args.ratio_points, args.repeats)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "basins.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
