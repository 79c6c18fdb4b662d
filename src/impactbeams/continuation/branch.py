"""Follow branches: steps, bifurcations located and labelled, grazing crossed, period doubling
switched.

A grazing is an event of the branch, not a place to shrink the step: when the orbit's
smallest free-flight gap changes sign over a step (at the corrected point or at any Newton
iterate of a failed step), the grazing is located on the secant plane, labelled, and the
branch resumes from the first corrected point beyond it, with the new contact sequence and a
tangent of its own. At a period doubling, while ``max_branches`` allows, the period-2 branch is
started from the doubling point displaced along the multiplier's -1 eigenvector and followed
after the branch it left.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from impactbeams.continuation.arclength import Follower, Point, Scaling, Settings
from impactbeams.continuation.events import (
    GRAZING,
    PERIOD_DOUBLING,
    detected,
    grazing_test,
    locate,
)
from impactbeams.continuation.problem import Problem
from impactbeams.params import ParameterError

# how a branch ended
BOUND, MAX_POINTS, MIN_STEP, INTERRUPTED = "bound", "max_points", "min_step", "interrupted"
ENDINGS = (BOUND, MAX_POINTS, MIN_STEP, INTERRUPTED)


@dataclasses.dataclass
class Branch:
    """One branch: its points in order, its period, how it ended, where it came from.

    ``origin``: (index of the branch, index of its point) it was switched from, None for the
    first.
    """

    points: list[Point]
    period: int
    scaling: Scaling
    ending: str = ""
    origin: tuple[int, int] | None = None


class ContinuationInterrupted(KeyboardInterrupt):
    """Ctrl-C during a continuation: ``branches`` holds what was computed (the last one cut)."""

    def __init__(self, branches: list[Branch]) -> None:
        super().__init__("continuation interrupted")
        self.branches = branches


Progress = Callable[[Branch, Point], None]


@dataclasses.dataclass(frozen=True)
class Span:
    """The parameter's range of the continuation and the direction it starts in (+1 or -1)."""

    low: float
    high: float
    direction: int = 1


def continue_branches(problem: Problem, z0: np.ndarray, p0: float, span: Span,
                      scaling: Scaling, settings: Settings,
                      progress: Progress | None = None) -> list[Branch]:
    """Follow the branch through (z0, p0) (a guess, corrected at p0) and those it switches to.

    Raises ParameterError if the start does not converge; `ContinuationInterrupted` (with the
    branches so far) on Ctrl-C.
    """
    follower = Follower(problem, scaling, settings)
    orientation = np.zeros(len(z0) + 1)
    orientation[-1] = span.direction
    first = follower.at_parameter(scaling.scaled(z0, p0), orientation).point
    if first is None:
        raise ParameterError(f"the start at {p0!r} did not converge: Newton on the periodic "
                             f"orbit took more than {settings.max_iterations} iterations from "
                             "the guess (give a better guess, e.g. more transient periods)")
    branches = [Branch([first], problem.period, scaling)]
    queue = [(follower, 0)]
    try:
        while queue:
            follower, index = queue.pop(0)
            for switch in _follow(follower, branches[index], span, progress):
                if len(branches) < settings.max_branches:
                    _switched(follower, branches, index, switch, queue)
    except KeyboardInterrupt:
        branches[-1].ending = branches[-1].ending or INTERRUPTED
        raise ContinuationInterrupted(branches) from None
    return branches


def _follow(follower: Follower, branch: Branch, span: Span,
            progress: Progress | None) -> list[int]:
    """Step ``branch`` to its end; the indices of its period-doubling points."""
    settings, ds = follower.settings, follower.settings.step
    current = branch.points[-1]
    while len(branch.points) < settings.max_points:
        point, taken, grazing = follower.step(current, ds)
        low, high = span.low * follower.scaling.parameter, span.high * follower.scaling.parameter
        if point is not None and not low <= point.x[-1] <= high:
            end = _at_bound(follower, current, point, low if point.x[-1] < low else high)
            _append(branch, _between(follower, current, end, progress), progress)
            branch.ending = BOUND
            break
        crossing = (point is not None and _grazes(current, point)) or (
            point is None and _any_crossing(current, grazing))
        if crossing:
            current, ds = _cross_grazing(follower, branch, current, taken, point, progress)
            if current is None:
                branch.ending = MIN_STEP
                break
            continue
        if point is None:
            branch.ending = MIN_STEP
            break
        _append(branch, _between(follower, current, point, progress), progress)
        current, ds = point, follower.next_step(taken, point.iterations)
    else:
        branch.ending = MAX_POINTS
    return [i for i, point in enumerate(branch.points) if point.label == PERIOD_DOUBLING]


def _append(branch: Branch, points: list[Point], progress: Progress | None) -> None:
    for point in points:
        branch.points.append(point)
        if progress is not None:
            progress(branch, point)


def _between(follower: Follower, a: Point, b: Point, progress: Progress | None) -> list[Point]:
    """The bifurcations located between ``a`` and ``b`` (in arclength order), then ``b``."""
    s_end = float(a.tangent @ (b.x - a.x))
    located = []
    for label, test in detected(a, b):
        if not (math.isfinite(test(a)) and math.isfinite(test(b))
                and (test(a) > 0) != (test(b) > 0)):
            continue  # a signature changed without its multiplier crossing (a collision)
        before, _ = locate(follower, a, s_end, b, test)
        if before is not None and before is not a:
            located.append(dataclasses.replace(before, label=label))
    located.sort(key=lambda point: float(a.tangent @ (point.x - a.x)))
    return [*located, b]


def _grazes(a: Point, b: Point) -> bool:
    g0, g1 = a.evaluation.grazing, b.evaluation.grazing
    return math.isfinite(g0) and math.isfinite(g1) and (g0 > 0) != (g1 > 0)


def _any_crossing(a: Point, values: tuple[float, ...]) -> bool:
    g0 = a.evaluation.grazing
    return math.isfinite(g0) and any(math.isfinite(g) and (g > 0) != (g0 > 0) for g in values)


def _cross_grazing(follower: Follower, branch: Branch, current: Point, taken: float,
                   end: Point | None, progress: Progress | None) -> tuple[Point | None, float]:
    """Locate the grazing ahead of ``current``, label it, resume beyond it.

    Returns the point to resume from (None if no corrected point beyond was found) and the
    step to take from it.
    """
    before, beyond = locate(follower, current, taken, end, grazing_test)
    if before is current:  # within the tolerance of the grazing already
        branch.points[-1] = dataclasses.replace(current, label=GRAZING)
        before = current
    else:
        _append(branch, [*_between(follower, current, before, progress)[:-1],
                         dataclasses.replace(before, label=GRAZING)], progress)
    s_grazing = float(current.tangent @ (before.x - current.x))
    step = follower.settings.min_step
    while beyond is None and s_grazing + step <= taken * 2.0:
        beyond = follower.at_arclength(current, s_grazing + step).point
        step *= 4.0
    if beyond is None:
        return None, step
    # the new contact sequence's own tangent, oriented as the branch went
    beyond = dataclasses.replace(beyond, tangent=_reoriented(beyond.tangent, current.tangent))
    _append(branch, [beyond], progress)
    return beyond, follower.settings.min_step * 16.0


def _reoriented(tangent: np.ndarray, previous: np.ndarray) -> np.ndarray:
    return tangent if tangent @ previous >= 0 else -tangent


def _at_bound(follower: Follower, a: Point, b: Point, bound: float) -> Point:
    """The branch's end at the parameter's bound, between ``a`` and ``b`` (b if it fails)."""
    weight = (bound - a.x[-1]) / (b.x[-1] - a.x[-1])
    guess = a.x + weight * (b.x - a.x)
    guess[-1] = bound
    end = follower.at_parameter(guess, a.tangent).point
    return end if end is not None else b


def _switched(follower: Follower, branches: list[Branch], index: int, at: int,
              queue: list[tuple[Follower, int]]) -> None:
    """Start the doubled-period branch at point ``at`` of branch ``index``; queue it."""
    point = branches[index].points[at]
    scaling, settings = follower.scaling, follower.settings
    doubled = Follower(follower.problem.iterated(2), scaling, settings)
    direction = _doubling_direction(point, scaling)
    # orthogonal to the old branch, whose points are period-2 orbits too
    direction -= (direction @ point.tangent) * point.tangent
    direction /= np.linalg.norm(direction)
    start = doubled.correct(point.x + settings.switch_distance * direction, direction,
                            direction).point
    if start is None:
        return
    branches.append(Branch([dataclasses.replace(start, label="")], 2 * branches[index].period,
                           scaling, origin=(index, at)))
    queue.append((doubled, len(branches) - 1))


def _doubling_direction(point: Point, scaling: Scaling) -> np.ndarray:
    """The eigenvector of the multiplier nearest -1, in x~ (no parameter part)."""
    monodromy = point.evaluation.jacobian + np.eye(len(point.x) - 1)
    values, vectors = np.linalg.eig(monodromy)
    vector = np.real(vectors[:, np.argmin(np.abs(values + 1.0))])
    return np.append(vector * scaling.state, 0.0) / np.linalg.norm(vector * scaling.state)
