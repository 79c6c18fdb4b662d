"""Scaling of the first-impact map: run time against grid size, t_max, modes and threads.

Every run is the public :func:`impactbeams.sweep.run_sweep` on the Fig. 5a ranges (Omega
10..400 rad/s, F0 1e-6..1e-3 N log, clearance 1.1e-5 m), after a warm-up call, best of
``repeats``. Compile time is measured apart, in fresh processes: once with an empty Numba cache
(cold: compilation) and once with the cache that run filled (warm: loading).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_sweep import first_call_seconds  # noqa: E402
from impactbeams.sweep import run_sweep, sweep_from_mapping  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@dataclasses.dataclass(frozen=True)
class ScalingConfig:
    """Sizes of the scaling study; see QUICK and FULL."""

    cells: tuple[int, ...] = (100, 1_000, 10_000, 100_000, 1_000_000)
    t_max: tuple[float, ...] = (0.1, 0.3, 1.0, 3.0, 10.0)
    n_modes: tuple[int, ...] = (1, 2, 5, 10, 20, 50, 100)
    side_cells: int = 10_000  # grid size of the t_max and n_modes series
    thread_cells: int = 1_000_000
    default_t_max: float = 1.0
    default_modes: int = 5
    repeats: int = 3


QUICK = ScalingConfig(cells=(100, 1_000, 10_000), t_max=(0.1, 0.3, 1.0, 3.0),
                      n_modes=(1, 5, 20, 50), side_cells=1_000, thread_cells=10_000, repeats=2)


def fig5a_sweep(cells: int, t_max: float, n_modes: int):
    """A square Fig. 5a grid of about ``cells`` cells."""
    side = max(1, round(math.sqrt(cells)))
    return sweep_from_mapping({
        "t_max": t_max, "n_modes": n_modes, "params": {"clearance": 1.1e-5},
        "axes": {"omega": {"min": 10.0, "max": 400.0, "num": side},
                 "force_amplitude": {"min": 1e-6, "max": 1e-3, "num": side, "scale": "log"}}},
        source="scaling grid")


def measure(sweep, threads: int, repeats: int) -> tuple[float, np.ndarray]:
    """Best wall time (s) of ``run_sweep`` over ``repeats`` runs, and the map."""
    run_sweep(sweep, threads=threads, progress=False)  # warm-up: kernels, modes
    best, values = math.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        values = run_sweep(sweep, threads=threads, progress=False).first_impact_time.values
        best = min(best, time.perf_counter() - start)
    return best, values


def _row(sweep, threads: int, repeats: int, **keys) -> dict:
    seconds, values = measure(sweep, threads, repeats)
    return {**keys, "cells": sweep.size, "threads": threads, "seconds": seconds,
            "cells_per_second": sweep.size / seconds,
            "impacted_fraction": float(np.isfinite(values).mean())}


def compile_times(sweep_path: str) -> dict[str, float]:
    """First kernel call in a fresh process: empty Numba cache (cold), then filled (warm)."""
    with tempfile.TemporaryDirectory() as cache:
        cold = first_call_seconds(sweep_path, cache)
        warm = first_call_seconds(sweep_path, cache)
    return {"cold_s": cold, "warm_cache_s": warm}


def scaling_study(cfg: ScalingConfig, log=print) -> dict:
    """All scaling series; JSON-ready."""
    threads = numba.config.NUMBA_NUM_THREADS
    d = cfg
    by_cells = [_row(fig5a_sweep(n, d.default_t_max, d.default_modes), threads, d.repeats,
                     target_cells=n) for n in d.cells]
    log("  grid-size series done")
    by_t = [_row(fig5a_sweep(d.side_cells, t, d.default_modes), threads, d.repeats, t_max=t)
            for t in d.t_max]
    log("  t_max series done")
    by_modes = [_row(fig5a_sweep(d.side_cells, d.default_t_max, n), threads, d.repeats,
                     n_modes=n) for n in d.n_modes]
    log("  n_modes series done")
    big = fig5a_sweep(d.thread_cells, d.default_t_max, d.default_modes)
    by_threads, maps = [], []
    for k in range(1, min(2, threads) + 1):
        seconds, values = measure(big, k, d.repeats)
        maps.append(values)
        by_threads.append({"threads": k, "cells": big.size, "seconds": seconds,
                           "cells_per_second": big.size / seconds})
    log("  threads series done")
    return {
        "config": dataclasses.asdict(cfg), "numba_threads": threads,
        "grid_size": by_cells, "t_max": by_t, "n_modes": by_modes, "threads": by_threads,
        "threads_bitwise_equal": all(np.array_equal(maps[0], m, equal_nan=True) for m in maps),
        "speedup_2_over_1_thread": (by_threads[0]["seconds"] / by_threads[-1]["seconds"]),
        "compile": compile_times(str(ROOT / "sweeps" / "fig5a-omega-force.toml")),
    }
