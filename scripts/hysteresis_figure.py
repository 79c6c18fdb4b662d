"""The hysteresis figure of docs/continuation.md: the branch against stepped-sine sweeps.

    python scripts/hysteresis_figure.py

Continues the shipped sweeps/continuation-stop-fold.toml (150..450 rad/s, as
`impactbeams continue`) and runs a stepped-sine sweep up and down over the same range with the
same fixed parameters (5 modes, 2.5 rad/s steps, 300 periods of dwell, the grid of
tests/test_hysteresis.py extended), then draws the branch's y1 on the section (stable solid,
unstable dashed, folds and grazings labelled) with the sweeps' samples over it, around the
folds:
docs/figures/hysteresis-stop-fold.png. Writes the folds, the band where the sweeps differ
(`impactbeams.longtime.hysteresis`) and the cells between which each sweep jumps to
docs/figures/hysteresis-stop-fold.json, with the date and the run's wall-clock time.
"""

from __future__ import annotations

import json
import os
import time
from datetime import date
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from impactbeams.continuation import continue_orbits, load_continuation
from impactbeams.io import write_text
from impactbeams.longtime import hysteresis
from impactbeams.plotting.branches import branch_units, draw_branches
from impactbeams.plotting.files import save_figure
from impactbeams.plotting.labels import case_title
from impactbeams.sweep import run_sweep, sweep_from_mapping
from impactbeams.variables import BIFURCATIONS

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "sweeps" / "continuation-stop-fold.toml"
FIGURE = ROOT / "docs" / "figures" / "hysteresis-stop-fold.png"
RESULTS = ROOT / "docs" / "figures" / "hysteresis-stop-fold.json"
STEP = 2.5  # rad/s: cells 2 rad/s or more past each fold (tests/test_hysteresis.py says why)
DWELL = 300
SWEEPS = {"up": ("^", "C3", 6), "down": ("v", "C2", 4)}  # marker, colour, size
VIEW = (260.0, 340.0)  # rad/s: the folds; below, the response is linear up to the grazing
MEASURE = "section_deflection_1"  # y1 on the section: what the sweeps sample


def stepped_sweep(continuation):
    """Up and down over the continuation's range, its fixed parameters, STEP apart."""
    params = continuation.params.as_dict()
    return sweep_from_mapping({
        "n_modes": 5, "transient_periods": DWELL, "sampled_periods": 2, "stepping": "both",
        "observables": ["poincare_deflection1", "poincare_velocity1"],
        "params": {key: params[key] for key in ("counterpart", "contact_stiffness",
                                                "damping_ratio", "force_amplitude")},
        "axes": {"omega": {"min": continuation.low, "max": continuation.high,
                           "num": round((continuation.high - continuation.low) / STEP) + 1}}},
        source="the stepped sweep of scripts/hysteresis_figure.py")


def draw(branch, stepped) -> None:
    """The branch's section deflection, the sweeps' samples over it (one marker per cell)."""
    figure = Figure(figsize=(7, 5), layout="constrained")
    axes = figure.add_subplot()
    (x_factor, _), (y_factor, _) = branch_units(branch, MEASURE)
    for direction, (marker, colour, size) in SWEEPS.items():
        row = stepped.sel(sweep_direction=direction)
        axes.plot(x_factor * row.omega, y_factor * row.poincare_deflection1.isel(period=-1),
                  marker, color=colour, markersize=size, markerfacecolor="none",
                  linestyle="none", label=f"stepped sweep {direction}")
    axes.set_xlim(x_factor * VIEW[0], x_factor * VIEW[1])
    axes.set_title(case_title(branch, MEASURE, ("branch_point",)), loc="left",
                   fontsize="medium", wrap=True)
    draw_branches(axes, branch, MEASURE)  # last: it places the event labels
    save_figure(figure, FIGURE)


def jumps(stepped) -> dict:
    """Where the rows differ, and the cells each sweep jumps between.

    The up sweep jumps after the band's last cell, the down sweep before its first.
    """
    omega = stepped.omega.values
    band = np.flatnonzero(hysteresis(stepped).values)
    return {"band": [float(omega[band[0]]), float(omega[band[-1]])],
            "up_jump": [float(omega[band[-1]]), float(omega[band[-1] + 1])],
            "down_jump": [float(omega[band[0]]), float(omega[band[0] - 1])]}


def main() -> None:
    """Continue, sweep, draw, write the numbers."""
    continuation = load_continuation(EXAMPLE)
    start = time.perf_counter()
    branch = continue_orbits(continuation)
    stepped = run_sweep(stepped_sweep(continuation))
    seconds = time.perf_counter() - start
    draw(branch, stepped)
    folds = branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index("fold")]
    report = {"date": date.today().isoformat(), "load_average": os.getloadavg()[0],
              "seconds": seconds, "step": STEP, "dwell_periods": DWELL,
              "cells": int(stepped.omega.size), "folds": sorted(float(f) for f in folds),
              **jumps(stepped)}
    write_text(RESULTS, json.dumps(report, indent=1) + "\n")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
