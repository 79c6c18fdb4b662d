"""Plots of simulated trajectories (Datasets from :func:`impactbeams.trajectory.simulate`).

Everything here reads saved Datasets; nothing is computed but unit scaling and selections.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

_MICRO = 1e6  # m -> um
_MILLI = 1e3  # N -> mN, s -> ms


def _title(dataset: xr.Dataset) -> str:
    a = dataset.attrs
    return (f"F0 = {a.get('force_amplitude', np.nan):g} N, Omega = {a.get('omega', np.nan):g} "
            f"rad/s, Delta = {a.get('clearance', np.nan):g} m, {a.get('n_modes', '?')} modes")


def _save(figure: Figure, path: str | Path) -> None:
    figure.savefig(path, dpi=150)


def plot_tips(axis: Axes, dataset: xr.Dataset) -> None:
    """Tip deflections y1(l1) and y2(l2) - Delta (um) against time (s), as the paper's Fig. 3a."""
    t = dataset.time.values
    axis.plot(t, dataset.tip_deflection_1 * _MICRO, lw=0.7, label="y1(l1)")
    axis.plot(t, dataset.tip_deflection_2 * _MICRO, lw=0.7, label="y2(l2) - Delta")
    axis.set_ylabel("tip deflection (um)")
    axis.legend(loc="upper right", fontsize="small")


def plot_run(dataset: xr.Dataset, path: str | Path) -> None:
    """Tips, contact force, restitution per impact and energy of one run, into ``path``."""
    figure = Figure(figsize=(8, 10), layout="constrained")
    axes = figure.subplots(4, 1, sharex=True)
    t = dataset.time.values
    plot_tips(axes[0], dataset)
    axes[1].plot(t, dataset.contact_force * _MILLI, lw=0.7, color="C3")
    axes[1].set_ylabel("contact force R (mN)")
    onset = dataset.impact_onset_time.values
    axes[2].plot(onset, dataset.restitution_coefficient, ".", ms=3, color="C2")
    axes[2].axhline(0.0, color="0.6", lw=0.5)
    axes[2].set_ylabel("restitution e")
    energy0 = float(dataset.energy[0])
    axes[3].plot(t, (dataset.energy - energy0) * 1e9, lw=0.7, label="E(t) - E(0)")
    if "work_of_force" in dataset:
        axes[3].plot(t, dataset.work_of_force * 1e9, lw=0.7, label="work of F")
    axes[3].set_ylabel("energy (nJ)")
    axes[3].set_xlabel("time t (s)")
    axes[3].legend(loc="upper left", fontsize="small")
    axes[0].set_title(f"{_title(dataset)}; status {dataset.attrs.get('status', '?')}")
    _save(figure, path)


def plot_surfaces(dataset: xr.Dataset, path: str | Path) -> None:
    """Deflection surfaces y_i(x_i, t) of both beams (the paper's Fig. 2); needs the fields."""
    figure = Figure(figsize=(11, 4.5), layout="constrained")
    for i, beam in enumerate(("1", "2")):
        axis = figure.add_subplot(1, 2, i + 1, projection="3d")
        field = dataset["deflection_" + beam]
        x, t = np.meshgrid(dataset["x" + beam].values, dataset.time.values)
        axis.plot_surface(x, t, field.values * _MICRO, cmap="viridis", linewidth=0,
                          rstride=max(1, t.shape[0] // 200), cstride=1)
        axis.set_xlabel(f"x{beam} (m)")
        axis.set_ylabel("t (s)")
        axis.set_zlabel(f"y{beam} (um)")
        axis.set_title(f"({'ab'[i]}) beam {beam}")
    figure.suptitle(_title(dataset))
    _save(figure, path)


def plot_paper_fig3(dataset: xr.Dataset, path: str | Path) -> None:
    """Tips (a), coefficient of restitution (b) and impact force (c), as the paper's Fig. 3."""
    figure = Figure(figsize=(8, 8), layout="constrained")
    axes = figure.subplots(3, 1)
    plot_tips(axes[0], dataset)
    axes[0].set_xlabel("t (s)")
    released = np.isfinite(dataset.restitution_coefficient.values)
    axes[1].plot(dataset.impact_onset_time.values[released],
                 dataset.restitution_coefficient.values[released], ".", ms=4, color="C2")
    axes[1].set_ylabel("restitution e")
    axes[1].set_xlabel("impact onset time (s)")
    axes[2].plot(dataset.time, dataset.contact_force * _MILLI, lw=0.7, color="C3")
    axes[2].set_ylabel("impact force R (mN)")
    axes[2].set_xlabel("t (s)")
    for axis, label in zip(axes, "abc", strict=True):
        axis.set_title(f"({label})", loc="left")
    figure.suptitle(_title(dataset))
    _save(figure, path)


def plot_divergence(datasets: Sequence[xr.Dataset], labels: Sequence[str],
                    path: str | Path) -> None:
    """Tips of nearby trajectories on common axes (the paper's Fig. 4), and their distance."""
    figure = Figure(figsize=(8, 8), layout="constrained")
    axes = figure.subplots(3, 1, sharex=True)
    for dataset, label in zip(datasets, labels, strict=True):
        axes[0].plot(dataset.time, dataset.tip_deflection_1 * _MICRO, lw=0.6, label=label)
        axes[1].plot(dataset.time, dataset.tip_deflection_2 * _MICRO, lw=0.6, label=label)
    distance = np.abs(datasets[0].tip_deflection_1.values - datasets[1].tip_deflection_1.values)
    axes[2].semilogy(datasets[0].time, np.maximum(distance * _MICRO, 1e-12), lw=0.6)
    axes[0].set_ylabel("(a) y1(l1) (um)")
    axes[1].set_ylabel("(b) y2(l2) - Delta (um)")
    axes[2].set_ylabel("|difference of y1(l1)| (um)")
    axes[2].set_xlabel("t (s)")
    axes[0].legend(fontsize="small", loc="upper right")
    figure.suptitle(_title(datasets[0]))
    _save(figure, path)


def plot_phase_portrait(dense: xr.Dataset, section: xr.Dataset, path: str | Path) -> None:
    """Phase plane (tip 1 velocity against deflection) and a Poincare section.

    ``section`` must be sampled once per forcing period (its ``time`` a multiple of 2 pi/Omega).
    """
    figure = Figure(figsize=(11, 4.8), layout="constrained")
    axes = figure.subplots(1, 2)
    axes[0].plot(dense.tip_deflection_1 * _MICRO, dense.tip_velocity_1 * _MILLI, lw=0.3)
    axes[0].set_title(f"phase plane, {float(dense.time[0]):g} s <= t <= "
                      f"{float(dense.time[-1]):g} s")
    axes[1].plot(section.tip_deflection_1 * _MICRO, section.tip_velocity_1 * _MILLI, ".",
                 ms=2)
    axes[1].set_title(f"Poincare section: {section.time.size} forcing periods")
    for axis in axes:
        axis.set_xlabel("y1(l1) (um)")
        axis.set_ylabel("dy1(l1)/dt (mm/s)")
    figure.suptitle(_title(section))
    _save(figure, path)
