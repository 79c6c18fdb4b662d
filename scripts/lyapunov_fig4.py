"""The paper's Fig. 4 case answered with a number: its largest Lyapunov exponent.

    python scripts/lyapunov_fig4.py [--horizon 40] [--out docs/figures/lyapunov_fig4.json]

The paper's parameters (F0 = 1 mN, Omega = 50 rad/s, Delta = 1.1e-5 m, no damping) with the
default spring law (Hertz k = 4.3e5 N/m) at the resolution rule's 4 n* = 32 modes per beam
(``recommended_modes``) and at 8 n* = 64. Finite-time exponents over two windows: the paper's
Fig. 4 horizon (0.5-3 s) and 5 s to ``--horizon``; and the exponent in consecutive 2-s batches
of the long window (the undamped beams keep absorbing energy from the force, so the exponent is
not stationary: see docs/lyapunov.md, made with ``--horizon 80``). Prints a table and writes
the numbers as JSON, with the horizon and the date: the results file that README.md and
docs/lyapunov.md quote (scripts/update_readme.py reads it). About 4 minutes on one core with
``--horizon 80`` (the 64-mode run dominates).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from datetime import date
from pathlib import Path

from impactbeams.compliant import recommended_modes
from impactbeams.kernels.tangent import recorded_run_sums
from impactbeams.packing import pack_run
from impactbeams.params import Params
from impactbeams.trajectory import run
from impactbeams.trajectory.lyapunov import lyapunov_exponents

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "docs" / "figures" / "lyapunov_fig4.json"
PAPER = Params()
PERIOD = 2 * math.pi / PAPER.omega
WINDOWS = {"fig4": (3.0, 4), "long": (None, 40)}  # (t_max or --horizon, transient periods)


def window_exponents(n_modes: int, t_max: float, transient: int) -> dict:
    """The largest exponent of one run over the complete periods after ``transient``."""
    start = time.perf_counter()
    packed = pack_run(PAPER, n_modes, t_max, t_max)
    trajectory = run(packed, 10**8)
    result = lyapunov_exponents(packed, trajectory, 1, transient)
    return {"n_modes": n_modes, "t_start": transient * PERIOD, "t_end": t_max,
            "exponent": float(result.values[0]), "error": float(result.errors[0]),
            "phases": int(trajectory.time.size), "seconds": time.perf_counter() - start}


def batch_exponents(n_modes: int, t_max: float, batch: float) -> list[float]:
    """The exponent over consecutive windows of about ``batch`` s from t = 0 (one run)."""
    packed = pack_run(PAPER, n_modes, t_max, t_max)
    trajectory = run(packed, 10**8)
    sums, counts, interval = recorded_run_sums(
        packed.tables, packed.phase_scalars, packed.switching, packed.settings,
        trajectory.segments, trajectory.t_end, 1, 0, max(1, round(t_max / batch)))
    return [float(value) for value in sums[:, 0] / (counts * interval)]


def main() -> None:
    """Compute, print and save the exponents."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizon", type=float, default=40.0, help="end of the long window (s)")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    base = recommended_modes(PAPER)
    rows = []
    for name, (t_max, transient) in WINDOWS.items():
        for n_modes in (base, 2 * base):
            row = {"window": name, **window_exponents(n_modes, t_max or args.horizon, transient)}
            rows.append(row)
            print(f"{name:5s} n_modes {n_modes:3d}  {row['t_start']:.2f}-{row['t_end']:.1f} s: "
                  f"{row['exponent']:.1f} +- {row['error']:.1f} 1/s  ({row['phases']} phases, "
                  f"{row['seconds']:.0f} s)", flush=True)
    batches = batch_exponents(base, args.horizon, 2.0)
    print("2-s batches at", base, "modes:", " ".join(f"{b:.0f}" for b in batches))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"horizon_s": args.horizon, "windows": rows,
                                    "batches_2s": batches, "date": f"{date.today()}"},
                                   indent=1) + "\n")


if __name__ == "__main__":
    main()
