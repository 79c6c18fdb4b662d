"""Make the paper-like figures: simulate, save each Dataset, then plot from the saved files.

    python scripts/make_figures.py [--data build/figure_data] [--out docs/figures] [--replot]

Fig. 2: deflection surfaces (F0 = 5e-4 N, Omega = 40 rad/s, 0 < t < 0.07 s); Fig. 3: tips,
restitution and impact force (F0 = 1e-3 N, Omega = 50 rad/s, 0 <= t <= 0.6 s); Fig. 4:
trajectories from uplift1 = 0 and 1e-6 m over 3 s; a phase plane and a Poincare section (once per
forcing period over 60 s). ``--replot`` only redraws from the saved Datasets.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import xarray as xr

from impactbeams.params import Params
from impactbeams.plotting import trajectories as plots
from impactbeams.trajectory import simulate

PAPER = Params()  # F0 = 1e-3 N, Omega = 50 rad/s, Delta = 1.1e-5 m, l1 = 0.1, l2 = 0.12
SECTION_PERIODS = 480  # 60 s of forcing at Omega = 50 rad/s


def _runs() -> dict[str, dict]:
    """Name -> simulate() arguments of every saved Dataset."""
    period = 2 * math.pi / PAPER.omega
    return {
        "fig2": dict(params=PAPER.replace(force_amplitude=5e-4, omega=40.0), t_max=0.07,
                     dt_output=1e-4, fields=True),
        "fig3": dict(params=PAPER, t_max=0.6, dt_output=2e-5),
        "fig4_a": dict(params=PAPER, t_max=3.0, dt_output=1e-4),
        "fig4_b": dict(params=PAPER.replace(uplift1=1e-6), t_max=3.0, dt_output=1e-4),
        "phase_plane": dict(params=PAPER, t_max=2.0, times=np.linspace(1.0, 2.0, 50_001)),
        "poincare": dict(params=PAPER, t_max=SECTION_PERIODS * period,
                         times=np.arange(1, SECTION_PERIODS + 1) * period * (1 - 1e-15)),
    }


def compute(data: Path) -> None:
    """Simulate every run and write it to ``data/<name>.nc``."""
    data.mkdir(parents=True, exist_ok=True)
    for name, arguments in _runs().items():
        dataset = simulate(**arguments)
        dataset.to_netcdf(data / f"{name}.nc")
        print(f"{name}: {dataset.impact.size} impacts, status {dataset.attrs['status']}")


def draw(data: Path, out: Path) -> None:
    """Draw every figure from the saved Datasets into ``out``."""
    out.mkdir(parents=True, exist_ok=True)

    def load(name: str) -> xr.Dataset:
        with xr.open_dataset(data / f"{name}.nc") as dataset:
            return dataset.load()

    plots.plot_surfaces(load("fig2"), out / "fig2_surfaces.png")
    plots.plot_paper_fig3(load("fig3"), out / "fig3_tips_restitution_force.png")
    plots.plot_run(load("fig3"), out / "fig3_run.png")
    plots.plot_divergence([load("fig4_a"), load("fig4_b")],
                          ["uplift1 = 0", "uplift1 = 1e-6 m"], out / "fig4_divergence.png")
    plots.plot_phase_portrait(load("phase_plane"), load("poincare"),
                              out / "phase_plane_poincare.png")
    print(f"figures in {out}")


def main() -> None:
    """Parse the options, compute (unless --replot) and draw."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("build/figure_data"))
    parser.add_argument("--out", type=Path, default=Path("docs/figures"))
    parser.add_argument("--replot", action="store_true", help="only redraw from saved data")
    args = parser.parse_args()
    if not args.replot:
        compute(args.data)
    draw(args.data, args.out)


if __name__ == "__main__":
    main()
