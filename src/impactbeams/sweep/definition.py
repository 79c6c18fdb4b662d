"""What a sweep is: its axes, fixed parameters and observables, read and validated from TOML.

A sweep file (names as in :mod:`impactbeams.params`)::

    t_max = 1.0                          # s, horizon of every cell
    n_modes = 5                          # free modes per beam (contact phase: 2 n_modes)
    observables = ["first_impact_time"]  # default
    transient_periods = 0                # forcing periods left out of long-time observables
    [params]                             # fixed parameters; the rest take the defaults
    clearance = 1.1e-5
    [axes.omega]                         # one table per swept parameter, in order
    min = 10.0
    max = 600.0
    num = 400
    scale = "linear"                     # or "log"
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from impactbeams import __version__
from impactbeams.kernels.layout import CELL_COLUMNS
from impactbeams.params import CONTACT_LAWS, ParameterError, Params, read_toml, require
from impactbeams.variables import PARAMETERS

FIRST_IMPACT = "first_impact_time"
DYNAMICS_OBSERVABLES = ("impact_count", "max_contact_force", "mean_restitution",
                        "contact_fraction")
LYAPUNOV = "lyapunov_exponent"  # spring law only; its own windowed run (kernels.lyapunov)
OBSERVABLES = (FIRST_IMPACT, *DYNAMICS_OBSERVABLES, LYAPUNOV)
# parameters that change a cell but not its geometry (its modes): the packed cell columns
CELL_PARAMETERS = tuple(name for name in CELL_COLUMNS if name != "geometry")
_TOP_LEVEL = ("t_max", "n_modes", "observables", "params", "axes", "transient_periods")
_AXIS_KEYS = ("min", "max", "num", "scale")
_MAX_MODES = 200


@dataclasses.dataclass(frozen=True)
class Axis:
    """One swept parameter: ``num`` values from ``min`` to ``max`` on a linear or log scale.

    The contact law is swept by its names instead (``choices``, scale ``"categorical"``).
    """

    name: str
    min: float
    max: float
    num: int
    scale: str
    choices: tuple[str, ...] = ()

    @property
    def values(self) -> np.ndarray:
        """The axis values, in the parameter's unit."""
        if self.choices:
            return np.array(self.choices)
        if self.num == 1:
            return np.array([self.min])
        space = np.geomspace if self.scale == "log" else np.linspace
        return space(self.min, self.max, self.num)

    def value(self, index: int) -> float | str:
        """The parameter value at ``index`` along the axis (a float, or a law's name)."""
        return self.choices[index] if self.choices else float(self.values[index])

    def definition(self) -> dict[str, Any]:
        """The axis as in the TOML file."""
        if self.choices:
            return {"values": list(self.choices)}
        return {"min": self.min, "max": self.max, "num": self.num, "scale": self.scale}


@dataclasses.dataclass(frozen=True)
class Sweep:
    """A validated sweep definition (see the module docstring)."""

    t_max: float
    n_modes: int
    observables: tuple[str, ...]
    fixed: Mapping[str, Any]
    axes: tuple[Axis, ...]
    source: str = "sweep"
    transient_periods: int = 0

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one entry per axis."""
        return tuple(axis.num for axis in self.axes)

    @property
    def size(self) -> int:
        """Number of cells."""
        return int(np.prod(self.shape))

    @property
    def needs_dynamics(self) -> bool:
        """Whether any observable needs the full dynamics (not the free phase alone)."""
        return any(name in (*DYNAMICS_OBSERVABLES, LYAPUNOV) for name in self.observables)

    @property
    def stored(self) -> list[str]:
        """Arrays a chunk yields: the observables, plus the run status of full-dynamics cells."""
        return [*self.observables, *(["dynamics_status"] if self.needs_dynamics else [])]

    def definition(self) -> dict[str, Any]:
        """The sweep as a plain dict in the TOML file's layout (canonical, for hashing)."""
        transient = {"transient_periods": self.transient_periods} if self.transient_periods else {}
        return {"t_max": self.t_max, "n_modes": self.n_modes,
                "observables": list(self.observables), "params": dict(self.fixed),
                "axes": {a.name: a.definition() for a in self.axes}, **transient}

    @property
    def base(self) -> Params:
        """The fixed parameters (defaults for the rest), before any axis is applied."""
        return Params.from_mapping(self.fixed, source=f"[params] of {self.source}")

    def fingerprint(self) -> str:
        """Hash of the definition and package version: a resumed run must match it."""
        text = json.dumps({"sweep": self.definition(), "version": __version__}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep TOML file; errors name the key and the value."""
    return sweep_from_mapping(read_toml(path), source=str(path))


def sweep_from_mapping(data: Mapping[str, Any], source: str = "sweep") -> Sweep:
    """Validate a sweep given as a mapping in the TOML file's layout."""
    for key in data:
        require(f"{key!r} in {source}", key, key in _TOP_LEVEL,
                f"unknown key; allowed top-level keys: {', '.join(_TOP_LEVEL)}")
    t_max = _number(data.get("t_max", 1.0), f"t_max in {source}")
    require(f"t_max in {source}", t_max, t_max > 0, "must be > 0", "s")
    n_modes = data.get("n_modes", 5)
    require(f"n_modes in {source}", n_modes,
            isinstance(n_modes, int) and not isinstance(n_modes, bool)
            and 1 <= n_modes <= _MAX_MODES, f"must be an integer from 1 to {_MAX_MODES}")
    observables = tuple(data.get("observables", [FIRST_IMPACT]))
    for name in observables:
        require(f"observables in {source}", name, name in OBSERVABLES,
                f"unknown observable; allowed: {', '.join(OBSERVABLES)}")
    require(f"observables in {source}", list(observables), len(observables) > 0,
            "must name at least one observable")
    transient = data.get("transient_periods", 0)
    require(f"transient_periods in {source}", transient,
            isinstance(transient, int) and not isinstance(transient, bool) and transient >= 0,
            "must be an integer >= 0 (forcing periods)")
    fixed = dict(data.get("params", {}))
    base = Params.from_mapping(fixed, source=f"[params] of {source}")
    axes_table = data.get("axes", {})
    require(f"[axes] of {source}", axes_table, isinstance(axes_table, dict) and axes_table,
            "a sweep needs at least one [axes.NAME] table")
    axes = tuple(_axis(name, spec, source) for name, spec in axes_table.items())
    sweep = Sweep(t_max, n_modes, observables, fixed, axes, source, transient)
    _check_grid(sweep, base)
    _check_lyapunov(sweep, base)
    return sweep


def _number(value: Any, name: str) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)
    require(name, value, ok, "must be a finite number")
    return float(value)


def _law_axis(spec: Any, where: str) -> Axis:
    """``[axes.contact_law]`` with ``values = ["tied", "spring"]`` (a subset, in any order)."""
    require(where, spec, isinstance(spec, dict) and set(spec) == {"values"},
            'must be a table with only values = [...], e.g. values = ["tied", "spring"]')
    laws = spec["values"]
    require(f"values in {where}", laws, isinstance(laws, list) and laws
            and all(law in CONTACT_LAWS for law in laws) and len(set(laws)) == len(laws),
            f"must be a list of distinct contact laws from {', '.join(CONTACT_LAWS)}")
    return Axis("contact_law", math.nan, math.nan, len(laws), "categorical", tuple(laws))


def _axis(name: str, spec: Any, source: str) -> Axis:
    where = f"[axes.{name}] of {source}"
    require(where, name, name in PARAMETERS,
            f"unknown parameter; allowed: {', '.join(PARAMETERS)}")
    if name == "contact_law":
        return _law_axis(spec, where)
    require(where, spec, isinstance(spec, dict), "must be a table with min, max, num, scale")
    for key in spec:
        require(f"{key!r} in {where}", key, key in _AXIS_KEYS,
                f"unknown key; allowed: {', '.join(_AXIS_KEYS)}")
    for key in ("min", "max", "num"):
        require(f"{key} in {where}", None, key in spec, "is required")
    lo, hi = _number(spec["min"], f"min in {where}"), _number(spec["max"], f"max in {where}")
    num, scale = spec["num"], spec.get("scale", "linear")
    require(f"num in {where}", num, isinstance(num, int) and not isinstance(num, bool)
            and num >= 1, "must be an integer >= 1")
    require(f"scale in {where}", scale, scale in ("linear", "log"), 'must be "linear" or "log"')
    require(f"max in {where}", hi, hi > lo or (hi == lo and num == 1),
            f"the range [{lo!r}, {hi!r}] is empty or reversed: need max > min "
            "(or max == min with num = 1)")
    if scale == "log":
        require(f"min in {where}", lo, lo > 0, "a log axis needs min > 0")
    return Axis(name, lo, hi, num, scale)


def _check_grid(sweep: Sweep, base: Params) -> None:
    """Reject a grid with any non-physical point before computing anything.

    Single-parameter limits are checked on every axis value; the one joint condition, the
    initial gap clearance + uplift1 - uplift2 > 0, on the whole grid.
    """
    for axis in sweep.axes:
        for index in range(axis.num):
            try:
                base.replace(**{axis.name: axis.value(index)})
            except ParameterError as error:
                raise ParameterError(f"axis {axis.name!r} of {sweep.source} reaches a "
                                     f"non-physical point: {error}") from None
    grids = {name: _cell_grid(sweep, base, name) for name in ("clearance", "uplift1", "uplift2")}
    gap = grids["clearance"] + grids["uplift1"] - grids["uplift2"]
    if np.any(gap <= 0):
        bad = np.unravel_index(np.argmin(gap), gap.shape)
        point = {a.name: a.value(i) for a, i in zip(sweep.axes, bad, strict=True)}
        raise ParameterError(f"the grid of {sweep.source} has points where the initial gap "
                             f"clearance + uplift1 - uplift2 <= 0, e.g. at {point}")


def _check_lyapunov(sweep: Sweep, base: Params) -> None:
    """The Lyapunov exponent is defined for the spring law only (docs/model.md)."""
    if LYAPUNOV not in sweep.observables:
        return
    laws = [axis.choices for axis in sweep.axes if axis.name == "contact_law"]
    require(f"observables in {sweep.source}", LYAPUNOV,
            set(laws[0] if laws else [base.contact_law]) == {"spring"},
            "needs the spring contact law on every cell (the tied law's projections and "
            "instantaneous impacts are not a flow whose linearisation converges in n_modes)")


def _cell_grid(sweep: Sweep, base: Params, name: str) -> np.ndarray:
    """Per-cell values of the cell parameter ``name``, broadcast to the grid shape."""
    grid = np.full(sweep.shape, getattr(base, name))
    for k, axis in enumerate(sweep.axes):
        if axis.name == name:
            shape = [1] * len(sweep.axes)
            shape[k] = axis.num
            grid = np.broadcast_to(axis.values.reshape(shape), sweep.shape).copy()
    return grid
