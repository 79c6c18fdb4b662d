"""Where the structure is touched: contacts as small objects, checked on creation.

A `Contact` is one point of beam 1 against a point of beam 2 or a rigid stop, from one side,
with its own clearance and, optionally, its own spring law's stiffness and dashpot; a
two-sided stop (backlash) is two contacts at one point, one below and one above
(`two_sided_stop`). ``Params(contacts=...)`` composes them as ``attachments1`` composes parts;
one contact is the simple form of the flat keys (``contact_position1``, ``contact_position2``,
``contact_side``, ``clearance``, ``contact_stiffness``, ``contact_damping``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from impactbeams import configuration
from impactbeams.checks import ParameterError, is_real, require

# each field of a contact, its unit, and the flat key of a run's parameters it stands for
FLAT_KEYS = {"position1": "contact_position1", "position2": "contact_position2",
             "side": "contact_side", "clearance": "clearance",
             "stiffness": "contact_stiffness", "damping": "contact_damping"}
_UNITS = {"position1": "m", "position2": "m", "clearance": "m", "stiffness": "N/m",
          "damping": "N s/m"}


@dataclasses.dataclass(frozen=True)
class Contact:
    """One contact: beam 1 at ``position1`` against beam 2 at ``position2`` (or a stop).

    ``position1``, ``position2`` (m from each beam's clamp; None: the tip; against a stop
    ``position2`` stays None); ``side``: ``"below"`` (what beam 1 meets is below it) or
    ``"above"``; ``clearance`` (m, > 0): the gap at rest; ``stiffness`` (N/m, > 0) and
    ``damping`` (N s/m, >= 0) of its spring law. A field left None takes the run's value
    (the tip, ``clearance``, ``contact_stiffness``, ``contact_damping``). Where the positions
    lie on the beams is checked by `Params`, which knows the lengths.
    """

    position1: float | None = None
    position2: float | None = None
    side: str = configuration.BELOW.name
    clearance: float | None = None
    stiffness: float | None = None
    damping: float | None = None

    def __post_init__(self) -> None:
        require("Contact.side", self.side, self.side in configuration.SIDES,
                f"must be one of {', '.join(map(repr, configuration.SIDES))}")
        for name, unit in _UNITS.items():
            value = getattr(self, name)
            if value is None:
                continue
            positive = name != "damping"
            ok = is_real(value) and math.isfinite(value) and (value > 0 if positive
                                                              else value >= 0)
            require(f"Contact.{name}", value, ok,
                    f"must be a finite real number {'> 0' if positive else '>= 0'}", unit)
            object.__setattr__(self, name, float(value))

    def flat(self) -> dict[str, Any]:
        """The flat keys of a run's parameters this contact gives (its fields not None)."""
        return {key: getattr(self, name) for name, key in FLAT_KEYS.items()
                if getattr(self, name) is not None}


def two_sided_stop(position1: float | None = None, clearance_below: float | None = None,
                   clearance_above: float | None = None, **law: float) -> tuple[Contact, Contact]:
    """A stop below and a stop above beam 1 at ``position1`` (m; None: the tip): backlash.

    ``clearance_below``, ``clearance_above`` (m): each stop's gap at rest (None: the run's
    clearance); ``law``: ``stiffness`` and/or ``damping``, shared by both.
    """
    return (Contact(position1, side=configuration.BELOW.name, clearance=clearance_below, **law),
            Contact(position1, side=configuration.ABOVE.name, clearance=clearance_above, **law))


def as_contact(name: str, value: Any) -> Contact:
    """``value`` as a Contact: a Contact as it is, a table (a TOML file's) built from its fields.

    Anything else raises ParameterError naming ``name`` and the fields allowed.
    """
    if isinstance(value, Contact):
        return value
    if isinstance(value, dict) and set(value) <= set(FLAT_KEYS):
        return Contact(**value)
    raise ParameterError(
        f"{name} = {value!r} is not allowed: a contact is an impactbeams.Contact or a table of "
        f"{', '.join(FLAT_KEYS)} (each optional)")
