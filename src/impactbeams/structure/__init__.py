"""Cantilevers with attachments: exact natural frequencies, modes and static flexibility.

A beam is uniform ``Segment``s from the clamp out (a stepped beam; one segment for a uniform
one) carrying ``PointMass`` and ``Spring`` attachments anywhere (a rotational spring at the
clamp makes it compliant). ``Cantilever.modes(n)`` gives the first ``n`` natural frequencies
from the exact characteristic equation, none missed (Wittrick-Williams count), with shapes
mass-normalised including the attachments; ``Cantilever.flexibility`` the exact static
Green's function with the springs. SciPy only; evaluated once per geometry.
"""

from impactbeams.structure.cantilever import Cantilever, StructureModes
from impactbeams.structure.parts import PointMass, Segment, Spring

__all__ = ["Cantilever", "PointMass", "Segment", "Spring", "StructureModes"]
