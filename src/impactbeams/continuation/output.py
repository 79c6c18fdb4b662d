"""The branches as one xarray Dataset along ``branch_point`` (registry: impactbeams.variables)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.continuation.arclength import Point
from impactbeams.continuation.branch import Branch
from impactbeams.continuation.events import LABELS
from impactbeams.params import flat_parameter, named_attributes, part_field
from impactbeams.variables import PARAMETERS, VARIABLES, attributes, validate

if TYPE_CHECKING:
    import xarray as xr

SECTION = "section"  # the stroboscopic sections of a period-p orbit, t = k T for k < p
STORED_MULTIPLIERS = 8  # the leading ones by modulus: the rest decay with the damped modes


def branches_dataset(branches: list[Branch], parameter: str,
                     attrs: Mapping[str, Any]) -> xr.Dataset:
    """The points of every branch, in order, with their parameter ``parameter`` as coordinate.

    ``attrs``: the global attributes (the caller's parameters and settings); the branches'
    endings and origins are added.
    """
    import xarray as xr

    rows = [(number, branch, point) for number, branch in enumerate(branches)
            for point in branch.points]
    scaling = branches[0].scaling
    states = np.array([point.state(scaling) for _, _, point in rows])
    multipliers = _multipliers([point for _, _, point in rows])
    data: dict[str, Any] = {
        "branch": np.array([number for number, _, _ in rows], dtype=np.int32),
        "orbit_period": np.array([branch.period for _, branch, _ in rows], dtype=np.int32),
        "stable": (np.nan_to_num(np.abs(multipliers), nan=0.0).max(axis=1) < 1.0).astype(np.int8),
        "bifurcation": np.array([LABELS.index(point.label or "none") for _, _, point in rows],
                                dtype=np.int8),
        "newton_iterations": np.array([point.iterations for _, _, point in rows],
                                      dtype=np.int32),
        "contacts_per_orbit": np.array([point.evaluation.contacts for _, _, point in rows],
                                       dtype=np.int32),
        "grazing_gap": np.array([point.evaluation.grazing for _, _, point in rows]),
        **_measures([point for _, _, point in rows]),
    }
    variables = {name: (_dims(name), values) for name, values in data.items()}
    variables["multiplier_modulus"] = (("branch_point", "multiplier"), np.abs(multipliers))
    variables["multiplier_argument"] = (("branch_point", "multiplier"), np.angle(multipliers))
    variables["section_state"] = (("branch_point", "state"), states)
    coords = {"branch_point": np.arange(len(rows), dtype=np.int64),
              **_sections(data),
              "multiplier": np.arange(multipliers.shape[1], dtype=np.int64),
              "state": np.arange(states.shape[1], dtype=np.int64),
              parameter: ("branch_point",
                          np.array([point.parameter(scaling) for _, _, point in rows]))}
    dataset = xr.Dataset(variables, coords=coords, attrs={
        **attrs, "continued_parameter": parameter,
        "branch_endings": " ".join(branch.ending for branch in branches),
        "branch_covered": " ".join(_covered(branch) for branch in branches),
        "branch_origins": " ".join("-" if branch.origin is None else
                                   f"{branch.origin[0]}:{branch.origin[1]}"
                                   for branch in branches)})
    for name in dataset.variables:
        if name in VARIABLES:
            dataset[name].attrs.update(attributes(str(name)))
    if flat_parameter(parameter) in PARAMETERS or part_field(parameter) is not None:
        dataset[parameter].attrs.update(named_attributes(parameter))
    validate(dataset)
    return dataset


def _covered(branch: Branch) -> str:
    """The interval of the parameter the branch's points span, "low:high" (its units)."""
    values = [point.parameter(branch.scaling) for point in branch.points]
    return f"{min(values)!r}:{max(values)!r}"


def _multipliers(points: list[Point]) -> np.ndarray:
    """The leading multipliers of each point (NaN where a point has fewer)."""
    count = min(STORED_MULTIPLIERS, max(len(point.evaluation.multipliers) for point in points))
    table = np.full((len(points), count), np.nan, dtype=complex)
    for row, point in zip(table, points, strict=True):
        mu = point.evaluation.multipliers[:count]
        row[:len(mu)] = mu
    return table


def _measures(points: list[Point]) -> dict[str, np.ndarray]:
    """The problem's named amplitudes, one array each (NaN where a point lacks one).

    A measure per section (registered along ``section``) is a row per point, as long as the
    longest period, NaN past each orbit's own.
    """
    names = dict.fromkeys(name for point in points for name in point.evaluation.measures)
    measures = {}
    for name in names:
        rows = [np.atleast_1d(point.evaluation.measures.get(name, np.nan)) for point in points]
        if _dims(name)[-1] != SECTION:
            measures[name] = np.concatenate(rows)
            continue
        table = np.full((len(rows), max(row.size for row in rows)), np.nan)
        for values, row in zip(table, rows, strict=True):
            values[:row.size] = row
        measures[name] = table
    return measures


def _dims(name: str) -> tuple[str, ...]:
    """The registry's dimensions of ``name``; ("branch_point",) for a problem's own measure."""
    return VARIABLES[name].dims if name in VARIABLES else ("branch_point",)


def _sections(data: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The ``section`` coordinate (k of the samples at t = k T), if a variable is along it."""
    widths = [values.shape[1] for name, values in data.items()
              if _dims(name)[-1] == SECTION]
    return {SECTION: np.arange(max(widths), dtype=np.int64)} if widths else {}

