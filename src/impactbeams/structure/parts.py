"""The parts of a cantilever: uniform segments and point attachments, checked on creation.

A beam is clamped at x = 0 and free at x = L; it is a series of uniform segments (a stepped
beam; one segment is a uniform beam) carrying point masses and springs to ground anywhere on
it. Every part refuses a value that is not allowed with one ParameterError naming it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from impactbeams.checks import ParameterError, is_real, require


def _check_fields(part: Any, units: dict[str, str], positive: bool) -> None:
    """Store each field of ``part`` named in ``units`` (name: unit) as a float.

    Raise ParameterError unless it is a finite real number > 0 (``positive``) or >= 0.
    """
    bound = "> 0" if positive else ">= 0"
    for name, unit in units.items():
        value = getattr(part, name)
        ok = is_real(value) and math.isfinite(value) and (value > 0 if positive else value >= 0)
        require(f"{type(part).__name__}.{name}", value, ok, f"must be a finite real number {bound}",
                unit)
        object.__setattr__(part, name, float(value))


@dataclasses.dataclass(frozen=True)
class Segment:
    """A uniform piece of the beam: ``length`` (m), ``EI`` (N m^2), ``rhoA`` (kg/m)."""

    length: float
    EI: float
    rhoA: float

    def __post_init__(self) -> None:
        _check_fields(self, SEGMENT_UNITS, positive=True)


SEGMENT_UNITS = {"length": "m", "EI": "N m^2", "rhoA": "kg/m"}  # each a finite number > 0
# each field's beam key (l, EI, rhoA: whose allowed values it takes) and what it is, in words
SEGMENT_KEYS = {"length": "l", "EI": "EI", "rhoA": "rhoA"}
SEGMENT_WORDS = {"length": "length", "EI": "bending stiffness", "rhoA": "mass per unit length"}


@dataclasses.dataclass(frozen=True)
class PointMass:
    """A rigid body fixed at ``position`` (m): ``mass`` (kg), ``rotary_inertia`` (kg m^2).

    It adds ``mass y(x)^2 / 2 + rotary_inertia y'(x)^2 / 2`` to the kinetic energy.
    """

    position: float
    mass: float
    rotary_inertia: float = 0.0

    def __post_init__(self) -> None:
        _check_fields(self, FIELD_UNITS[PointMass], positive=False)


@dataclasses.dataclass(frozen=True)
class Spring:
    """Linear springs to ground at ``position`` (m), on the deflection and on the slope.

    ``stiffness`` (N/m) acts on the deflection, ``rotational_stiffness`` (N m/rad) on the slope.

    They add ``stiffness y(x)^2 / 2 + rotational_stiffness y'(x)^2 / 2`` to the strain
    energy. A rotational spring at ``position = 0`` makes the clamp compliant.
    """

    position: float
    stiffness: float = 0.0
    rotational_stiffness: float = 0.0

    def __post_init__(self) -> None:
        _check_fields(self, FIELD_UNITS[Spring], positive=False)


Attachment = PointMass | Spring
# each part's numeric fields and their units: every one a finite real number >= 0
FIELD_UNITS = {PointMass: {"position": "m", "mass": "kg", "rotary_inertia": "kg m^2"},
               Spring: {"position": "m", "stiffness": "N/m", "rotational_stiffness": "N m/rad"}}
# what each field is, in words (a swept or continued field's long_name)
FIELD_WORDS = {"position": "distance from the clamp", "mass": "point mass",
               "rotary_inertia": "rotary inertia", "stiffness": "stiffness to ground",
               "rotational_stiffness": "rotational stiffness to ground"}


def check_attachments(attachments: tuple[Any, ...], length: float,
                      name: str = "attachments") -> None:
    """Raise ParameterError for an attachment that is not a part, or not on the beam.

    Masses and translational springs act at 0 < x <= L (at the clamp the deflection is held,
    so they would do nothing); a rotational spring at x = 0 is the compliant clamp.
    """
    for index, part in enumerate(attachments):
        item = f"{name}[{index}]"
        if not isinstance(part, (PointMass, Spring)):
            raise ParameterError(f"{item} = {part!r} is not allowed: must be a PointMass or a "
                                 "Spring (impactbeams.structure)")
        at_clamp_allowed = isinstance(part, Spring) and part.stiffness == 0.0
        low = "0 <=" if at_clamp_allowed else "0 <"
        require(f"{item}.position", part.position,
                (part.position >= 0.0 if at_clamp_allowed else part.position > 0.0)
                and part.position <= length,
                f"must lie on the beam, {low} x <= {length!r} (at the clamp, x = 0, only a "
                "rotational spring acts)", "m")


def check_clamp(attachments: tuple[Any, ...]) -> None:
    """Raise ParameterError if the clamp's rotational springs (if any) sum to zero.

    A compliant clamp without stiffness would let the whole beam turn as a rigid body.
    """
    at_clamp = [p for p in attachments if isinstance(p, Spring) and p.position == 0.0]
    total = sum(p.rotational_stiffness for p in at_clamp)
    if at_clamp and total == 0.0:
        require("Spring.rotational_stiffness at position 0", total, False,
                "must be > 0 (a spring at the clamp makes it compliant; without stiffness the "
                "beam would turn freely about it)", "N m/rad")


def as_part(name: str, value: Any) -> Any:
    """``value`` as a part: a PointMass or Spring as it is, a table (a TOML file's) built.

    A table with ``position`` and ``mass`` (and ``rotary_inertia``) is a point mass, one with
    ``position`` and ``stiffness`` and/or ``rotational_stiffness`` a spring; anything else is
    returned for `check_attachments` to refuse, and a table that fits neither raises
    ParameterError naming ``name``.
    """
    if not isinstance(value, dict):
        return value
    for kind, fields in FIELD_UNITS.items():
        if "position" in value and set(value) <= set(fields) and len(value) > 1 and (
                kind is Spring or "mass" in value):
            return kind(**value)
    raise ParameterError(
        f"{name} = {value!r} is not allowed: a point mass is a table of position, mass and "
        "rotary_inertia (optional); a spring, of position, stiffness and/or "
        "rotational_stiffness")


def as_segment(name: str, value: Any) -> Any:
    """``value`` as a Segment: a Segment as it is, a table (a TOML file's) of its fields built.

    A table must give exactly ``length``, ``EI`` and ``rhoA``, else ParameterError naming
    ``name``; anything else is returned for the caller to refuse.
    """
    if not isinstance(value, dict):
        return value
    if set(value) != set(SEGMENT_UNITS):
        raise ParameterError(f"{name} = {value!r} is not allowed: a segment is a table of "
                             "length (m), EI (N m^2) and rhoA (kg/m)")
    try:
        return Segment(**value)
    except ParameterError as error:
        raise ParameterError(f"{name}: {error}") from None
