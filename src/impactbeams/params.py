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
``clearance``      m       Delta, gap between the tips (the contact points) at rest (> 0)
``force_amplitude`` N      F0 of the tip force F(t) = F0 sin(omega t) on beam 1 (downward);
                           default 1e-3, but 0 when ``base_amplitude`` is given: a study that
                           names its shaker is driven by it alone unless it names F0 too
``omega``          rad/s   forcing frequency Omega
``uplift1``,       m       initial tip uplifts delta_1, delta_2 (static tip-load shape)
``uplift2``
``damping_ratio``  1       modal damping ratio zeta, 0 <= zeta < 1: damps each cantilever
                           mode's whole coordinate <y, Y_n> (``variables.DAMPING_LAW``);
                           must be 0 with a ``structure1`` that has damping of its own
``contact_law``    -       "spring" (compliant, default) or "tied" (the paper's law)
``contact_stiffness`` N/m  k of the spring law (default: Hertz, steel sphere of radius 1 mm
                           on steel, linearised at 1 mN: ``hertz_stiffness``)
``contact_damping`` N s/m  c of the spring law's dashpot (default 0)
``counterpart``    -       what beam 1's tip meets: "beam" (beam 2, default) or "stop" (a
                           fixed rigid stop ``clearance`` below it: no beam 2, so beam 2's
                           keys are refused when given and their defaults are ignored)
``base_amplitude`` m       U0 of the shaker's motion u_b(t) = U0 sin(omega t) (default 0; the
                           tied law takes it with shaker = "both" only); at most 0.2 times the
                           shortest shaken beam (small deflections, ``check_joint``)
``contact_position1`` m  where the contact acts on beam 1: its distance from the clamp,
                           0 < x1 <= l1 (default: not given, the tip l1, bit for bit)
``contact_position2`` m  where it acts on beam 2 (counterpart = "beam"): 0 < x2 <= l2
                           (default: the tip l2)
``contact_side``   -       which way beam 1 closes the contact: "below" (default: what it meets
                           is below it, it moves down onto it) or "above" (it moves up onto it)
``segments1``,    -       a stepped beam: its uniform `impactbeams.Segment`s from the clamp out
``segments2``              (each its length, EI and rhoA; a TOML array of tables
                           [[params.segments1]]) in place of l, EI, rhoA (``Params.l1``, ``EI1``,
                           ``rhoA1`` are then derived: `Params._take_segments`); one segment
                           given so is the keys l, EI, rhoA
``contacts``       -       two or more contacts (`impactbeams.Contact`: each its point, side,
                           clearance and law; a TOML array of tables [[params.contacts]]); one
                           contact given so is the keys above (`fold_contacts`); clearance,
                           contact_stiffness, contact_damping are the defaults of the contacts
                           leaving theirs out (refused where every contact gives its own)
``shaker``         -       which clamps the shaker carries: "both" (default: both beams'
                           clamps, or beam 1's and the stop's mount, which then moves with it),
                           "beam1" (a stop stays fixed) or "beam2" (beam 2's clamp, or a stop's
                           mount)
``start``          -       initial state: "rest" (at rest in the absolute frame, default)
                           or "steady" (on the no-contact steady response to every drive)
=================  ======  ==========================================================
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import os
import reprlib
import tomllib
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams import configuration
from impactbeams.checks import (  # noqa: F401  (their old home: modules above import them here)
    ParameterError,
    is_integer,
    is_real,
    require,
    require_integer,
)
from impactbeams.configuration import BEAM, BOTH, ContactLaw, Counterpart, Mount, Side
from impactbeams.kernels import layout
from impactbeams.structure.contacts import FLAT_KEYS, Contact, as_contact
from impactbeams.structure.parts import (
    FIELD_UNITS,
    FIELD_WORDS,
    SEGMENT_KEYS,
    SEGMENT_UNITS,
    SEGMENT_WORDS,
    Attachment,
    Segment,
    Spring,
    as_part,
    as_segment,
    check_attachments,
    check_clamp,
)
from impactbeams.variables import PARAMETERS, parameter_attributes

if TYPE_CHECKING:  # imported where used: only a run with attachments or a structure needs them
    from impactbeams.structure.cantilever import Cantilever
    from impactbeams.structure.user import MatrixStructure, ModalStructure

STEEL_E = 210e9  # Pa
STEEL_RHO = 7850.0  # kg/m^3
STEEL_POISSON = 0.3
STRIP_WIDTH = 5e-3  # m
PAPER_A = 0.7  # m^2/s, a = sqrt(EI / rhoA) of both beams in the paper
STRIP_THICKNESS = PAPER_A / math.sqrt(STEEL_E / (12.0 * STEEL_RHO))  # m, gives a = 0.7

MATERIAL_KEYS = ("E", "rho", "width", "thickness")
MATERIAL_DEFAULTS = {"E": STEEL_E, "rho": STEEL_RHO, "width": STRIP_WIDTH,
                     "thickness": STRIP_THICKNESS}


class ArgumentTypeError(ParameterError, TypeError):
    """An argument of a public function has a type that is not allowed.

    A TypeError, as Python expects, and a ParameterError, so that a caller (the command line)
    that reports refused inputs in one line reports this one too.
    """


def _strip_stiffness(material: Mapping[str, Any]) -> tuple[Any, Any]:
    """Return (EI, rhoA) of a rectangular strip from E, rho, width, thickness (floats or arrays)."""
    E, rho, b, h = (material[k] for k in MATERIAL_KEYS)
    return E * b * h**3 / 12.0, rho * b * h


DEFAULT_EI, DEFAULT_RHOA = _strip_stiffness(MATERIAL_DEFAULTS)


def require_type(name: str, value: Any, condition: bool, allowed: str) -> None:
    """Raise ArgumentTypeError naming the argument, the value given, its type and what is allowed.

    ``allowed`` completes "must be ...".
    """
    if not condition:
        raise ArgumentTypeError(f"{name} = {reprlib.repr(value)} ({type(value).__name__}) is "
                                f"not allowed: must be {allowed}")


def unknown_key(what: str, key: Any, where: str, allowed: Collection[str]) -> ParameterError:
    """The error of an unknown ``what`` (key, parameter, ...) ``key`` in ``where``.

    It names the key, the nearest allowed one (a spelling slip, or an abbreviation of a
    longer name) and every allowed one.
    """
    return ParameterError(f"unknown {what} {key!r} in {where}{nearest(key, allowed)}; allowed: "
                          f"{', '.join(allowed)}")


def nearest(key: Any, allowed: Collection[str]) -> str:
    """`` (did you mean 'NAME'?)`` for the allowed name nearest ``key``, or "" if none is near."""
    if not isinstance(key, str):
        return ""
    close = difflib.get_close_matches(key, list(allowed), n=1) or sorted(
        name for name in allowed if len(key) > 1 and name.startswith(key))[:1]
    return f" (did you mean {close[0]!r}?)" if close else ""


def is_path(value: Any) -> bool:
    """Whether ``value`` names a file: a str or an os.PathLike (pathlib.Path)."""
    return isinstance(value, (str, os.PathLike))


def require_finite(name: str, value: Any, unit: str = "") -> float:
    """Return value as float, or raise ParameterError if it is not a finite real number."""
    require(name, value, is_real(value) and math.isfinite(value), "must be a finite real number",
            unit)
    return float(value)


# --- allowed values ------------------------------------------------------------------------
# Every limit below is explained in docs/limits.md ("Allowed values").

# A tip deflection (uplift, static deflection under F0, each tip's share of the clearance) of
# at most this fraction of the beam's length: small-deflection theory. The tip's axial
# shortening, (3/5) w^2 / l for the static tip-load shape, which the linear model leaves out,
# stays below 12 % of w.
MAX_DEFLECTION = 0.2
MAX_MODES = 200  # free modes per beam: the package's limit (docs/limits.md)
# a simulated run's default cap on its phases (free flights and contacts: about half as many
# contacts), beyond which it stops with status "event_limit"
MAX_EVENTS = 200_000
# the largest chunk of a sweep: about 1.3 GB of cell rows and results (kernels.layout.CELL_COLUMNS
# and an output per cell), and well below HDF5's 4 GiB limit on a compressed block (here, not in
# sweep/, so that `impactbeams --help` need not import the sweep package)
MAX_CHUNK_CELLS = 2**24
# the frequencies on which `impactbeams.orbits.grazing_frequencies` brackets its roots by
# default (here, not in orbits/, so that `impactbeams --help` need not import the orbits)
GRAZING_BRACKETS = 2001
# rad/s: a continuum beam's frequencies stay far below its lattice vibrations (~1e13 rad/s)
MAX_FREQUENCY = 1e12
MAX_CONTACT_STIFFNESS = 1e12  # N/m: beyond it the contact frequencies leave double precision
FIRST_CANTILEVER_ROOT = 1.8751040687119611  # b_1 of cos b cosh b + 1 = 0


@dataclasses.dataclass(frozen=True)
class Range:
    """The allowed values of one numeric parameter (SI units).

    ``sign``: ``"> 0"``, ``">= 0"`` or ``""`` (any sign); then magnitudes from ``low`` to
    ``high`` (``high`` itself excluded if ``high_open``), for the reason ``why``. ``rule``
    replaces the generated wording.
    """

    sign: str = ""
    low: float = 0.0
    high: float = math.inf
    high_open: bool = False
    why: str = ""
    rule: str = ""

    def sign_holds(self, value: Any) -> Any:
        """Elementwise: the value (a float or an array) has the allowed sign."""
        if self.sign == "> 0":
            return value > 0
        return value >= 0 if self.sign == ">= 0" else value == value  # all (NaN: refused before)

    def magnitude_holds(self, value: Any) -> Any:
        """Elementwise: |value| within [low, high] (or [low, high))."""
        size = abs(value)
        below = size < self.high if self.high_open else size <= self.high
        return (size >= self.low) & below

    def describe(self, failed_sign: bool) -> str:
        """What is allowed, for the message of a value that failed the sign or the magnitude."""
        if self.rule:
            return self.rule
        if failed_sign:
            return f"must be {self.sign}"
        if self.low == 0:
            return f"must be {'<' if self.high_open else '<='} {self.high:g}"
        return f"must be from {self.low:g} to {self.high:g}"


def _beam_ranges(key: str, parameter_range: Range) -> dict[str, Range]:
    return {key + i: parameter_range for i in ("1", "2")}


RANGES: dict[str, Range] = {
    **_beam_ranges("l", Range("> 0", 1e-6, 1e3, why="a 1 um micro-cantilever to a 1 km structure")),
    **_beam_ranges("EI", Range("> 0", 1e-24, 1e17, why="a nanowire to a tall building")),
    **_beam_ranges("rhoA", Range("> 0", 1e-18, 1e7, why="a nanowire to a tall building")),
    **_beam_ranges("E", Range("> 0", 1e3, 1e13, why="soft gels to ten times diamond")),
    **_beam_ranges("rho", Range("> 0", 0.1, 1e5, why="aerogels to four times osmium")),
    **_beam_ranges("width", Range("> 0", 1e-9, 1e3, why="a nanometre to a kilometre")),
    **_beam_ranges("thickness", Range("> 0", 1e-9, 1e3, why="a nanometre to a kilometre")),
    "clearance": Range("> 0"),
    "force_amplitude": Range(">= 0"),
    "omega": Range(">= 0", high=MAX_FREQUENCY,
                   why="a continuum beam model does not hold at higher frequencies"),
    "uplift1": Range(),
    "uplift2": Range(),
    "damping_ratio": Range(">= 0", high=1.0, high_open=True,
                           rule="must satisfy 0 <= damping_ratio < 1 (underdamped modes)"),
    "contact_stiffness": Range("> 0", high=MAX_CONTACT_STIFFNESS,
                               rule=f"must be > 0 and <= {MAX_CONTACT_STIFFNESS:g}"),
    "contact_damping": Range(">= 0"),
    "base_amplitude": Range(">= 0"),
    # a point of each beam, from its clamp (how far along it: `Params._check_contact_point`)
    "contact_position1": Range("> 0"),
    "contact_position2": Range("> 0"),
}

# names a grid point for a message: "" for one set of parameters, or the swept values at an
# index of the corner grid of a sweep
PointName = Callable[[tuple[int, ...]], str]


@functools.cache
def _FIELDS() -> tuple[dataclasses.Field, ...]:  # noqa: N802
    return dataclasses.fields(Params)


def no_point(index: tuple[int, ...]) -> str:
    """No grid point to name: the values are one set of parameters."""
    return ""


def _first_failure(ok: Any) -> tuple[int, ...] | None:
    """Index of the first False in ``ok`` (a bool or a boolean array), or None if all hold."""
    # one set of parameters (a bool): the common case, kept cheap (np.ndim costs 1 us)
    if isinstance(ok, (bool, np.bool_)) or np.ndim(ok) == 0:
        return None if ok else ()
    if ok.all():
        return None
    return tuple(int(i) for i in np.unravel_index(np.argmin(ok), ok.shape))


def check_range(name: str, value: Any, point: PointName = no_point) -> None:
    """Raise ParameterError if any element of ``value`` is not an allowed value of ``name``.

    ``value``: a float or an array of them (every element is checked, vectorised).
    """
    allowed, unit = RANGES[name], PARAMETERS[name].units
    if isinstance(value, float):  # one value, the common case: no arrays (np.ndim costs 1 us)
        values, finite = value, math.isfinite(value)
    else:
        values = float(value) if np.ndim(value) == 0 else np.asarray(value, dtype=float)
        finite = np.isfinite(values)
    for holds, failed_sign in ((finite, None), (allowed.sign_holds(values), True),
                               (allowed.magnitude_holds(values), False)):
        index = _first_failure(holds)
        if index is None:
            continue
        bad = value_at(values, index)
        rule = ("must be a finite real number" if failed_sign is None
                else allowed.describe(failed_sign))
        why = f": {allowed.why}" if allowed.why and not failed_sign else ""
        unit_text = f" ({unit})" if unit != "1" else ""
        raise ParameterError(f"{point(index)}{name} = {bad!r} is not allowed: {rule}{unit_text}"
                             f"{why}")


def check_joint(values: Mapping[str, Any], point: PointName = no_point,
                partner: Counterpart = BEAM, mount: Mount = BOTH,
                compliance1: float | None = None,
                contact: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> None:
    """Raise ParameterError unless the resolved parameters are jointly allowed.

    ``values``: every numeric field of [`Params`][] (EI/rhoA form), as floats or arrays that
    broadcast against each other (a sweep's corner grid). Each condition is monotone in every
    parameter, so a sweep that passes at the corners of its box passes everywhere. Against a
    ``partner`` without beam 2 (a stop) beam 1 alone closes the clearance, and uplift2 must be 0.

    Small deflections bound every drive by a tip deflection of MAX_DEFLECTION times the
    beam's length: the tip force by its static deflection F0 l1^3 / (3 EI1), the shaker by
    its own motion U0, which each beam it carries (``mount``; a stop's mount drives beam 1)
    passes to its tip against a counterpart that does not follow, and more near a resonance.

    ``contact``: (s, u1(x1), u2(x2)), the contact's side and each beam's unit tip-load shape at
    its contact point (`Params.contact_shapes`; 1 at the tips): the uplifts must leave the
    initial gap at the contact point, clearance + s (u1 uplift1 - u2 uplift2), open.
    """
    # one set of parameters (floats: the common case, a period map per corrector iterate) is
    # checked in float arithmetic, a grid in arrays
    v = {name: value if type(value) is float else np.asarray(value, dtype=float)
         for name, value in values.items()}
    stop = not partner.has_beam2
    if stop:
        require_all("uplift2", v["uplift2"], v["uplift2"] == 0, point, lambda j: (
            "must be 0 with counterpart = 'stop' (there is no beam 2 to lift)"))
    # the tips close the clearance by deflecting, each by at most MAX_DEFLECTION of its length
    reach = v["l1"] if stop else v["l1"] + v["l2"]
    require_all("clearance", v["clearance"], v["clearance"] <= MAX_DEFLECTION * reach, point,
                lambda j: _deflection_rule("the clearance", "l1" if stop else "(l1 + l2)",
                                           reach, j))
    for i in ("1", "2"):
        require_all(f"uplift{i}", v[f"uplift{i}"],
                    np.abs(v[f"uplift{i}"]) <= MAX_DEFLECTION * v[f"l{i}"], point,
                    lambda j, i=i: _deflection_rule(f"|uplift{i}|", f"l{i}", v[f"l{i}"], j))
    side, shape1, shape2 = contact
    if contact == (1.0, 1.0, 1.0):  # at the tips, from below
        gap, formula = v["clearance"] + v["uplift1"] - v["uplift2"], "clearance + uplift1 - uplift2"
        named = "uplift2"
    else:
        gap = v["clearance"] + side * (shape1 * v["uplift1"] - shape2 * v["uplift2"])
        formula = (f"at the contact point, clearance {'+' if side > 0 else '-'} "
                   f"({shape1:.6g} uplift1 - {shape2:.6g} uplift2)")
        named = "uplift1"
    require_all(named, v[named], gap > 0, point, lambda j: (
        f"the initial gap {formula} = {value_at(gap, j)!r} m must be > 0 (m)"))
    uniform = compliance1 is None  # else beam 1's tip compliance with its attachments (m/N)
    compliance = v["l1"] ** 3 / (3.0 * v["EI1"]) if uniform else compliance1
    static = v["force_amplitude"] * compliance
    formula = "F0 l1^3 / (3 EI1)" if uniform else "F0 c1 (c1 with beam 1's attachments)"
    require_all("force_amplitude", v["force_amplitude"], static <= MAX_DEFLECTION * v["l1"],
                point, lambda j: _deflection_rule(
                    f"its static tip deflection {formula} = {value_at(static, j):.3g} m",
                    "l1", v["l1"], j) + ", i.e. force_amplitude <= "
                f"{MAX_DEFLECTION * value_at(v['l1'] / compliance, j):.3g} N for this beam 1")
    beams = mount.shaken_beams(partner)
    shaken = v["l" + beams[0]] if len(beams) == 1 else np.minimum(v["l1"], v["l2"])
    require_all("base_amplitude", v["base_amplitude"],
                v["base_amplitude"] <= MAX_DEFLECTION * shaken, point,
                lambda j: _deflection_rule(
                    "the shaker's motion", "l" + beams[0] if len(beams) == 1 else "min(l1, l2)",
                    shaken, j))
    for i in ("1", "2"):
        fundamental = (np.sqrt(v[f"EI{i}"] / v[f"rhoA{i}"])
                       * (FIRST_CANTILEVER_ROOT / v[f"l{i}"]) ** 2)
        require_all(f"l{i}", v[f"l{i}"], fundamental <= MAX_FREQUENCY, point,
                    lambda j, i=i, f=fundamental: (
                        f"beam {i}'s fundamental frequency sqrt(EI{i} / rhoA{i}) (1.875 / l{i})^2"
                        f" = {value_at(f, j):.3g} rad/s must be <= {MAX_FREQUENCY:g} rad/s: a "
                        "continuum beam model does not hold at higher frequencies (check "
                        f"l{i}, EI{i}, rhoA{i} or the material keys)"))


def value_at(array: Any, index: tuple[int, ...]) -> float:
    """Element ``index`` of the grid that ``array`` broadcasts to (numpy's trailing alignment)."""
    array = np.asarray(array)
    own = index[len(index) - array.ndim:] if array.ndim else ()
    return float(array[tuple(min(k, n - 1) for k, n in zip(own, array.shape, strict=True))])


def _deflection_rule(what: str, length: str, lengths: np.ndarray, index: tuple[int, ...]) -> str:
    limit = MAX_DEFLECTION * value_at(lengths, index)
    return (f"{what} must be <= {MAX_DEFLECTION:g} {length} = {limit:.3g} m (small deflections: "
            "the beam model is linear)")


def require_all(name: str, value: np.ndarray, ok: np.ndarray, point: PointName,
                rule: Callable[[tuple[int, ...]], str]) -> None:
    """Raise ParameterError naming ``name``'s value where ``ok`` fails first."""
    index = _first_failure(ok)
    if index is not None:
        raise ParameterError(f"{point(index)}{name} = {value_at(value, index)!r} is not allowed: "
                             f"{rule(index)}")


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


# the laws, counterparts and shaker mounts by name (`impactbeams.configuration`), the default
# first: the spring law, whose first contacts converge in the number of modes
CONTACT_LAWS = tuple(configuration.LAWS)
DEFAULT_CONTACT_LAW = CONTACT_LAWS[0]
# what beam 1's tip meets: beam 2's tip, or a fixed rigid stop (no modes, no compliance)
COUNTERPARTS = tuple(configuration.COUNTERPARTS)
# where the contact acts along each beam (m from the clamp; None: the tip), `Params.contact_point`
CONTACT_POSITIONS = ("contact_position1", "contact_position2")
# keys that describe beam 2: refused when given with a counterpart that has no beam 2
BEAM2_KEYS = ("l2", "EI2", "rhoA2", *(key + "2" for key in MATERIAL_KEYS), "attachments2",
              "segments2", "contact_position2")
# several contacts (`impactbeams.Contact`), each with its own point, side, clearance and law
CONTACTS = "contacts"
# the run's keys a Contact stands for (with several contacts, each contact's own)
CONTACT_FIELDS = tuple(FLAT_KEYS.values())
# those of them that are the defaults of contacts leaving theirs out (the point and side are not)
CONTACT_LAW_KEYS = ("clearance", "contact_stiffness", "contact_damping")
# the flat keys that say where and from which side the one contact acts: given with
# ``contacts``, they would say it twice
_CONTACT_PLACE = (*CONTACT_POSITIONS, "contact_side")
# each beam's point masses and springs (`impactbeams.structure`), given from Python
ATTACHMENTS = ("attachments1", "attachments2")
# each beam as uniform segments from the clamp out (a stepped beam), in place of l, EI, rhoA
BEAM_SEGMENTS = ("segments1", "segments2")
# |l - the segments' total| (relative) within which a given l is that length: the total is
# rounded once (math.fsum), a length typed in decimals may be an ulp or two off it
_SAME_LENGTH = 8 * np.finfo(float).eps
# beam 1 as the user's own structure (`impactbeams.structure.user`): an object or a .npz file
USER_STRUCTURE = "structure1"
# what a user structure replaces: beam 1's keys (l1, EI1, rhoA1 are then its equivalent beam's)
BEAM1_KEYS = ("l1", "EI1", "rhoA1", *(key + "1" for key in MATERIAL_KEYS), "attachments1",
              "segments1", "contact_position1")
_EQUIVALENT_BEAM1 = ("l1", "EI1", "rhoA1")
# fields a run's parameters (Datasets, files) name only when they differ from the default: the
# attachments, a stepped beam's segments, a user structure and where and from which side the
# contact acts
_ONLY_IF_GIVEN = (*ATTACHMENTS, *BEAM_SEGMENTS, USER_STRUCTURE, *CONTACT_POSITIONS,
                  "contact_side", "contacts")
SHAKERS = tuple(configuration.MOUNTS)  # which clamps the shaker carries (impactbeams.drive)
# the parameters whose value is a name, and the names allowed (the default first)
CHOICES = {"contact_law": CONTACT_LAWS, "counterpart": COUNTERPARTS,
           "contact_side": tuple(configuration.SIDES), "shaker": SHAKERS, "start": layout.STARTS}
# N, the paper's tip force: the default drive of a study that names no base motion
DEFAULT_FORCE_AMPLITUDE = 1e-3
# said once per run of a stop on a shaker whose shaker is left to its default (`moving_stop`)
MOVING_STOP = ("shaker = 'both' (the default) moves the stop with beam 1's clamp, as on one "
               "shaker table: set shaker = 'beam1' for a fixed stop, or shaker = 'both' to say "
               "so")
# no joint rule (`check_joint`, `Params._check_together`) reads these: a change of them alone
# is checked on its own (a continuation in Omega asks for Params at every corrector iterate)
UNJOINED = ("omega",)
DRIVES = ("force_amplitude", "base_amplitude")  # their defaults depend on which are given


def moving_stop(stop: bool, shaken: bool, named: bool) -> str | None:
    """`MOVING_STOP` where a ``stop`` on a shaker (``shaken``) moves with it unasked.

    ``named``: whether the shaker was given; one not given carries both clamps (the default).
    """
    return MOVING_STOP if stop and shaken and not named else None


DEFAULT_TIP_RADIUS = 1e-3  # m, of the default contact stiffness
DEFAULT_CONTACT_FORCE = 1e-3  # N, force scale of the default contact stiffness
DEFAULT_CONTACT_STIFFNESS = hertz_stiffness(DEFAULT_TIP_RADIUS, DEFAULT_CONTACT_FORCE)


@dataclasses.dataclass(frozen=True, init=False)
class Params:
    """Parameters of the two-beam impact model (SI units, see the module docstring).

    Build it with keywords, the material keys among them (``Params(clearance=2e-5)``,
    ``Params(width1=0.02)``), from a mapping ([`from_mapping`][]) or from a TOML file
    ([`from_toml`][]). Every value is validated on construction; a bad value, or an unknown
    key, raises [`ParameterError`][].
    """

    l1: float = 0.1
    l2: float = 0.12
    EI1: float = DEFAULT_EI
    EI2: float = DEFAULT_EI
    rhoA1: float = DEFAULT_RHOA
    rhoA2: float = DEFAULT_RHOA
    clearance: float = 1.1e-5
    force_amplitude: float | None = None  # DEFAULT_FORCE_AMPLITUDE, or 0 (`_resolve_drives`)
    omega: float = 50.0
    uplift1: float = 0.0
    uplift2: float = 0.0
    damping_ratio: float = 0.0
    contact_law: str = DEFAULT_CONTACT_LAW
    contact_stiffness: float = DEFAULT_CONTACT_STIFFNESS
    contact_damping: float = 0.0
    counterpart: str = BEAM.name
    base_amplitude: float | None = None  # 0.0; None: not given (`_resolve_drives`)
    shaker: str = BOTH.name
    start: str = "rest"
    attachments1: tuple[Attachment, ...] = ()
    attachments2: tuple[Attachment, ...] = ()
    segments1: tuple[Segment, ...] = ()  # two or more; one segment is l1, EI1, rhoA1
    segments2: tuple[Segment, ...] = ()
    structure1: MatrixStructure | ModalStructure | None = None
    contact_position1: float | None = None  # m from beam 1's clamp; None: its tip
    contact_position2: float | None = None  # m from beam 2's clamp; None: its tip
    contact_side: str = configuration.BELOW.name
    contacts: tuple[Contact, ...] = ()  # two or more (`impactbeams.Contact`); one: the flat keys

    def __init__(self, **values: Any) -> None:
        """Every parameter by keyword (SI units); the material keys replace a beam's EI, rhoA."""
        given = _field_values(fold_contacts(values, "Params()"), "Params()", given_fields=False)
        for field in dataclasses.fields(self):
            object.__setattr__(self, field.name, given.get(field.name, field.default))
        # kept as the drives are (`replace`): whether ``shaker = "both"`` moves a stop unasked
        object.__setattr__(self, "_shaker_named", "shaker" in given)
        self.__post_init__()

    def __post_init__(self) -> None:
        self._resolve_drives()
        self._take_segments()
        for name, allowed in CHOICES.items():
            value = getattr(self, name)
            require(name, value, isinstance(value, str) and value in allowed,
                    f"must be one of {', '.join(map(repr, allowed))}")
        for name in self.numeric_names():
            self._set_checked(name, getattr(self, name))
        for name in CONTACT_POSITIONS:
            if getattr(self, name) is not None:
                object.__setattr__(self, name, require_finite(name, getattr(self, name), "m"))
        for name in ATTACHMENTS:
            parts = getattr(self, name)
            require(name, parts, isinstance(parts, (tuple, list)),
                    "must be a tuple of impactbeams.structure.PointMass and Spring parts (in a "
                    "TOML file: an array of tables)")
            object.__setattr__(self, name, tuple(as_part(f"{name}[{index}]", part)
                                                 for index, part in enumerate(parts)))
        if not self.partner.has_beam2:
            for field in dataclasses.fields(Params):
                if field.name in BEAM2_KEYS:
                    require(field.name, getattr(self, field.name),
                            getattr(self, field.name) == field.default, _NO_BEAM2)
        if self.structure1 is not None:
            self._take_structure1()
        self._check_together()

    def _take_structure1(self) -> None:
        """Beam 1 as the user's structure (an object, or a .npz file read here).

        Beam 1's own keys must be left out; l1, EI1 and rhoA1 become those of its equivalent
        uniform cantilever (its length scale, its tip compliance l1^3 / (3 EI1), its fundamental
        frequency), which only the checks and the cost estimates read.
        """
        from impactbeams.structure.user import MatrixStructure, ModalStructure, read_structure

        structure = self.structure1
        if isinstance(structure, (str, Path)):
            structure = read_structure(structure, USER_STRUCTURE)
        require(USER_STRUCTURE, structure, isinstance(structure, (MatrixStructure, ModalStructure)),
                "must be an impactbeams.MatrixStructure, a ModalStructure or the path of a .npz "
                "file")
        # (the segments' own: named; a contact's position names one of the structure's DOFs)
        derived = (*(_EQUIVALENT_BEAM1 if self.segments1 else ()), "contact_position1")
        for field in dataclasses.fields(Params):
            if field.name in BEAM1_KEYS and field.name not in derived:
                require(field.name, getattr(self, field.name),
                        getattr(self, field.name) == field.default, _STRUCTURE_IS_BEAM1)
        require(USER_STRUCTURE, structure, self.law.tangent_flow,
                f"contact_law = {self.contact_law!r} supports the paper's uniform beams only: "
                "use contact_law = 'spring' with a user structure")
        structure.require_run_damping(self.damping_ratio)
        EI = structure.length**3 / (3.0 * structure.tip_compliance)
        fundamental = float(structure.modes(1).frequencies[0])
        rhoA = EI * (FIRST_CANTILEVER_ROOT / structure.length) ** 4 / fundamental**2
        for name, value in (("structure1", structure), ("l1", structure.length), ("EI1", EI),
                            ("rhoA1", rhoA)):
            object.__setattr__(self, name, value)

    def _take_segments(self) -> None:
        """Each stepped beam's l, EI and rhoA: its length, tip compliance and mass.

        l is the segments' total length, EI that of the uniform beam of the same tip
        compliance (l^3 / (3 EI)) and rhoA its mean mass per length: the input checks and the
        cost estimates read them; the runs take the segments (`structure`).
        """
        for i in ("1", "2"):
            segments = getattr(self, "segments" + i)
            if not segments:
                continue
            bare = _cantilever(segments, ())
            length = bare.length
            for key, value in (("l", length), ("EI", length**3 / (3.0 * bare.tip_compliance)),
                               ("rhoA", math.fsum(s.length * s.rhoA for s in segments) / length)):
                object.__setattr__(self, key + i, value)

    def derived_keys(self) -> tuple[str, ...]:
        """The beams' l, EI, rhoA that are derived, not given: a stepped beam's, a structure's.

        A Dataset and a copy (`replace`) leave them out: the segments or the structure say them.
        """
        keys = _EQUIVALENT_BEAM1 if self.structure1 is not None else ()
        for i in ("1", "2"):
            if getattr(self, "segments" + i):
                keys += ("l" + i, "EI" + i, "rhoA" + i)
        return keys

    def _set_checked(self, name: str, value: Any) -> None:
        """Set the numeric parameter ``name`` to ``value`` as a float, if allowed."""
        value = require_finite(name, value, PARAMETERS[name].units)
        check_range(name, value)
        object.__setattr__(self, name, value)

    def _check_together(self) -> None:
        """The joint rules of the numeric parameters, the choices and the attachments.

        With several contacts each contact's own run (`each_contact`) is checked whole.
        """
        if self.contacts:
            if self.law.projects:
                raise ParameterError(
                    f"{CONTACTS}: {len(self.contacts)} contacts are not allowed with contact_law "
                    f"= {self.contact_law!r} (the paper's law ties the tips in one contact): use "
                    "contact_law = 'spring' for several contacts")
            for index, contact in enumerate(self.contacts):
                require(f"{CONTACTS}[{index}]", contact, contact not in self.contacts[:index],
                        "must differ from the contacts before it (the same contact twice)")
            object.__setattr__(self, "_each_contact",
                               tuple(self._alone(i) for i in range(len(self.contacts))))
            return
        for which, name in enumerate(ATTACHMENTS, start=1):
            parts = getattr(self, name)
            if not parts:  # the common case, checked once per period map of a continuation
                continue
            check_attachments(parts, getattr(self, f"l{which}"), name)
            check_clamp(parts)
            require(name, parts, self.law.tangent_flow,
                    f"contact_law = {self.contact_law!r} supports the paper's uniform beams "
                    "only: use contact_law = 'spring' for a beam with attachments")
        for name in BEAM_SEGMENTS:
            require(name, getattr(self, name), not getattr(self, name) or self.law.tangent_flow,
                    f"contact_law = {self.contact_law!r} supports the paper's uniform beams "
                    "only: use contact_law = 'spring' for a stepped beam")
        self._check_contact_point()
        # a compliant clamp lets the tip force deflect the tip more than l1^3 / (3 EI1)
        check_joint(self.numeric(), partner=self.partner, mount=self.mount,
                    compliance1=self.structure(1).tip_compliance if self.attachments1 else None,
                    contact=self.contact_shapes)
        if self.structure1 is not None and "1" in self.mount.shaken_beams(self.partner):
            self.structure1.require_support(self.base_amplitude)
        # with one clamp moving, the tied tips' quasi-static part would carry a moving
        # clearance: not built
        require("base_amplitude", self.base_amplitude,
                self.base_amplitude == 0.0 or self.law.tangent_flow
                or self.mount.carries_both_clamps,
                "with contact_law = 'tied' the shaker must carry both clamps (shaker = 'both', "
                f"not {self.shaker!r}), or use contact_law = 'spring'")

    def _alone(self, index: int) -> Params:
        """These parameters with contact ``index`` of ``contacts`` alone (its errors named)."""
        try:
            return self.replace(**{CONTACTS: (self.contacts[index],)})
        except ParameterError as error:
            raise ParameterError(f"{CONTACTS}[{index}]: {error}") from None

    @property
    def several_contacts(self) -> bool:
        """Whether the run has two or more contacts (``contacts``)."""
        return bool(self.contacts)

    def each_contact(self) -> tuple[Params, ...]:
        """Each contact's own run: these parameters with that contact alone, by the flat keys.

        ``(self,)`` for one contact. The free phase of all of them is the same (the contacts'
        points, sides and laws act only in contact), which is what the first contact among
        several is found from (`impactbeams.trajectory.first_contact`).
        """
        return getattr(self, "_each_contact", (self,))

    def _check_contact_point(self) -> None:
        """A contact position on its beam (0 < x <= l); elsewhere than the tips only if compliant.

        On a user structure (``structure1``) beam 1's position must name one of its points
        (its contact DOFs' positions, or its tip, the force DOF).

        The tied law (the paper's) ties the tips from below: its contact modes are those of
        tied tips (or of beam 1 pinned at its tip), so a contact elsewhere or from above is
        refused, naming the parameter, before any compute.
        """
        for which, name in enumerate(CONTACT_POSITIONS, start=1):
            position, length = getattr(self, name), getattr(self, f"l{which}")
            require(name, position, position is None or 0.0 < position <= length,
                    f"must be > 0 and <= l{which} = {length!r} (m: a point of beam {which}, "
                    "its distance from the clamp)")
        if self.structure1 is not None and self.contact_position1 is not None:
            self.structure1.require_position(CONTACT_POSITIONS[0], self.contact_position1)
        if (self.at_tips and self.side.sign > 0.0) or self.law.tangent_flow:
            return
        name = next((key for key, tip in zip(CONTACT_POSITIONS, (self.l1, self.l2), strict=True)
                     if getattr(self, key) not in (None, tip)), "contact_side")
        require(name, getattr(self, name), False,
                f"contact_law = {self.contact_law!r} (the paper's law) ties the tips, beam 1 "
                "moving down onto its counterpart: use contact_law = 'spring' for a contact "
                "elsewhere or from above")

    def _resolve_drives(self) -> None:
        """The drives not given: no base motion; the tip force only if no base motion is named.

        A study of a shaker (``base_amplitude`` given, whatever its value) gets no tip force
        unless it gives ``force_amplitude`` too; without a shaker the tip force is the paper's
        1 mN. Which were given is kept (``_given_drives``, not a field): a copy (`replace`)
        resolves the others again, as if built with its changes.
        """
        given = frozenset(name for name in DRIVES if getattr(self, name) is not None)
        object.__setattr__(self, "_given_drives", given)
        named_base = self.base_amplitude is not None
        if not named_base:
            object.__setattr__(self, "base_amplitude", 0.0)
        if self.force_amplitude is None:
            object.__setattr__(self, "force_amplitude",
                               0.0 if named_base else DEFAULT_FORCE_AMPLITUDE)

    @staticmethod
    @functools.cache
    def numeric_names() -> tuple[str, ...]:
        """Names of the numeric parameters (all but the named choices), in field order."""
        return tuple(f.name for f in dataclasses.fields(Params)
                     if f.name not in CHOICES and f.name not in ATTACHMENTS
                     and f.name not in BEAM_SEGMENTS and f.name not in (USER_STRUCTURE, CONTACTS)
                     and f.name not in CONTACT_POSITIONS)

    def numeric(self) -> dict[str, float]:
        """The numeric parameters by name (SI units)."""
        return {name: getattr(self, name) for name in self.numeric_names()}

    @property
    def law(self) -> ContactLaw:
        """The contact law (`impactbeams.configuration.ContactLaw`) named by ``contact_law``."""
        return configuration.LAWS[self.contact_law]

    @property
    def partner(self) -> Counterpart:
        """What beam 1's tip meets (`impactbeams.configuration.Counterpart`): ``counterpart``."""
        return configuration.COUNTERPARTS[self.counterpart]

    @property
    def side(self) -> Side:
        """Which way beam 1 closes the contact (`impactbeams.configuration.Side`)."""
        return configuration.SIDES[self.contact_side]

    @property
    def contact_point(self) -> tuple[float, float]:
        """Where the contact acts: (x1, x2), m from each beam's clamp (x2 = 0.0 at a stop).

        The tips (l1, l2) unless ``contact_position1`` / ``contact_position2`` say otherwise.
        """
        x1 = self.l1 if self.contact_position1 is None else self.contact_position1
        if not self.partner.has_beam2:
            return x1, 0.0
        return x1, self.l2 if self.contact_position2 is None else self.contact_position2

    @property
    def contact_shapes(self) -> tuple[float, float, float]:
        """(s, u1(x1), u2(x2)): the side's sign and each beam's unit tip-load shape there.

        u_i(x) = (3 l x^2 - x^3) / (2 l^3) on a bare beam (its static deflection under a tip
        force, per unit tip deflection: how an uplift moves the contact point), that of the
        beam with its attachments or of the user's structure (at its contact DOF) otherwise;
        exactly (1.0, 1.0, 1.0) at the tips from below.
        """
        shapes = []
        for which, x in enumerate(self.contact_point, start=1):
            length = getattr(self, f"l{which}")
            if x == length or (which == 2 and not self.partner.has_beam2):
                shapes.append(1.0)
            elif which == 1 and self.structure1 is not None:  # at one of its contact DOFs
                shapes.append(float(self.structure1.unit_tip_shape(np.array([x]))[0]))
            elif not self.uniform_beam(which):
                shapes.append(float(self.structure(which).unit_tip_shape(np.array([x]))[0]))
            else:
                shapes.append((3.0 * length * x * x - x**3) / (2.0 * length**3))
        return self.side.sign, shapes[0], shapes[1]

    @property
    def at_tips(self) -> bool:
        """Whether the contact acts between the tips (or beam 1's tip and a stop)."""
        return (self.contact_position1 in (None, self.l1)
                and (self.contact_position2 in (None, self.l2) or not self.partner.has_beam2))

    @property
    def mount(self) -> Mount:
        """The clamps the shaker carries (`impactbeams.configuration.Mount`): ``shaker``."""
        return configuration.MOUNTS[self.shaker]

    @property
    def shaker_named(self) -> bool:
        """Whether ``shaker`` was given (not left to its default, "both")."""
        return getattr(self, "_shaker_named", True)

    @property
    def damped(self) -> bool:
        """Whether any free mode is damped: ``damping_ratio`` > 0 or beam 1's own damping."""
        return self.damping_ratio > 0.0 or (self.structure1 is not None
                                            and self.structure1.has_damping)

    def moving_stop(self) -> str | None:
        """The line that says a shaker left at "both" moves the stop too (None if it does not).

        Against a stop, with base motion, the default ``shaker = "both"`` carries the stop's
        mount with beam 1's clamp (a shaker table with both on it): the gap sees only beam 1's
        motion relative to its clamp. Said once per run where the shaker was not named.
        """
        return moving_stop(not self.partner.has_beam2, self.base_amplitude > 0.0,
                           self.shaker_named)

    @property
    def initial_gap(self) -> float:
        """Gap at the contact point at t = 0 (m): clearance + uplift1 - uplift2 at the tips.

        Elsewhere ``clearance + s (u1(x1) uplift1 - u2(x2) uplift2)`` (`contact_shapes`).
        """
        side, shape1, shape2 = self.contact_shapes
        if (side, shape1, shape2) == (1.0, 1.0, 1.0):
            return self.clearance + self.uplift1 - self.uplift2
        return self.clearance + side * (shape1 * self.uplift1 - shape2 * self.uplift2)

    def structure(self, which: int) -> Cantilever:
        """Beam ``which`` (1 or 2) as a cantilever: its segments, carrying its ``attachments``.

        A beam not given by ``segments`` is one segment of its l, EI, rhoA.
        """
        i = str(which)
        segments = getattr(self, "segments" + i) or _uniform(
            getattr(self, "l" + i), getattr(self, "EI" + i), getattr(self, "rhoA" + i))
        return _cantilever(segments, getattr(self, "attachments" + i))

    def uniform_beam(self, which: int) -> bool:
        """Whether beam ``which`` is the textbook cantilever: one segment, nothing attached.

        Its modes, tip compliance and static shape are then in closed form.
        """
        i = str(which)
        return not (getattr(self, "attachments" + i) or getattr(self, "segments" + i))

    @property
    def grounded_springs(self) -> int:
        """The most springs to ground on one beam (`preflight.highest_frequency`'s bound).

        A translational and a rotational spring at one point count apart; a spring at the clamp
        does not count (a compliant clamp softens the beam).
        """
        return max(sum((part.stiffness > 0) + (part.rotational_stiffness > 0)
                       for part in parts if isinstance(part, Spring) and part.position > 0)
                   for parts in (self.attachments1, self.attachments2))

    @property
    def step_factors(self) -> tuple[float, float]:
        """How far each beam's frequencies may lie above those of its l, EI, rhoA (1 if uniform).

        A stepped beam's Rayleigh quotient is at most max(EI) / min(rhoA) times that of the
        same shape on a beam of unit EI and rhoA, so (min-max) each of its frequencies is at
        most sqrt(max(EI) / min(rhoA)) / sqrt(EI / rhoA) times its equivalent uniform beam's
        (`preflight.highest_frequency`'s bound).
        """
        factors = []
        for i in ("1", "2"):
            segments = getattr(self, "segments" + i)
            factors.append(math.sqrt(max(s.EI for s in segments) / min(s.rhoA for s in segments)
                                     * getattr(self, "rhoA" + i) / getattr(self, "EI" + i))
                           if segments else 1.0)
        return factors[0], factors[1]

    @property
    def tip_compliance(self) -> tuple[float, float]:
        """Static tip compliances c_i of the two cantilevers (m/N), l_i^3 / (3 EI_i) if uniform.

        A rigid stop gives way by nothing: c2 = 0.
        """
        c2 = self._tip_compliance(2) if self.partner.has_beam2 else 0.0
        return (self._tip_compliance(1) if self.structure1 is None
                else self.structure1.tip_compliance), c2

    def _tip_compliance(self, which: int) -> float:
        """Beam ``which``'s tip compliance (m/N), l^3 / (3 EI) for a bare beam.

        With attachments its cantilever's (the Green's function: a module loaded only then).
        """
        i = str(which)
        if not self.uniform_beam(which):
            return self.structure(which).tip_compliance
        return getattr(self, "l" + i) ** 3 / (3 * getattr(self, "EI" + i))

    @property
    def wave_constant(self) -> tuple[float, float]:
        """a_i = sqrt(EI_i / rhoA_i) of the two beams (m^2/s)."""
        return math.sqrt(self.EI1 / self.rhoA1), math.sqrt(self.EI2 / self.rhoA2)

    def as_dict(self) -> dict[str, Any]:
        """All parameters by name, in the resolved EI/rhoA form; attachments only if any.

        With a user structure (``structure1``) beam 1 is that structure: its equivalent beam's
        l1, EI1, rhoA1 are left out.
        """
        # floats, names and frozen parts only: no deep copy needed (dataclasses.asdict's cost)
        derived = self.derived_keys()
        return {field.name: getattr(self, field.name) for field in _FIELDS()
                if (field.name not in _ONLY_IF_GIVEN
                    or getattr(self, field.name) != field.default)
                and field.name not in derived}

    def replace(self, **changes: Any) -> Params:
        """Return a copy with some parameters changed (material keys allowed).

        A drive left to its default stays a default: ``Params().replace(base_amplitude=U0)``
        is ``Params(base_amplitude=U0)``, a shaker study without tip force. A law key that
        every contact gives its own of is refused among the changes (`refuse_unused_law_keys`)
        and left out of the copy's other values.
        """
        contacts = changes.get(CONTACTS, self.contacts)
        refuse_unused_law_keys(changes, contacts, "Params.replace()")
        if changes.keys() <= _CHECKED_ALONE and not (
                not self.partner.has_beam2 and changes.keys() & BEAM2_KEYS) and not (
                self.structure1 is not None and changes.keys() & BEAM1_KEYS) and not (
                (self.segments1 or self.segments2)
                and changes.keys() & set(self.derived_keys())):
            # numbers other than the drives, on parameters already checked: only the changes
            # and the joint rules need checking (a continuation changes one per period map)
            changed = object.__new__(Params)  # copy.copy's reduce protocol takes 5 us
            changed.__dict__.update(self.__dict__)
            for name, value in changes.items():
                changed._set_checked(name, value)
            if changed.contacts or not changes.keys() <= set(UNJOINED):
                changed._check_together()  # (with several contacts it builds each one's run)
            return changed
        unused = set_by_every_contact(contacts)
        base = {name: value for name, value in self.as_dict().items()
                if (name not in DRIVES or name in getattr(self, "_given_drives", DRIVES))
                and name not in unused}
        if not self.shaker_named:
            del base["shaker"]
        for i in ("1", "2"):
            if any(k + i in changes for k in MATERIAL_KEYS):
                del base["EI" + i], base["rhoA" + i]
            if changes.get("segments" + i):  # the segments replace the beam's l, EI, rhoA
                for key in ("l", "EI", "rhoA"):
                    base.pop(key + i, None)
        if not configuration.counterpart_named(changes.get("counterpart", self.counterpart)
                                               ).has_beam2:  # beam 2 left at its defaults
            base = {key: value for key, value in base.items() if key not in BEAM2_KEYS}
        return Params.from_mapping({**base, **changes})

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any], source: str = "parameters") -> Params:
        """Build from a mapping of names to values, resolving the material keys of each beam.

        ``source`` names where the mapping came from, for error messages.
        """
        require_type("mapping", mapping, isinstance(mapping, Mapping),
                     "a mapping of parameter names to values")
        refuse_unused_law_keys(mapping, mapping.get(CONTACTS, ()), source)
        return cls(**_field_values(mapping, source, given_fields=True))

    @classmethod
    def from_toml(cls, path: str | Path) -> Params:
        """Read the ``[params]`` table of a TOML file; unspecified keys take the defaults."""
        data = read_toml(path)
        for key in data:
            if key != "params":
                raise ParameterError(f"unknown key {key!r} in {path}{nearest(key, ['params'])}: "
                                     "a parameters file has only a [params] table")
        return cls.from_mapping(require_table(data, "params", str(path)),
                                source=f"[params] of {path}")


# the numbers `Params.replace` checks alone on parameters already checked: all but the drives
_CHECKED_ALONE = frozenset(Params.numeric_names()) - frozenset(DRIVES)
_NO_BEAM2 = "counterpart = 'stop' has no beam 2: leave beam 2's keys out"
_STRUCTURE_IS_BEAM1 = "structure1 is beam 1 (a user structure): leave beam 1's keys out"


@functools.lru_cache(maxsize=64)
def _cantilever(segments: tuple[Segment, ...],
                attachments: tuple[Attachment, ...]) -> Cantilever:
    """The checked `Cantilever` of a beam, built once (a run asks for it often, 15 us each)."""
    from impactbeams.structure.cantilever import Cantilever

    return Cantilever(segments, attachments)


@functools.lru_cache(maxsize=64)
def _uniform(length: float, EI: float, rhoA: float) -> tuple[Segment]:
    """The one segment of a uniform beam (m, N m^2, kg/m), built once."""
    return (Segment(length, EI, rhoA),)


def modes_per_beam(n_modes: int, partner: Counterpart) -> str:
    """``"16 modes per beam"``, or against a stop (one beam) ``"16 modes of beam 1"``."""
    return f"{n_modes} modes {partner.modes_words}"


def _field_values(values: Mapping[str, Any], source: str, given_fields: bool,
                  ) -> dict[str, Any]:
    """[`Params`][]' fields given in ``values`` (from ``source``), the material keys resolved.

    An unknown key, or a key of beam 2 against a stop, raises ParameterError: any such key of
    a mapping that is ``given_fields`` (a file's, a user's); of keywords, which copies of a
    Params pass whole (``dataclasses.replace``), beam 2's material keys only (its fields at
    their defaults are checked on construction).
    """
    for key in values:
        if key not in PARAMETERS and key not in (*ATTACHMENTS, *BEAM_SEGMENTS, USER_STRUCTURE,
                                                 CONTACTS):
            raise unknown_key("parameter", key, source, [*sorted(PARAMETERS), *ATTACHMENTS,
                                                         *BEAM_SEGMENTS, USER_STRUCTURE, CONTACTS])
    if not configuration.counterpart_named(values.get("counterpart")).has_beam2:
        refuse_beam2([key for key in values if given_fields or key[:-1] in MATERIAL_KEYS],
                     source)
    return resolve_materials(fold_segments(values, source), source)


def fold_segments(values: Mapping[str, Any], source: str) -> dict[str, Any]:
    """``values`` with each beam's ``segments`` checked: one segment becomes its l, EI, rhoA.

    Beside segments, the beam's EI, rhoA or material keys raise ParameterError (each segment
    gives its own), and so does its l unless it is the segments' total length (then it is
    dropped: `Params._take_segments` sets it). Each segment's values must be allowed values
    of l, EI and rhoA. One segment is the simple form: its fields replace the flat keys, so
    that it gives the uniform beam's run bit for bit; two or more stay ``segments``.
    """
    folded = dict(values)
    for i in ("1", "2"):
        name = "segments" + i
        if name not in folded:
            continue
        segments = folded.pop(name)
        require(name, segments, isinstance(segments, (tuple, list)),
                "must be a tuple of impactbeams.Segment (in a TOML file: an array of tables, "
                f"[[params.{name}]])")
        segments = tuple(as_segment(f"{name}[{j}]", s) for j, s in enumerate(segments))
        if not segments:
            continue
        for j, segment in enumerate(segments):
            require(f"{name}[{j}]", segment, isinstance(segment, Segment),
                    "must be an impactbeams.Segment (its length, EI and rhoA)")
            for field, key in SEGMENT_KEYS.items():
                check_range(key + i, getattr(segment, field),
                            lambda index, at=f"{name}[{j}].{field}": f"{at}: ")
        given = [key + i for key in ("EI", "rhoA", *MATERIAL_KEYS) if key + i in folded]
        if given:
            raise ParameterError(
                f"{', '.join(given)} in {source} {'is' if len(given) == 1 else 'are'} not "
                f"allowed with {name}: each segment gives its own EI and rhoA (leave beam {i}'s "
                f"{', '.join(given)} out)")
        total = math.fsum(s.length for s in segments)
        if "l" + i in folded:
            length = folded.pop("l" + i)
            require("l" + i, length, is_real(length) and abs(length - total) <= _SAME_LENGTH
                    * total, f"must equal the total length of {name}, {total!r} m (or be left "
                    "out: the segments give it)", "m")
        folded.update({"l" + i: segments[0].length, "EI" + i: segments[0].EI,
                       "rhoA" + i: segments[0].rhoA} if len(segments) == 1 else {name: segments})
    return folded


# the tuple parameters whose elements' fields are parameters of their own, named
# NAME.INDEX.FIELD: a contact's (``contacts.0.clearance``), an attachment's
# (``attachments1.0.mass``) and a segment's (``segments1.0.EI``)
ELEMENT_PARAMETERS = (CONTACTS, *ATTACHMENTS, *BEAM_SEGMENTS)
# the fields of any attachment (a point mass's or a spring's) and their units
ATTACHMENT_FIELDS = {name: unit for units in FIELD_UNITS.values() for name, unit in units.items()}
# each kind of a beam's element (its parts, its segments) and its fields' units
PART_FIELDS = {**FIELD_UNITS, Segment: SEGMENT_UNITS}


def element_field(name: str) -> tuple[str, int, str] | None:
    """(tuple parameter, index, field) of a name ``NAME.INDEX.FIELD``; None for any other.

    Only the form is read here (NAME one of ``ELEMENT_PARAMETERS``, an index of digits);
    what checks the name against the parameters (`impactbeams.sweep.definition`'s axes,
    `impactbeams.continuation.run.check_continued`) checks the index and the field.
    """
    parts = name.split(".")
    if len(parts) != 3 or parts[0] not in ELEMENT_PARAMETERS or not parts[1].isdigit() or not (
            parts[1] == "0" or not parts[1].startswith("0")):
        return None
    return parts[0], int(parts[1]), parts[2]


def contact_field(name: str) -> tuple[int, str] | None:
    """(index, field) of a contact's field ``contacts.INDEX.FIELD``; None for any other name."""
    field = element_field(name)
    return field[1:] if field is not None and field[0] == CONTACTS else None


def attachment_field(name: str) -> tuple[str, int, str] | None:
    """(attachments, index, field) of ``attachments1.INDEX.FIELD`` (or 2); None for others."""
    field = element_field(name)
    return field if field is not None and field[0] in ATTACHMENTS else None


def part_field(name: str) -> tuple[str, int, str] | None:
    """(tuple, index, field) of a beam's part's or segment's field; None for others.

    ``attachments1.0.mass`` or ``segments1.0.EI`` (or of beam 2): a field that changes the
    beam's geometry, checked at every value of its axis (`impactbeams.sweep.definition`).
    """
    field = element_field(name)
    return field if field is not None and field[0] != CONTACTS else None


def check_part_field(params: Params, what: str, name: str) -> None:
    """``name`` (``attachments1.INDEX.FIELD``, ``segments1...``) is a field of a part of params.

    A beam of one segment is its l, EI, rhoA (continue those).
    """
    which, index, field = part_field(name)
    parts = getattr(params, which)
    require(what, name, index < len(parts),
            f"there are {len(parts)} parts in params.{which}"
            + (f" (indices 0 to {len(parts) - 1})" if parts else "")
            + (" (one segment is the beam's l, EI, rhoA: continue those)"
               if which in BEAM_SEGMENTS and not parts else ""))
    fields = PART_FIELDS[type(parts[index])]
    require(what, name, field in fields,
            f"{which}[{index}] is a {type(parts[index]).__name__}: its fields are "
            f"{', '.join(fields)}")


def flat_parameter(name: str) -> str:
    """The parameter ``name`` sets in a run: a contact's field its flat key, any other itself.

    ``contacts.0.clearance`` sets contact 0's run's ``clearance`` (`Params.each_contact`); an
    attachment's field (``attachments1.0.mass``) has no flat key: itself.
    """
    field = contact_field(name)
    return name if field is None else FLAT_KEYS[field[1]]


def named_attributes(name: str) -> dict[str, str]:
    """CF attributes (units, long_name) of the parameter ``name`` as a coordinate.

    A contact's field (``contacts.0.clearance``) has its flat key's, naming the contact; an
    attachment's field (``attachments1.0.mass``) or a segment's (``segments1.0.EI``) its unit,
    naming the part.
    """
    element = element_field(name)
    if element is not None and element[0] != CONTACTS:
        which, index, field = element
        units, words = ((ATTACHMENT_FIELDS, FIELD_WORDS) if which in ATTACHMENTS
                        else (SEGMENT_UNITS, SEGMENT_WORDS))
        return {"units": units[field], "long_name": f"{words[field]} of {which}[{index}]"}
    attributes = parameter_attributes(flat_parameter(name))
    if element is not None:
        attributes["long_name"] += f" of {CONTACTS}[{element[1]}]"
    return attributes


def check_parameter(name: str, value: Any, point: PointName = no_point) -> None:
    """Raise ParameterError unless ``value`` (a float or an array) is allowed for ``name``.

    A numeric parameter's or a contact field's range (`check_range` of its flat key); a
    segment's field, that of its beam's key (``segments1.0.EI``: ``EI1``'s); an attachment's
    field, a finite real number >= 0 (where the part lies on its beam, the parameters' joint
    check).
    """
    field = part_field(name)
    if field is not None and field[0] in BEAM_SEGMENTS:
        check_range(SEGMENT_KEYS[field[2]] + field[0][-1], value, point)
        return
    if field is None:
        check_range(flat_parameter(name), value, point)
        return
    values = np.asarray(value, dtype=float)
    require_all(name, values, np.isfinite(values) & (values >= 0.0), point, lambda j: (
        f"must be a finite real number >= 0 ({ATTACHMENT_FIELDS[field[2]]})"))


def parameter_value(params: Params, name: str) -> Any:
    """The value of ``params``' parameter ``name``: its own, or that field of one element."""
    field = element_field(name)
    if field is None:
        return getattr(params, name)
    which, index, field_name = field
    if which == CONTACTS:  # a contact's run's value, its own or the flat default
        return getattr(params.each_contact()[index], FLAT_KEYS[field_name])
    return getattr(getattr(params, which)[index], field_name)


def with_parameter(params: Params, name: str, value: Any) -> Params:
    """``params`` with its parameter ``name`` (or that field of one element) set to ``value``."""
    field = element_field(name)
    if field is None:
        return params.replace(**{name: value})
    return params.replace(**with_element_fields({field[0]: getattr(params, field[0]),
                                                 name: value}))


def with_element_fields(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` with each ``NAME.INDEX.FIELD`` value set in that element of ``NAME``.

    An element is a part or contact (its field replaced) or a file's table (the field added:
    a swept field is left out of it).
    """
    plain: dict[str, Any] = {}
    elements: dict[str, list[Any]] = {}
    for name, value in values.items():
        field = element_field(name)
        if field is None:
            plain[name] = value
            continue
        which, index, field_name = field
        given = elements.setdefault(which, list(values.get(which, ())))
        given[index] = ({**given[index], field_name: value} if isinstance(given[index], dict)
                        else dataclasses.replace(given[index], **{field_name: value}))
    return {**plain, **{which: tuple(given) for which, given in elements.items()}}


def require_one_contact(params: Params, what: str) -> None:
    """Raise ParameterError if ``params`` has several contacts, which ``what`` cannot take yet.

    What several contacts can do so far is the first contact among them
    (`impactbeams.trajectory.first_contact`; docs/limits.md, "Several contacts").
    """
    if params.several_contacts:
        raise ParameterError(
            f"{CONTACTS}: {len(params.contacts)} contacts are not allowed in {what}, which takes "
            "one contact so far; several run in impactbeams.first_contact, "
            "contact_sequence and simulate (docs/limits.md, 'Several contacts')")


def fold_contacts(values: Mapping[str, Any], source: str,
                  given: Collection[str] | None = None) -> dict[str, Any]:
    """``values`` with ``contacts`` checked: one contact becomes the flat keys it stands for.

    A contact's point and side given twice (``contacts`` with ``contact_position1``,
    ``contact_position2`` or ``contact_side``) raise ParameterError; the run's ``clearance``,
    ``contact_stiffness`` and ``contact_damping`` are the defaults of a contact's fields left
    None, and one of them ``given`` (default: every key of ``values``) where every contact
    gives its own raises ParameterError (`refuse_unused_law_keys`). One contact is the simple
    form: its fields replace the flat keys, so that it gives today's run bit for bit; two or
    more stay ``contacts``.
    """
    if CONTACTS not in values:
        return dict(values)
    contacts = values[CONTACTS]
    require(CONTACTS, contacts, isinstance(contacts, (tuple, list)),
            "must be a tuple of impactbeams.Contact (in a TOML file: an array of tables, "
            "[[params.contacts]])")
    contacts = tuple(as_contact(f"{CONTACTS}[{i}]", c) for i, c in enumerate(contacts))
    refuse_unused_law_keys(values if given is None else given, contacts, source)
    defaults = {field.name: field.default for field in _FIELDS()}
    for key in _CONTACT_PLACE:  # a copy (dataclasses.replace) passes the default side whole
        if contacts and values.get(key) not in (None, defaults[key]):
            raise ParameterError(
                f"{key} = {values[key]!r} in {source} is not allowed with {CONTACTS}: give each "
                f"contact's point and side in its Contact, or one contact by the flat keys")
    rest = {key: value for key, value in values.items() if key != CONTACTS}
    if len(contacts) == 1:
        return {**rest, **contacts[0].flat()}
    return {**rest, CONTACTS: contacts} if contacts else rest


def set_by_every_contact(contacts: Any) -> tuple[str, ...]:
    """The run's law keys (``clearance``, ...) that every one of ``contacts`` gives its own of.

    Those a run's flat value would be the default of for no contact. ``contacts``: Contact
    objects or their tables; () if there are none or one is not a contact (refused elsewhere).
    """
    try:
        checked = [as_contact(CONTACTS, contact) for contact in contacts]
    except (ParameterError, TypeError):
        return ()
    return tuple(key for key in CONTACT_LAW_KEYS
                 if checked and all(key in contact.flat() for contact in checked))


def without_unused_law_keys(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` (a run's parameters by name) without the law keys no contact takes.

    What a Dataset records: a flat ``clearance`` beside contacts that each give their own
    would read as a value of the run.
    """
    unused = set_by_every_contact(values.get(CONTACTS, ()))
    return {name: value for name, value in values.items() if name not in unused}


def refuse_unused_law_keys(given: Collection[str], contacts: Any, source: str) -> None:
    """Raise ParameterError if a key of ``given`` is a law key every contact gives its own of.

    ``clearance``, ``contact_stiffness`` and ``contact_damping`` beside ``contacts`` are the
    defaults of the contacts that leave theirs out: given where none does, the value would
    go unused without a word.
    """
    for key in set_by_every_contact(contacts):
        if key in given:
            field = next(name for name, flat in FLAT_KEYS.items() if flat == key)
            value = f" = {given[key]!r}" if isinstance(given, Mapping) else ""
            every = "the contact gives" if len(contacts) == 1 else f"each of the {len(contacts)} "\
                "contacts gives"
            raise ParameterError(
                f"{key}{value} in {source} is not allowed: {every} its own {field}, so it would "
                f"be used by none (it is the default of a contact that leaves its {field} out): "
                f"leave {key} out, or {field} out of a contact")


def refuse_beam2(given: Any, source: str) -> None:
    """Raise ParameterError if ``given`` (names) holds a key of beam 2: a stop has no beam 2."""
    for key in given:
        if key.removeprefix("--") in BEAM2_KEYS:
            raise ParameterError(f"{key} in {source} is not allowed: {_NO_BEAM2}")


def resolve_materials(values: Mapping[str, Any], source: str = "parameters",
                      point: PointName = no_point) -> dict[str, Any]:
    """``values`` with each beam's material keys (checked) replaced by its EI and rhoA.

    Unspecified material keys of a beam that has some take the steel-strip defaults. Values may
    be floats or arrays that broadcast (a sweep's corner grid); ``source`` names where they
    came from, ``point`` the grid point of an array element, for error messages.
    """
    resolved = dict(values)
    for i in ("1", "2"):
        material = {k: resolved.pop(k + i) for k in MATERIAL_KEYS if k + i in resolved}
        if not material:
            continue
        direct = [k + i for k in ("EI", "rhoA") if k + i in resolved]
        if direct:
            raise ParameterError(
                f"{source}: both {', '.join(direct)} and material keys "
                f"{', '.join(k + i for k in material)} are given for beam {i}, whose material "
                f"keys replace EI{i} and rhoA{i}: give one or the other")
        for key, value in material.items():
            if not isinstance(value, np.ndarray):  # a given value (a sweep's corners: arrays)
                require_finite(key + i, value, PARAMETERS[key + i].units)
            check_range(key + i, value, point)
        resolved["EI" + i], resolved["rhoA" + i] = _strip_stiffness(
            {**MATERIAL_DEFAULTS, **material})
    return resolved


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file, turning a missing file or bad syntax into a clear error."""
    require_type("path", path, is_path(path), "the path of a TOML file (str or pathlib.Path)")
    try:
        with open(path, "rb") as stream:
            return tomllib.load(stream)
    except FileNotFoundError:
        raise ParameterError(f"file {str(path)!r} does not exist") from None
    except OSError as error:
        raise ParameterError(f"cannot read {str(path)!r}: {error.strerror or error}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise ParameterError(f"{path} is not valid TOML: {error}") from None


def require_table(data: Mapping[str, Any], key: str, source: str) -> dict[str, Any]:
    """``data[key]`` (default: empty) if it is a TOML table; otherwise a ParameterError."""
    table = data.get(key, {})
    require(f"{key} in {source}", table, isinstance(table, dict),
            f"must be a table: a [{key}] section, or {key} = {{...}}")
    return table
