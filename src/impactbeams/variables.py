"""Registry of output variables: one place for names, dimensions, units and descriptions.

Used both to build Datasets (:func:`attributes`) and to check them (:func:`validate`).
"""

from __future__ import annotations

import dataclasses

import xarray as xr


@dataclasses.dataclass(frozen=True)
class Variable:
    """An output variable: its dimensions, CF ``units``, ``long_name`` and a description."""

    dims: tuple[str, ...]
    units: str
    long_name: str
    description: str


# dims "*" = the swept parameters of a map, in sweep order
VARIABLES: dict[str, Variable] = {
    "first_impact_time": Variable(
        ("*",), "s", "time before the first impact",
        "first time in (0, t_max] at which the tip gap closes; NaN where no impact by t_max"),
    "impacted": Variable(
        ("*",), "1", "impact flag",
        "1 where the tips impact by t_max, 0 where they do not"),
    "impact_count": Variable(
        ("*",), "1", "number of impacts",
        "number of contact onsets in [0, t_max] (full dynamics)"),
    "max_contact_force": Variable(
        ("*",), "N", "largest contact force",
        "largest contact force R over [0, t_max]; 0 where no impact (full dynamics)"),
    "mean_restitution": Variable(
        ("*",), "1", "mean coefficient of restitution",
        "mean of e = -(dg/dt at separation) / (dg/dt at onset) over completed impacts; "
        "NaN where no impact has separated (full dynamics)"),
    "contact_fraction": Variable(
        ("*",), "1", "fraction of time in contact",
        "time spent in the contact phase divided by t_max (full dynamics)"),
}


def attributes(name: str) -> dict[str, str]:
    """CF attributes (units, long_name, description) of a registered variable."""
    variable = VARIABLES[name]
    return {"units": variable.units, "long_name": variable.long_name,
            "description": variable.description}


def validate(dataset: xr.Dataset) -> None:
    """Raise ValueError if a registered variable in ``dataset`` lacks its units or long_name."""
    for name in dataset.data_vars:
        if name not in VARIABLES:
            continue
        expected = attributes(name)
        for key in ("units", "long_name"):
            if dataset[name].attrs.get(key) != expected[key]:
                raise ValueError(f"variable {name!r} has {key} = "
                                 f"{dataset[name].attrs.get(key)!r}, expected {expected[key]!r}")
