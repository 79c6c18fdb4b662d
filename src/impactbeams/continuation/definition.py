"""A continuation file (TOML), read and checked: `load_continuation`.

::

    n_modes = 5                # free modes per beam (default: those that resolve the contact)
    period = 1                 # forcing periods of the orbit
    transient_periods = 300    # the guess: period maps from the run's start at the first value
    [params]                   # fixed parameters; the rest take the defaults
    counterpart = "stop"
    [continuation]
    parameter = "omega"        # any numeric parameter but the uplifts
    min = 150.0
    max = 450.0
    direction = "up"           # "up": from min (or start) upward; "down": from max (or start)
    step = 2.0                 # first step, in the parameter's units (default range / 100)
    min_step = 1e-7            # default range * 1e-9
    max_step = 10.0            # default range / 20
    max_points = 1000          # per branch
    max_branches = 2           # the started branch and the period-2 branches it switches to
    state_scale = 1.1e-4       # m of tip motion counted like the whole range (default 10
                               # clearances; docs/continuation.md)
    method = "auto"            # the corrector: "newton", "newton-picard" or "auto" (Newton up
                               # to 48 coordinates 2 N, Newton-Picard above)
    subspace = 8               # Newton-Picard's carried directions (default 8, at most 2 N)
    micro_contacts = "locate"  # or "summarise": changes of the contacts within an episode
                               # labelled chatter, not located (stiff contacts)
    [curve]                    # optional: then the branch's event is followed in two
                               # parameters (continuation.twoparameter), the range above
                               # its box for the first
    kind = "fold"              # the branch's event: "grazing", "fold", "period_doubling" or
                               # "neimark_sacker"
    which = 0                  # the first such event located on the branch (0), or a later one
    second = "force_amplitude" # the second parameter (its start value: [params]')
    min = 5e-5
    max = 2e-4
    direction = "up"           # of the second parameter from its start
    step = 0.02                # arclength steps, in units of the second's range
    min_step = 1e-9
    max_step = 0.05
    max_points = 200
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

from impactbeams.continuation.run import Continuation
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

if TYPE_CHECKING:
    from impactbeams.continuation.twoparameter import CurvePlan

_TOP_LEVEL = ("n_modes", "period", "transient_periods", "params", "continuation", "curve")
_RANGE_KEYS = {"parameter": "parameter", "min": "low", "max": "high", "direction": "direction",
               "start": "start", "step": "step", "min_step": "min_step", "max_step": "max_step",
               "max_points": "max_points", "max_branches": "max_branches",
               "state_scale": "state_scale", "method": "method", "subspace": "subspace",
               "micro_contacts": "micro_contacts"}
_INTEGERS = ("n_modes", "period", "transient_periods", "max_points", "max_branches",
             "subspace", "which")
_CURVE_KEYS = ("kind", "which", "second", "min", "max", "direction", "step", "min_step",
               "max_step", "max_points")


def load_continuation(path: str | os.PathLike[str]) -> Continuation:
    """Read and check the continuation file ``path`` (ParameterError naming what is wrong)."""
    data = read_toml(path)
    source = str(path)
    for key in data:
        if key not in _TOP_LEVEL:
            raise unknown_key("top-level key", key, source, _TOP_LEVEL)
    table = require_table(data, "continuation", source)
    for key in table:  # before the required keys: a misspelt one is why one is missing
        if key not in _RANGE_KEYS:
            raise unknown_key("key", key, f"[continuation] of {source}", _RANGE_KEYS)
    missing = [key for key in ("parameter", "min", "max") if key not in table]
    if missing:
        raise ParameterError(f"[continuation] of {source} needs parameter, min and max: "
                             f"{', '.join(missing)} missing")
    values: dict[str, Any] = {_RANGE_KEYS[key]: value for key, value in table.items()}
    values.update({key: data[key] for key in ("n_modes", "period", "transient_periods")
                   if key in data})
    for key, value in values.items():
        _check_type(key, value, source)
    params = Params.from_mapping(require_table(data, "params", source),
                                 source=f"[params] of {source}")
    return Continuation(params, **values)


def _check_type(key: str, value: Any, source: str) -> None:
    """A number where a number is expected, an integer where an integer, a name for the rest."""
    where = f"{key} in {source}"
    if key in _INTEGERS:
        require(where, value, is_integer(value), "must be an integer")
    elif key in ("parameter", "direction", "method", "micro_contacts", "kind", "second"):
        require(where, value, isinstance(value, str), "must be a name (a string)")
    elif not is_real(value):
        raise ParameterError(f"{where} = {value!r} is not allowed: must be a number")


def load_curve(path: str | os.PathLike[str], continuation: Continuation) -> CurvePlan | None:
    """The ``[curve]`` table of the continuation file ``path``, checked; None without one.

    Everything but the event itself is checked here, before the branch is computed
    (`CurvePlan`): which event the branch will have is only known after.
    """
    from impactbeams.continuation.twoparameter import CurvePlan

    data = read_toml(path)
    if "curve" not in data:
        return None
    source = str(path)
    table = require_table(data, "curve", source)
    for key in table:
        if key not in _CURVE_KEYS:
            raise unknown_key("key", key, f"[curve] of {source}", _CURVE_KEYS)
    missing = [key for key in ("kind", "second", "min", "max") if key not in table]
    if missing:
        raise ParameterError(f"[curve] of {source} needs kind, second, min and max: "
                             f"{', '.join(missing)} missing")
    for key, value in table.items():
        _check_type(key, value, f"[curve] of {source}")
    options = {("low" if key == "min" else "high" if key == "max" else key): value
               for key, value in table.items()}
    return CurvePlan(continuation, **options)
