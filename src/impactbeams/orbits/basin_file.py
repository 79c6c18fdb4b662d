"""A basin map as a sweep file (TOML), read and checked: `load_basins`, `BasinPlan`.

`impactbeams run` runs a file with a ``[basins]`` table as the basins sweep kind: at the fixed
``[params]``, the initial states of a plane (or random ones) are cells, run in chunks, saved
and resumed, on threads or a Dask cluster, as `impactbeams basins` runs them::

    n_modes = 5                  # free modes per beam (default: as simulate's)
    [params]                     # the fixed parameters, omega > 0
    counterpart = "stop"
    omega = 300.0
    [basins]
    axis1 = [-4e-5, 4e-5]        # beam 1's initial tip deflection (m), or z[i] with coordinates
    axis2 = [-1.2e-2, 1.2e-2]    # its initial tip velocity (m/s), or z[j]
    points = 41                  # initial states along each axis (default 41)
    random = 400                 # instead of points: random states in the box (basin stability)
    seed = 0                     # of the random states (with random only; default 0)
    coordinates = [0, 5]         # the plane of z[i], z[j] (modal units): default the tip plane
    max_periods = 1200           # forcing periods before a state counts as not settled
    states = "starts.npz"        # instead of the plane: rows of section states z = (q, q')
    attractors = "curve.nc"      # a continuation's output: its orbits at [params] label first

``states`` (a .npy, .npz or basin map's .nc, `impactbeams.orbits.basin_inputs.read_states`)
replaces axis1, axis2 and what fills the plane; ``attractors`` names an `impactbeams continue`
output whose branches cross the continued parameter's value in ``[params]``
(`basin_inputs.continued_orbits`). Relative paths are from the basins file's folder.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.orbits.basin_cells import Settling
from impactbeams.orbits.basin_inputs import continued_orbits, read_states, section_dimension
from impactbeams.orbits.basin_map import basin_stability, basins, default_modes
from impactbeams.params import (
    ParameterError,
    Params,
    is_integer,
    is_real,
    read_toml,
    require,
    require_table,
    unknown_key,
)
from impactbeams.variables import BASIN_POINTS

if TYPE_CHECKING:
    import xarray as xr

_TOP_LEVEL = ("n_modes", "params", "basins")
_KEYS = ("axis1", "axis2", "points", "random", "seed", "coordinates", "max_periods", "states",
         "attractors")
_PLANE_FILLS = ("points", "random", "seed", "coordinates")  # how a plane is filled


@dataclasses.dataclass(frozen=True)
class BasinPlan:
    """A basin map to compute: the model, the box of the plane and how it is filled.

    ``box``: ((low, high), (low, high)) of the plane's axes; ``points`` states a side
    (default `BASIN_POINTS`) or ``random`` states drawn from ``seed``; ``coordinates``,
    ``n_modes``, ``max_periods`` as `impactbeams.orbits.basins`'. ``states``: a file of
    initial states instead of the plane (box None); ``attractors``: a continuation's file
    whose orbits label first (`impactbeams.orbits.basin_inputs`). ``name``: how a message
    names a key (``"--{}"`` on the command line). Check with `checked`.
    """

    params: Params
    box: tuple[tuple[float, float], tuple[float, float]] | None
    points: int | None = None
    random: int | None = None
    seed: int | None = None
    coordinates: tuple[int, int] | None = None
    n_modes: int | None = None
    max_periods: int | None = None
    states: Path | None = None
    attractors: Path | None = None
    name: str = "--{}"

    def checked(self) -> BasinPlan:
        """Itself, once its choices fit together (ParameterError naming the key).

        The values themselves are checked by `basins` before any run.
        """
        name = self.name.format
        if self.states is not None:
            given = ["axis1"] * (self.box is not None) + [
                key for key in _PLANE_FILLS if getattr(self, key) is not None]
            if given:
                raise ParameterError(f"{name(given[0])} is not allowed with {name('states')}: "
                                     "the states are given whole, no plane is filled")
            return self
        missing = [key for key, side in zip(("axis1", "axis2"), self.box or (None, None),
                                             strict=True) if side is None]
        if missing:
            raise ParameterError(f"{name(missing[0])} is needed: the plane's two axes "
                                 f"{name('axis1')} and {name('axis2')}, or {name('states')}")
        if self.random is not None and self.points is not None:
            raise ParameterError(f"{name('points')} is not allowed with {name('random')}: the "
                                 "states are drawn at random in the box")
        if self.random is None and self.seed is not None:
            raise ParameterError(f"{name('seed')} = {self.seed} is not allowed without "
                                 f"{name('random')}: a grid's states are not drawn at random")
        for key, (low, high) in zip(("axis1", "axis2"), self.box, strict=True):
            if not low < high:
                raise ParameterError(f"{name(key)} = {low!r},{high!r} is not allowed: need "
                                     "LOW < HIGH")
        return self

    def run(self, **options: Any) -> xr.Dataset:
        """The map (`basins`) or the random sample (`basin_stability`).

        ``options``: theirs (output, chunk_cells, workers, progress, client).
        """
        n_modes = default_modes(self.params) if self.n_modes is None else self.n_modes
        given = () if self.attractors is None else continued_orbits(
            self.attractors, self.params, n_modes, self.name.format("attractors"))
        common = {"n_modes": n_modes, "attractors": given,
                  "settling": Settling(**({} if self.max_periods is None
                                          else {"max_periods": self.max_periods})), **options}
        if self.states is not None:
            states = read_states(self.states, self.name.format("states"),
                                 section_dimension(self.params, n_modes))
            return basins(self.params, initial_states=states, **common)
        common["coordinates"] = self.coordinates
        if self.random is not None:
            return basin_stability(self.params, self.random, self.box, seed=self.seed or 0,
                                   **common)
        axes = tuple(np.linspace(low, high, self.points or BASIN_POINTS)
                     for low, high in self.box)
        return basins(self.params, axes, **common)


def load_basins(path: str | os.PathLike[str]) -> BasinPlan:
    """Read and check the basins file ``path`` (ParameterError naming what is wrong)."""
    data = read_toml(path)
    source = str(path)
    for key in data:
        if key not in _TOP_LEVEL:
            raise unknown_key("top-level key", key, f"{source} (a basins file)", _TOP_LEVEL)
    table = require_table(data, "basins", source)
    for key in table:
        if key not in _KEYS:
            raise unknown_key("key", key, f"[basins] of {source}", _KEYS)
    where = f"[basins] of {source}"
    missing = [key for key in ("axis1", "axis2") if key not in table]
    if missing and "states" not in table:
        raise ParameterError(f"{where} needs axis1 and axis2 (or states): "
                             f"{', '.join(missing)} missing")
    box = None if missing else tuple(
        tuple(float(end) for end in _pair(f"{key} in {where}", table[key], is_real,
                                          "two numbers [LOW, HIGH]"))
        for key in ("axis1", "axis2"))
    files = {key: _path(f"{key} in {where}", table[key], Path(path).parent)
             for key in ("states", "attractors") if key in table}
    counts = {key: _integer(f"{key} in {where}", table[key])
              for key in ("points", "random", "seed", "max_periods") if key in table}
    coordinates = (_pair(f"coordinates in {where}", table["coordinates"], is_integer,
                         "two integer indices [I, J]") if "coordinates" in table else None)
    n_modes = _integer(f"n_modes in {source}", data["n_modes"]) if "n_modes" in data else None
    params = Params.from_mapping(require_table(data, "params", source),
                                 source=f"[params] of {source}")
    plan = BasinPlan(params, box, coordinates=coordinates,  # type: ignore[arg-type]
                     n_modes=n_modes, **counts, **files, name=f"{{}} in {where}")
    return plan.checked()


def _path(where: str, value: Any, folder: Path) -> Path:
    """A file named in the basins file: a non-empty string, relative to the file's folder."""
    require(where, value, isinstance(value, str) and value.strip() != "",
            "must be the path of a file (a string)")
    return folder / Path(value).expanduser()


def _pair(where: str, value: Any, kind: Callable[[Any], bool], allowed: str) -> tuple:
    require(where, value, isinstance(value, list) and len(value) == 2
            and all(kind(item) for item in value), f"must be {allowed}")
    return tuple(value)


def _integer(where: str, value: Any) -> int:
    require(where, value, is_integer(value), "must be an integer")
    return int(value)
