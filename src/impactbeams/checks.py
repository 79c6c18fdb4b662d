"""The checks every input goes through: one ParameterError naming a parameter and its value.

Each says which parameter, which value, and what is allowed.

Below `impactbeams.params` so that the parts of a structure (`impactbeams.structure`), which
`Params` composes, check their own values with the same words.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np


class ParameterError(ValueError):
    """A model or run parameter has a value that is not allowed."""


def require(name: str, value: Any, condition: bool, allowed: str, unit: str = "") -> None:
    """Raise ParameterError naming the parameter, its value and what is allowed."""
    if not condition:
        unit_text = f" ({unit})" if unit else ""
        raise ParameterError(f"{name} = {value!r} is not allowed: {allowed}{unit_text}")


def is_real(value: Any) -> bool:
    """Whether ``value`` is a real number (int or float, not bool, not a string)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def is_integer(value: Any) -> bool:
    """Whether ``value`` is an integer (Python's or NumPy's, not bool)."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def require_integer(name: str, value: Any, low: int, high: float = math.inf) -> int:
    """Return ``value`` as an int if it is an integer from ``low`` to ``high``.

    Otherwise raise ParameterError.
    """
    allowed = f"from {low} to {high}" if math.isfinite(high) else f">= {low}"
    require(name, value, is_integer(value) and low <= value <= high,
            f"must be an integer {allowed}")
    return int(value)
