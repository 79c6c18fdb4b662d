"""Bifurcation curves in the plane of two parameters (`impactbeams.continuation.twoparameter`).

The first parameter across, the second up, in the prefixed units of their size; the orbits
solid where stable but for the bifurcating multiplier (`curve_stable`), dashed where not; the
codimension-two points marked and labelled where a label fits (`branches.place_labels`), the
start circled. `draw_curves` draws several on one axes, over a map of the same plane if
given (a first-impact map, or a long-time sweep: where the orbits impact, how often, ...);
`draw_curve` draws one. A closed-form grazing curve (`impactbeams.orbits.grazing_curve`, the
linear response's, `impactbeams grazing` with a parameter besides omega) is drawn with them as
a dotted line of its own colour (no stability, no codimension-two points): the check of a
continued grazing curve by eye.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.ticker import ScalarFormatter

from impactbeams.params import ParameterError
from impactbeams.plotting.arrays import PlainArray, PlainDataset, as_plain
from impactbeams.plotting.branches import _draw_branch, place_labels
from impactbeams.plotting.labels import axis_label, display_units
from impactbeams.plotting.selection import choose_variable, select
from impactbeams.variables import CURVE_EVENTS

MARKERS = {"end": ("s", "E"), "turning_point": ("v", "T"), "cusp": ("D", "CP"),
           "grazing": ("^", "G"), "contact_merge": ("<", "M"), "contact_split": (">", "S"),
           "resonance_1_1": ("*", "R1"), "resonance_1_2": ("*", "R2"),
           "resonance_1_3": ("*", "R3"), "resonance_1_4": ("*", "R4"),
           "fold_neimark_sacker": ("P", "LPNS"), "flip_neimark_sacker": ("X", "PDNS")}
CLOSED_FORM = "closed_form_grazing"  # the kind of a closed-form grazing curve
KIND_NAMES = {"grazing": "grazing", "fold": "fold", "period_doubling": "period doubling",
              "neimark_sacker": "Neimark-Sacker", CLOSED_FORM: "closed-form grazing"}
# one colour per kind of curve; over a map's colours the first is black
COLOURS = ("C0", "C3", "C2", "C1", "C4")
OVER_MAP_COLOURS = ("k", "C3", "C1", "C6", "C4")

Units = tuple[float, str]  # the factor from SI and the units drawn (`display_units`)
Labelled = list[tuple[float, float, str]]  # (x, y, text) of each codimension-two point


def draw_curve(axes: Axes, dataset: xr.Dataset, colour: str = "C0",
               label_events: bool = True,
               units: tuple[Units, Units] | None = None) -> None:
    """Draw one curve's Dataset on ``axes``: the first parameter across, the second up.

    Its codimension-two points are marked (and labelled where a label fits if
    ``label_events``; place them after everything is drawn, since the labels are placed on
    the laid-out axes). ``units``: the first's and second's (factor, units) drawn, by
    default those of the curve's own values.
    """
    labelled = _draw(axes, dataset, colour, units or _units([dataset]))
    if label_events:
        place_labels(axes, labelled)


def draw_curves(axes: Axes, curves: Sequence[xr.Dataset],
                over: xr.Dataset | PlainDataset | None = None, variable: str | None = None,
                *, values: Mapping[str, float | str] | None = None,
                indices: Mapping[str, int | str] | None = None, scale: str | None = None,
                contours: int | Sequence[float] | None = None) -> list[str]:
    """Draw ``curves`` in their (common) parameters' plane, over the map ``over`` if given.

    One colour per kind of curve (fold, grazing, ...), one legend entry each: curves of one
    kind followed from the same start up and down join as one line.

    ``over``: a Dataset over the same two parameters (a first-impact map of `run_sweep`, or
    a long-time sweep), whose ``variable`` is drawn as a colour map under the curves
    (default first_impact_time, else its first variable; ``values``, ``indices``,
    ``scale`` and ``contours`` as [`draw`][impactbeams.plotting.draw]'s: slice its other
    dimensions, e.g. a stepped sweep's ``sweep_direction``). The limits are the map's outer
    edges, widened to the curves where they go past them. Both are drawn in the same units
    (the prefix of the larger of the two). Codimension-two points are labelled last.

    ParameterError, before anything is drawn, if the curves are not in the same plane or
    the map's axes are not their parameters (or are in other units). Returns the slices'
    notes.
    """
    first, second = _plane_of(curves)
    plane, name, notes = (None, "", []) if over is None else _select_plane(
        over, variable, values, indices, curves[0])
    units = _units(curves, plane)
    if plane is not None:
        from impactbeams.plotting.maps import draw_map

        draw_map(axes, _in_units(plane, (first, second), units), name, scale, contours,
                 fill=False)
        limits = axes.get_xlim(), axes.get_ylim()
    labelled: Labelled = []
    palette = COLOURS if plane is None else OVER_MAP_COLOURS
    kinds = list(dict.fromkeys(kind_of(curve) for curve in curves))
    for number, curve in enumerate(curves):
        kind = kinds.index(kind_of(curve))
        first_of_kind = all(kind_of(other) != kind_of(curve) for other in curves[:number])
        draw = _draw_closed_form if kind_of(curve) == CLOSED_FORM else _draw
        labelled += draw(axes, curve, palette[kind % len(palette)], units, first_of_kind)
    if plane is not None:  # the map's edges, or the curves' ends past them (NaN: no point)
        for set_limits, (low, high), parameter, (factor, _) in zip(
                (axes.set_xlim, axes.set_ylim), limits, (first, second), units, strict=True):
            drawn = np.concatenate([factor * curve[parameter].values for curve in curves])
            set_limits(min(low, float(np.nanmin(drawn))), max(high, float(np.nanmax(drawn))))
    place_labels(axes, labelled)
    return notes


def _draw(axes: Axes, dataset: xr.Dataset, colour: str, units: tuple[Units, Units],
          in_legend: bool = True) -> Labelled:
    """One curve's line, start and marked codimension-two points; returns their labels.

    ``in_legend``: whether its line has a legend entry (the first curve of its kind).
    """
    first, second = dataset.attrs["curve_parameters"].split()
    (x_factor, x_units), (y_factor, y_units) = units
    x, y = x_factor * dataset[first].values, y_factor * dataset[second].values
    # one line in the parameters' plane: drawn as a period-1 branch is (full width)
    _draw_branch(axes, x, y[:, None], dataset.curve_stable.values, np.ones(x.size, dtype=bool),
                 colour, f"{KIND_NAMES[dataset.attrs['curve_kind']]} curve" if in_legend
                 else "_nolegend_", period=1)
    axes.plot(x[:1], y[:1], "o", color=colour, markerfacecolor="none", markersize=7)
    codes = dataset.curve_event.values
    labelled = []
    for code in np.unique(codes[codes > 0]):
        name = CURVE_EVENTS[code]
        marker, text = MARKERS[name]
        at = codes == code
        axes.plot(x[at], y[at], marker, color="k", markersize=6, linestyle="none")
        labelled += [(px, py, text) for px, py in zip(x[at], y[at], strict=True)]
    axes.set_xlabel(axis_label(dataset[first], x_units))
    axes.set_ylabel(axis_label(dataset[second], y_units))
    for axis in (axes.xaxis, axes.yaxis):  # a map's log axis keeps its own ticks
        if isinstance(axis.get_major_formatter(), ScalarFormatter):
            axis.get_major_formatter().set_useOffset(False)
    return labelled


def _draw_closed_form(axes: Axes, dataset: xr.Dataset, colour: str,
                      units: tuple[Units, Units], in_legend: bool = True) -> Labelled:
    """A closed-form grazing curve's line (dotted: no orbit's stability); no labels."""
    first, second = parameters_of(dataset)
    (x_factor, _), (y_factor, _) = units
    axes.plot(x_factor * dataset[first].values, y_factor * dataset[second].values, ":",
              color=colour, linewidth=2.0,
              label=f"{KIND_NAMES[CLOSED_FORM]} curve (linear response)" if in_legend
              else "_nolegend_")
    return []


def kind_of(curve: xr.Dataset) -> str:
    """A curve's kind: its ``curve_kind``, or ``CLOSED_FORM`` for a closed-form grazing one."""
    return str(curve.attrs.get("curve_kind", CLOSED_FORM))


def parameters_of(curve: xr.Dataset) -> tuple[str, str]:
    """The (first, second) parameters of a curve: a closed-form grazing one's is omega first."""
    if "curve_parameters" in curve.attrs:
        first, second = curve.attrs["curve_parameters"].split()
        return first, second
    return "omega", str(curve.attrs["grazing_parameter"])


def is_curve(dataset: xr.Dataset | PlainDataset) -> bool:
    """Whether ``dataset`` draws as a curve in a plane of two parameters (this module).

    A continued bifurcation curve, or a closed-form grazing curve in (omega, a drive or the
    clearance); the grazing frequencies of one drive (``grazing_parameter`` omega) are points.
    """
    return "curve_kind" in dataset.attrs or dataset.attrs.get(
        "grazing_parameter", "omega") != "omega"


def _plane_of(curves: Sequence[xr.Dataset]) -> tuple[str, str]:
    """The parameters (first, second) every one of ``curves`` is drawn in."""
    if not curves:
        raise ParameterError("curves = [] is not allowed: give at least one curve's Dataset")
    planes = [parameters_of(curve) for curve in curves]
    for number, plane in enumerate(planes):
        if plane != planes[0]:
            raise ParameterError(f"curve {number} is in ({', '.join(plane)}), not in the first "
                                 f"one's plane ({', '.join(planes[0])}): draw them apart")
    first, second = planes[0]
    return first, second


def _select_plane(over: xr.Dataset | PlainDataset, variable: str | None,
                  values: Mapping[str, float | str] | None,
                  indices: Mapping[str, int | str] | None,
                  curve: xr.Dataset) -> tuple[PlainDataset, str, list[str]]:
    """``over`` sliced to a map of ``variable`` over ``curve``'s parameters, its notes.

    ParameterError naming the axes or units that differ from the curve's.
    """
    plain = as_plain(over)
    name = choose_variable(plain, variable)
    data, notes = select(plain, name, values or {}, indices or {})
    dims = data[name].dims
    parameters = parameters_of(curve)
    missing = [p for p in parameters if p not in dims]
    if missing:
        raise ParameterError(f"the map (--over) is not over the curve's parameters "
                             f"({', '.join(parameters)}): its {name} is over "
                             f"({', '.join(dims) or 'no axis'}), without {' or '.join(missing)}")
    others = [d for d in dims if d not in parameters]
    if others:
        raise ParameterError(f"the map's (--over) {name} is also over {', '.join(others)}: "
                             "slice it (--slice NAME=VALUE or --slice-index NAME=I) to a map "
                             f"of the curve's parameters ({', '.join(parameters)})")
    for parameter in parameters:
        axis, own = data[parameter], curve[parameter].attrs.get("units", "")
        if axis.dtype.kind not in "iuf" or axis.attrs.get("units", "") != own:
            given = (f"in {axis.attrs.get('units', '')!r}" if axis.dtype.kind in "iuf"
                     else "named choices")
            raise ParameterError(f"the map's (--over) {parameter} is {given}, the curve's "
                                 f"in {own!r}: draw a map of the same units")
    return data, name, notes


def _units(curves: Sequence[xr.Dataset],
           plane: PlainDataset | None = None) -> tuple[Units, Units]:
    """Each parameter's (factor, units) drawn: the prefix of the curves' and map's values."""
    first, second = _plane_of(curves)
    units = []
    for parameter in (first, second):
        values = [curve[parameter].values for curve in curves]
        if plane is not None:
            values.append(plane[parameter].values)
        units.append(display_units(np.concatenate(values),
                                   curves[0][parameter].attrs.get("units", "")))
    return units[0], units[1]


def _in_units(plane: PlainDataset, parameters: tuple[str, str],
              units: tuple[Units, Units]) -> PlainDataset:
    """``plane`` with its axes in ``units`` and its maps over (first, second) in that order."""
    variables: dict[str, PlainArray] = {}
    for key, array in plane.variables.items():
        if set(array.dims) == set(parameters):
            array = array.transpose(*parameters)
        variables[key] = array
    for parameter, (factor, drawn) in zip(parameters, units, strict=True):
        axis = plane[parameter]
        variables[parameter] = dataclasses.replace(axis, values=factor * axis.values,
                                                   attrs={**axis.attrs, "units": drawn})
    return PlainDataset(variables, frozenset(plane.coords), plane.attrs)
