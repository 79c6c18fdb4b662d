"""Cantilevers with attachments: exact natural frequencies, modes and static flexibility.

A beam is uniform ``Segment``s from the clamp out (a stepped beam; one segment for a uniform
one) carrying ``PointMass`` and ``Spring`` attachments anywhere (a rotational spring at the
clamp makes it compliant). ``Cantilever.modes(n)`` gives the first ``n`` natural frequencies
from the exact characteristic equation, none missed (Wittrick-Williams count), with shapes
mass-normalised including the attachments; ``Cantilever.flexibility`` the exact static
Green's function with the springs. SciPy only; evaluated once per geometry. Where the
structure is touched: ``Contact``s (``two_sided_stop``: one below and one above a point).
"""

from importlib import import_module
from typing import Any

# each name's module, imported when first asked for: `Params` checks its parts on every
# creation, but the eigen-solvers (cantilever, flexibility) only with attachments (waves, whose
# quadrature every beam's fields use, is numpy only)
_MODULES = {"Cantilever": "cantilever", "StructureModes": "cantilever", "PointMass": "parts",
            "Segment": "parts", "Spring": "parts", "Contact": "contacts",
            "two_sided_stop": "contacts"}
__all__ = ["Cantilever", "Contact", "PointMass", "Segment", "Spring", "StructureModes",
           "two_sided_stop"]


def __getattr__(name: str) -> Any:
    if name in _MODULES:
        return getattr(import_module(f"impactbeams.structure.{_MODULES[name]}"), name)
    raise AttributeError(f"module 'impactbeams.structure' has no attribute {name!r}")
