"""Plots of simulated trajectories (Datasets from [`impactbeams.trajectory.simulate`][]).

Everything here reads saved Datasets; nothing is computed but unit scaling and selections.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from impactbeams.configuration import BEAM, BELOW, LAWS, SIDES, counterpart_named
from impactbeams.plotting.arrays import PlainDataset
from impactbeams.plotting.files import save_figure
from impactbeams.plotting.labels import base_motion, quantity
from impactbeams.variables import PARAMETERS

_MICRO = 1e6  # m -> µm
_MILLI = 1e3  # N -> mN, s -> ms
_LEGEND_ROOM = 1.3  # a force panel's top over its largest peak: a row of legend above them
# the tips in mathtext, as in docs/model.md: y2 is drawn minus the clearance
_TIP1, _TIP2 = "$y_1(l_1)$", BEAM.second_tip


def _parameter(dataset: xr.Dataset, name: str) -> str:
    """``"$F_0$ = 0.001 N"``: the registry's symbol and units, numbers as on the maps."""
    return quantity(name, dataset.attrs.get(name, np.nan), PARAMETERS[name].units)


def _case(dataset: xr.Dataset) -> str:
    """Every nonzero drive (tip force, base motion and its clamps), Omega and the clearance."""
    a = dataset.attrs
    drives = [_parameter(dataset, "force_amplitude")] if a.get("force_amplitude", 0.0) else []
    if a.get("base_amplitude", 0.0):
        drives.append(base_motion(a["base_amplitude"], a))
    return ", ".join([*drives, *(_parameter(dataset, name) for name in ("omega", "clearance"))])


def _law(dataset: xr.Dataset) -> str:
    """Contact law, its stiffness and the number of modes, e.g. for a column title."""
    a = dataset.attrs
    modes = f"{a.get('n_modes', '?')} modes"
    if "contact_law" not in a:
        return modes
    law = LAWS[a["contact_law"]]
    if not law.compliant:
        return f"{law.name} law, {modes}"
    text = f"{law.name} law, {_parameter(dataset, 'contact_stiffness')}"
    if a.get("contact_damping", 0.0):
        text += f", {_parameter(dataset, 'contact_damping')}"
    resolved = a.get("contact_resolved", 1)
    return f"{text}, {modes}" + ("" if resolved else " (unresolved)")


def _title(dataset: xr.Dataset) -> str:
    against = counterpart_named(dataset.attrs.get("counterpart")).words
    return f"{_case(dataset)}{', ' + against if against else ''}\n{_law(dataset)}"


def plot_tips(axis: Axes, dataset: xr.Dataset) -> None:
    """Tip deflections y1(l1) and y2(l2) - Delta (µm) against time (s), as the paper's Fig. 3a.

    A contact elsewhere than the tips (``contact_deflection_1`` in the Dataset): beam 1's
    deflection at its contact point and, where it touches, its counterpart's there,
    y2(x2) - s Delta (s the contact's side), over beam 1's tip in grey.
    """
    t = dataset.time.values
    if "contact_deflection_1" not in dataset:
        axis.plot(t, dataset.tip_deflection_1 * _MICRO, lw=0.7, label=_TIP1)
        axis.plot(t, dataset.tip_deflection_2 * _MICRO, lw=0.7,
                  label=counterpart_named(dataset.attrs.get("counterpart")).second_tip)
        axis.set_ylabel("tip deflection (µm)")
        axis.legend(loc="upper right", fontsize="small")
        return
    clearance = float(dataset.attrs["clearance"])
    side = SIDES[dataset.attrs.get("contact_side", BELOW.name)].sign
    # against a stop, y2 is the stop's own motion: tip_deflection_2 is it minus the clearance
    other = (dataset.contact_deflection_2 if "contact_deflection_2" in dataset
             else dataset.tip_deflection_2 + clearance)
    axis.plot(t, dataset.tip_deflection_1 * _MICRO, lw=0.5, color="0.6", label=_TIP1)
    axis.plot(t, dataset.contact_deflection_1 * _MICRO, lw=0.7, color="C0",
              label=r"$y_1(x_1)$, contact point")
    axis.plot(t, (other - side * clearance) * _MICRO, lw=0.7, color="C1",
              label=r"counterpart, $y_2(x_2) - s\Delta$")
    axis.set_ylabel("deflection (µm)")
    axis.legend(loc="upper right", fontsize="small")


def plot_run(dataset: xr.Dataset, path: str | Path) -> None:
    """Tips, contact force, restitution per impact and energy of one run, into ``path``."""
    figure = Figure(figsize=(8, 10), layout="constrained")
    axes = figure.subplots(4, 1, sharex=True)
    t = dataset.time.values
    plot_tips(axes[0], dataset)
    plot_contact_force(axes[1], dataset)
    onset = dataset.impact_onset_time.values
    axes[2].plot(onset, dataset.restitution_coefficient, ".", ms=3, color="C2")
    axes[2].axhline(0.0, color="0.6", lw=0.5)
    axes[2].set_ylabel("restitution $e$")
    energy0 = float(dataset.energy[0])
    axes[3].plot(t, (dataset.energy - energy0) * 1e9, lw=0.7, label="$E(t) - E(0)$")
    if "work_of_force" in dataset:
        axes[3].plot(t, dataset.work_of_force * 1e9, lw=0.7, label="work of $F$")
    axes[3].set_ylabel("energy (nJ)")
    axes[3].set_xlabel("time $t$ (s)")
    axes[3].legend(loc="upper left", fontsize="small")
    axes[0].set_title(f"{_title(dataset)}; status {dataset.attrs.get('status', '?')}",
                      wrap=True)
    save_figure(figure, path)


def plot_contact_force(axis: Axes, dataset: xr.Dataset | PlainDataset) -> None:
    """Contact force R (mN): every contact's peak as a stem at its onset, over R(t) sampled.

    The samples alone miss most contacts (each lasts a fraction of a millisecond: the Fig. 3
    run at dt_output = 1e-4 s has 126 of its 6001 samples in one of its 682 contacts, and
    their largest force is half the largest peak); the stems are the peaks themselves
    (``impact_peak_force``, certified maxima).
    """
    axis.plot(dataset["time"].values, dataset["contact_force"].values * _MILLI, lw=0.6,
              color="C3", label="$R$ at the output times")
    peaks = dataset["impact_peak_force"].values * _MILLI
    onsets = dataset["impact_onset_time"].values
    axis.vlines(onsets, 0.0, peaks, colors="k", lw=0.4)
    axis.plot(onsets, peaks, ".", ms=2.5, color="k", label="peak of each contact")
    axis.axhline(0.0, color="0.6", lw=0.5)
    if peaks.size and peaks.max() > 0:  # room above the peaks for the legend's one row
        axis.set_ylim(top=_LEGEND_ROOM * peaks.max())
    axis.legend(loc="upper right", fontsize="small", ncols=2)
    axis.set_ylabel("contact force $R$ (mN)")


def _draw_surface(axis: Axes, dataset: xr.Dataset, beam: str, rows: int) -> None:
    """Beam ``beam``'s deflection surface, at most about ``rows`` time rows drawn."""
    field = dataset["deflection_" + beam]
    x, t = np.meshgrid(dataset["x" + beam].values, dataset.time.values)
    axis.plot_surface(x, t, field.values * _MICRO, cmap="viridis", linewidth=0,
                      rstride=max(1, t.shape[0] // rows), cstride=1)
    axis.set_xlabel(f"$x_{beam}$ (m)")
    axis.set_ylabel("$t$ (s)")
    axis.set_zlabel(f"$y_{beam}$ (µm)")


def plot_surfaces_laws(datasets: Sequence[xr.Dataset], path: str | Path,
                       dpi: float = 90) -> None:
    """Deflection surfaces of several runs (rows) for both beams (columns); need the fields."""
    figure = Figure(figsize=(10, 4.2 * len(datasets)), layout="constrained")
    for row, dataset in enumerate(datasets):
        for i, beam in enumerate(("1", "2")):
            axis = figure.add_subplot(len(datasets), 2, 2 * row + i + 1, projection="3d")
            _draw_surface(axis, dataset, beam, 100)
            axis.set_title(f"({'abcdefgh'[2 * row + i]}) beam {beam}; {_law(dataset)}",
                           fontsize="medium")
    figure.suptitle(_case(datasets[0]), wrap=True)
    save_figure(figure, path, dpi=dpi)


def _fig3_panels(axes: Sequence[Axes], dataset: xr.Dataset) -> None:
    """Fig. 3's three panels (untitled), with the episodes' restitution and the contacts' peaks."""
    plot_tips(axes[0], dataset)
    axes[0].set_xlabel("$t$ (s)")
    released = np.isfinite(dataset.restitution_coefficient.values)
    axes[1].plot(dataset.impact_onset_time.values[released],
                 dataset.restitution_coefficient.values[released], ".", ms=2, color="C2",
                 label="per contact")
    axes[1].set_ylabel("restitution $e$")
    axes[1].set_xlabel("impact onset time (s)")
    plot_contact_force(axes[2], dataset)
    axes[2].set_xlabel("$t$ (s)")
    if "episode_restitution" in dataset:
        axes[1].plot(dataset.episode_onset_time, dataset.episode_restitution, "D", ms=5,
                     color="C1", mec="k", mew=0.5, label="per episode")
        values = np.concatenate([dataset.restitution_coefficient.values,
                                 dataset.episode_restitution.values])
        values = values[np.isfinite(values)]
        if values.size and np.all(values > 0):  # spans decades: log scale
            axes[1].set_yscale("log")
        else:
            axes[1].axhline(0.0, color="0.6", lw=0.5)
        axes[1].legend(loc="best", fontsize="small")


def plot_paper_fig3_laws(datasets: Sequence[xr.Dataset], path: str | Path) -> None:
    """Fig. 3 of several runs (e.g. tied and spring law) side by side, one column each.

    Rows: the tips, the restitution of every contact and of every episode, the contact force
    (`plot_contact_force`: the peak of every contact). Panels are lettered down each column,
    (a)-(c) the first run's, (d)-(f) the second's; each column is titled with its law.
    """
    figure = Figure(figsize=(6 * len(datasets), 8.5), layout="constrained")
    axes = figure.subplots(3, len(datasets), squeeze=False)
    for row in (0, 2):  # tips and forces on common scales; restitution may differ by decades
        for axis in axes[row, 1:]:
            axis.sharey(axes[row, 0])
    for j, (column, dataset) in enumerate(zip(axes.T, datasets, strict=True)):
        _fig3_panels(column, dataset)
        for i, axis in enumerate(column):
            axis.set_title(f"({chr(ord('a') + 3 * j + i)})", loc="left")
        column[0].set_title(_law(dataset), loc="right", fontsize="medium")
    figure.suptitle(_case(datasets[0]), wrap=True)
    save_figure(figure, path)


def plot_divergence_laws(groups: Sequence[Sequence[xr.Dataset]], labels: Sequence[str],
                         path: str | Path) -> None:
    """Fig. 4 for several laws side by side: ``groups[j]`` are the nearby runs of column j.

    Tips of the first two runs of each group; distances of every other run to the first.
    """
    figure = Figure(figsize=(6 * len(groups), 8), layout="constrained")
    axes = figure.subplots(3, len(groups), sharex=True, sharey="row", squeeze=False)
    for column, datasets in zip(axes.T, groups, strict=True):
        _divergence_panels(column, datasets, labels)
        column[0].set_title(_law(datasets[0]))
    figure.suptitle(_case(groups[0][0]), wrap=True)
    save_figure(figure, path, dpi=110)


def _divergence_panels(axes: Sequence[Axes], datasets: Sequence[xr.Dataset],
                       labels: Sequence[str]) -> None:
    """Tips of the first two runs; distance of every other run's tip 1 to the first's."""
    for dataset, label in zip(datasets[:2], labels[:2], strict=True):
        axes[0].plot(dataset.time, dataset.tip_deflection_1 * _MICRO, lw=0.6, label=label)
        axes[1].plot(dataset.time, dataset.tip_deflection_2 * _MICRO, lw=0.6, label=label)
    for j, (dataset, label) in enumerate(zip(datasets[1:], labels[1:], strict=True)):
        distance = np.abs(datasets[0].tip_deflection_1.values - dataset.tip_deflection_1.values)
        axes[2].semilogy(datasets[0].time, np.maximum(distance * _MICRO, 1e-12), lw=0.4 if
                         len(datasets) > 2 else 0.6, color=f"C{j + 1}" if len(datasets) > 2
                         else "C0", label=f"{label} vs {labels[0]}")
    axes[0].set_ylabel(f"(a) {_TIP1} (µm)")
    axes[1].set_ylabel(f"(b) {_TIP2} (µm)")
    axes[2].set_ylabel(f"|difference of {_TIP1}| (µm)")
    axes[2].set_xlabel("$t$ (s)")
    axes[0].legend(fontsize="small", loc="upper right")
    if len(datasets) > 2:
        axes[2].legend(fontsize="small", loc="lower right")


def plot_phase_portrait_laws(denses: Sequence[xr.Dataset], sections: Sequence[xr.Dataset],
                             path: str | Path) -> None:
    """Phase planes and Poincare sections of several runs, one row each (same axes).

    ``sections[j]`` must be sampled once per forcing period (its ``time`` a multiple of
    2 pi/Omega).
    """
    figure = Figure(figsize=(11, 4.3 * len(denses)), layout="constrained")
    axes = figure.subplots(len(denses), 2, sharex="col", sharey="col", squeeze=False)
    for row, dense, section in zip(axes, denses, sections, strict=True):
        _phase_panels(row, dense, section)
        for axis in row:
            axis.set_title(f"{_law(section)}\n{axis.get_title()}", fontsize="medium")
            axis.tick_params(labelbottom=True)
    figure.suptitle(_case(sections[0]), wrap=True)
    save_figure(figure, path)


def _phase_panels(axes: Sequence[Axes], dense: xr.Dataset, section: xr.Dataset) -> None:
    axes[0].plot(dense.tip_deflection_1 * _MICRO, dense.tip_velocity_1 * _MILLI, lw=0.3)
    axes[0].set_title(f"phase plane, {float(dense.time[0]):g} s ≤ $t$ ≤ "
                      f"{float(dense.time[-1]):g} s")
    axes[1].plot(section.tip_deflection_1 * _MICRO, section.tip_velocity_1 * _MILLI, ".",
                 ms=2)
    axes[1].set_title(f"Poincaré section: {section.time.size} forcing periods")
    for axis in axes:
        axis.set_xlabel(f"{_TIP1} (µm)")
        axis.set_ylabel(r"$\dot y_1(l_1)$ (mm/s)")
