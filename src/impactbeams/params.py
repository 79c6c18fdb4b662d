"""Model parameters: the two beams, the clearance and the forcing, in SI units.

Names are the same everywhere (Python, TOML files, CLI options with dashes, Dataset attributes):

=================  ======  ==========================================================
name               unit    meaning
=================  ======  ==========================================================
``l1``, ``l2``     m       beam lengths
``EI1``, ``EI2``   N m^2   bending stiffness
``rhoA1``,         kg/m    mass per unit length
``rhoA2``
``E1`` ...         Pa      material alternative to ``EI``/``rhoA``: Young's modulus
``rho1`` ...       kg/m^3  density
``width1`` ...     m       strip width
``thickness1``...  m       strip thickness
``clearance``      m       Delta, gap between the tips at rest (> 0)
``force_amplitude`` N      F0 of the tip force F(t) = F0 sin(omega t) on beam 1 (downward)
``omega``          rad/s   forcing frequency Omega
``uplift1``,       m       initial tip uplifts delta_1, delta_2 (static tip-load shape)
``uplift2``
``damping_ratio``  1       modal damping ratio zeta, 0 <= zeta < 1: damps each cantilever
                           mode's whole coordinate <y, Y_n> (``variables.DAMPING_LAW``)
``contact_law``    -       "spring" (compliant, default) or "tied" (the paper's law)
``contact_stiffness`` N/m  k of the spring law (default: Hertz, steel sphere of radius 1 mm
                           on steel, linearised at 1 mN: ``hertz_stiffness``)
``contact_damping`` N s/m  c of the spring law's dashpot (default 0)
=================  ======  ==========================================================
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from impactbeams.variables import PARAMETERS

STEEL_E = 210e9  # Pa
STEEL_RHO = 7850.0  # kg/m^3
STEEL_POISSON = 0.3
STRIP_WIDTH = 5e-3  # m
PAPER_A = 0.7  # m^2/s, a = sqrt(EI / rhoA) of both beams in the paper
STRIP_THICKNESS = PAPER_A / math.sqrt(STEEL_E / (12.0 * STEEL_RHO))  # m, gives a = 0.7

MATERIAL_KEYS = ("E", "rho", "width", "thickness")
MATERIAL_DEFAULTS = {"E": STEEL_E, "rho": STEEL_RHO, "width": STRIP_WIDTH,
                     "thickness": STRIP_THICKNESS}


class ParameterError(ValueError):
    """A model or run parameter has a value that is not allowed."""


def _strip_stiffness(material: Mapping[str, float]) -> tuple[float, float]:
    """Return (EI, rhoA) of a rectangular strip from E, rho, width, thickness."""
    E, rho, b, h = (material[k] for k in MATERIAL_KEYS)
    return E * b * h**3 / 12.0, rho * b * h


DEFAULT_EI, DEFAULT_RHOA = _strip_stiffness(MATERIAL_DEFAULTS)


def require(name: str, value: Any, condition: bool, allowed: str, unit: str = "") -> None:
    """Raise ParameterError naming the parameter, its value and what is allowed."""
    if not condition:
        unit_text = f" ({unit})" if unit else ""
        raise ParameterError(f"{name} = {value!r} is not allowed: {allowed}{unit_text}")


def require_finite(name: str, value: Any, unit: str = "") -> float:
    """Return value as float, or raise ParameterError if it is not a finite real number."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    require(name, value, ok and math.isfinite(value), "must be a finite real number", unit)
    return float(value)


def hertz_stiffness(tip_radius: float, force: float, youngs_modulus1: float = STEEL_E,
                    poisson1: float = STEEL_POISSON, youngs_modulus2: float = STEEL_E,
                    poisson2: float = STEEL_POISSON) -> float:
    """Linearised Hertz stiffness (N/m) of a sphere (radius in m) on a flat at a force (N).

    F = 4/3 E* sqrt(R) d^(3/2) gives dF/dd = (6 E*^2 R F)^(1/3), with the contact modulus
    1 / E* = (1 - nu1^2) / E1 + (1 - nu2^2) / E2 (Pa).
    """
    for name, value in (("tip_radius", tip_radius), ("force", force)):
        require(name, value, require_finite(name, value) > 0, "must be > 0")
    contact_modulus = 1.0 / ((1 - poisson1**2) / youngs_modulus1
                             + (1 - poisson2**2) / youngs_modulus2)
    return (6.0 * contact_modulus**2 * tip_radius * force) ** (1.0 / 3.0)


CONTACT_LAWS = ("spring", "tied")
DEFAULT_TIP_RADIUS = 1e-3  # m, of the default contact stiffness
DEFAULT_CONTACT_FORCE = 1e-3  # N, force scale of the default contact stiffness
DEFAULT_CONTACT_STIFFNESS = hertz_stiffness(DEFAULT_TIP_RADIUS, DEFAULT_CONTACT_FORCE)
MAX_CONTACT_STIFFNESS = 1e12  # N/m: beyond it the contact frequencies leave double precision


@dataclasses.dataclass(frozen=True)
class Params:
    """Parameters of the two-beam impact model (SI units, see the module docstring).

    Build it with keywords (``Params(clearance=2e-5)``), from a mapping that may use the
    material keys (:meth:`from_mapping`) or from a TOML file (:meth:`from_toml`). Every value is
    validated on construction; a bad value raises :class:`ParameterError`.
    """

    l1: float = 0.1
    l2: float = 0.12
    EI1: float = DEFAULT_EI
    EI2: float = DEFAULT_EI
    rhoA1: float = DEFAULT_RHOA
    rhoA2: float = DEFAULT_RHOA
    clearance: float = 1.1e-5
    force_amplitude: float = 1e-3
    omega: float = 50.0
    uplift1: float = 0.0
    uplift2: float = 0.0
    damping_ratio: float = 0.0
    contact_law: str = "spring"
    contact_stiffness: float = DEFAULT_CONTACT_STIFFNESS
    contact_damping: float = 0.0

    def __post_init__(self) -> None:
        require("contact_law", self.contact_law, self.contact_law in CONTACT_LAWS,
                f"must be one of {', '.join(map(repr, CONTACT_LAWS))}")
        for field in dataclasses.fields(self):
            if field.name == "contact_law":
                continue
            value = require_finite(field.name, getattr(self, field.name),
                                   PARAMETERS[field.name].units)
            object.__setattr__(self, field.name, value)
        require("contact_stiffness", self.contact_stiffness,
                0 < self.contact_stiffness <= MAX_CONTACT_STIFFNESS,
                f"must be > 0 and <= {MAX_CONTACT_STIFFNESS:g}", "N/m")
        require("contact_damping", self.contact_damping, self.contact_damping >= 0,
                "must be >= 0", "N s/m")
        for name in ("l1", "l2", "EI1", "EI2", "rhoA1", "rhoA2", "clearance"):
            require(name, getattr(self, name), getattr(self, name) > 0, "must be > 0",
                    PARAMETERS[name].units)
        for name in ("force_amplitude", "omega"):
            require(name, getattr(self, name), getattr(self, name) >= 0, "must be >= 0",
                    PARAMETERS[name].units)
        require("damping_ratio", self.damping_ratio, 0 <= self.damping_ratio < 1,
                "must satisfy 0 <= damping_ratio < 1 (underdamped modes)")
        gap = self.initial_gap
        require("uplift2", self.uplift2, gap > 0,
                f"the initial gap clearance + uplift1 - uplift2 = {gap!r} m must be > 0", "m")

    @property
    def initial_gap(self) -> float:
        """Gap between the tips at t = 0: clearance + uplift1 - uplift2 (m)."""
        return self.clearance + self.uplift1 - self.uplift2

    @property
    def tip_compliance(self) -> tuple[float, float]:
        """Static tip compliances c_i = l_i^3 / (3 EI_i) of the two cantilevers (m/N)."""
        return self.l1**3 / (3 * self.EI1), self.l2**3 / (3 * self.EI2)

    @property
    def wave_constant(self) -> tuple[float, float]:
        """a_i = sqrt(EI_i / rhoA_i) of the two beams (m^2/s)."""
        return math.sqrt(self.EI1 / self.rhoA1), math.sqrt(self.EI2 / self.rhoA2)

    def as_dict(self) -> dict[str, float | str]:
        """All parameters by name, in the resolved EI/rhoA form."""
        return dataclasses.asdict(self)

    def replace(self, **changes: Any) -> Params:
        """Return a copy with some parameters changed (material keys allowed)."""
        base = self.as_dict()
        for i in ("1", "2"):
            if any(k + i in changes for k in MATERIAL_KEYS):
                del base["EI" + i], base["rhoA" + i]
        return Params.from_mapping({**base, **changes})

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any], source: str = "parameters") -> Params:
        """Build from a mapping of names to values, resolving the material keys of each beam.

        ``source`` names where the mapping came from, for error messages.
        """
        values = dict(mapping)
        for key in values:
            if key not in PARAMETERS:
                raise ParameterError(f"unknown parameter {key!r} in {source}; allowed: "
                                     f"{', '.join(sorted(PARAMETERS))}")
        for i in ("1", "2"):
            material = {k: values.pop(k + i) for k in MATERIAL_KEYS if k + i in values}
            if not material:
                continue
            direct = [k + i for k in ("EI", "rhoA") if k + i in values]
            if direct:
                raise ParameterError(
                    f"{source} gives both {', '.join(direct)} and material keys "
                    f"{', '.join(k + i for k in material)} for beam {i}: give one or the other")
            for key, value in material.items():
                unit = PARAMETERS[key + i].units
                require(key + i, value, require_finite(key + i, value, unit) > 0, "must be > 0",
                        unit)
            EI, rhoA = _strip_stiffness({**MATERIAL_DEFAULTS, **material})
            values["EI" + i], values["rhoA" + i] = EI, rhoA
        return cls(**values)

    @classmethod
    def from_toml(cls, path: str | Path) -> Params:
        """Read the ``[params]`` table of a TOML file; unspecified keys take the defaults."""
        data = read_toml(path)
        for key in data:
            if key != "params":
                raise ParameterError(f"unknown key {key!r} in {path}: a parameters file has "
                                     "only a [params] table")
        return cls.from_mapping(data.get("params", {}), source=f"[params] of {path}")


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file, turning a missing file or bad syntax into a clear error."""
    try:
        with open(path, "rb") as stream:
            return tomllib.load(stream)
    except FileNotFoundError:
        raise ParameterError(f"file {str(path)!r} does not exist") from None
    except tomllib.TOMLDecodeError as error:
        raise ParameterError(f"{path} is not valid TOML: {error}") from None
