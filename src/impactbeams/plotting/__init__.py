"""Figures drawn from saved Datasets only (no computation happens in plotting code).

[`draw`][] puts one variable of a sweep on a matplotlib Axes, as the dataset's shape asks:
a colour map over two swept axes, a line over one, a bifurcation diagram for samples per
cell (a ``period`` dimension) over one; [`plot_dataset`][] draws into a file. Both take an
xarray Dataset or a [`PlainDataset`][impactbeams.plotting.arrays.PlainDataset] (a file read
without xarray, `impactbeams.plotting.arrays.read_figure_data`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from impactbeams.params import ParameterError, is_path, is_real, require, require_type
from impactbeams.plotting.arrays import PlainArray, PlainDataset, as_plain, is_dataset
from impactbeams.plotting.events import chosen_events
from impactbeams.plotting.files import save_figure
from impactbeams.plotting.labels import case_title
from impactbeams.plotting.missing import note_empty
from impactbeams.plotting.selection import (
    OVERLAID_DIMENSIONS,
    SAMPLE_DIMENSIONS,
    choose_variable,
    parse_assignments,
    parse_levels,
    select,
)
from impactbeams.preflight import registered

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["draw", "parse_assignments", "parse_levels", "plot_dataset"]


def draw(axes: Axes, dataset: xr.Dataset | PlainDataset, variable: str | None = None, *,
         values: Mapping[str, float | str] | None = None,
         indices: Mapping[str, int | str] | None = None, scale: str | None = None,
         contours: int | Sequence[float] | None = None, title: str | None = None) -> list[str]:
    """Draw ``variable`` (default first_impact_time) of ``dataset`` on ``axes``.

    ``values`` slices dimensions at the grid values nearest the given ones (SI units, in log
    distance on log axes), ``indices`` at grid indices; the rest decides the figure: two
    swept dimensions give a colour map (with a colour bar), one a line, one plus ``period``
    (Poincare samples) a bifurcation diagram; a stepped sweep's directions
    (``sweep_direction``) over one axis are overlaid, one colour each. ``scale``: "log" or
    "linear" colours (or y axis of a line), None to choose (log when positive data span more
    than 1.5 decades). ``contours``: labelled contour lines on a map, a number of round levels
    or the levels. ``title``: None for the fixed parameters and slices, "" for none.

    Returns one note per slice saying which grid value it used. Raises ParameterError for an
    unknown variable or dimension, or a shape that cannot be drawn.
    """
    dataset = as_plain(dataset)
    name = choose_variable(dataset, variable)
    data, notes = select(dataset, name, values or {}, indices or {})
    field = data[name]
    grid = [d for d in field.dims if d not in (*SAMPLE_DIMENSIONS, *OVERLAID_DIMENSIONS)]
    overlaid = len(grid) == 1 and any(d in field.dims for d in OVERLAID_DIMENSIONS)
    samples = any(d in field.dims for d in SAMPLE_DIMENSIONS)
    if contours is not None and len(field.dims) != 2:
        raise ParameterError(f"contour lines need a map of two dimensions; {name} has "
                             f"{_dimensions(field)}")
    if overlaid:  # a stepped sweep's directions over one axis: a curve each
        from impactbeams.plotting.lines import draw_directions

        draw_directions(axes, data, name, scale)
    elif samples and grid:
        if len(grid) > 1:
            raise ParameterError(f"a bifurcation diagram needs one swept axis: {name} has "
                                 f"{_dimensions(field)}; slice all but one (--slice "
                                 "NAME=VALUE) or draw one sample (--slice-index period=I)")
        from impactbeams.plotting.lines import draw_bifurcation

        draw_bifurcation(axes, data, name)
    elif name == "contact_force" and "impact_peak_force" in data.variables:
        # a run's force: its samples miss most contacts, each contact's peak is drawn too
        from impactbeams.plotting.labels import axis_label
        from impactbeams.plotting.trajectories import plot_contact_force

        plot_contact_force(axes, data)
        axes.set_xlabel(axis_label(data["time"]))
    elif field.ndim == 1:
        from impactbeams.plotting.lines import draw_line

        draw_line(axes, data, name, scale)
    elif field.ndim == 2:
        from impactbeams.plotting.maps import draw_map

        draw_map(axes, data, name, scale, contours)
    elif field.ndim == 0:
        raise ParameterError(f"nothing to draw: {name} is a single value after slicing, "
                             f"{field.item():g} {field.attrs.get('units', '')}; slice fewer "
                             "dimensions")
    else:
        raise ParameterError(f"a map needs a 2-D sweep (a line a 1-D one): {name} has "
                             f"{_dimensions(field)}; slice the others (--slice NAME=VALUE)")
    axes.set_title(case_title(data, name, field.dims) if title is None else title,
                   loc="left", fontsize="medium", wrap=True)
    if not np.isfinite(np.asarray(field.values, dtype=float)).any():
        notes.append(note_empty(axes, data, name))
    return notes


def _check_arguments(dataset: object, path: object, variable: object, values: object,
                     indices: object, title: object, dpi: object, events: object) -> None:
    """The types of [`plot_dataset`][]'s arguments (same names), dpi's and events' values.

    The dataset's registered names must be as registered (`impactbeams.variables.validate`).
    """
    require_type("dataset", dataset, is_dataset(dataset),
                 "an xarray.Dataset or an impactbeams.plotting.arrays.PlainDataset")
    registered(dataset, "dataset")
    require_type("path", path, is_path(path), "the path of an image file (str or pathlib.Path)")
    for name, value in (("variable", variable), ("title", title)):
        require_type(name, value, value is None or isinstance(value, str), "None or a str")
    for name, value in (("values", values), ("indices", indices)):
        require_type(name, value, value is None or isinstance(value, Mapping),
                     "None or a mapping of dimension names to values")
    require("dpi", dpi, is_real(dpi) and 0 < dpi < float("inf"), "must be a finite number > 0")
    chosen_events(events)


def _plot_branches(dataset: xr.Dataset, path: str | Path, variable: str | None,
                   title: str | None, dpi: float, diagram: xr.Dataset | None,
                   hz: bool, events: str | Sequence[str] | None) -> list[str]:
    """A continuation's frequency-response curve into ``path``."""
    from impactbeams.plotting.branches import draw_branches

    if diagram is not None:
        registered(diagram, "diagram")
    figure = Figure(figsize=(7, 5), layout="constrained")
    axes = figure.subplots()
    axes.set_title(case_title(dataset, variable or "tip_amplitude_1", ("branch_point",))
                   if title is None else title, loc="left", fontsize="medium", wrap=True)
    draw_branches(axes, dataset, variable, diagram, hz, events)  # last: it places labels laid out
    save_figure(figure, path, dpi)
    return []


def _plot_curve(curves: Sequence[xr.Dataset], path: str | Path, title: str | None, dpi: float,
                diagram: xr.Dataset | None, variable: str | None,
                slices: Mapping[str, object]) -> list[str]:
    """Bifurcation curves in their parameters' plane into ``path``, over the map ``diagram``.

    ``variable``: the map's; ``slices``: `draw_curves`' values, indices, scale, contours.
    """
    from impactbeams.plotting.curves import draw_curves

    if diagram is not None:
        registered(diagram, "diagram")
    figure = Figure(figsize=(7, 5), layout="constrained")
    axes = figure.subplots()
    axes.set_title(case_title(curves[0], curves[0].attrs["curve_parameters"].split()[1],
                              ("branch_point",)) if title is None else title,
                   loc="left", fontsize="medium", wrap=True)
    axes.plot([], [], "k-", label="stable")
    axes.plot([], [], "k--", label="unstable")
    notes = draw_curves(axes, curves, diagram, variable,
                        **slices)  # type: ignore[arg-type]  # last: it places labels laid out
    axes.legend(fontsize="small", loc="best")
    save_figure(figure, path, dpi)
    return notes


def _plot_basins(dataset: xr.Dataset, path: str | Path, title: str | None,
                 dpi: float) -> list[str]:
    """A basin map with its attractors' legend into ``path``."""
    from impactbeams.plotting.basins import draw_basins

    figure = Figure(figsize=(9, 5), layout="constrained")
    axes = figure.subplots()
    draw_basins(axes, dataset)
    axes.set_title(case_title(dataset, "basin", tuple(dataset["basin"].dims)) if title is None
                   else title, loc="left", fontsize="medium", wrap=True)
    save_figure(figure, path, dpi)
    return []


# the command line's name of each option of plot_dataset that a figure may not take
_OPTIONS = {"values": "--slice", "indices": "--slice-index", "scale": "--log / --linear",
            "contours": "--contours"}


def _refuse_options(figure: str, **given: object) -> None:
    """ParameterError naming the first option ``given`` (not None or empty) ``figure`` ignores."""
    for name, value in given.items():
        if value is not None and value != {}:
            raise ParameterError(f"{name} ({_OPTIONS[name]}) = {value!r} is not allowed: "
                                 f"{figure} take none")


def _require_xarray(dataset: xr.Dataset | PlainDataset, figure: str) -> None:
    """TypeError unless ``dataset`` is an xarray Dataset: ``figure`` is drawn from one."""
    if isinstance(dataset, PlainDataset):
        raise TypeError(f"{figure} is drawn from an xarray.Dataset, not a PlainDataset: read "
                        "the file with impactbeams.plotting.arrays.read_figure_data")


def _dimensions(field: PlainArray) -> str:
    return "dimensions " + ", ".join(f"{d} ({field.sizes[d]})" for d in field.dims)


def plot_dataset(dataset: xr.Dataset | PlainDataset, path: str | Path,
                 variable: str | None = None, *,
                 values: Mapping[str, float | str] | None = None,
                 indices: Mapping[str, int | str] | None = None, scale: str | None = None,
                 contours: int | Sequence[float] | None = None, title: str | None = None,
                 dpi: float = 150, diagram: xr.Dataset | None = None,
                 hz: bool = False, events: str | Sequence[str] | None = None,
                 curves: Sequence[xr.Dataset] = ()) -> list[str]:
    """Draw ``dataset`` into the image file ``path`` (format from its extension).

    A simulated run without options gets its overview (tips, force, restitution, energy); a
    basin map (`impactbeams.orbits.basins`) its labels over the initial states with the
    attractors' legend (`impactbeams.plotting.basins`); a
    continuation's branches their frequency-response curve (over the bifurcation diagram
    ``diagram`` if given; its frequency axis in Hz if ``hz``; the events drawn and labelled as
    ``events`` says, `impactbeams.plotting.branches.draw_branches`); a bifurcation curve its
    parameters' plane (over the map ``diagram`` of the same plane if given, its
    ``variable`` sliced as ``values`` and ``indices`` say,
    `impactbeams.plotting.curves.draw_curves`), with ``curves``, more curves of its plane, on
    the same axes; anything else is drawn by [`draw`][], whose options these are.
    ``dataset``: an xarray Dataset, or for a sweep's map a
    [`PlainDataset`][impactbeams.plotting.arrays.PlainDataset] (a file read without xarray).
    Returns its notes.
    """
    _check_arguments(dataset, path, variable, values, indices, title, dpi, events)
    if curves and "curve_kind" not in dataset.attrs:
        raise ParameterError("--with is not allowed: it adds bifurcation curves to a "
                             "bifurcation curve's plot, and this Dataset is none")
    if "curve_kind" in dataset.attrs:
        _require_xarray(dataset, "a bifurcation curve")
        slices = {"values": values, "indices": indices, "scale": scale, "contours": contours}
        if diagram is None:
            _refuse_options("a bifurcation curve without a map under it (--over), drawn "
                            "whole in its parameters' plane,", **slices)
        given = [name for name, value in (("events (--events)", events is not None),
                                          ("--hz", hz)) if value]
        if given:
            raise ParameterError(f"{given[0]} is not allowed: a bifurcation curve is drawn in "
                                 "its parameters' plane with its codimension-two points")
        if diagram is None and variable is not None:
            raise ParameterError(f"variable (--var) = {variable!r} is not allowed: a "
                                 "bifurcation curve is drawn in its parameters' plane; --var "
                                 "chooses what a map under it (--over) shows")
        return _plot_curve([dataset, *curves], path, title, dpi, diagram, variable, slices)
    if "branch_point" in dataset.dims:
        _require_xarray(dataset, "a continuation's branches")
        _refuse_options("a continuation's branches, drawn whole along their parameter,",
                        values=values, indices=indices, scale=scale, contours=contours)
        return _plot_branches(dataset, path, variable, title, dpi, diagram, hz, events)
    given = [name for name, value in (("diagram (--over)", diagram is not None), ("--hz", hz),
                                      ("events (--events)", events is not None)) if value]
    if given:
        raise ParameterError(f"{given[0]} is for a continuation's file only: this Dataset has "
                             "no branch_point dimension")
    if "attractor" in dataset.dims and variable in (None, "basin"):
        _require_xarray(dataset, "a basin map")
        _refuse_options("a basin map, drawn whole over its initial states,", values=values,
                        indices=indices, scale=scale, contours=contours)
        return _plot_basins(dataset, path, title, dpi)
    options = values or indices or scale or contours is not None or title is not None
    if "time" in dataset.dims and variable is None and not options:
        from impactbeams.plotting.trajectories import plot_run

        _require_xarray(dataset, "a run's overview")
        plot_run(dataset, path)
        return []
    figure = Figure(figsize=(7, 5), layout="constrained")
    notes = draw(figure.subplots(), dataset, variable, values=values, indices=indices,
                 scale=scale, contours=contours, title=title)
    save_figure(figure, path, dpi)
    return notes
