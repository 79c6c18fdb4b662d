"""What a figure shows: the variable, slices of the other dimensions, and what NaN means."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.params import ParameterError

if TYPE_CHECKING:
    from impactbeams.plotting.arrays import PlainArray, PlainDataset

DEFAULT_VARIABLE = "first_impact_time"
# dimensions of samples within one cell (stroboscopic Poincare samples), not grid axes
SAMPLE_DIMENSIONS = ("period",)
# dimensions drawn as overlaid curves, one colour each, over one swept axis
OVERLAID_DIMENSIONS = ("sweep_direction",)


def choose_variable(dataset: PlainDataset, variable: str | None) -> str:
    """``variable`` if the dataset has it; by default first_impact_time, else the first one."""
    names = [str(name) for name in dataset.data_vars]
    if variable is None:
        if not names:
            raise ParameterError("the dataset holds no variable to draw")
        return DEFAULT_VARIABLE if DEFAULT_VARIABLE in names else names[0]
    if variable not in names:
        raise ParameterError(f"no variable {variable!r} in the dataset; it has "
                             f"{', '.join(names)}")
    return variable


def select(dataset: PlainDataset, variable: str, values: Mapping[str, float | str],
           indices: Mapping[str, int | str]) -> tuple[PlainDataset, list[str]]:
    """Slice ``dataset`` at the grid values nearest ``values`` and at ``indices``, by dimension.

    Dimensions of length 1 are dropped as well. Returns the sliced dataset and one note per
    slice saying which grid value was used.
    """
    dims = dataset[variable].dims
    positions, notes = {}, []
    for requests, by_value in ((values, True), (indices, False)):
        for name, wanted in requests.items():
            if name not in dims:
                raise ParameterError(f"cannot slice {name!r}: {variable} has dimensions "
                                     f"{', '.join(map(str, dims))}")
            coordinate = dataset[name]
            index = _nearest(coordinate, wanted) if by_value else _index(coordinate, wanted)
            positions[name] = index
            notes.append(_slice_note(coordinate, wanted, index, by_value))
    sliced = dataset.isel(positions)
    return sliced.isel({d: 0 for d in sliced[variable].dims if sliced.sizes[d] == 1}), notes


def _nearest(coordinate: PlainArray, wanted: float | str) -> int:
    """Index of the grid value nearest ``wanted`` (in log distance on a log axis)."""
    grid, name = coordinate.values, coordinate.name
    if grid.dtype.kind in "OUS":  # named choices, e.g. a swept contact law
        matches = np.flatnonzero(grid == wanted)
        if not matches.size:
            raise ParameterError(f"{name} = {wanted!r} is not on the grid; it has "
                                 f"{', '.join(map(str, grid))}")
        return int(matches[0])
    try:
        number = float(wanted)
    except ValueError:
        raise ParameterError(f"{name} = {wanted!r} is not a number") from None
    low, high = float(grid.min()), float(grid.max())
    slack = 1e-9 * (high - low)  # the ends written in decimal may round differently
    if not low - slack <= number <= high + slack:
        raise ParameterError(f"{name} = {number:g} is outside the grid, {low:g} to {high:g} "
                             f"{coordinate.attrs.get('units', '')}".rstrip())
    log = coordinate.attrs.get("scale") == "log"
    distance = np.abs(np.log(grid / number) if log else grid - number)
    return int(np.argmin(distance))


def _index(coordinate: PlainArray, wanted: int | str) -> int:
    size = coordinate.size
    try:
        index = int(wanted)
    except ValueError:
        raise ParameterError(f"index {wanted!r} of {coordinate.name} is not an integer") from None
    if not -size <= index < size:
        raise ParameterError(f"index {index} of {coordinate.name} is out of range: it has "
                             f"{size} values, 0 to {size - 1}")
    return index % size


def _slice_note(coordinate: PlainArray, wanted: float | str, index: int,
                by_value: bool) -> str:
    value = coordinate.values[index]
    named = coordinate.dtype.kind not in "iuf"  # a choice (a direction, a law): found by name
    text = str(value) if named else f"{value:.6g}"
    units = coordinate.attrs.get("units", "")
    used = f"{coordinate.name} = {text} {'' if units == '1' else units}".rstrip()
    position = f"index {index} of 0..{coordinate.size - 1}"
    if by_value and named:
        return f"slice {used} ({position})"
    if by_value:
        return f"slice {coordinate.name} = {wanted}: nearest grid value {used} ({position})"
    return f"slice at {position}: {used}"


def parse_assignments(texts: Sequence[str], option: str) -> dict[str, str]:
    """``["clearance=1e-4", ...]`` -> ``{"clearance": "1e-4", ...}`` (``option`` for errors)."""
    pairs = {}
    for text in texts:
        name, equals, value = text.partition("=")
        if not equals or not name.strip() or not value.strip():
            raise ParameterError(f"{option} {text!r} is not NAME=VALUE")
        pairs[name.strip()] = value.strip()
    return pairs


def parse_levels(text: str | None) -> int | list[float] | None:
    """``"8"`` -> 8 contour lines; ``"0.01,0.1,0.5"`` -> those levels; None -> None."""
    if text is None:
        return None
    try:
        count = int(text)
    except ValueError:
        count = None
    if count is not None:
        if count < 1:
            raise ParameterError(f"--contours {text} is not allowed: must be >= 1")
        return count
    try:
        levels = [float(part) for part in text.split(",")]
    except ValueError:
        raise ParameterError(f"--contours {text!r} is neither a number of lines (e.g. 8) nor "
                             "levels separated by commas (e.g. 0.01,0.1,0.5)") from None
    return sorted(levels)
