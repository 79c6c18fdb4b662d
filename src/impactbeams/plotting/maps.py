"""Contour maps of a sweep in the style of the paper's Fig. 5."""

from __future__ import annotations

from pathlib import Path

import matplotlib.colors
import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from impactbeams.params import ParameterError


def _label(coordinate: xr.DataArray) -> str:
    return f"{coordinate.attrs.get('long_name', coordinate.name)} ({coordinate.attrs['units']})"


def plot_map(dataset: xr.Dataset, path: str | Path, variable: str = "first_impact_time") -> None:
    """Filled contours of ``variable`` over a 2-D sweep, the no-impact region hatched.

    The first swept parameter is the x axis, the second the y axis; log axes stay log.
    """
    if variable not in dataset:
        raise ParameterError(f"{variable!r} is not in the dataset; it has "
                             f"{', '.join(map(str, dataset.data_vars))}")
    field = dataset[variable]
    if field.ndim != 2:
        raise ParameterError(f"a contour map needs a 2-D sweep; {variable} has dimensions "
                             f"{field.dims}: select a slice first (e.g. with xarray's .isel)")
    x_name, y_name = field.dims
    x, y = dataset[x_name], dataset[y_name]
    values = field.transpose(y_name, x_name).values
    figure = Figure(figsize=(7, 5), layout="constrained")
    axes = figure.subplots()
    finite = values[np.isfinite(values)]
    if finite.size:
        # times before impact span decades: log-spaced levels when they are all positive
        if finite.min() > 0 and finite.max() > finite.min():
            levels = np.geomspace(finite.min(), finite.max(), 21)
            norm = matplotlib.colors.LogNorm(finite.min(), finite.max())
        else:
            levels, norm = 21, None
        filled = axes.contourf(x.values, y.values, values, levels=levels, norm=norm,
                               cmap="viridis")
        bar = figure.colorbar(filled, ax=axes)
        bar.set_label(f"{field.attrs['long_name']} ({field.attrs['units']})")
    if "impacted" in dataset:
        no_impact = (dataset["impacted"].transpose(y_name, x_name).values == 0).astype(float)
        if no_impact.any():
            axes.contourf(x.values, y.values, no_impact, levels=[0.5, 1.5], colors="none",
                          hatches=["///"])
            axes.contour(x.values, y.values, no_impact, levels=[0.5], colors="k",
                         linewidths=0.8)
    for coordinate, set_scale in ((x, axes.set_xscale), (y, axes.set_yscale)):
        if coordinate.attrs.get("scale") == "log":
            set_scale("log")
    axes.set_xlabel(_label(x))
    axes.set_ylabel(_label(y))
    t_max = dataset.attrs.get("t_max")
    axes.set_title(f"{field.attrs['long_name']}; hatched: no impact by t_max = {t_max} s")
    figure.savefig(path, dpi=150)
