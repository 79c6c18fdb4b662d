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
import functools
import math
from collections.abc import Callable, Iterable

import numpy as np

from impactbeams.continuation.arclength import (
    KINK_STEP,
    SUMMARISE,
    Follower,
    Point,
    Scaling,
    Settings,
    crosses,
    oriented,
    same_piece,
)
from impactbeams.continuation.events import (
    CHATTER,
    CONTACT_MERGE,
    CONTACT_SPLIT,
    GRAZING,
    PERIOD_DOUBLING,
    Located,
    PointAt,
    continuous_root,
    detected,
    grazing_test,
    guess_at,
    interval_test,
    locate,
    near_zero,
)
from impactbeams.continuation.problem import Problem
from impactbeams.params import ParameterError

# how a branch ended
BOUND, MAX_POINTS, MIN_STEP, INTERRUPTED = "bound", "max_points", "min_step", "interrupted"
# ... and: back at one of its own earlier points (an isola, a loop of a period-2 branch); a
# period-p branch back on its period-p/2 origin (at a period doubling of it); too little
# advance over the last Settings.stall_points steps
CLOSED_LOOP, JOINED_ORIGIN, STALLED = "closed_loop", "joined_origin", "stalled"
RETRACED = "retraced"  # back on its own earlier points the other way: a jump, not the branch
ENDINGS = (BOUND, MAX_POINTS, MIN_STEP, INTERRUPTED, CLOSED_LOOP, JOINED_ORIGIN, STALLED,
           RETRACED)
# endings short of the range, not by the branch
INCOMPLETE = (MAX_POINTS, MIN_STEP, STALLED, RETRACED)


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


class Steps(list):
    """The points the steps reached, with their x~ as rows of one array (`positions`).

    The closed-loop test reads every earlier step's x~ at every step: the array grows with
    the list (steps are only appended) instead of being built again, which was quadratic in
    the points (about a tenth of a 6000-point branch's time).
    """

    def __init__(self, points: Iterable[Point] = ()) -> None:
        super().__init__(points)
        self._rows, self._filled = np.empty((0, 0)), 0

    def positions(self) -> np.ndarray:
        """The steps' x~, one row each."""
        if len(self._rows) < len(self):
            rows = np.empty((2 * len(self), self[0].x.size))
            if self._filled:
                rows[:self._filled] = self._rows[:self._filled]
            self._rows = rows
        for i in range(self._filled, len(self)):
            self._rows[i] = self[i].x
        self._filled = len(self)
        return self._rows[:self._filled]


@dataclasses.dataclass
class Position:
    """What `_follow` carries from one step to the next (saved by a checkpoint).

    ``current``: the point the next step starts from; ``ds``: that step; ``steps``: the
    points the steps reached (not the located ones between); ``near``: the point before the
    grazing ``current`` was resumed past.
    """

    current: Point
    ds: float
    steps: Steps
    near: Point | None = None


@dataclasses.dataclass
class Course:
    """A continuation at the top of a step: everything its results depend on from there.

    ``branches`` so far; ``follower`` steps branch ``index`` from ``position``; ``queue``:
    the branches switched to and still to follow, each with its follower.
    """

    branches: list[Branch]
    follower: Follower
    index: int
    position: Position
    queue: list[tuple[Follower, int]]


Checkpoint = Callable[[Course], None]


@dataclasses.dataclass(frozen=True)
class Span:
    """The parameter's range of the continuation and the direction it starts in (+1 or -1)."""

    low: float
    high: float
    direction: int = 1


def continue_branches(problem: Problem, z0: np.ndarray, p0: float, span: Span,
                      scaling: Scaling, settings: Settings,
                      progress: Progress | None = None, checkpoint: Checkpoint | None = None,
                      resume: Course | None = None) -> list[Branch]:
    """Follow the branch through (z0, p0) (a guess, corrected at p0) and those it switches to.

    ``checkpoint`` is called with the `Course` at the top of every step; from a ``resume``
    (such a `Course`), the continuation goes on as it would have from there, bit for bit
    (``z0``, ``p0`` unused). Raises ParameterError if the start does not converge;
    `ContinuationInterrupted` (with the branches so far) on Ctrl-C.
    """
    if resume is None:
        follower = Follower(problem, scaling, settings)
        orientation = np.zeros(len(z0) + 1)
        orientation[-1] = span.direction
        first = follower.at_parameter(scaling.scaled(z0, p0), orientation).point
        if first is None:
            raise ParameterError(f"the start at {p0!r} did not converge: Newton on the "
                                 f"periodic orbit took more than {settings.max_iterations} "
                                 "iterations from the guess (give a better guess, e.g. more "
                                 "transient periods)")
        branches = [Branch([follower.kept(first)], problem.period, scaling)]
        queue, at = [(follower, 0)], None
    else:
        branches, at = resume.branches, resume.position
        queue = [(resume.follower, resume.index), *resume.queue]
    try:
        while queue:
            follower, index = queue.pop(0)
            save = None if checkpoint is None else functools.partial(
                _save, checkpoint, branches, follower, index, queue)
            for switch in _follow(follower, branches[index], span, progress, at, save):
                if len(branches) < settings.max_branches:
                    _switched(follower, branches, index, switch, queue)
            at = None
    except KeyboardInterrupt:
        branches[-1].ending = branches[-1].ending or INTERRUPTED
        raise ContinuationInterrupted(branches) from None
    return branches


def _save(checkpoint: Checkpoint, branches: list[Branch], follower: Follower, index: int,
          queue: list[tuple[Follower, int]], position: Position) -> None:
    checkpoint(Course(branches, follower, index, position, queue))


def _follow(follower: Follower, branch: Branch, span: Span, progress: Progress | None,
            at: Position | None = None,
            save: Callable[[Position], None] | None = None) -> list[int]:
    """Step ``branch`` to its end; the indices of its period-doubling points.

    From its last point, or from ``at``; ``save`` is called with the `Position` at the top of
    every step.
    """
    settings = follower.settings
    at = at or Position(branch.points[-1], settings.step, Steps([branch.points[-1]]))
    current, ds, steps, near = at.current, at.ds, Steps(at.steps), at.near
    low, high = span.low * follower.scaling.parameter, span.high * follower.scaling.parameter
    while len(branch.points) < settings.max_points:
        if save is not None:
            save(Position(current, ds, steps, near))
        if not low <= current.x[-1] <= high:  # resumed past an event beyond the bound
            _end_at_bound(follower, branch, steps, low, high, progress)
            break
        ending = _ended(branch, steps, ds, settings)
        if ending:
            branch.ending = ending
            break
        point, taken, grazing = follower.step(current, ds)
        if point is not None and _another_strand(current, point, settings.micro_contacts):
            if taken / 2.0 < settings.min_step:
                branch.ending = MIN_STEP
                break
            ds = taken / 2.0  # refused: a shorter step stays on this strand
            continue
        if point is not None and not low <= point.x[-1] <= high:
            end = _at_bound(follower, current, point, low if point.x[-1] < low else high)
            if end is None and taken / 2.0 >= settings.min_step:
                ds = taken / 2.0  # no orbit at the bound from there (an event between)
                continue
            _append(follower, branch, _advance_or_end(follower, current, end or current), progress)
            branch.ending = BOUND
            break
        if point is not None:
            # the events between located (`_advance`: nonsmooth ones where the contacts
            # changed, smooth ones within each piece)
            try:
                _append(follower, branch, _advance(follower, current, point), progress)
            except _Jumped:  # another branch reached (near a fold at an event), or a piece
                # of the search met a change it could not locate: a shorter step
                if taken / 2.0 < settings.min_step:
                    branch.ending = MIN_STEP
                    break
                ds = taken / 2.0
                continue
            current, ds, near = point, follower.next_step(taken, current, point), None
            steps.append(current)
            continue
        crossing = crosses(current.evaluation.grazing, grazing)  # no point: a failed step
        resumed = crossing and _cross_grazing(follower, branch, current, taken, progress)
        if resumed:
            near, (current, ds) = current, resumed
            steps.append(current)
            continue
        if crossing and taken / 2.0 >= settings.min_step:
            ds = taken / 2.0  # an iterate crossed, not the branch, or no way across: smaller
            continue
        if near is None and len(steps) > 1 and not same_piece(steps[-2], current):
            near = steps[-2]  # current was reached across a change of the contacts
        if near is not None:
            # no step from a point at the grazing (the far side's Jacobian is singular
            # there): on from a point a little beyond it, across the grazing surface
            found = _reached_beyond(follower, near, current)
            near = None
            if found is not None:
                (current, ds), points = found
                _append(follower, branch, points, progress)
                steps.append(current)
                continue
        branch.ending = MIN_STEP
        break
    else:
        branch.ending = MAX_POINTS
    return [i for i, point in enumerate(branch.points) if point.label == PERIOD_DOUBLING]


def _another_strand(start: Point, point: Point, micro_contacts: str) -> bool:
    """Whether a step from ``start`` converged on another strand of the branch, not its own.

    One step crosses one change of the contacts at most where it stays on its strand (a
    contact appears or vanishes, two merge or one splits: the contacts per orbit change by
    one; a step that crosses two is refused and retried shorter until the changes lie in two
    steps): more is a jump of the corrector to a part of the branch the steps never
    reached (issue 31's stiff stop: from 149.57 to 151.37 rad/s and from 5 to 2 contacts per
    orbit, nothing between located; going down at its default modes, from 158.8315 to
    158.7376 rad/s and from 9 to 7). With ``micro_contacts = "summarise"`` the contacts
    within an episode may change many times within a step (chatter, not located): the impact
    episodes per orbit are counted instead.
    """
    count = ((lambda p: p.evaluation.episodes) if micro_contacts == SUMMARISE
             else (lambda p: p.evaluation.contacts))
    return abs(count(point) - count(start)) > 1


# a section sample spread this small against the tip amplitude: the orbit repeats after half
# its period (a period-2 branch back on its period-1 origin); a period-2 orbit's spread grows
# like the square root of the distance from its doubling, ~3e-2 at the switch distance
JOINED_SPREAD = 1e-7
# the steps kept out of the closed-loop test: the branch's own last ones; and a loop is at
# least this many steps long
RECENT_STEPS, LOOP_STEPS = 5, 20
# ... and the branch is back on its earlier path, not beside it, when it is this near (in
# steps) the polyline of the earlier steps: a chord of a step that turns by max_angle = 0.25
# rad lies within 0.03 steps of the arc, while two strands of an S between two tight folds
# run side by side half a step apart (measured on the stiff stop at 156.37 rad/s: 0.47)
ON_PATH = 0.1


def _ended(branch: Branch, steps: Steps, ds: float, settings: Settings) -> str:
    """How the branch ends at its last point, "" if it goes on.

    ``steps``: the points reached by the steps so far (not the located ones between).
    """
    x, tangent = steps[-1].x, steps[-1].tangent
    if len(steps) > RECENT_STEPS + 1:
        earlier = steps[:-RECENT_STEPS]
        xs = steps.positions()
        distances = np.linalg.norm(xs[:-RECENT_STEPS] - x, axis=1)
        nearest = int(np.argmin(distances))
        # one pass over the steps' lengths (a loop in Python here was quadratic in the points)
        travelled = float(np.sum(np.linalg.norm(np.diff(xs[nearest:], axis=0), axis=1)))
        if travelled < LOOP_STEPS * ds:  # creeping, not round a loop
            nearest = -1
        # the same place the same way: a loop; the other way: the branch retraces itself (a
        # step jumped onto its own earlier part). After a fold the branch returns near its
        # way out only within a few steps of it (excluded).
        if (nearest >= 0 and distances[nearest] < 0.5 * ds
                and _off_path(xs[:-RECENT_STEPS], nearest, x) < ON_PATH * ds
                and same_piece(earlier[nearest], steps[-1])):
            if earlier[nearest].tangent @ tangent > 0.9:
                return CLOSED_LOOP
            if earlier[nearest].tangent @ tangent < -0.9:
                return RETRACED
    if branch.origin is not None and len(steps) > 1 and _repeats_early(branch.points[-1]):
        return JOINED_ORIGIN
    if len(steps) > settings.stall_points and np.linalg.norm(
            x - steps[-1 - settings.stall_points].x) < settings.stall_advance:
        return STALLED
    return ""


def _off_path(xs: np.ndarray, k: int, x: np.ndarray) -> float:
    """The distance from ``x`` to the polyline of the rows ``xs`` next to row ``k``."""
    def to_segment(a: np.ndarray, b: np.ndarray) -> float:
        chord = b - a
        along = float(np.clip((x - a) @ chord / max(chord @ chord, 1e-300), 0.0, 1.0))
        return float(np.linalg.norm(x - a - along * chord))

    return min(to_segment(xs[k], xs[j]) for j in (k - 1, k + 1) if 0 <= j < len(xs))


def _repeats_early(point: Point) -> bool:
    """Whether the orbit's section samples all coincide: it is of a shorter period."""
    samples = np.atleast_1d(point.evaluation.measures.get("section_deflection_1", np.nan))
    size = point.evaluation.measures.get("tip_amplitude_1", np.nan)
    spread = float(np.ptp(samples)) if samples.size > 1 else math.nan
    return spread <= JOINED_SPREAD * size


# an event of the same kind this close (x~) to the branch's last one of that kind is that one
REPEATED = 1e-9


def _repeats(points: list[Point], point: Point, tolerance: float) -> bool:
    """Whether ``point``'s label is an event ``points`` (a branch's, in order) already carry.

    The last of them with that label is the same event when it lies within ``REPEATED`` of
    ``point`` (found from both sides of a step searched twice), or when it is the last of
    ``points`` and its parameter is ``point``'s to ``tolerance`` (x~): the two sides of one
    located event, each at it to the location tolerance (a grazing labelled on the near side's
    last point, then on the far side's first, which lies on it to round-off: 7 and 8 contacts
    per orbit 1e-12 rad/s apart on the stiff stop going down at 163.3051438 rad/s, where the
    state moved by more than ``REPEATED``).
    """
    last = next((p for p in reversed(points) if p.label == point.label), None)
    if last is None:
        return False
    return bool(np.linalg.norm(last.x - point.x) <= REPEATED
                or (last is points[-1] and abs(last.x[-1] - point.x[-1]) <= tolerance))


def _append(follower: Follower, branch: Branch, points: list[Point],
            progress: Progress | None) -> None:
    """Append ``points`` with their measures; one that is the last point relabelled replaces it.

    An event is stored once, on the point that carried it first (`_repeats`): a point
    labelled with an event the branch already carries is not appended, and the last point
    relabelled with one that its predecessor carries keeps its own label.
    """
    tolerance = follower.settings.locate_tolerance
    for point in points:
        last = point.x is branch.points[-1].x
        if point.label and _repeats(branch.points[:-1] if last else branch.points, point,
                                    tolerance):
            if not last:
                continue
            point = dataclasses.replace(point, label=branch.points[-1].label)
        if last:
            point = branch.points[-1] = dataclasses.replace(
                point, evaluation=branch.points[-1].evaluation)
        else:
            point = follower.kept(point)
            branch.points.append(point)
        if progress is not None:
            progress(branch, point)


# a point beyond an event is a direction to orient the far side by from this many Newton
# tolerances on (closer, the direction is Newton's error)
FAR = 100
# a step across which a smooth bifurcation is detected is searched in SAMPLES[0] pieces, a
# piece where one is detected again in SAMPLES[1], and so on: to 1 / 4096 of the step. The
# first sampling finds crossings that hide each other at the step's ends; within a piece, the
# detected crossing is then narrowed by fewer samples a level
SAMPLES = (16, 16, 4, 4)
# ... when a multiplier other than the crossing ones lies this near the circle at an end, in
# units of the largest change of a modulus over the step (`_may_hide_crossings`)
NEAR_CIRCLE = 4.0
# bisections of a step whose signature changed without its test function changing sign (two
# crossings, or a multiplier that left the kind in between, e.g. a complex pair turned real)
MAX_SUBDIVISIONS = 6


def _between(follower: Follower, a: Point, b: Point,
             plane: tuple[np.ndarray, np.ndarray] | None = None, depth: int = 0) -> list[Point]:
    """The smooth bifurcations located between ``a`` and ``b`` (in order), then ``b``.

    ``a`` and ``b`` lie on one smooth piece of the branch. Points between are corrected on
    planes s along ``a``'s tangent from ``a`` (across the chord from ``a`` to ``b`` where the
    branch turns back within the step, `_along`), or along ``plane`` = (origin, unit normal)
    when given. A kind whose signature changed but whose test function has the same sign at
    both ends is sought in both halves of the step (at most ``MAX_SUBDIVISIONS`` times).
    """
    origin, normal = plane if plane is not None else (a.x, _along(a, b))

    def point_at(s: float, guess: np.ndarray | None = None) -> Point | None:
        return follower.correct(origin + s * normal, normal, normal, guess).point

    found = detected(a, b)
    if found and depth < len(SAMPLES) and _may_hide_crossings(a, b, len(found)):
        # crossings close together (a pair that leaves and returns within the step) show at
        # the ends as one, or none: the step is sampled, and each piece searched on its own
        width, pieces = float(normal @ (b.x - origin)), SAMPLES[depth]
        ends = _sampled(point_at, a, b, width, pieces)
        found_points = [point for start, end in zip(ends[:-1], ends[1:], strict=True)
                        for point in _advance(follower, start, end, depth + 1)]
        # the samples only served the search: the branch keeps what was located, and b
        return [point for point in found_points if point.label] + [b]
    if depth < MAX_SUBDIVISIONS and not all(_brackets(test, a, b) for _, test in found):
        # a signature changed without its test function changing sign: two crossings, or a
        # multiplier that left its kind in the step (a complex pair turned real): look closer
        middle = point_at(0.5 * float(normal @ (b.x - origin)))
        if middle is not None and same_piece(a, middle) and same_piece(middle, b):
            return (_between(follower, a, middle, plane, depth + 1)
                    + _between(follower, middle, b, plane, depth + 1))
    located = []
    for label, test in found:
        if not _brackets(test, a, b):
            continue
        tolerance = follower.settings.locate_tolerance
        root = locate(point_at, a, float(normal @ (b.x - origin)), b, test, tolerance,
                      near_zero(test, a, b, tolerance))
        if not continuous_root(test, a, b, root, tolerance):
            # the test jumps there (the multiplier it follows changed kind: a pair turned
            # real), no bifurcation; a crossing may lie on either side of the jump
            return _beside_jump(follower, a, b, root, depth)
        # (``a`` itself when the root is there: it replaces ``a`` on the branch, `_append`)
        located.append((root.s, dataclasses.replace(root.before, label=label)))
    if depth < MAX_SUBDIVISIONS and not all(same_piece(a, point) for _, point in located):
        # the contacts changed and changed back within the step: two nonsmooth events hide
        middle = point_at(0.5 * float(normal @ (b.x - origin)))
        if middle is not None:
            return (_advance(follower, a, middle, depth + 1)
                    + _advance(follower, middle, b, depth + 1))
    return [point for _, point in sorted(located, key=lambda pair: pair[0])] + [b]


def _sampled(point_at: PointAt, a: Point, b: Point, width: float, pieces: int) -> list[Point]:
    """``a``, the points corrected at ``pieces - 1`` equal steps to ``width``, ``b``, in order.

    Each from the branch interpolated between the last point corrected and ``b``
    (`guess_at`); a point where Newton failed is left out.
    """
    points, last = [a], (0.0, 0.0, a)
    for k in range(1, pieces):
        s = width * k / pieces
        point = point_at(s, guess_at(last, (width, 0.0, b), s))
        if point is not None:
            points.append(point)
            last = (s, 0.0, point)
    return [*points, b]


def _along(a: Point, b: Point) -> np.ndarray:
    """The normal of the planes a step from ``a`` to ``b`` on one smooth piece is searched on.

    ``a``'s tangent, whose planes cut the branch once each while it turns by less than 90
    degrees from it. Where it has turned back further by ``b`` (``b``'s tangent has a part
    against ``a``'s, or ``b`` lies behind ``a``'s plane: a piece between two located changes
    of the contacts is not bound by the step's largest angle), those planes reach no farther
    than where the branch is orthogonal to ``a``'s tangent, and a fold or period doubling
    beyond was not located: planes across the chord, which the branch crosses once each as it
    turns by up to 180 degrees, reach all of it.
    """
    chord = b.x - a.x
    if not np.any(chord) or (a.tangent @ b.tangent > 0.0 and a.tangent @ chord > 0.0):
        return a.tangent
    return chord / np.linalg.norm(chord)


def _beside_jump(follower: Follower, a: Point, b: Point, jump: Located,
                 depth: int) -> list[Point]:
    """The bifurcations from ``a`` to ``b`` on both sides of a test's ``jump``, then ``b``.

    Each side is searched on its own (``MAX_SUBDIVISIONS`` deep at most); the jump's bracket
    only served the search: the branch keeps what was located, and b.
    """
    if depth >= MAX_SUBDIVISIONS:
        return [b]
    sides = [(a, jump.before)] + ([(jump.beyond, b)] if jump.beyond is not None else [])
    found = [point for start, end in sides if end is not start
             for point in _advance(follower, start, end, depth + 1)]
    return [point for point in found if point.label] + [b]


def _may_hide_crossings(a: Point, b: Point, crossings: int) -> bool:
    """Whether more multipliers than the ``crossings`` detected could cross within the step.

    A crossing hidden at the step's ends (a pair that leaves and returns, a second pair
    that leaves with it) needs a multiplier other than the detected ones near the circle at
    either end: within ``NEAR_CIRCLE`` times the most any modulus changed over the step. A
    complex pair is one multiplier here, as it is one crossing (a Neimark-Sacker point):
    counted twice, every step over a Neimark-Sacker point was sampled (most of the samples
    of the stiff stop's branch, a sixth of its time). Elsewhere (a stiff contact's branch:
    every multiplier but the crossing one far inside) the step is searched without sampling.
    """
    multipliers = [point.evaluation.multipliers for point in (a, b)]
    moduli = [np.sort(np.abs(mu)) for mu in multipliers]
    if moduli[0].size != moduli[1].size:
        return True
    near = NEAR_CIRCLE * float(np.max(np.abs(moduli[1] - moduli[0]), initial=0.0))
    # of each conjugate pair only the member above the real axis (eigvals gives exact pairs)
    return max(int(np.count_nonzero((np.abs(np.abs(mu) - 1.0) <= near) & (mu.imag >= 0.0)))
               for mu in multipliers) > crossings


def _brackets(test: Callable[[Point], float], a: Point, b: Point) -> bool:
    """Whether ``test`` is finite at ``a`` and ``b`` and changes sign between them."""
    return math.isfinite(test(a)) and math.isfinite(test(b)) and (test(a) > 0) != (test(b) > 0)


def _advance(follower: Follower, a: Point, b: Point, depth: int = 0) -> list[Point]:
    """The points from ``a`` (excluded) to ``b``, events located, whatever lies between.

    On one smooth piece: `_between`. Across a change of the contact sequence: the nonsmooth
    event is located on planes across the chord from ``a`` to ``b`` (the grazing value, or the
    contacts per orbit by bisection for a merge or split), labelled at the last point before
    it (a grazing whose contact at zero depth is the far side's: at the first past it), and smooth
    bifurcations are sought only within each side's piece; then on from the first point past
    it. Unlocated (no corrected point past it on the planes, or more than ``MAX_SUBDIVISIONS``
    events in a row): ``b`` unlabelled, or `_Jumped` for a step longer than ``KINK_STEP`` (a
    shorter one will reach it); `_Jumped` also when ``b`` is on another branch.
    """
    if same_piece(a, b):
        return _between(follower, a, b, depth=depth)
    label, test = _nonsmooth(a, b, follower.settings.micro_contacts)
    if label == CHATTER:
        return [dataclasses.replace(b, label=CHATTER)]
    # on planes across a's tangent (its parameter rate pins the parameter, `events.locate`);
    # else across the chord from a to b, which reach b whatever the kink at the event
    chord = (b.x - a.x) / np.linalg.norm(b.x - a.x)
    for normal in (a.tangent, chord):
        _, before, past, _ = _located_change(follower, a, b, normal, test)
        if past is not None and not (before is a and past is b):
            break
    if past is None or depth >= MAX_SUBDIVISIONS or (before is a and past is b):
        if depth == 0 and np.linalg.norm(b.x - a.x) > KINK_STEP:
            raise _Jumped  # not located from here: a shorter step will reach it
        return [b]
    if np.linalg.norm(past.x - before.x) > JUMP * np.linalg.norm(b.x - a.x):
        raise _Jumped  # the map is continuous: the two sides of an event of one branch meet
    label = GRAZING if _at_zero_depth(a, b, before, past) else merge_or_split(a, b)
    # forward on the far side is toward b (the kink may exceed 90 degrees); where b is past
    # itself but for Newton's error, away from a
    far = b.x - past.x
    past = oriented(past, far if np.linalg.norm(far) > FAR * follower.settings.tolerance
                    else past.x - a.x)
    near = _between(follower, a, before)[:-1] if before is not a else []
    rest = [] if past is b else _advance(follower, past, b, depth + 1)
    if label == GRAZING and not _at_zero_depth(a, b, before):
        # the contact at zero depth is the far side's (on the near side another contact, or
        # free flight, was nearer 0): its point carries the label and its zero gap
        return [*near, before, dataclasses.replace(past, label=label), *rest]
    return [*near, dataclasses.replace(before, label=label), past, *rest]


def _located_change(follower: Follower, a: Point, b: Point, normal: np.ndarray,
                    test: Callable[[Point], float]) -> Located:
    """The change of the contacts from ``a`` to ``b`` located on planes along ``normal``.

    By ``test``'s root (the grazing or the interval value, if either changed sign); where
    that jumps instead (its sign changed without a contact at zero depth), or neither
    changed sign, within the last bracket by the root of the value nearest 0 of either
    (`_nearest_value`), then by bisection on the contacts where that jumps too.
    """
    tests = [(_sided(test, a), _value_tolerance(follower, test, a))] if test in (
        grazing_test, interval_test) else []
    # the nearest value needs no value tolerance: one side's may stay away from 0 (the other
    # contact's value stands in there), and the bracket is all a change of contacts needs
    nearest = _sided(_nearest_value, a)
    tests += [(nearest, math.inf), (_contacts_of(a), math.inf)]
    located = Located(0.0, a, b, False)
    for each, value_tolerance in tests:
        if located.beyond is None:  # no corrected point past the last bracket: all of it
            located = Located(0.0, a, b, False)
        located = _narrowed(follower, a, normal, located, each, value_tolerance,
                            may_jump=each is not tests[-1][0], one_sided=each is nearest)
        if located.root:
            break
    return located


def _narrowed(follower: Follower, a: Point, normal: np.ndarray, bracket: Located,
              test: Callable[[Point], float], value_tolerance: float, may_jump: bool,
              one_sided: bool) -> Located:
    """``test``'s root located within ``bracket`` (on planes along ``normal`` from ``a``)."""
    offset = bracket.s

    def point_at(s: float, guess: np.ndarray | None = None) -> Point | None:
        return follower.correct(a.x + (offset + s) * normal, normal, normal, guess).point

    located = locate(point_at, bracket.before,
                     float(normal @ (bracket.beyond.x - a.x)) - offset, bracket.beyond, test,
                     follower.settings.locate_tolerance, value_tolerance, may_jump, one_sided)
    return located._replace(s=offset + located.s)


def _nearest_value(point: Point) -> float:
    """The magnitude of the grazing or interval value nearest 0 (m), 1 if neither is known.

    At a change of the contacts that neither value's sign shows, the one that goes to 0 is
    the changing contact's (a shallow contact appearing beside a deeper one's release, an
    interval closing while another is nearer 0 on the far side): its magnitude, signed by
    the side (`_sided`), is a root a secant finds in a few solves where bisection takes 30.
    """
    values = [abs(value) for value in (point.evaluation.grazing, point.evaluation.interval)
              if math.isfinite(value)]
    return min(values, default=1.0)


SMALLEST = math.ulp(0.0)  # the least positive float (a denormal)


def _sided(test: Callable[[Point], float], a: Point) -> Callable[[Point], float]:
    """``test``'s magnitude, signed by the side of the change a point's contacts are on.

    The side of ``a`` (its contacts per orbit) has ``a``'s sign. Where the test jumps (a gap's
    extremum that the samples of a long contact miss, so that another contact's stands in
    for it), its sign may belie the contacts: a bracket by sign alone would then hold the
    change on one side only, and shrink toward the wrong end. A value of exactly 0 (``a`` at
    a grazing located before) counts as the least positive float: its side stays told.
    """
    contacts, sign = a.evaluation.contacts, math.copysign(1.0, test(a))

    def sided(point: Point) -> float:
        same = point.evaluation.contacts == contacts
        return (abs(test(point)) or SMALLEST) * (sign if same else -sign)

    return sided


def _value_tolerance(follower: Follower, test: Callable[[Point], float], start: Point,
                     ) -> float:
    """How small a located grazing's gap, or interval value, must be (m).

    The location tolerance of its value at ``start``, but not below the problem's
    ``gap_round_off`` (if it has one): from a start already near the event, a tolerance
    relative to its value asks for less than the round-off of a gap, which no bracket
    reaches (each solve then halves a bracket pinned long before, up to MAX_LOCATING).
    """
    return max(follower.settings.locate_tolerance * abs(test(start)),
               getattr(follower.problem, "gap_round_off", 0.0))


def _advance_or_end(follower: Follower, a: Point, b: Point) -> list[Point]:
    """`_advance`, or ``b`` unlabelled where no shorter step can be tried (a bound, ...)."""
    try:
        return _advance(follower, a, b)
    except _Jumped:
        return [b]


# the last points on both sides of a located change of the contacts are this close (against
# the step) on one branch: the period map is continuous, only its Jacobian jumps. Farther
# apart, the step's end is on another branch (two meet at a fold at a contact change, where
# a short step can land on either)
JUMP = 1e-3


class _Jumped(Exception):
    """A step whose ends lie on two branches, or across an event not located from its start."""


def _nonsmooth(a: Point, b: Point, micro_contacts: str,
               ) -> tuple[str, Callable[[Point], float]]:
    """The kind of the contact-sequence change between ``a`` and ``b`` and its test function.

    A grazing when the grazing value changes sign (a contact at zero depth), located at its
    root; else a merge or split, located at the root of the interval value where it changes
    sign (the gap's maximum between contacts), else by bisection on the contacts. With
    ``micro_contacts = "summarise"`` a change that keeps the episodes per orbit is `CHATTER`,
    not located: only an episode's appearance or disappearance is.
    """
    if micro_contacts == SUMMARISE and a.evaluation.episodes == b.evaluation.episodes:
        return CHATTER, grazing_test
    if crosses(a.evaluation.grazing, (b.evaluation.grazing,)):
        return GRAZING, grazing_test
    if crosses(a.evaluation.interval, (b.evaluation.interval,)):
        return merge_or_split(a, b), interval_test
    return merge_or_split(a, b), _contacts_of(a)


def _contacts_of(a: Point) -> Callable[[Point], float]:
    """A test whose sign is whether a point has ``a``'s contacts per orbit (+1) or not (-1)."""
    contacts = a.evaluation.contacts

    def same_contacts(point: Point) -> float:
        return 1.0 if point.evaluation.contacts == contacts else -1.0

    return same_contacts


# a located change of the contacts is a grazing when the grazing value at the event is this
# small against its values at the step's ends: a contact at zero depth (else the free interval
# between two contacts closed or opened, and the shallowest contact is not at the event)
ZERO_DEPTH = 1e-3


def _at_zero_depth(a: Point, b: Point, *points: Point) -> bool:
    """Whether one of ``points`` has a contact at zero depth against the step's ends a, b."""
    scale = max(abs(a.evaluation.grazing), abs(b.evaluation.grazing))
    return min(abs(point.evaluation.grazing) for point in points) <= ZERO_DEPTH * scale


def merge_or_split(a: Point, b: Point) -> str:
    """A change of the contacts from ``a`` to ``b`` that is no grazing: fewer is a merge."""
    return CONTACT_MERGE if b.evaluation.contacts < a.evaluation.contacts else CONTACT_SPLIT


# distances beyond a grazing tried for the first point of the new contact sequence, as
# fractions of the step that crossed it
BEYOND = (1e-2, 4e-2, 0.16, 0.64, 2.5e-3, 6.25e-4, 1.6e-4)


def _cross_grazing(follower: Follower, branch: Branch, current: Point, taken: float,
                   progress: Progress | None) -> tuple[Point, float] | None:
    """Locate the grazing ahead of ``current`` where the step failed, label it, resume beyond.

    Newton failed at the step's end but its iterates crossed the grazing. The grazing is
    bracketed on secant planes of ``current``. Beyond it the branch may turn within a sliver of
    the parameter (a multiplier jumps): the first point of the new contact sequence is
    corrected on a plane across the grazing value's gradient, at a distance where the gap has
    changed sign, so that it exists whichever way the branch turns. Returns that point and the
    step to take from it; None, labelling nothing, if none is found (a Newton iterate crossed,
    not the branch). Not bracketed, or no change of the contacts: labels nothing and resumes
    short of it (`_short_of_grazing`).
    """
    # Newton from the tangent's point on each plane, not from a guess between the bracket's
    # ends (`guess_at`): a grazing at a fold has the branch's other strand close beside it,
    # which such a guess converges on (going down the stiff stop at 152.754 rad/s it then
    # retraced the branch it came along)
    _, grazing, past, root = locate(lambda s, _: follower.at_arclength(current, s).point,
                                    current, taken, None, grazing_test,
                                    follower.settings.locate_tolerance,
                                    _value_tolerance(follower, grazing_test, current),
                                    may_jump=True)
    if past is not None:  # the branch is reachable across it on these planes after all
        try:
            _append(follower, branch, _advance(follower, current, past), progress)
        except _Jumped:
            return None
        # forward is away from where the branch came from (near a fold past the grazing, the
        # tangent oriented like current's may point back to the grazing)
        return oriented(past, past.x - current.x), max(taken / 2.0, follower.settings.min_step)
    if not root:
        return _short_of_grazing(follower, branch, current, grazing, taken, progress)
    found = _beyond(follower, current, grazing, taken)
    if found is None:
        return None
    if grazing is current:  # within the tolerance of the grazing already
        _append(follower, branch, [dataclasses.replace(current, label=GRAZING)], progress)
    else:
        _append(follower, branch, [*_advance_or_end(follower, current, grazing)[:-1],
                         dataclasses.replace(grazing, label=GRAZING)], progress)
    # no smooth bifurcation is sought across the grazing: the multipliers jump there
    _append(follower, branch, [found[0]], progress)
    return found


def _beyond(follower: Follower, current: Point, at: Point, taken: float,
            ) -> tuple[Point, float] | None:
    """The first point of the new contact sequence past the grazing ``at``, and its distance.

    Corrected on a plane across the grazing value's gradient at ``at``, toward the other sign
    of the gap than ``current``'s, at the first of ``BEYOND``'s distances where the gap has
    changed sign and the contacts are not ``current``'s: it exists whichever way the branch
    turns. ``at``: the grazing, as located (still ``current``'s side) or just past it.
    Oriented away from ``at``. None if none is found.
    """
    # toward the other sign of the gap than current's (at's own, where current is at the
    # grazing to round-off)
    side = -np.sign(current.evaluation.grazing) or np.sign(at.evaluation.grazing)
    gradient = follower.grazing_gradient(at.x)
    if not side or not np.any(gradient):
        return None
    normal = side * gradient / np.linalg.norm(gradient)
    for fraction in BEYOND:
        distance = max(fraction * taken, follower.settings.min_step)
        beyond = follower.correct(at.x + distance * normal, normal, normal).point
        if beyond is not None and _grazes(current, beyond) and not _same_contacts(current,
                                                                                   beyond):
            return oriented(beyond, beyond.x - at.x), distance
    return None


# scales of the distance beyond a grazing tried by `_reached_beyond`, in the first step's
NEARER = (1.0, 1.0 / 16.0, 1.0 / 256.0)


def _reached_beyond(follower: Follower, near: Point, at: Point,
                    ) -> tuple[tuple[Point, float], list[Point]] | None:
    """`_beyond` the grazing ``at`` (reached from ``near``), and the points from ``at`` to it.

    A point beyond that the way from ``at`` does not reach on the branch (`_Jumped`: it lies
    past a further change of the contacts, on the next piece but one) is given up for one
    nearer. None if none is found.
    """
    for scale in NEARER:
        found = _beyond(follower, near, at, scale * follower.settings.step)
        if found is None:
            continue
        try:
            return found, _advance(follower, at, found[0])
        except _Jumped:
            continue
    return None


def _grazes(a: Point, b: Point) -> bool:
    return crosses(a.evaluation.grazing, (b.evaluation.grazing,))


def _same_contacts(a: Point, b: Point) -> bool:
    return a.evaluation.contacts == b.evaluation.contacts


def _short_of_grazing(follower: Follower, branch: Branch, current: Point, last: Point,
                      taken: float, progress: Progress | None) -> tuple[Point, float] | None:
    """Resume where the grazing value changed sign without a grazing located.

    No corrected point beyond was found and the root is not within the bracket: the branch
    turned back across ``current``'s planes, at a fold, before reaching the grazing, and it
    resumes from ``last``, the farthest point reached, to cross the grazing on planes of its
    own. Returns None if that is ``current``.
    """
    if last is current:
        return None
    _append(follower, branch, _advance_or_end(follower, current, last), progress)
    return last, max(taken / 2.0, follower.settings.min_step)


def _end_at_bound(follower: Follower, branch: Branch, steps: list[Point], low: float,
                  high: float, progress: Progress | None) -> None:
    """End ``branch`` at the bound its last step point went past (resumed past an event).

    The points beyond the range go; the end is corrected at the bound between the last step
    points on both sides of it (the last one inside if that fails).
    """
    inside = [point for point in steps if low <= point.x[-1] <= high]
    branch.points[:] = [point for point in branch.points if low <= point.x[-1] <= high]
    last = steps[-1]
    if inside:
        end = _at_bound(follower, inside[-1], last, low if last.x[-1] < low else high)
        if end is not None:
            _append(follower, branch, [end], progress)
    branch.ending = BOUND


def _at_bound(follower: Follower, a: Point, b: Point, bound: float) -> Point | None:
    """The branch's end at the parameter's bound, between ``a`` and ``b`` (None if it fails)."""
    weight = (bound - a.x[-1]) / (b.x[-1] - a.x[-1])
    guess = a.x + weight * (b.x - a.x)
    guess[-1] = bound
    return follower.at_parameter(guess, a.tangent).point


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
    branches.append(Branch([doubled.kept(dataclasses.replace(start, label=""))],
                           2 * branches[index].period,
                           scaling, origin=(index, at)))
    queue.append((doubled, len(branches) - 1))


def _doubling_direction(point: Point, scaling: Scaling) -> np.ndarray:
    """The eigenvector of the multiplier nearest -1, in x~ (no parameter part)."""
    monodromy = point.evaluation.jacobian + np.eye(len(point.x) - 1)
    values, vectors = np.linalg.eig(monodromy)
    vector = np.real(vectors[:, np.argmin(np.abs(values + 1.0))])
    return np.append(vector * scaling.state, 0.0) / np.linalg.norm(vector * scaling.state)
