"""Follow branches: steps, bifurcations located, grazings crossed, period doublings switched.

A grazing is an event of the branch, not a place to shrink the step: when the orbit's
smallest free-flight gap changes sign over a step (at the corrected point or at any Newton
iterate of a failed step), the grazing is located on the secant plane, labelled, and the
branch resumes from the first corrected point beyond it, with the new contact sequence and a
tangent of its own. A grazing is labelled only where corrected points on both sides bracket it
and their contacts per orbit differ; otherwise the branch resumes short of it (a fold before it
can put it out of reach of the secant planes). At a period doubling, while ``max_branches``
allows, the period-2 branch is started from the doubling point displaced along the
multiplier's -1 eigenvector and followed after the branch it left.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from impactbeams.continuation.arclength import Follower, Point, Scaling, Settings, crosses
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
    """Ctrl-C during a continuation: ``branches`` holds what was computed (the last one cut).

    `impactbeams.continuation.continue_orbits` adds their ``dataset``.
    """

    dataset = None

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
            _append(branch, _between(follower, current, end), progress)
            branch.ending = BOUND
            break
        crossing = (point is not None and _grazes(current, point)) or (
            point is None and crosses(current.evaluation.grazing, grazing))
        resumed = crossing and _cross_grazing(follower, branch, current, taken, point, progress)
        if resumed:
            current, ds = resumed
            continue
        if crossing and taken / 2.0 >= settings.min_step:
            ds = taken / 2.0  # an iterate crossed, not the branch, or no way across: smaller
            continue
        if point is None:
            branch.ending = MIN_STEP
            break
        _append(branch, _between(follower, current, point), progress)
        current, ds = point, follower.next_step(taken, point.iterations)
    else:
        branch.ending = MAX_POINTS
    return [i for i, point in enumerate(branch.points) if point.label == PERIOD_DOUBLING]


def _append(branch: Branch, points: list[Point], progress: Progress | None) -> None:
    for point in points:
        branch.points.append(point)
        if progress is not None:
            progress(branch, point)


def _between(follower: Follower, a: Point, b: Point,
             plane: tuple[np.ndarray, np.ndarray] | None = None) -> list[Point]:
    """The bifurcations located between ``a`` and ``b`` (in order), then ``b``.

    Points between are corrected on planes s along ``a``'s tangent from ``a``, or along
    ``plane`` = (origin, unit normal) when given.
    """
    origin, normal = plane if plane is not None else (a.x, a.tangent)

    def point_at(s: float) -> Point | None:
        return follower.correct(origin + s * normal, normal, normal).point

    located = []
    for label, test in detected(a, b):
        if not (math.isfinite(test(a)) and math.isfinite(test(b))
                and (test(a) > 0) != (test(b) > 0)):
            continue  # a signature changed without its multiplier crossing (a collision)
        s, before, _, _ = locate(point_at, a, float(normal @ (b.x - origin)), b, test,
                                 follower.settings.locate_tolerance)
        if before is not a:
            located.append((s, dataclasses.replace(before, label=label)))
    return [point for _, point in sorted(located, key=lambda pair: pair[0])] + [b]


def _grazes(a: Point, b: Point) -> bool:
    return crosses(a.evaluation.grazing, (b.evaluation.grazing,))


# distances beyond a grazing tried for the first point of the new contact sequence, as
# fractions of the step that crossed it
BEYOND = (1e-2, 4e-2, 0.16, 0.64, 2.5e-3, 6.25e-4, 1.6e-4)


def _cross_grazing(follower: Follower, branch: Branch, current: Point, taken: float,
                   end: Point | None, progress: Progress | None) -> tuple[Point, float] | None:
    """Locate the grazing ahead of ``current``, label it, resume beyond it.

    The grazing is bracketed on secant planes of ``current``. Beyond it the branch may turn
    within a sliver of the parameter (a multiplier jumps): the first point of the new contact
    sequence is corrected on a plane across the grazing value's gradient, at a distance where
    the gap has changed sign, so that it exists whichever way the branch turns. Returns that
    point and the step to take from it; None, labelling nothing, if none is found (a Newton
    iterate crossed, not the branch). Not bracketed, or no change of the contacts: labels
    nothing and resumes short of it (`_short_of_grazing`).
    """
    _, grazing, past, root = locate(lambda s: follower.at_arclength(current, s).point,
                                    current, taken, end, grazing_test,
                                    follower.settings.locate_tolerance)
    if not root or (past is not None and _same_contacts(grazing, past)):
        return _short_of_grazing(follower, branch, current, grazing, past, taken, progress)
    gradient = follower.grazing_gradient(grazing.x)
    # across the grazing surface, toward the other sign of the gap
    normal = -np.sign(current.evaluation.grazing) * gradient
    normal /= np.linalg.norm(normal)
    for fraction in BEYOND:
        distance = max(fraction * taken, follower.settings.min_step)
        beyond = follower.correct(grazing.x + distance * normal, normal, normal).point
        if beyond is not None and _grazes(current, beyond) and not _same_contacts(grazing,
                                                                                   beyond):
            break
    else:
        return None
    if grazing is current:  # within the tolerance of the grazing already
        branch.points[-1] = dataclasses.replace(current, label=GRAZING)
    else:
        _append(branch, [*_between(follower, current, grazing)[:-1],
                         dataclasses.replace(grazing, label=GRAZING)], progress)
    if grazing.tangent @ normal < 0:  # oriented into the new contact sequence, as beyond's
        grazing = dataclasses.replace(grazing, tangent=-grazing.tangent)
    _append(branch, _between(follower, grazing, beyond, (grazing.x, normal)), progress)
    return beyond, distance


def _same_contacts(a: Point, b: Point) -> bool:
    return a.evaluation.contacts == b.evaluation.contacts


def _short_of_grazing(follower: Follower, branch: Branch, current: Point, last: Point,
                      past: Point | None, taken: float,
                      progress: Progress | None) -> tuple[Point, float] | None:
    """Resume where the grazing value changed sign without a grazing located.

    Either no corrected point beyond was found and the root is not within the bracket
    (``past`` None: the branch turned back across ``current``'s planes, at a fold, before
    reaching the grazing) and the branch resumes from ``last``, the farthest point reached, to
    cross the grazing on planes of its own; or the value jumped across 0 between two orbits of
    the same contacts (it is the gap of whichever of a free-flight minimum and the shallowest
    contact is nearer 0) and the branch resumes from ``past``. Returns None if neither moved
    from ``current``.
    """
    resume = last if past is None else past
    if resume is current:
        return None
    _append(branch, _between(follower, current, resume), progress)
    return resume, max(taken / 2.0, follower.settings.min_step)


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
