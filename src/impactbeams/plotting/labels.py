"""Labels of figures: symbols and units from the registry, numbers as a reader writes them."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.variables import LONG_TIME_VARIABLES, PARAMETERS, VARIABLES

if TYPE_CHECKING:
    import xarray as xr

    from impactbeams.plotting.arrays import PlainArray, PlainDataset

# fixed parameters that say which case a map shows, in this order (others only when sliced)
_CASE = ("omega", "force_amplitude", "clearance", "uplift1", "uplift2", "damping_ratio")
_ZERO_BY_DEFAULT = ("uplift1", "uplift2", "damping_ratio")  # named only when nonzero
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


def axis_label(array: PlainArray | xr.DataArray) -> str:
    r"""Label of a coordinate or variable: symbol and units, e.g. ``"$\Omega$ (rad/s)"``.

    A swept parameter is named by its symbol alone (its long name is in the caption); an
    output variable by its long name and symbol. Without units the parentheses are left out.
    """
    name = str(array.name)
    words = array.attrs.get("long_name", name.replace("_", " "))
    if name in PARAMETERS:
        words = symbol(name) or words.split(":")[0]
    elif symbol(name):
        words = f"{words} {symbol(name)}"
    units = units_text(array.attrs.get("units", ""))
    return f"{words} ({units})" if units else words


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


def quantity(name: str, value: Any, units: str) -> str:
    r"""``"$\Omega$ = 50 rad/s"``: a parameter's symbol (or name), value and units."""
    text = format_number(float(value)) if isinstance(value, int | float | np.number) else value
    unit = units_text(units)
    return f"{symbol(name) or name.replace('_', ' ')} = {text}" + (f" {unit}" if unit else "")


def case_title(dataset: PlainDataset | xr.Dataset, variable: str, shown: tuple[str, ...]) -> str:
    """The fixed parameters, slices and run settings behind a figure of ``variable``.

    ``shown``: the dimensions drawn (their values are on the axes, not in the title).
    """
    values: dict[str, tuple[Any, str]] = {}
    for name in _CASE:
        if name in dataset.attrs and name not in dataset.dims:
            values[name] = (dataset.attrs[name], PARAMETERS[name].units)
    for name, coordinate in dataset.coords.items():  # sliced dimensions: scalar coordinates
        if coordinate.ndim == 0 and name not in shown:
            values[str(name)] = (coordinate.item(), coordinate.attrs.get("units", ""))
    parts = [quantity(n, v, u) for n, (v, u) in values.items()
             if not (n in _ZERO_BY_DEFAULT and v == 0)]
    parts += _run_settings(dataset.attrs, law=variable not in _LAW_FREE,
                           long_time=variable in LONG_TIME_VARIABLES)
    return ", ".join(parts)


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
    if attrs.get("counterpart") == "stop":
        parts.append("against a stop")
    return parts
