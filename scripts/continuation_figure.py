"""The frequency-response figure of docs/continuation.md and the numbers the page quotes.

    python scripts/continuation_figure.py

Continues the shipped sweeps/continuation-stop-fold.toml (`impactbeams continue`), runs a
brute-force bifurcation diagram from rest over the same frequencies (5 modes, 300 transient
periods, 20 samples per Omega), and draws the branch over it with `impactbeams plot --over`:
docs/figures/continuation-stop-fold.png. Writes the located bifurcations, the branch's size and
its time per point to docs/figures/continuation-stop-fold.json, with the date and the machine's
load (the timings are wall-clock, inflated by other work on the machine). The results go to
results/ (the branch and the diagram as netCDF).
"""

from __future__ import annotations

import json
import os
import time
from datetime import date
from pathlib import Path

import numpy as np

from impactbeams.cli import main
from impactbeams.continuation import load_continuation
from impactbeams.io import write_text
from impactbeams.plotting import plot_dataset
from impactbeams.preflight import read_netcdf
from impactbeams.sweep import run_sweep
from impactbeams.sweep.definition import sweep_from_mapping
from impactbeams.variables import BIFURCATIONS

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "sweeps" / "continuation-stop-fold.toml"
FIGURE = ROOT / "docs" / "figures" / "continuation-stop-fold.png"
RESULTS = ROOT / "docs" / "figures" / "continuation-stop-fold.json"
BRANCH = ROOT / "results" / "continuation-stop-fold.nc"
DIAGRAM = ROOT / "results" / "continuation-stop-fold-diagram.nc"


def diagram_sweep():
    """A long-time sweep from rest over the continuation's range and parameters."""
    continuation = load_continuation(EXAMPLE)
    fixed = {key: value for key, value in continuation.params.as_dict().items()
             if key in ("counterpart", "contact_stiffness", "damping_ratio", "force_amplitude")}
    return sweep_from_mapping({
        "n_modes": 5, "observables": ["poincare_deflection1", "response_period"],
        "transient_periods": 300, "sampled_periods": 20, "params": fixed,
        "axes": {"omega": {"min": continuation.low, "max": continuation.high, "num": 151}}},
        source="the diagram of scripts/continuation_figure.py")


def main_figure() -> None:
    """Continue, sweep, draw, write the numbers."""
    start = time.perf_counter()
    assert main(["continue", str(EXAMPLE), "-o", str(BRANCH), "--quiet"]) == 0
    seconds = time.perf_counter() - start
    run_sweep(diagram_sweep(), DIAGRAM)
    with read_netcdf(BRANCH, "branch") as branch, read_netcdf(DIAGRAM, "diagram") as diagram:
        plot_dataset(branch, FIGURE, diagram=diagram)
        codes = branch.bifurcation.values
        located = [{"label": BIFURCATIONS[code], "omega": float(branch.omega[i]),
                    "contacts_after": int(branch.contacts_per_orbit[min(i + 1, codes.size - 1)])}
                   for i, code in enumerate(codes) if code]
        report = {"date": date.today().isoformat(), "load_average": os.getloadavg()[0],
                  "points": int(branch.branch_point.size), "seconds": seconds,
                  "seconds_per_point": seconds / int(branch.branch_point.size),
                  "n_modes": int(branch.attrs["n_modes"]), "located": located,
                  "largest_amplitude": float(np.max(branch.tip_amplitude_1))}
    write_text(RESULTS, json.dumps(report, indent=1) + "\n")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main_figure()
