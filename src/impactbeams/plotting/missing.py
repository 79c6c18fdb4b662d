"""Cells without a value (NaN, e.g. no impact by t_max): drawn light grey and said so."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Patch

from impactbeams.plotting.labels import format_number
from impactbeams.plotting.scales import MISSING_COLOUR

if TYPE_CHECKING:
    from impactbeams.plotting.arrays import PlainDataset


def missing_note(dataset: PlainDataset, variable: str, t_max: str = "$t_\\max$") -> str:
    """What the NaN cells of ``variable`` mean: no impact by t_max where ``impacted`` says so.

    ``t_max``: how to write t_max (mathtext for a figure; "t_max" for a terminal).
    """
    field = dataset[variable]
    if "impacted" in dataset and dataset["impacted"].dims == field.dims and np.array_equal(
            np.isnan(field.values), dataset["impacted"].values == 0):
        horizon = dataset.attrs.get("t_max")
        return ("no impact" if horizon is None
                else f"no impact by {t_max} = {format_number(float(horizon))} s")
    return "no value (NaN)"


def note_empty(axes: Axes, dataset: PlainDataset, variable: str) -> str:
    """Say on ``axes`` that ``variable`` has no value in any cell (e.g. no cell impacts).

    Returns the same note in plain text, for the terminal.
    """
    axes.text(0.5, 0.5, f"{missing_note(dataset, variable)} in any cell",
              transform=axes.transAxes, ha="center", va="center",
              bbox={"facecolor": "white", "edgecolor": "0.6"})
    return (f"{variable} has no value in any cell ({missing_note(dataset, variable, 't_max')}):"
            " drawn all grey")


def add_missing_legend(axes: Axes, note: str, below: bool = False) -> None:
    """A grey swatch saying what the grey (NaN) cells mean, in the axes' best corner.

    ``below``: under the axes instead (a colour bar's), the note broken after "by" to fit.
    """
    if below:
        note = note.replace(" by ", " by\n", 1)
    swatch = Patch(facecolor=MISSING_COLOUR, edgecolor="0.6", label=note)
    placement = ({"loc": "upper left", "bbox_to_anchor": (0.0, -0.01), "borderaxespad": 0.0}
                 if below else {"loc": "best"})
    axes.legend(handles=[swatch], frameon=not below, fontsize="small", handlelength=1.2,
                handletextpad=0.5, **placement)


def shade_missing(axes: Axes, x_edges: np.ndarray, missing: np.ndarray) -> None:
    """Grey vertical bands over the cells of a line (edges ``x_edges``) that are ``missing``."""
    padded = np.concatenate([[False], missing, [False]])
    starts = np.flatnonzero(padded[1:-1] & ~padded[:-2])
    stops = np.flatnonzero(padded[1:-1] & ~padded[2:])
    for start, stop in zip(starts, stops, strict=True):
        axes.axvspan(x_edges[start], x_edges[stop + 1], color=MISSING_COLOUR, lw=0, zorder=0)
