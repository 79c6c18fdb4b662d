"""Measure how impacts converge with the number of modes; write docs/modal_convergence.md.

    python scripts/modal_convergence.py [--out docs/modal_convergence.md]

The paper's Fig. 3 case (F0 = 1e-3 N, Omega = 50 rad/s, 0 <= t <= 0.6 s) with 4, 5, 10, 20 and
50 free modes per beam (twice as many contact modes).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import xarray as xr

from impactbeams.params import Params
from impactbeams.trajectory import simulate

MODES = (4, 5, 10, 20, 50)
T_MAX = 0.6


def _row(n_modes: int) -> dict[str, float]:
    start = time.perf_counter()
    ds = simulate(Params(), T_MAX, n_modes=n_modes, dt_output=1e-3)
    elapsed = time.perf_counter() - start
    first = ds.isel(impact=0)
    second_cycle = ds.impact_onset_time.where(ds.impact_onset_time > 0.1).min()
    kinetic = float(first.impact_kinetic_energy_loss)
    before = kinetic + _kinetic_after_first_onset(ds)
    return {
        "modes": n_modes,
        "first onset (s)": float(first.impact_onset_time),
        "first closing speed (m/s)": -float(first.impact_velocity),
        "KE kept at 1st onset": 1 - kinetic / before,
        "first duration (ms)": 1e3 * float(first.impact_duration),
        "first peak force (mN)": 1e3 * float(first.impact_peak_force),
        "first impulse (uN s)": 1e6 * float(first.impact_impulse),
        "first restitution": float(first.restitution_coefficient),
        "first onset after 0.1 s (s)": float(second_cycle),
        "impacts in 0.6 s": ds.impact.size,
        "median restitution": float(ds.restitution_coefficient.median()),
        "largest force (mN)": 1e3 * float(ds.impact_peak_force.max()),
        "run time (s)": elapsed,
    }


def _kinetic_after_first_onset(ds: xr.Dataset) -> float:
    """Kinetic energy just after the first onset (J), from a sample at the onset time."""
    onset = float(ds.impact_onset_time[0])
    params = Params(**{k: ds.attrs[k] for k in Params().as_dict()})
    after = simulate(params, onset, n_modes=int(ds.attrs["n_modes"]), times=np.array([onset]))
    return float(after.kinetic_energy[0])


def _table(rows: list[dict[str, float]]) -> str:
    keys = [k for k in rows[0] if k != "modes"]
    lines = ["| quantity | " + " | ".join(f"{r['modes']} modes" for r in rows) + " |",
             "|---|" + "---|" * len(rows)]
    for key in keys:
        cells = []
        for row in rows:
            value = row[key]
            precise = "onset" in key or "speed" in key
            cells.append(f"{value:d}" if isinstance(value, int) else f"{value:.10g}"
                         if precise else f"{value:.4g}")
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    """Run every mode count and write the Markdown report."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path("docs/modal_convergence.md"))
    args = parser.parse_args()
    simulate(Params(), 0.01)  # compile the kernels before timing
    rows = [_row(n) for n in MODES]
    reference = rows[-1]
    onset_gap = {r["modes"]: abs(r["first onset (s)"] - reference["first onset (s)"])
                 for r in rows[:-1]}
    speed_gap = {r["modes"]: abs(r["first closing speed (m/s)"]
                                 / reference["first closing speed (m/s)"] - 1) for r in rows[:-1]}
    text = f"""# Modal convergence of the impact dynamics

Produced by `python scripts/modal_convergence.py`: the paper's Fig. 3 case (F0 = 1e-3 N,
Omega = 50 rad/s, Delta = 1.1e-5 m, l1 = 0.1 m, l2 = 0.12 m, 0 <= t <= {T_MAX} s), with n free
modes per beam and 2n contact modes. "KE kept" is the kinetic energy just after the first
onset projection over the kinetic energy just before it. Run times include the output grid
(1 ms) and the per-impact table.

{_table(rows)}

## Reading

* The first impact time and closing speed come from the free phase only and converge fast.
  Distance of the first onset time from the 50-mode value:
  {", ".join(f"n = {n}: {d:.1e} s" for n, d in onset_gap.items())}; relative distance of
  the closing speed: {", ".join(f"n = {n}: {d:.1e}" for n, d in speed_gap.items())}.
  (The tests check the first impact against the finite-element reference to 2e-10 s.)
* Everything that happens at or after the first onset does not converge: the onset projection
  keeps more kinetic energy as modes are added ([the model](model.md#switching): the loss
  of the truncated modal model shrinks with N), contacts get shorter, impacts more numerous,
  and the contact force and coefficient of restitution change with n. This is the "modal
  non-convergence" of Szalai (2014) and Melcher, Champneys & Wagg (2013).
* The paper states that the solutions with 4 and 5 modes are "almost identical". Measured
  here, 4 and 5 modes agree on the first impact time to
  {abs(rows[0]["first onset (s)"] - rows[1]["first onset (s)"]):.1e} s but not on the impact
  sequence: the number of impacts, the contact durations, the peak forces and the
  restitution coefficients already differ between 4 and 5 modes, and far more at 10, 20 and
  50 modes. The slow motion (the tip histories between impact clusters, the onset of each
  cluster) is much less sensitive: see "first onset after 0.1 s".
* The coefficient of restitution is measured in the free basis just after the release, where
  the exact model has zero relative tip velocity: it is a truncation quantity.
"""
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
