"""Make the paper-like figures: simulate, save each Dataset, then plot from the saved files.

    python scripts/make_figures.py [--data build/figure_data] [--out docs/figures] [--replot]

Every figure shows the paper's tied law (at the paper's 5 modes per beam) beside the default
spring law (Hertz k = 4.3e5 N/m, at the n_modes that resolves it, ``recommended_modes``: 32).
Fig. 2: deflection surfaces (F0 = 5e-4 N, Omega = 40 rad/s, 0 < t < 0.07 s); Fig. 3: tips,
restitution and impact force (F0 = 1e-3 N, Omega = 50 rad/s, 0 <= t <= 0.6 s), and the spring
run's energy (fig3_run); Fig. 4: trajectories from uplift1 = 0 and 1e-6 m over 3 s (the
paper's), and the distance to one from uplift1 = 1e-12 m; a phase plane and a Poincare section
(once per forcing period over 60 s). ``--replot`` only redraws from the saved Datasets. About
1.5 minutes on one core.

The numbers the README quotes about Fig. 4 are written with the figures, from the same saved
Datasets, into ``fig4.json`` (dated; read by scripts/update_readme.py): the distance between
the tips of beam 1 from uplift1 = 0 and 1e-6 m over the first 0.1 s and over the 3 s, the tip's
amplitude, and the distance from uplift1 = 1e-12 m at the end of the first impact episode.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from datetime import date
from pathlib import Path

import numpy as np
import xarray as xr

from impactbeams.compliant import recommended_modes
from impactbeams.params import Params
from impactbeams.plotting import trajectories as plots
from impactbeams.trajectory import simulate

PAPER = Params()  # F0 = 1e-3 N, Omega = 50 rad/s, Delta = 1.1e-5 m, l1 = 0.1, l2 = 0.12
LAWS = {  # name -> (parameters, n_modes)
    "tied": (PAPER.replace(contact_law="tied"), 5),  # the paper's law and mode count
    "spring": (PAPER.replace(contact_law="spring"), recommended_modes(PAPER)),  # Hertz k
}
SECTION_PERIODS = 480  # 60 s of forcing at Omega = 50 rad/s


def _runs() -> dict[str, dict]:
    """Name -> simulate() arguments of every saved Dataset (``<figure>_<law>``)."""
    period = 2 * math.pi / PAPER.omega
    runs = {}
    for law, (params, n_modes) in LAWS.items():
        common = dict(n_modes=n_modes, energy_balance=False)
        runs |= {
            f"fig2_{law}": dict(params=params.replace(force_amplitude=5e-4, omega=40.0),
                                t_max=0.07, dt_output=1e-4, fields=True, **common),
            f"fig3_{law}": dict(params=params, t_max=0.6, dt_output=2e-5, n_modes=n_modes,
                                energy_balance=law == "spring"),  # fig3_run: work of F
            f"fig4_a_{law}": dict(params=params, t_max=3.0, dt_output=1e-4, **common),
            f"fig4_b_{law}": dict(params=params.replace(uplift1=1e-6), t_max=3.0,
                                  dt_output=1e-4, **common),
            f"fig4_c_{law}": dict(params=params.replace(uplift1=1e-12), t_max=3.0,
                                  dt_output=1e-4, **common),
            f"phase_plane_{law}": dict(params=params, t_max=2.0,
                                       times=np.linspace(1.0, 2.0, 50_001), **common),
            f"poincare_{law}": dict(params=params, t_max=SECTION_PERIODS * period,
                                    times=np.arange(1, SECTION_PERIODS + 1) * period
                                    * (1 - 1e-15), **common),
        }
    return runs


def compute(data: Path) -> None:
    """Simulate every run and write it to ``data/<name>.nc``."""
    data.mkdir(parents=True, exist_ok=True)
    for name, arguments in _runs().items():
        start = time.perf_counter()
        dataset = simulate(**arguments)
        dataset.to_netcdf(data / f"{name}.nc")
        print(f"{name}: {dataset.impact.size} contacts, {dataset.episode.size} episodes, "
              f"status {dataset.attrs['status']}, {time.perf_counter() - start:.1f} s",
              flush=True)


def draw(data: Path, out: Path) -> None:
    """Draw every figure from the saved Datasets into ``out``."""
    out.mkdir(parents=True, exist_ok=True)

    def load(name: str) -> list[xr.Dataset]:
        datasets = []
        for law in LAWS:
            with xr.open_dataset(data / f"{name}_{law}.nc") as dataset:
                datasets.append(dataset.load())
        return datasets

    plots.plot_surfaces_laws(load("fig2"), out / "fig2_surfaces.png")
    fig3 = load("fig3")
    plots.plot_paper_fig3_laws(fig3, out / "fig3_tips_restitution_force.png")
    plots.plot_run(fig3[list(LAWS).index("spring")], out / "fig3_run.png")
    plots.plot_divergence_laws(list(zip(load("fig4_a"), load("fig4_b"), load("fig4_c"),
                                        strict=True)),
                               ["uplift1 = 0", "uplift1 = 1e-6 m", "uplift1 = 1e-12 m"],
                               out / "fig4_divergence.png")
    plots.plot_phase_portrait_laws(load("phase_plane"), load("poincare"),
                                   out / "phase_plane_poincare.png")
    summary = {law: fig4_distances(*runs) for law, runs in
               zip(LAWS, zip(load("fig4_a"), load("fig4_b"), load("fig4_c"), strict=True),
                   strict=True)}
    summary["date"] = f"{date.today()}"
    (out / "fig4.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"figures and fig4.json in {out}")


def fig4_distances(base: xr.Dataset, uplift: xr.Dataset, tiny: xr.Dataset) -> dict:
    """Fig. 4's distances (m) between beam 1's tips, from uplift1 = 0, 1e-6 m and 1e-12 m."""
    tip = base.tip_deflection_1
    apart = np.abs(tip - uplift.tip_deflection_1)
    episode_end = float(base.episode_onset_time[0] + base.episode_duration[0])
    early = base.time <= 0.1
    return {
        "n_modes": int(base.attrs["n_modes"]), "t_max_s": float(base.time[-1]),
        "uplift_m": float(uplift.attrs["uplift1"]), "tiny_uplift_m": float(tiny.attrs["uplift1"]),
        "distance_max_first_0.1s_m": float(apart.where(early).max()),
        "distance_max_m": float(apart.max()),
        "distance_final_m": float(apart[-1]),
        "tip_amplitude_m": float(np.abs(tip).max()),
        "first_episode_end_s": episode_end,
        "tiny_uplift_distance_at_first_episode_end_m": float(np.abs(
            tip - tiny.tip_deflection_1).sel(time=episode_end, method="nearest")),
    }


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
