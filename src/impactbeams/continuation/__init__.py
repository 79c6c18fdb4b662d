"""Continuation of periodic orbits: branches, stability, bifurcations, frequency responses.

`continue_orbits` follows the beams' periodic orbits along one parameter
(`Continuation` says what), `load_continuation` reads a continuation file; `continue_curve`
follows a branch's grazing, fold or period doubling in two parameters (`BifurcationCurve`);
the engine (`arclength`, `events`, `branch`) is generic over a `problem.Problem`.
"""

from impactbeams.continuation.branch import ContinuationInterrupted
from impactbeams.continuation.definition import load_continuation
from impactbeams.continuation.run import CONTINUABLE, Continuation, continue_orbits
from impactbeams.continuation.twoparameter import BifurcationCurve, continue_curve

__all__ = ["CONTINUABLE", "BifurcationCurve", "Continuation", "ContinuationInterrupted",
           "continue_curve", "continue_orbits", "load_continuation"]
