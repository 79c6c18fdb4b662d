"""Figures drawn from saved Datasets only (no computation happens in plotting code)."""

from __future__ import annotations

from pathlib import Path

import xarray as xr


def plot_dataset(dataset: xr.Dataset, path: str | Path) -> None:
    """Draw a sweep map or a simulated run, whichever ``dataset`` holds, into ``path``."""
    if "time" in dataset.dims:
        from impactbeams.plotting.trajectories import plot_run

        plot_run(dataset, path)
    else:
        from impactbeams.plotting.maps import plot_map

        plot_map(dataset, path)
