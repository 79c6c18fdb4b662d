"""What a sweep is: its axes, fixed parameters and observables, read and validated from TOML.

A sweep file (names as in `impactbeams.params`)::

    t_max = 1.0                          # s, horizon of every cell
    n_modes = 5                          # free modes per beam (contact phase: 2 n_modes)
    observables = ["first_impact_time"]  # default
    transient_periods = 0                # forcing periods left out (Lyapunov, long-time only)
    sampled_periods = 200                # stroboscopic samples (long-time observables only)
    period_tolerance = 1e-4              # of the period detection (module longtime)
    max_period = 16
    stepping = "both"                    # stepped-sine rows: "up", "down", "both" (long-time)
    stepped_axis = "omega"               # the axis they step along (default omega)
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
import itertools
import json
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from impactbeams import __version__
from impactbeams.configuration import LAWS, ContactLaw, counterpart_named
from impactbeams.kernels.layout import CELL_COLUMNS
from impactbeams.longtime import LongTime, Stepping
from impactbeams.params import (
    ATTACHMENT_FIELDS,
    ATTACHMENTS,
    BEAM_SEGMENTS,
    CHOICES,
    CONTACT_FIELDS,
    CONTACT_LAW_KEYS,
    CONTACT_LAWS,
    CONTACT_POSITIONS,
    CONTACTS,
    MATERIAL_KEYS,
    MAX_MODES,
    PART_FIELDS,
    USER_STRUCTURE,
    ParameterError,
    Params,
    PointName,
    attachment_field,
    check_joint,
    check_parameter,
    check_range,
    contact_field,
    flat_parameter,
    fold_contacts,
    is_integer,
    is_path,
    is_real,
    no_point,
    part_field,
    read_toml,
    refuse_beam2,
    refuse_unused_law_keys,
    require,
    require_all,
    require_table,
    require_type,
    resolve_materials,
    unknown_key,
    value_at,
    with_element_fields,
)
from impactbeams.preflight import (
    MAX_PHASE,
    check_run,
    highest_frequency,
    require_memory,
)
from impactbeams.structure.contacts import FLAT_KEYS, Contact
from impactbeams.structure.parts import SEGMENT_UNITS
from impactbeams.variables import (
    LONG_TIME_VARIABLES,
    PARAMETERS,
    POINCARE_VARIABLES,
    VARIABLES,
    parameter_text,
)

FIRST_IMPACT = "first_impact_time"
FIRST_CONTACT = "first_contact"  # several contacts: which one closes first
DYNAMICS_OBSERVABLES = ("impact_count", "max_contact_force", "mean_restitution",
                        "contact_fraction")
# several contacts: each contact's share of the full dynamics (along "contact")
CONTACT_OBSERVABLES = ("contact_impact_count", "contact_max_force")
LYAPUNOV = "lyapunov_exponent"  # spring law only; its own windowed run (kernels.lyapunov)
# the long run's stroboscopic samples (along a trailing dimension "period") and what they give
POINCARE_OBSERVABLES = POINCARE_VARIABLES
LONG_TIME_OBSERVABLES = LONG_TIME_VARIABLES
OBSERVABLES = (FIRST_IMPACT, *DYNAMICS_OBSERVABLES, *CONTACT_OBSERVABLES, LYAPUNOV,
               *LONG_TIME_OBSERVABLES)
# parameters that change a cell but not its geometry (its modes): the packed cell columns
CELL_PARAMETERS = tuple(name for name in CELL_COLUMNS if name != "geometry")
LONG_TIME_KEYS = ("sampled_periods", "period_tolerance", "max_period")  # of LongTime
STEPPING_KEYS = ("stepping", "stepped_axis")  # of Stepping
# a stepped sweep's cells' end states (modal, on the section at the horizon): restart points
STEPPED_END_STATE = ("final_displacement", "final_velocity")
_TOP_LEVEL = ("t_max", "n_modes", "observables", "params", "axes", "transient_periods",
              *LONG_TIME_KEYS, *STEPPING_KEYS)
_AXIS_KEYS = ("min", "max", "num", "scale")
# Distinct geometries (values of the axes that change the modes) per sweep: each one's modes are
# computed serially before the map runs, 0.4 ms (5 modes, first impact) to 2 s (200 modes, tied
# dynamics) each (docs/limits.md).
MAX_GEOMETRIES = 10_000
MAX_SEGMENTS = 100_000  # phases per cell (per forcing period for the Lyapunov exponent's
# windowed run) in a full-dynamics sweep; more: dynamics_status = 1
# a long run holds this many segments at once (4 arrays of 2 n_modes floats each, per thread)
LONG_RUN_CAPACITY = 2048


EXACT_VALUES = 2**20  # the longest axis whose values Axis.value builds
# an axis on one field of one of several contacts: "contacts.0.clearance" (in a sweep file
# [axes."contacts.0.clearance"]); its values are that contact's field's, in the flat key's unit
CONTACT_AXIS = CONTACTS + ".{index}.{field}"
# an axis on one field of one part a beam carries or of one of its segments:
# "attachments1.0.mass", "segments1.0.EI" (its unit the field's)
ATTACHMENT_AXIS = "{which}.{index}.{field}"
# the contact fields an axis may sweep: its point on each beam and its law's (its side is a
# name); a point moves the contact's gap weights: a geometry axis
SWEPT_CONTACT_FIELDS = tuple(field for field, key in FLAT_KEYS.items()
                             if key in (*CONTACT_LAW_KEYS, *CONTACT_POSITIONS))


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

    @property
    def first(self) -> float | str:
        """The first value, without computing the others (linspace and geomspace start at min)."""
        return self.choices[0] if self.choices else self.min

    def value(self, index: int) -> float | str:
        """The parameter value at ``index`` along the axis (a float, or a law's name).

        Exactly ``values[index]``; on an axis too long to build (more than ``EXACT_VALUES``
        values, only ever sampled by the cost estimate), from the spacing's formula.
        """
        if self.choices:
            return self.choices[index]
        if self.num <= EXACT_VALUES:
            return float(self.values[index])
        share = index / (self.num - 1)
        if self.scale == "log":
            return self.min * (self.max / self.min) ** share
        return self.min + (self.max - self.min) * share

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
    long_time: LongTime | None = None  # how long-time observables sample the run
    stepping: Stepping | None = None  # stepped-sine rows instead of independent cells

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one entry per axis; a stepped sweep's rows' directions first."""
        directions = (len(self.stepping.directions),) if self.stepping else ()
        return (*directions, *(axis.num for axis in self.axes))

    @property
    def stepped_dimension(self) -> int | None:
        """The position in ``shape`` of the axis a stepped sweep steps along (None if not)."""
        if self.stepping is None:
            return None
        return 1 + [axis.name for axis in self.axes].index(self.stepping.axis)

    @property
    def size(self) -> int:
        """Number of cells."""
        return math.prod(self.shape)

    @property
    def needs_dynamics(self) -> bool:
        """Whether any observable needs the full dynamics (not the free phase alone)."""
        return (any(name in (*DYNAMICS_OBSERVABLES, *CONTACT_OBSERVABLES, LYAPUNOV)
                    for name in self.observables) or self.long_time is not None)

    def value_shape(self, name: str) -> tuple[int, ...]:
        """Shape of one cell's value of stored array ``name``, e.g. (sampled periods,) or ().

        Its registered dimensions after the grid's (variables.VARIABLES), here ``period``,
        ``coordinate`` or ``contact`` (several contacts).
        """
        lengths = {"period": self.long_time.sampled_periods} if self.long_time else {}
        lengths["coordinate"] = self.free_coordinates
        lengths["contact"] = len(self.fixed.get(CONTACTS, ()))
        return tuple(lengths[dim] for dim in VARIABLES[name].dims[1:])

    @property
    def free_coordinates(self) -> int:
        """N, the free modal coordinates of a cell: n_modes per beam (beam 1 only at a stop)."""
        return self.n_modes * self.base.partner.beams

    @property
    def stored(self) -> list[str]:
        """Arrays a chunk yields: the observables, the status of full-dynamics runs, end states.

        The end states (``STEPPED_END_STATE``) are a stepped sweep's only; ``first_contact``
        a sweep's of several contacts (whose ``[params]`` keep ``contacts`` only then).
        """
        return [*self.observables, *(["dynamics_status"] if self.needs_dynamics else []),
                *([FIRST_CONTACT] if CONTACTS in self.fixed else []),
                *(STEPPED_END_STATE if self.stepping is not None else ())]

    def definition(self) -> dict[str, Any]:
        """The sweep as a plain dict in the TOML file's layout (canonical, for hashing)."""
        transient = {"transient_periods": self.transient_periods} if self.transient_periods else {}
        long_time = ({} if self.long_time is None else
                     {key: getattr(self.long_time, key) for key in LONG_TIME_KEYS})
        stepping = ({} if self.stepping is None else
                    {"stepping": self.stepping.direction, "stepped_axis": self.stepping.axis})
        return {"t_max": self.t_max, "n_modes": self.n_modes,
                "observables": list(self.observables),
                "params": {name: parameter_text(value) for name, value in self.fixed.items()},
                "axes": {a.name: a.definition() for a in self.axes}, **transient, **long_time,
                **stepping}

    @property
    def base(self) -> Params:
        """The parameters of the grid's first point: every axis at its first value."""
        return self.params_at({})

    def params_at(self, changes: Mapping[str, Any]) -> Params:
        """The parameters of the grid point with the swept ``changes`` (name: value).

        The other axes are at their first values; the fixed parameters, then the defaults, fill
        the rest.
        """
        first = {axis.name: axis.first for axis in self.axes}
        return Params.from_mapping(with_element_fields({**self.fixed, **first, **changes}),
                                   source=f"[params] of {self.source}")

    def fingerprint(self) -> str:
        """Hash of the definition and package version: a resumed run must match it."""
        text = json.dumps({"sweep": self.definition(), "version": __version__}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def load_sweep(path: str | os.PathLike[str]) -> Sweep:
    """Read and validate a sweep TOML file; errors name the key and the value."""
    return sweep_from_mapping(read_toml(path), source=str(path))


def as_sweep(sweep: Sweep | str | os.PathLike[str]) -> Sweep:
    """``sweep`` itself, or the sweep file at that path, loaded by [`load_sweep`][]."""
    if isinstance(sweep, Sweep):
        return sweep
    require_type("sweep", sweep, is_path(sweep),
                 "a Sweep (load_sweep, sweep_from_mapping) or the path of a sweep TOML file")
    return load_sweep(sweep)


def sweep_from_mapping(data: Mapping[str, Any], source: str = "sweep") -> Sweep:
    """Validate a sweep given as a mapping in the TOML file's layout.

    Everything is checked before anything is computed, vectorised over the axes (no per-cell
    work): keys, types, every axis value, conflicts, every grid point's parameters (at the
    corners of the grid, which suffices: every condition is monotone in each parameter), the
    modes and horizon, and the expected memory. NumPy scalars are taken as Python numbers.
    """
    require_type("data", data, isinstance(data, Mapping),
                 "a mapping in the sweep file's layout, e.g. tomllib.load of a sweep file")
    require_type("source", source, isinstance(source, str), "a str naming the sweep in messages")
    for key in data:
        if key not in _TOP_LEVEL:
            raise unknown_key("top-level key", key, source, _TOP_LEVEL)
    t_max = _number(data.get("t_max", 1.0), f"t_max in {source}")
    require(f"t_max in {source}", t_max, t_max > 0, "must be > 0", "s")
    n_modes = data.get("n_modes", 5)
    require(f"n_modes in {source}", n_modes, is_integer(n_modes) and 1 <= n_modes <= MAX_MODES,
            f"must be an integer from 1 to {MAX_MODES}")
    observables = _observables(data.get("observables", [FIRST_IMPACT]), source)
    transient = _transient_periods(data, observables, source)
    # one contact given as a table is its flat keys (`impactbeams.params.fold_contacts`)
    given = require_table(data, "params", source)
    fixed = fold_contacts({name: _plain(value) for name, value in given.items()},
                          f"[params] of {source}")
    axes_table = _flat_axes(require_table(data, "axes", source), source)
    require(f"[axes] of {source}", axes_table, bool(axes_table),
            "a sweep needs at least one [axes.NAME] table")
    axes = tuple(_axis(name, spec, source) for name, spec in axes_table.items())
    _check_conflicts(fixed, axes, source)
    _check_contact_axes(fixed, axes, source)
    _check_part_axes(fixed, axes, source)
    if not counterpart_named(fixed.get("counterpart")).has_beam2:  # its keys are mistakes
        refuse_beam2(fixed, f"[params] of {source}")
        refuse_beam2([axis.name for axis in axes], f"[axes] of {source}")
    long_time = _long_time(data, observables, source)
    sweep = Sweep(t_max, int(n_modes), observables, fixed, axes, source, transient, long_time,
                  _stepping(data, long_time, axes, source))
    _check_grid(sweep)
    _check_lyapunov(sweep)
    _check_cost(sweep)
    return sweep


def _flat_axes(table: dict[str, Any], source: str) -> dict[str, Any]:
    """``table`` with the unquoted TOML form of contact axes read as their names.

    ``[axes.contacts.0.clearance]`` is nested tables (contacts, an index, a field): the axis
    ``contacts.0.clearance``. A contact's axes so written take the place of the first of them.
    """
    nested = table.get(CONTACTS)
    if not (isinstance(nested, dict) and nested and all(
            isinstance(index, str) and index.isdigit() and isinstance(fields, dict)
            for index, fields in nested.items())):
        return table
    flat: dict[str, Any] = {}
    for name, spec in table.items():
        named = ({name: spec} if name != CONTACTS else
                 {CONTACT_AXIS.format(index=index, field=field): axis
                  for index, fields in spec.items() for field, axis in fields.items()})
        for key, axis in named.items():
            require(f"[axes] of {source}", key, key not in flat,
                    f"names the axis {key!r} twice (quoted and as nested tables): give it once")
            flat[key] = axis
    return flat


def _contact_axis(name: str, where: str) -> str:
    """The flat key whose range a ``contacts.INDEX.FIELD`` axis takes (its form checked)."""
    field = contact_field(name)
    example = CONTACT_AXIS.format(index=0, field="clearance")
    require(where, name, field is not None,
            f"an axis on a contact's field is named contacts.INDEX.FIELD, e.g. {example!r} "
            "(INDEX: the contact's place in [[params.contacts]], from 0)")
    index, name_of_field = field
    if name_of_field in SWEPT_CONTACT_FIELDS:
        return FLAT_KEYS[name_of_field]
    if name_of_field in FLAT_KEYS:
        raise ParameterError(
            f"{where} = {name!r} is not allowed: a contact's {name_of_field} is not sweepable "
            f"(give it in the contact: one sweep per side); sweepable: "
            f"{', '.join(SWEPT_CONTACT_FIELDS)}")
    raise unknown_key("contact field", name_of_field, where, SWEPT_CONTACT_FIELDS)


def _part_axis(name: str, where: str) -> None:
    """Refuse an ``attachments1.INDEX.FIELD`` (``segments1``) axis not on a part's field."""
    field, which = part_field(name), name.split(".")[0]
    kind, fields = (("attachment", ATTACHMENT_FIELDS) if which in ATTACHMENTS
                    else ("segment", SEGMENT_UNITS))
    example = "mass" if which in ATTACHMENTS else "EI"
    require(where, name, field is not None,
            f"an axis on {'an' if which in ATTACHMENTS else 'a'} {kind}'s field is named "
            f"{which}.INDEX.FIELD, e.g. "
            f"{ATTACHMENT_AXIS.format(which=which, index=0, field=example)!r} (INDEX: the "
            f"{'part' if which in ATTACHMENTS else kind}'s place in that array of tables, "
            "from 0)")
    if field[2] not in fields:
        raise unknown_key(f"{kind} field", field[2], where, fields)


def _check_part_axes(fixed: Mapping[str, Any], axes: tuple[Axis, ...], source: str) -> None:
    """Refuse an axis on a part's (a segment's) field beyond them, not its, or given twice.

    The field must be left out of the part's table (a part built in Python gives them all:
    give it as a table to sweep one of its fields); the table, with it, must be a part.
    """
    for axis in axes:
        field = part_field(axis.name)
        if field is None:
            continue
        which, index, name = field
        where = f"{axis_table(axis.name)} of {source}"
        parts = fixed.get(which, ())
        count = len(parts) if isinstance(parts, (list, tuple)) else 0  # (Params checks it)
        require(where, axis.name, index < count, f"there are {count} parts in {which} of "
                "[params]" + (f" (indices 0 to {count - 1})" if count else ""))
        part = parts[index]
        if not isinstance(part, dict):  # a part: it gives every field it has
            fields = PART_FIELDS.get(type(part), {})
            table = {key: getattr(part, key) for key in fields if key != name}
            raise ParameterError(
                f"{where} = {axis.name!r} is not allowed: {which}[{index}] = {part!r} " + (
                    f"gives its {name}: give the part as a table without it to sweep it, "
                    f"e.g. {table}" if name in fields else f"has no field {name!r}"))
        if name in part:
            raise ParameterError(
                f"{where} = {axis.name!r} is not allowed: is given both in [params] ({which}"
                f"[{index}].{name} = {part[name]!r}) and as an axis: remove one of them")
    swept = {axis.name: axis.num for axis in axes if part_field(axis.name) is not None}
    require(f"[axes] of {source}", swept, math.prod(swept.values()) <= MAX_GEOMETRIES,
            f"the parts' axes give {math.prod(swept.values())} geometries, each checked as "
            f"parameters (up to 1 ms) before its modes are built: at most {MAX_GEOMETRIES}")


def _check_contact_axes(fixed: Mapping[str, Any], axes: tuple[Axis, ...], source: str) -> None:
    """Refuse an axis on a contact's field without several contacts, or the index, or given twice.

    The field must be left out of the contact (else it would be given twice), and no flat law
    key may be left to no contact once the axes set theirs (`refuse_unused_law_keys`).
    """
    contacts = fixed.get(CONTACTS, ())
    for axis in axes:
        field = contact_field(axis.name)
        if field is None:
            continue
        index, name = field
        where = f"{axis_table(axis.name)} of {source}"
        require(where, axis.name, len(contacts) >= 2,
                "sweeps a field of one of several contacts, and [params] has fewer than two "
                f"([[params.contacts]]): one contact is the flat keys, sweep [axes."
                f"{FLAT_KEYS[name]}]")
        require(where, axis.name, index < len(contacts),
                f"there are {len(contacts)} contacts in [params] (indices 0 to "
                f"{len(contacts) - 1})")
        given = getattr(contacts[index], name)
        require(where, axis.name, given is None,
                f"is given both in [params] ({CONTACTS}[{index}].{name} = {given!r}) and as an "
                "axis: remove one of them")
    swept = [axis.name for axis in axes if contact_field(axis.name) is not None]
    if swept:  # a flat law key used by no contact once the axes set theirs
        refuse_unused_law_keys(fixed, with_element_fields(
            {**fixed, **dict.fromkeys(swept, 1.0)})[CONTACTS], f"[params] of {source}")


def _transient_periods(data: Mapping[str, Any], observables: tuple[str, ...], source: str) -> int:
    """The forcing periods left out: given only with an observable that leaves them out."""
    where = f"transient_periods in {source}"
    if "transient_periods" not in data:
        return 0
    transient = data["transient_periods"]
    users = (LYAPUNOV, *LONG_TIME_OBSERVABLES)
    require(where, transient, any(name in users for name in observables),
            f"only {', '.join(users)} use it (observables here: {', '.join(observables)})")
    require(where, transient, is_integer(transient) and transient >= 0,
            "must be an integer >= 0 (forcing periods)")
    return int(transient)


def _plain(value: Any) -> Any:
    """A NumPy scalar as the Python number it holds (the definition is hashed as JSON)."""
    return value.item() if isinstance(value, np.generic) else value


def _long_time(data: Mapping[str, Any], observables: tuple[str, ...],
               source: str) -> LongTime | None:
    """The long-time sampling: its keys only with a long-time observable, defaults for the rest."""
    given = {key: data[key] for key in LONG_TIME_KEYS if key in data}
    if not any(name in LONG_TIME_OBSERVABLES for name in observables):
        require(f"{', '.join(given)} in {source}", list(given.values()), not given,
                "only long-time observables use it: "
                f"{', '.join(LONG_TIME_OBSERVABLES)}")
        return None
    try:
        return LongTime(**given)
    except ParameterError as error:
        raise ParameterError(f"{error} (in {source})") from None


def _stepping(data: Mapping[str, Any], long_time: LongTime | None, axes: tuple[Axis, ...],
              source: str) -> Stepping | None:
    """Stepped-sine rows: only for long-time observables, along a swept drive axis."""
    given = {key: data[key] for key in STEPPING_KEYS if key in data}
    if not given:
        return None
    keys = ", ".join(given)
    require(f"{keys} in {source}", list(given.values()), long_time is not None,
            "stepped-sine sweeps carry a long run's state: only long-time observables use it "
            f"({', '.join(LONG_TIME_OBSERVABLES)})")
    require(f"stepped_axis in {source}", given.get("stepped_axis"), "stepping" in given,
            'needs stepping = "up", "down" or "both"')
    try:
        stepping = Stepping(given["stepping"], given.get("stepped_axis", "omega"))
    except ParameterError as error:
        raise ParameterError(f"{error} (in {source})") from None
    swept = [axis.name for axis in axes]
    require(f"stepped_axis in {source}", stepping.axis, stepping.axis in swept,
            f"is not swept: step along one of the swept axes ({', '.join(swept)}), given by "
            "stepped_axis, or add [axes." + stepping.axis + "]")
    return stepping


def _number(value: Any, name: str) -> float:
    require(name, value, is_real(value) and math.isfinite(value), "must be a finite number")
    return float(value)


def _observables(value: Any, source: str) -> tuple[str, ...]:
    where = f"observables in {source}"
    require(where, value, isinstance(value, list) and bool(value),
            f'must be a non-empty list of names, e.g. ["{FIRST_IMPACT}"]')
    for name in value:
        if name not in OBSERVABLES:
            raise unknown_key("observable", name, f"the observables of {source}", OBSERVABLES)
    require(where, value, len(set(value)) == len(value), "must name each observable once")
    return tuple(value)


def _law_axis(spec: Any, where: str) -> Axis:
    """``[axes.contact_law]`` with ``values = ["tied", "spring"]`` (a subset, in any order)."""
    require(where, spec, isinstance(spec, dict) and set(spec) == {"values"},
            'must be a table with only values = [...], e.g. values = ["tied", "spring"]')
    laws = spec["values"]
    require(f"values in {where}", laws, isinstance(laws, list) and laws
            and all(law in CONTACT_LAWS for law in laws) and len(set(laws)) == len(laws),
            f"must be a list of distinct contact laws from {', '.join(CONTACT_LAWS)}")
    return Axis("contact_law", math.nan, math.nan, len(laws), "categorical", tuple(laws))


def axis_table(name: str) -> str:
    """The sweep file's table of the axis ``name``: ``[axes.omega]``, ``[axes."contacts.0.x"]``."""
    return f'[axes."{name}"]' if "." in name else f"[axes.{name}]"


def _axis(name: str, spec: Any, source: str) -> Axis:
    where = f"{axis_table(name)} of {source}"
    require(where, name, name not in ATTACHMENTS, f"{name} is not sweepable: give a beam's "
            "parts in [params], and sweep one part's field as "
            f"[axes.\"{ATTACHMENT_AXIS.format(which=name, index=0, field='mass')}\"]")
    require(where, name, name not in BEAM_SEGMENTS, f"{name} is not sweepable: give a beam's "
            "segments in [params], and sweep one segment's field as "
            f"[axes.\"{ATTACHMENT_AXIS.format(which=name, index=0, field='EI')}\"]")
    require(where, name, name != CONTACTS, f"{name} is not sweepable: give the contacts in "
            "[params] (one sweep per set of contacts), and sweep a contact's field as "
            f"[axes.\"{CONTACT_AXIS.format(index=0, field='clearance')}\"]")
    if name.startswith(CONTACTS + "."):
        _contact_axis(name, where)
        return _numeric_axis(name, spec, where, source)
    if name.split(".")[0] in (*ATTACHMENTS, *BEAM_SEGMENTS):
        _part_axis(name, where)
        return _numeric_axis(name, spec, where, source)
    require(where, name, name != USER_STRUCTURE, f"{name} is not sweepable: give the "
            "structure in [params] (one sweep per structure)")
    if name not in PARAMETERS:
        raise unknown_key("parameter", name, f"[axes] of {source}", PARAMETERS)
    if name == "contact_law":
        return _law_axis(spec, where)
    require(where, name, name not in CHOICES,  # a name, not a number: only the law is swept
            f"{name} is not sweepable: give it in [params] (one sweep per {name})")
    return _numeric_axis(name, spec, where, source)


def _numeric_axis(name: str, spec: Any, where: str, source: str) -> Axis:
    """Axis ``name`` over values of that parameter (its allowed range) from its table ``spec``."""
    require(where, spec, isinstance(spec, dict), "must be a table with min, max, num, scale")
    for key in spec:
        if key not in _AXIS_KEYS:
            raise unknown_key("key", key, where, _AXIS_KEYS)
    for key in ("min", "max", "num"):
        require(f"{key} in {where}", None, key in spec, "is required")
    lo, hi = _number(spec["min"], f"min in {where}"), _number(spec["max"], f"max in {where}")
    num, scale = spec["num"], spec.get("scale", "linear")
    require(f"num in {where}", num, is_integer(num) and num >= 1, "must be an integer >= 1")
    require(f"scale in {where}", scale, scale in ("linear", "log"), 'must be "linear" or "log"')
    require(f"max in {where}", hi, hi > lo or (hi == lo and num == 1),
            f"the range [{lo!r}, {hi!r}] is empty or reversed: need max > min "
            "(or max == min with num = 1)")
    require(f"num in {where}", num, num > 1 or hi == lo,
            f"one value cannot span [{lo!r}, {hi!r}]: give num >= 2, or max = min")
    if scale == "log":
        require(f"min in {where}", lo, lo > 0, "a log axis needs min > 0")
    # the values run monotonically from min to max (both exact): checking the ends suffices
    check_parameter(name, np.array([lo, hi]),
                    lambda index: f"axis {name!r} of {source} reaches a non-physical point: ")
    return Axis(name, lo, hi, int(num), scale)


def _check_conflicts(fixed: Mapping[str, Any], axes: tuple[Axis, ...], source: str) -> None:
    """Refuse a parameter given twice: fixed and swept, or a beam by EI/rhoA and by material."""
    swept = {axis.name for axis in axes}
    for name in sorted(swept & set(fixed)):
        raise ParameterError(f"{name} is given both in [params] ({name} = {fixed[name]!r}) and "
                             f"as [axes.{name}] of {source}: remove one of them")
    given = {**{name: "[params]" for name in fixed}, **{name: "[axes]" for name in swept}}
    for i in ("1", "2"):
        beam = [key + i for key in ("l", "EI", "rhoA", *MATERIAL_KEYS) if key + i in swept]
        if fixed.get("segments" + i) and beam:
            raise ParameterError(
                f"[axes.{beam[0]}] of {source} is not allowed with segments{i} in [params]: the "
                f"segments give beam {i}'s length, EI and rhoA (one sweep per stepped beam)")
        direct = [k + i for k in ("EI", "rhoA") if k + i in given]
        material = [k + i for k in MATERIAL_KEYS if k + i in given]
        if direct and material:
            where = lambda names: ", ".join(f"{n} ({given[n]})" for n in names)  # noqa: E731
            raise ParameterError(
                f"beam {i} of {source} is given both by {where(direct)} and by the material "
                f"keys {where(material)}, which replace EI{i} and rhoA{i}: give one or the other")


def _corners(sweep: Sweep) -> tuple[dict[str, Any], PointName]:
    """Every numeric parameter on the grid's corners, and a namer of the corner points.

    Axis ``k`` varies along dimension ``k`` over its two ends (one value if num = 1); fixed
    parameters are scalars, the others take the defaults. Material keys are resolved.
    """
    dims = len(sweep.axes)
    ends = []
    values: dict[str, Any] = {name: value for name, value in sweep.fixed.items()
                              if name not in CHOICES and name not in ATTACHMENTS
                              and name not in BEAM_SEGMENTS and name != USER_STRUCTURE
                              and name not in CONTACT_POSITIONS}
    for k, axis in enumerate(sweep.axes):
        axis_ends = np.array([axis.min, axis.max] if axis.num > 1 and not axis.choices
                             else [axis.min])
        ends.append(axis_ends)
        if not axis.choices and part_field(axis.name) is None:  # (a part: `_check_points`)
            values[axis.name] = axis_ends.reshape([-1 if d == k else 1 for d in range(dims)])

    def point(index: tuple[int, ...]) -> str:
        # a condition alike along the leading axes has fewer dimensions (NumPy's trailing
        # alignment): name the axes it depends on, or none if it fails everywhere
        depends = slice(dims - len(index), dims)
        named = ", ".join(f"{axis.name} = {float(axis_ends[min(i, axis_ends.size - 1)])!r}"
                          for axis, axis_ends, i in zip(sweep.axes[depends], ends[depends],
                                                        index, strict=True)
                          if not axis.choices)
        return (f"at the grid point {named} of {sweep.source}: " if named
                else f"at every grid point of {sweep.source}: ")

    resolved = resolve_materials(values, f"[params] of {sweep.source}", point)
    defaults = Params().numeric()
    # a stepped beam's (one segment's too) or a user structure's l, EI, rhoA: the first
    # point's (a segment's axis: `_check_points`)
    given = [key + i for i in ("1", "2") if sweep.fixed.get("segments" + i)
             for key in ("l", "EI", "rhoA")]
    derived = {name: getattr(sweep.base, name) for name in (*sweep.base.derived_keys(), *given)}
    return {**defaults, **derived, **resolved}, point


def contact_sweeps(sweep: Sweep) -> tuple[Sweep, ...]:
    """Each contact's own sweep: ``sweep`` with that contact of ``contacts`` alone (flat keys).

    The first contact among several is, cell by cell, the earliest of these sweeps' first
    impacts (`impactbeams.trajectory.several`): the free phase does not depend on the contacts.
    A contact's sweep has the axes that change its run (`contact_axes`): the axes on its own
    fields as their flat keys (``contacts.1.clearance`` is its ``clearance``), not those on
    another contact's; with none left, one axis of one value, its clearance.
    """
    return tuple(_contact_sweep(sweep, index, contact)
                 for index, contact in enumerate(sweep.fixed[CONTACTS]))


def contact_axes(sweep: Sweep, index: int) -> tuple[int, ...]:
    """Positions of ``sweep``'s axes that change contact ``index``'s run.

    All but the axes on the other contacts' fields.
    """
    fields = [contact_field(axis.name) for axis in sweep.axes]
    return tuple(k for k, field in enumerate(fields) if field is None or field[0] == index)


def _contact_sweep(sweep: Sweep, index: int, contact: Contact) -> Sweep:
    axes = tuple(dataclasses.replace(sweep.axes[k], name=flat_parameter(sweep.axes[k].name))
                 for k in contact_axes(sweep, index))
    # one contact's run has no per-contact observables (its own are impact_count, ...)
    observables = tuple(name for name in sweep.observables
                        if name not in CONTACT_OBSERVABLES) or (FIRST_IMPACT,)
    swept = {axis.name for axis in axes}
    fixed = {name: value for name, value in {**sweep.fixed, **contact.flat()}.items()
             if name != CONTACTS and name not in swept}
    if not axes:  # its run is the same in every cell: a grid of one cell
        clearance = sweep.base.each_contact()[index].clearance
        axes = (Axis("clearance", clearance, clearance, 1, "linear"),)
        fixed.pop("clearance", None)
    return dataclasses.replace(sweep, fixed=fixed, axes=axes, observables=observables,
                               source=f"{sweep.source}, {CONTACTS}[{index}]",
                               stepping=_contact_stepping(sweep, index))


def _contact_stepping(sweep: Sweep, index: int) -> Stepping | None:
    """Contact ``index``'s own sweep's stepping: along its name of the stepped axis, if kept.

    (That sweep is checked and planned, never stepped: `plan._several_dynamics` steps the
    sweep of several contacts.)
    """
    stepping = sweep.stepping
    kept = [sweep.axes[k].name for k in contact_axes(sweep, index)]
    if stepping is None or stepping.axis not in kept:
        return None
    return dataclasses.replace(stepping, axis=flat_parameter(stepping.axis))


def _check_several(sweep: Sweep) -> None:
    """Refuse what a sweep of several contacts cannot do yet: one line, before any work.

    It maps the first contact among them (``first_impact_time``), the full dynamics'
    observables (``DYNAMICS_OBSERVABLES``), the Lyapunov exponent and the long-time ones,
    stepped or not, and sweeps no flat contact key (each contact has its own: which one an axis
    would change is not said; an axis ``contacts.INDEX.FIELD`` says it).
    """
    for axis in sweep.axes:
        require(f"[axes.{axis.name}] of {sweep.source}", axis.name,
                axis.name not in CONTACT_FIELDS,
                f"{axis.name} is not sweepable with {CONTACTS}: each contact has its own; "
                f"sweep one contact's as [axes.\"{CONTACTS}.INDEX.FIELD\"] (INDEX from 0; "
                f"FIELD one of {', '.join(SWEPT_CONTACT_FIELDS)}), its side one sweep each")


def _check_points(sweep: Sweep) -> None:
    """With an axis on a contact's point or a part's field, grid points as parameters (checked).

    Where a contact point may lie (0 < x <= l) and the initial gap there (its unit tip-load
    shape is monotone in x and in l) hold on the whole grid if they hold at its corners; the
    corner grid's joint check (`_corners`) sees one point per contact, not the axis. The axis
    is a flat key (``contact_position1``: the one contact's) or one contact's field. A part's
    rules (on its beam; the tip compliance the drive's check reads, not monotone in a
    rotational spring's place) are checked at every value of its axis, the other axes at
    their ends; so are a segment's, and there the modes and horizon too (its beam's l, EI,
    rhoA and frequency bound, which the corners take from the first point, move with it).
    """
    if not any(flat_parameter(axis.name) in CONTACT_POSITIONS
               or part_field(axis.name) is not None for axis in sweep.axes):
        return
    values = [axis.values if part_field(axis.name) is not None
              else (axis.first,) if axis.choices or axis.num == 1 else (axis.min, axis.max)
              for axis in sweep.axes]
    stepped = any(axis.name.split(".")[0] in BEAM_SEGMENTS for axis in sweep.axes)
    springs = _grounded_springs(sweep) if stepped else 0  # (the grid's most: once)
    for point in itertools.product(*values):
        changes = {axis.name: _plain(value)
                   for axis, value in zip(sweep.axes, point, strict=True)}
        try:
            params = sweep.params_at(changes)
            if stepped:
                check_run(params.numeric(), sweep.t_max, sweep.n_modes,
                          springs=springs, structure1=params.structure1,
                          steps=params.step_factors)
                _check_long_time(sweep, params.numeric(), no_point, params.step_factors)
        except ParameterError as error:
            named = ", ".join(f"{name} = {value!r}" for name, value in changes.items())
            raise ParameterError(f"at the grid point {named} of {sweep.source}: {error}"
                                 ) from None


def _check_grid(sweep: Sweep) -> None:
    """Reject a grid with any non-physical point before computing anything.

    The fixed parameters are checked at the grid's first point (names, types, values); every
    condition on several parameters, and the modes and horizon, at all corners of the grid.
    """
    if CONTACTS in sweep.fixed:  # (one contact given as a table is folded to the flat keys)
        _check_several(sweep)
        _check_points(sweep)
        for each in contact_sweeps(sweep):
            _check_grid(each)
        return
    given = [name for name in sweep.observables if name in CONTACT_OBSERVABLES]
    require(f"observables in {sweep.source}", given, not given,
            "each contact's share is a map of several contacts' ([[params.contacts]]); with "
            "one contact map impact_count and max_contact_force")
    _check_points(sweep)
    values, point = _corners(sweep)
    for name in ("EI1", "EI2", "rhoA1", "rhoA2"):  # from the material keys, if swept
        check_range(name, values[name], point)
    check_joint(values, point, sweep.base.partner, sweep.base.mount,
                contact=sweep.base.contact_shapes)
    if sweep.base.structure1 is not None and "1" in sweep.base.mount.shaken_beams(
            sweep.base.partner):
        sweep.base.structure1.require_support(values["base_amplitude"])
    if sweep.base.structure1 is not None:
        sweep.base.structure1.require_run_damping(values["damping_ratio"])
    check_run(values, sweep.t_max, sweep.n_modes, point, _grounded_springs(sweep),
              sweep.base.structure1, sweep.base.step_factors)
    _check_long_time(sweep, values, point, sweep.base.step_factors)


def _grounded_springs(sweep: Sweep) -> int:
    """The most springs to ground on one beam anywhere on the grid (`Params.grounded_springs`).

    A spring's stiffness axis may start at 0: every part's axis at its largest value (where
    a stiffness is > 0 if it is anywhere; a place at its largest is a checked grid point).
    """
    largest = {axis.name: axis.max for axis in sweep.axes if attachment_field(axis.name)}
    return sweep.params_at(largest).grounded_springs


def _check_long_time(sweep: Sweep, values: Mapping[str, Any], point: PointName,
                     steps: tuple[float, float]) -> None:
    """Long runs need a forcing period, and a horizon within double precision's phase range.

    Each cell runs (transient_periods + sampled_periods) forcing periods; the longest run is
    at the smallest Omega, a corner of the grid.
    """
    if sweep.long_time is None:
        return
    omega = np.asarray(values["omega"], dtype=float)
    require_all("omega", omega, omega > 0, point, lambda j: (
        "long-time observables sample once per forcing period: need omega > 0 (rad/s)"))
    periods = sweep.transient_periods + sweep.long_time.sampled_periods
    horizon = sweep.long_time.horizon(omega, sweep.transient_periods)
    highest = highest_frequency(values, sweep.n_modes, _grounded_springs(sweep),
                                sweep.base.structure1, steps)
    phase = np.maximum(highest, omega) * horizon
    require_all("transient_periods + sampled_periods", periods, phase <= MAX_PHASE, point,
                lambda j: (f"the run of {value_at(horizon, j):.3g} s turns the fastest "
                           f"oscillation through {value_at(phase, j):.3g} rad, more than "
                           f"{MAX_PHASE:g} rad (double precision keeps a phase to ~0.1 eps "
                           "omega t): use fewer periods or modes"))


def _check_lyapunov(sweep: Sweep) -> None:
    """The Lyapunov exponent is defined for the spring law only (docs/model.md)."""
    if LYAPUNOV not in sweep.observables:
        return
    laws = [axis.choices for axis in sweep.axes if axis.name == "contact_law"]
    require(f"observables in {sweep.source}", LYAPUNOV,
            all(LAWS[law].tangent_flow for law in (laws[0] if laws else [sweep.base.contact_law])),
            "needs the spring contact law on every cell (the tied law's projections and "
            "instantaneous impacts are not a flow whose linearisation converges in n_modes)")


def geometry_count(sweep: Sweep) -> int:
    """Distinct geometries of the grid: the product of the geometry axes' ``num``."""
    return math.prod(axis.num for axis in _geometry_axes(sweep))


def _geometry_axes(sweep: Sweep) -> list[Axis]:
    return [sweep.axes[k] for k in geometry_axes(sweep)]


def geometry_axes(sweep: Sweep) -> tuple[int, ...]:
    """Positions of the axes that change the modes: all but the cell parameters' axes.

    A spring-law dynamics map solves its contact phase for the damping ratio, so there the
    damping ratio changes the modes too.
    """
    per_cell = set(CELL_PARAMETERS)
    if sweep.needs_dynamics and any(law.compliant for law in contact_laws(sweep)):
        per_cell.discard("damping_ratio")
    return tuple(k for k, a in enumerate(sweep.axes) if flat_parameter(a.name) not in per_cell)


def contact_laws(sweep: Sweep) -> list[ContactLaw]:
    """The contact laws a sweep runs."""
    for axis in sweep.axes:
        if axis.name == "contact_law":
            return [LAWS[name] for name in axis.choices]
    return [sweep.base.law]


def default_chunk_cells(sweep: Sweep) -> int:
    """2^20 cells per chunk (2^16 for full dynamics, far costlier per cell): about a second of work.

    Large enough that the fixed cost of a chunk (starting the kernel's threads, its file, its
    netCDF block, a Dask task) stays small beside its computation, which matters on a busy
    machine where every start of the threads waits for the cores; small enough that an
    interrupt loses little and a cube streams in pieces of tens of MB. A map of up to 2^20 cells
    is therefore computed in one pass. Long-time observables take seconds per cell: chunks of
    a hundredth of the sweep, 1 to 64 cells, so that progress shows, an interrupt loses little
    and the threads, each running a chunk of its own (``run.local_runner``), finish together.
    """
    if sweep.stepping is not None:
        return row_cells(sweep)
    if sweep.long_time is not None:
        return int(min(max(sweep.size // 100, 1), 64))
    return 2**16 if sweep.needs_dynamics else 2**20


def row_cells(sweep: Sweep) -> int:
    """The cells of a stepped sweep's chunk of one row: the stepped axis and every later axis.

    A row's cells run one after the other, each from its predecessor's state: a chunk holds
    whole rows (the later axes' rows run beside it), so that it is computed, saved and
    resumed as a unit and a resumed run gives the same file.
    """
    return math.prod(sweep.shape[sweep.stepped_dimension:])


def expected_memory(sweep: Sweep, threads: int | None = None, in_memory: bool = False) -> int:
    """Peak memory (bytes) of running ``sweep`` on ``threads`` (default: all cores).

    Memory: a streamed run (``write_sweep``, what ``impactbeams run`` does) holds a chunk at a
    time (`chunk_memory`); ``in_memory`` (``run_sweep`` without an output) also holds the
    results (one float64 array of every cell per stored value and the Dataset's copy: 16
    bytes per cell and value, plus 4 for ``impacted`` and its temporaries; the traced peak
    of a first-impact map, netCDF writing included, is 18.04 bytes per cell). Both add the plan
    (8 x 2N float64 per geometry; a dynamics map 10 (2N)^2, with its stacking copy) and a
    dynamics map's per-thread segment buffers (MAX_SEGMENTS x (4 x 2N + 3) float64; a long
    run's LONG_RUN_CAPACITY of them and its samples' states). Time and both:
    `impactbeams.sweep.estimate`.
    """
    threads = threads or os.cpu_count() or 1
    coordinates = 2 * sweep.n_modes
    geometries = geometry_count(sweep)
    results = sweep.size * (16 * stored_values(sweep) + 4) if in_memory else 0
    over_t_max = _runs_over_t_max(sweep)
    if sweep.needs_dynamics:
        plan = 2 * geometries * 8 * 10 * coordinates**2
        buffers = threads * MAX_SEGMENTS * (4 * coordinates + 3) * 8 if over_t_max else 0
    else:
        plan, buffers = 2 * geometries * 8 * 8 * coordinates, 0
    if sweep.long_time is not None:  # each cell's own run, in windows of LONG_RUN_CAPACITY
        buffers += threads * (LONG_RUN_CAPACITY * (4 * coordinates + 3)
                              + sweep.long_time.sampled_periods * (2 * coordinates + 5)) * 8
    return chunk_memory(sweep) + results + plan + buffers


def run_kind(sweep: Sweep) -> str:
    """The kind of run whose kernels a sweep compiles most of (``compilation.ENTRY_KERNELS``)."""
    if sweep.long_time is not None:
        return "long_time"
    if LYAPUNOV in sweep.observables:
        return "lyapunov"
    return "dynamics" if sweep.needs_dynamics else "first_impact"


def _runs_over_t_max(sweep: Sweep) -> bool:
    """Whether any observable needs a run over [0, t_max] (all but the long-time ones)."""
    return any(name not in LONG_TIME_OBSERVABLES for name in sweep.observables)


def chunk_memory(sweep: Sweep) -> int:
    """Bytes a run of ``sweep`` holds for its chunk being computed and the one being written.

    Per cell of a default chunk: its cell rows (56 bytes), the kernel's output (8 per
    column), 24 per stored value (the chunk's arrays, its saved copy, the file's variables)
    and 18 for HDF5's buffers of a block (the uncompressed block in its cache and the
    compressed one; outside Python's allocator). Traced peaks of a streamed first-impact map:
    69 to 81 bytes per chunk cell (against 106 here).
    """
    from impactbeams.kernels.layout import OUT_COLUMNS

    columns = len(OUT_COLUMNS) if sweep.needs_dynamics else 1
    cells = min(sweep.size, default_chunk_cells(sweep))
    return cells * (56 + 8 * columns + 24 * stored_values(sweep) + 18)


def stored_values(sweep: Sweep) -> int:
    """Values per cell of the stored arrays (a stroboscopic observable has one per sample)."""
    return sum(math.prod(sweep.value_shape(name)) for name in sweep.stored)


def _check_cost(sweep: Sweep) -> None:
    """Refuse a sweep with too many geometries, or one that would not fit in memory."""
    geometries = geometry_count(sweep)
    if geometries > MAX_GEOMETRIES:
        swept = ", ".join(f"{axis.name}: num = {axis.num}" for axis in _geometry_axes(sweep)
                          if axis.num > 1)
        raise ParameterError(
            f"the geometry axes of {sweep.source} ({swept}) give {geometries} distinct "
            f"geometries; at most {MAX_GEOMETRIES} are allowed, since each one's modes are "
            "computed one after the other before the map starts: use fewer values there")
    require_memory(f"the grid of {sweep.source} ({' x '.join(map(str, sweep.shape))} = "
                   f"{sweep.size} cells)", expected_memory(sweep),
                   "use fewer cells (smaller num) or split the sweep into several files")
