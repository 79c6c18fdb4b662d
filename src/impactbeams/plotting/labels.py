"""Labels of figures: symbols and units from the registry, numbers as a reader writes them."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.configuration import MOUNTS, counterpart_named
from impactbeams.params import CONTACTS, contact_field
from impactbeams.structure.contacts import FLAT_KEYS
from impactbeams.variables import LONG_TIME_VARIABLES, PARAMETERS, VARIABLES

if TYPE_CHECKING:
    import xarray as xr

    from impactbeams.plotting.arrays import PlainArray, PlainDataset

# fixed parameters that say which case a map shows, in this order (others only when sliced)
_CASE = ("omega", "force_amplitude", "base_amplitude", "clearance", "uplift1", "uplift2",
         "damping_ratio")
# named only when nonzero: a drive that is off is no part of the case
_ZERO_BY_DEFAULT = ("force_amplitude", "base_amplitude", "uplift1", "uplift2", "damping_ratio")
# the prefixes a reader uses for lengths, forces and times, largest first: a value is written
# with the largest whose number is >= 1 (20 µm, not 2e-05 m; 0.5 mN, not 5e-04 N; 30 ms)
_PREFIXED = {"m": ((1.0, "m"), (1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm")),
             "N": ((1.0, "N"), (1e-3, "mN"), (1e-6, "µN"), (1e-9, "nN")),
             "s": ((1.0, "s"), (1e-3, "ms"), (1e-6, "µs"), (1e-9, "ns"))}
# quantities of the free phase before any contact: independent of the contact law
_LAW_FREE = ("first_impact_time", "impacted")


def units_text(units: str) -> str:
    """CF units as mathtext: ``"N m^2"`` -> ``"N m$^{2}$"``, ``"m s-1"`` -> ``"m s$^{-1}$"``.

    Dimensionless ``"1"`` gives ``""``.
    """
    if units in ("", "1"):
        return ""
    units = re.sub(r"\^(-?\d+)", r"$^{\1}$", units)
    return re.sub(r"(?<=[A-Za-z])(-\d+)\b", r"$^{\1}$", units)


def symbol(name: str) -> str:
    """The registry's mathtext symbol of a parameter or variable, ``""`` if it has none."""
    entry = PARAMETERS.get(name) or VARIABLES.get(name)
    return entry.symbol if entry is not None else ""


def axis_label(array: PlainArray | xr.DataArray, units: str | None = None) -> str:
    r"""Label of a coordinate or variable: symbol and units, e.g. ``"$\Omega$ (rad/s)"``.

    A swept parameter is named by its symbol alone (its long name is in the caption); an
    output variable by its long name and symbol. Without units the parentheses are left out.
    ``units``: the units drawn, if not the array's own (`display_units`).
    """
    name = str(array.name)
    words = array.attrs.get("long_name", name.replace("_", " "))
    if name in PARAMETERS:
        words = symbol(name) or words.split(":")[0]
    elif symbol(name):
        words = f"{words} {symbol(name)}"
    units = units_text(array.attrs.get("units", "") if units is None else units)
    return f"{words} ({units})" if units else words


def display_units(values: np.ndarray, units: str) -> tuple[float, str]:
    """The factor and units to draw ``values`` (in ``units``) in.

    Lengths, forces and times take the prefix of their largest magnitude (``1e6, "µm"`` for
    tens of µm, ``1e3, "ms"`` for times below a second), so that an axis or colour bar needs
    no offset or power of ten; others stay (1.0, ``units``).
    """
    finite = np.abs(np.asarray(values, dtype=float))
    finite = finite[np.isfinite(finite)]
    prefixes = _PREFIXED.get(units, ())
    if not prefixes or finite.size == 0 or finite.max() == 0:
        return 1.0, units
    scale, prefixed = next(((scale, name) for scale, name in prefixes if finite.max() >= scale),
                           prefixes[-1])
    return 1.0 / scale, prefixed


def format_number(value: float, digits: int = 3) -> str:
    """``value`` with ``digits`` significant digits: decimal from 1e-3 to 1e4, else m x 10^e."""
    if value == 0 or not math.isfinite(value):
        return f"{value:g}"
    if 1e-3 <= abs(value) < 1e4:
        return f"{value:.{digits}g}"
    return power_of_ten(value, digits)


def power_of_ten(value: float, digits: int = 3) -> str:
    r"""``value`` as mathtext m x 10^e (``$10^{-5}$`` when m = 1, ``$2\times10^{-5}$``)."""
    mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
    mantissa = mantissa.rstrip("0").rstrip(".")
    power = f"10^{{{int(exponent)}}}"
    if mantissa in ("1", "-1"):
        return f"${mantissa[:-1]}{power}$"
    return f"${mantissa}\\times{power}$"


def tick_labels(ticks: np.ndarray) -> list[str]:
    """Labels of log-scale ticks, all in one style: decimal if every tick allows it."""
    decimal = all(t == 0 or 1e-3 <= abs(t) < 1e4 for t in ticks)
    return [f"{t:g}" if decimal else power_of_ten(t) for t in ticks]


def with_units(value: float, units: str, digits: int = 3) -> str:
    """``value`` and its units as read: lengths and forces with a prefix (``"20 µm"``).

    Other units as `format_number` writes the value, with `units_text`.
    """
    for scale, prefixed in _PREFIXED.get(units, ()):
        if abs(value) >= scale and abs(value) < 1e4 * scale:
            return f"{value / scale:.{digits}g} {prefixed}"
    unit = units_text(units)
    return format_number(value, digits) + (f" {unit}" if unit else "")


def quantity(name: str, value: Any, units: str, index: int | None = None) -> str:
    r"""``"$\Omega$ = 50 rad/s"``: a parameter's symbol (or name), value and units.

    Lengths and forces take the prefix a reader uses (`with_units`); a forcing frequency is
    also given in Hz. ``index``: of one contact's value, a subscript (``"$\Delta_{1}$"``).
    """
    named = symbol(name) or name.replace("_", " ")
    if index is not None:
        named = f"{named[:-1]}_{{{index}}}$" if named.endswith("$") else f"{named} {index}"
    if not isinstance(value, int | float | np.number):
        unit = units_text(units)
        return f"{named} = {value}" + (f" {unit}" if unit else "")
    text = f"{named} = {with_units(float(value), units)}"
    if name == "omega" and units == "rad/s" and value > 0:
        text += f" ({float(value) / (2 * math.pi):.3g} Hz)"
    return text


def base_motion(amplitude: float, attrs: Mapping[str, Any]) -> str:
    """The base motion's ``amplitude`` (m) and which clamps the shaker of ``attrs`` carries.

    E.g. ``"$U_0$ = 5 µm on both clamps"``.
    """
    return f"{quantity('base_amplitude', amplitude, 'm')} {shaker_place(attrs)}".rstrip()


def shaker_place(attrs: Mapping[str, Any]) -> str:
    """Where the shaker of ``attrs`` sits, e.g. ``"on both clamps"`` (``""`` if not said)."""
    mount = MOUNTS.get(attrs.get("shaker"))
    return mount.place(counterpart_named(attrs.get("counterpart"))) if mount else ""


def case_title(dataset: PlainDataset | xr.Dataset, variable: str, shown: tuple[str, ...]) -> str:
    """The fixed parameters, slices and run settings behind a figure of ``variable``.

    ``shown``: the dimensions drawn (their values are on the axes, not in the title).
    """
    values: dict[str, tuple[Any, str]] = {}
    clearances = contact_clearances(dataset.attrs)
    for name in _CASE:
        if name == "clearance" and clearances:  # each contact's own, but one on an axis
            values.update({f"{CONTACTS}.{j}.clearance": (value, PARAMETERS[name].units)
                           for j, value in clearances.items()
                           if f"{CONTACTS}.{j}.clearance" not in _varied(dataset, shown)})
        elif name in dataset.attrs and name not in dataset.dims:
            values[name] = (dataset.attrs[name], PARAMETERS[name].units)
    for name, coordinate in dataset.coords.items():  # sliced dimensions: scalar coordinates
        if coordinate.ndim == 0 and name not in shown:
            values[str(name)] = (coordinate.item(), coordinate.attrs.get("units", ""))
    parts = [_case_part(n, v, u, dataset.attrs) for n, (v, u) in values.items()
             if not (n in _ZERO_BY_DEFAULT and v == 0)]
    if "base_amplitude" in (*dataset.dims, dataset.attrs.get("continued_parameter")):
        parts.append(f"shaker {shaker_place(dataset.attrs)}")  # U0 on an axis: where it acts
    parts += _run_settings(dataset.attrs, law=variable not in _LAW_FREE,
                           long_time=variable in LONG_TIME_VARIABLES)
    return ", ".join(parts)


def _case_part(name: str, value: Any, units: str, attrs: Mapping[str, Any]) -> str:
    """One fixed parameter of a title, e.g. a contact's field with its subscript.

    The base motion with its place; a contact's field (``contacts.INDEX.FIELD``) as its flat
    key's symbol with the contact's index.
    """
    if name == "base_amplitude":
        return base_motion(value, attrs)
    field = contact_field(name)
    return (quantity(name, value, units) if field is None
            else quantity(FLAT_KEYS[field[1]], value, units, index=field[0]))


# one contact of a ``contacts`` attribute (`variables.parameter_text`) and its own clearance
_CONTACT_TEXT = re.compile(r"Contact\((.*?)\)")
_OWN_CLEARANCE = re.compile(r"\bclearance=([^,)]+)")


def contact_clearances(attrs: Mapping[str, Any]) -> dict[int, float]:
    """Each contact's clearance (m) by index, of several contacts' ``attrs``; {} for one.

    A contact without its own (``clearance=None``) has the run's flat ``clearance`` (left
    out if the attributes have none).
    """
    text = attrs.get("contacts")
    contacts = _CONTACT_TEXT.findall(text) if isinstance(text, str) else []
    if len(contacts) < 2:
        return {}
    clearances = {}
    for j, fields in enumerate(contacts):
        own = _OWN_CLEARANCE.search(fields)
        value = attrs.get("clearance") if own is None or own.group(1) == "None" else float(
            own.group(1))
        if value is not None:
            clearances[j] = float(value)
    return clearances


def _varied(dataset: PlainDataset | xr.Dataset, shown: tuple[str, ...]) -> set[str]:
    """The parameters a figure's axes vary: its dimensions, a branch's or curve's parameters."""
    attrs = dataset.attrs
    return {*map(str, dataset.dims), *shown, *str(attrs.get("curve_parameters", "")).split(),
            str(attrs.get("continued_parameter", ""))}


def _run_settings(attrs: Mapping[str, Any], law: bool, long_time: bool) -> list[str]:
    """The window a variable covers (t_max, or the long run's periods), modes and law."""
    parts = []
    if long_time:  # not over [0, t_max]: over the sampled periods after the transient
        if "transient_periods" in attrs and "sampled_periods" in attrs:
            parts.append(f"{attrs['transient_periods']} "
                         f"{'dwell' if 'stepping' in attrs else 'transient'} + "
                         f"{attrs['sampled_periods']} sampled periods")
    elif "t_max" in attrs:
        parts.append(f"$t_\\max$ = {format_number(float(attrs['t_max']))} s")
    if "n_modes" in attrs:
        parts.append(f"{attrs['n_modes']} modes")
    if law and "contact_law" in attrs:
        parts.append(f"{attrs['contact_law']} law")
    against = counterpart_named(attrs.get("counterpart")).words
    if against:
        parts.append(against)
    return parts
