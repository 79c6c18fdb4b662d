"""Pseudo-arclength continuation: predictor along the tangent, Newton corrector, step control.

The unknowns are x = (z, p), scaled to x~ = (z w_z, p w_p) by a [`Scaling`][] so that the
state and the parameter count alike in the arclength. A branch point carries its unit tangent
t (in x~), the null vector of the Jacobian [dr/dz, dr/dp] oriented like the previous one.
A step of length ds predicts x~ + ds t and corrects by Newton on

    r(z, p) = 0,    t . (x~ - x~_predicted) = 0     (Keller's pseudo-arclength condition).

The step halves when Newton fails to converge within ``max_iterations`` (or stops
contracting) and shrinks when the angle between consecutive tangents, or between the tangent
and the step's secant, exceeds ``max_angle`` on one smooth piece of the branch (across a
change of the orbit's contact sequence the tangent jumps however small the step: such a step
is kept once below ``KINK_STEP`` and the event between located); it grows by 1.5 after a step
that took at most 3 iterations, up to ``max_step`` (and, with ``Settings.turn_aim``, no
further than its turn allows).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from impactbeams.continuation.problem import Evaluation, Problem, parameter_derivative
from impactbeams.params import ParameterError

GRADIENT_STEP = 1e-7  # x~ units
# a step that turns by more than max_angle onto another contact sequence is kept once it is
# this short (x~ units: 1e-4 of the range): the kink is then the branch's, not a jump of the
# corrector onto another part of the branch (which a longer step can reach)
KINK_STEP = 1e-4
# a Newton correction at most this large (x~ units) is checked by a chord step before another
# linearisation: quadratic convergence then puts the next one near 1e-12 or below
CHORD_CHECK = 1e-6
# a branch's Settings.turn_aim: the turn of a step, in max_angle, its length aims at. Measured
# on the stiff stop from 140 to 160 rad/s (16 modes): a step grown by 1.5 after each quick
# correction was refused for its turn in 1013 of 3000 corrections; aiming at 0.8, 85 of 1960
# (24 % less CPU), at 0.6 more points (the aim well below the limit), at 0.95 120 of 1800. The
# turn is proportional to the step only where the branch's curvature is smooth: a margin below 1
TURN_AIM = 0.8
# a correction this small (x~ units, of order 1) moves x~ by its round-off only
ROUND_OFF_STEP = 1e-15
# what to do with a change of the contacts within an episode (Settings.micro_contacts)
LOCATE, SUMMARISE = "locate", "summarise"
MICRO_CONTACTS = (LOCATE, SUMMARISE)


@dataclasses.dataclass(frozen=True)
class Settings:
    """How a branch is followed; lengths and tolerances in the scaled unknowns x~.

    ``step``, ``min_step``, ``max_step``: the first, smallest and largest arclength steps.
    ``tolerance``: Newton stops when its correction's largest component is below it (the
    residual is then ~ tolerance^2 at quadratic convergence). ``max_angle`` (rad): between the
    tangents of consecutive points. ``locate_tolerance``: a bifurcation or grazing is located
    until the parameter is known to this much (in x~ units, i.e. times 1 / w_p in the
    parameter). ``switch_distance``: how far from a period-doubling point the period-2 branch
    starts. ``max_branches``: branches in all, the started one included (each period doubling
    found starts one, while there is room). ``micro_contacts``: "locate" every change of the
    contact sequence, or "summarise" those within an episode (label chatter, not located).
    ``stall_points``, ``stall_advance``: the branch has stalled, and ends, when its last
    ``stall_points`` steps moved it less than ``stall_advance`` in all (x~ units).
    ``turn_aim``: on one smooth piece, the turn (a fraction of ``max_angle``) a step's length
    aims at from the last step's turn (`Follower.next_step`, `_shrink`); None: a refused step
    halves, and an accepted one grows or shrinks by its Newton iterations only.
    """

    step: float = 1e-2
    min_step: float = 1e-7
    max_step: float = 0.1
    max_points: int = 1000
    tolerance: float = 1e-10
    max_iterations: int = 8
    max_angle: float = 0.25
    locate_tolerance: float = 1e-11
    switch_distance: float = 1e-3
    max_branches: int = 2
    micro_contacts: str = LOCATE
    stall_points: int = 100
    stall_advance: float = 1e-4
    turn_aim: float | None = None

    def __post_init__(self) -> None:
        for name in ("step", "min_step", "max_step", "tolerance", "max_angle",
                     "locate_tolerance", "switch_distance", "stall_advance"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"{name} = {value!r} is not allowed: must be a finite "
                                     "number > 0")
        if not self.min_step <= self.step <= self.max_step:
            raise ParameterError(f"step = {self.step!r} is not allowed: must lie from min_step "
                                 f"= {self.min_step!r} to max_step = {self.max_step!r}")
        if self.turn_aim is not None and not 0.0 < self.turn_aim < 1.0:
            raise ParameterError(f"turn_aim = {self.turn_aim!r} is not allowed: must be None "
                                 "or a number > 0 and < 1")
        if self.micro_contacts not in MICRO_CONTACTS:
            raise ParameterError(f"micro_contacts = {self.micro_contacts!r} is not allowed: "
                                 f"must be one of {', '.join(map(repr, MICRO_CONTACTS))}")
        for name in ("max_points", "max_iterations", "max_branches", "stall_points"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ParameterError(f"{name} = {value!r} is not allowed: must be an integer "
                                     ">= 1")


@dataclasses.dataclass(frozen=True)
class Scaling:
    """x~ = (z * state, p * parameter)."""

    state: np.ndarray
    parameter: float

    def scaled(self, z: np.ndarray, p: float) -> np.ndarray:
        """x~ of (z, p)."""
        return np.append(z * self.state, p * self.parameter)

    def unscaled(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        """(z, p) of x~."""
        return x[:-1] / self.state, float(x[-1] / self.parameter)


@dataclasses.dataclass(frozen=True, eq=False)
class Point:
    """A point of a branch: x~, its unit tangent, what was read there, how it was found.

    ``label``: "" for a regular point, else the bifurcation located there.
    """

    x: np.ndarray
    tangent: np.ndarray
    evaluation: Evaluation
    iterations: int
    label: str = ""
    crossed: bool = False  # whether Newton's iterates met other contacts than the point's

    def state(self, scaling: Scaling) -> np.ndarray:
        """The section state z."""
        return scaling.unscaled(self.x)[0]

    def parameter(self, scaling: Scaling) -> float:
        """The parameter p."""
        return scaling.unscaled(self.x)[1]


@dataclasses.dataclass(frozen=True)
class Correction:
    """A corrector's outcome: the point (None if Newton failed) and its iterates x~."""

    point: Point | None
    iterates: tuple[np.ndarray, ...]


class Follower:
    """Corrects and steps along one problem's branch (one period, one scaling)."""

    def __init__(self, problem: Problem, scaling: Scaling, settings: Settings) -> None:
        self.problem, self.scaling, self.settings = problem, scaling, settings

    def linearised(self, x: np.ndarray, rate: np.ndarray | None = None,
                   ) -> tuple[Evaluation, np.ndarray, np.ndarray]:
        """The evaluation at x~ (no measures), its scaled Jacobian in x~ and dr/dp.

        The Jacobian of the scaled residual is n x n+1; dr/dp is ``rate`` if given, else
        taken by differences at x~.
        """
        z, p = self.scaling.unscaled(x)
        evaluation = self.problem.evaluate(z, p, grazing=False)
        if rate is None:
            # a problem may difference its own parameter (a curve's: on a grazing curve every
            # point is at a change of the contacts, where the narrowed step is round-off)
            derivative = getattr(self.problem, "parameter_derivative", parameter_derivative)
            rate = derivative(self.problem, z, p, 1.0 / self.scaling.parameter, evaluation)
        w = self.scaling.state
        jacobian = np.hstack([w[:, None] * evaluation.jacobian / w[None, :],
                              (w * rate / self.scaling.parameter)[:, None]])
        return evaluation, jacobian, rate

    def correct(self, predicted: np.ndarray, direction: np.ndarray,
                orientation: np.ndarray, start: np.ndarray | None = None) -> Correction:
        """Newton from ``predicted`` on r = 0, direction . (x~ - predicted) = 0.

        From ``start`` instead if given: a nearer guess (on that plane or off it: Newton's
        first step reaches the plane, an affine constraint), but for an ``approximate``
        problem (its basis takes one subspace iteration an evaluation: a solve with fewer
        leaves a fold's test less converged, 1e-8 against 7e-10 on the shipped example's
        fold, above what locating it asks for). The tangent of the point found
        is oriented along ``orientation``. The measures (and the grazing value) are read at
        the point found only. A problem whose dr/dz is an approximation (``approximate``:
        Newton-Picard) keeps the first iterate's dr/dp for the whole corrector: its
        iteration is a chord one anyway, and the tangent's parameter part still vanishes
        exactly where dr/dz is singular (a fold), whatever dr/dp.
        """
        frozen, contacts = getattr(self.problem, "approximate", False), set()
        x = (predicted if start is None or frozen else start).copy()
        iterates, previous, rate = [], math.inf, None
        for iteration in range(1, self.settings.max_iterations + 1):
            try:
                evaluation, jacobian, rate = self.linearised(x, rate if frozen else None)
            except (ParameterError, RuntimeError):  # out of the allowed values, or a run stopped
                break
            iterates.append(x.copy())
            contacts.add(evaluation.contacts)
            system = np.vstack([jacobian, direction])
            delta = _newton_step(system, evaluation.residual * self.scaling.state, direction,
                                 x - predicted)
            if delta is None:
                break
            size = float(np.max(np.abs(delta)))
            if size > self.settings.tolerance and iteration > 2 and size > previous:
                break  # not contracting: a smaller step will do
            found, iterations = x + delta, iteration
            if (self.settings.tolerance < size <= CHORD_CHECK and not frozen
                    and iteration < self.settings.max_iterations):
                # Newton is quadratic here: its next correction (within the iterations
                # allowed, as Newton's own) is read from a run at x~ + delta with this
                # Jacobian (a chord step: the next Newton correction to ~ size relative), not
                # from a new linearisation. Where it is below the tolerance, dr/dz (the
                # multipliers, the tangent) is taken at x~ + delta from its run, which the
                # problem keeps, as Newton's last iterate would be; the point is x~ + delta +
                # chord (x~ + delta where the chord is round-off: its run is then the
                # measures' too). dr/dp, a run more by forward differences, stays this
                # iterate's: it tilts the tangent by ~ size, and not where its parameter part
                # vanishes (a fold). Else Newton goes on from x~ + delta
                try:
                    chord = self._chord(found, system, direction, predicted, contacts)
                    chord_size = math.inf if chord is None else float(np.max(np.abs(chord)))
                    if chord_size <= self.settings.tolerance:
                        evaluation, jacobian, _ = self.linearised(found, rate)
                        size, iterations = 0.0, iteration + 1
                        if chord_size > ROUND_OFF_STEP:
                            found = found + chord
                except (ParameterError, RuntimeError):
                    break
            if size <= self.settings.tolerance:
                try:
                    measured = self._measured(found, evaluation.with_multipliers())
                except (ParameterError, RuntimeError):  # the point found is out of reach
                    break
                point = Point(found, tangent_of(jacobian, orientation), measured, iterations,
                              crossed=bool(contacts - {measured.contacts}))
                return Correction(point, tuple(iterates))
            x, previous = found, size
        return Correction(None, tuple(iterates))

    def _chord(self, x: np.ndarray, system: np.ndarray, direction: np.ndarray,
               predicted: np.ndarray, contacts: set[int]) -> np.ndarray | None:
        """The chord step at x~ with an earlier iterate's ``system``; None if not finite.

        The contacts of x~'s run join ``contacts`` (those Newton's iterates met).
        """
        z, p = self.scaling.unscaled(x)
        evaluation = self.problem.evaluate(z, p, jacobian=False, grazing=False)
        contacts.add(evaluation.contacts)
        return _newton_step(system, evaluation.residual * self.scaling.state, direction,
                            x - predicted)

    def _measured(self, x: np.ndarray, evaluation: Evaluation) -> Evaluation:
        """``evaluation`` with the contacts, the grazing and interval values read at x~.

        x~ is the point found, after Newton's last correction: its run costs what a run
        at the last iterate would, and the grazing value there is the orbit's to round-off,
        not to the correction (up to 1e-10 of ``state_scale``: 1e-14 m of gap, 3e-8 rad/s of a
        grazing's frequency on the shipped example).
        """
        z, p = self.scaling.unscaled(x)
        measured = self.problem.evaluate(z, p, jacobian=False)
        return dataclasses.replace(evaluation, grazing=measured.grazing,
                                   interval=measured.interval, contacts=measured.contacts,
                                   episodes=measured.episodes)

    def kept(self, point: Point) -> Point:
        """``point`` with its named measures: it is kept on the branch (the others are not)."""
        if point.evaluation.measures:
            return point
        z, p = self.scaling.unscaled(point.x)
        return dataclasses.replace(point, evaluation=dataclasses.replace(
            point.evaluation, measures=self.problem.measures(z, p)))

    def grazing_values(self, correction: Correction) -> tuple[float, ...]:
        """The grazing values of a correction's iterates (read only when a step failed)."""
        values = []
        for x in correction.iterates:
            z, p = self.scaling.unscaled(x)
            values.append(self.problem.evaluate(z, p, jacobian=False).grazing)
        return tuple(values)

    def at_parameter(self, x: np.ndarray, orientation: np.ndarray) -> Correction:
        """Newton at the fixed parameter of x~ (a start, or the end at a bound)."""
        along_p = np.zeros_like(x)
        along_p[-1] = 1.0
        return self.correct(x, along_p, orientation)

    def at_arclength(self, start: Point, s: float, guess: np.ndarray | None = None,
                     ) -> Correction:
        """The point at arclength ``s`` along ``start``'s tangent (the secant plane).

        Newton starts from ``guess`` if given, else from the tangent's point on that plane.
        """
        return self.correct(start.x + s * start.tangent, start.tangent, start.tangent, guess)

    def grazing_gradient(self, x: np.ndarray) -> np.ndarray:
        """The gradient in x~ of the grazing value, by forward differences.

        Steps of ``GRADIENT_STEP``: x~ is of order 1, so the error is ~1e-7 relative, enough
        for the direction of a plane.
        """
        z, p = self.scaling.unscaled(x)
        value = self.problem.evaluate(z, p, jacobian=False).grazing
        gradient = np.empty_like(x)
        for j in range(len(x)):
            shifted = x.copy()
            shifted[j] += GRADIENT_STEP
            z, p = self.scaling.unscaled(shifted)
            gradient[j] = (self.problem.evaluate(z, p, jacobian=False).grazing - value) / (
                GRADIENT_STEP)
        return gradient

    def step(self, start: Point, ds: float) -> tuple[Point | None, float, tuple[float, ...]]:
        """The next point from ``start`` with a step ``ds`` (halved as needed).

        Returns the point (None below ``min_step``), the step taken, and the grazing values
        that tell whether a grazing lies ahead when the last attempt failed (its point's, if
        it turned too far, else its iterates'; empty when a point was found).
        """
        while True:
            correction = self.at_arclength(start, ds)
            point = correction.point
            if point is not None and (self.turns_within(start, point)
                                      or ds <= self.settings.min_step
                                      or (ds <= KINK_STEP and not same_piece(start, point))):
                # across a change of the contact sequence the tangent jumps however small the
                # step (the branch has a kink): the caller locates the event in between. Past
                # a kink of more than 90 degrees the tangent oriented like the previous one
                # would point back: forward is away from the start
                return oriented(point, point.x - start.x), ds, ()
            # a point that turned too far tells by its own grazing value whether a grazing
            # lies ahead; a failed correction by its iterates' (run again for it)
            grazing = ((point.evaluation.grazing,) if point is not None
                       else self.grazing_values(correction))
            if crosses(start.evaluation.grazing, grazing):
                return None, ds, grazing
            aim = self.settings.turn_aim
            ds *= (_shrink(_turn(start, point), aim * self.settings.max_angle)
                   if aim is not None and point is not None and same_piece(start, point)
                   else 0.5)
            if ds < self.settings.min_step:
                return None, ds, grazing

    def turns_within(self, start: Point, point: Point) -> bool:
        """Whether a step from ``start`` to ``point`` turned by at most ``max_angle``."""
        return _turn(start, point) <= self.settings.max_angle

    def next_step(self, taken: float, start: Point, point: Point) -> float:
        """The step after one of length ``taken`` from ``start`` that reached ``point``.

        It grows after a quick convergence and shrinks after a slow one, unless Newton's
        iterates met another contact sequence: then a nonsmooth event is just ahead, where
        Newton converges slowly however small the step (the map's Jacobian jumps there), and
        the step grows to cross it (the event is then located between). With a ``turn_aim``,
        on one smooth piece, it grows no further than the turn it took predicts a turn of
        ``turn_aim`` times ``max_angle`` for (the turn grows with the step: a longer one would
        be refused, and its correction lost), and shrinks at most by half.
        """
        iterations = point.iterations
        factor = 1.5 if iterations <= 3 or point.crossed else (
            1.0 if iterations <= 5 else 0.7)
        aim, turn = self.settings.turn_aim, _turn(start, point)
        if aim is not None and turn > 0.0 and same_piece(start, point):
            factor = min(factor, max(aim * self.settings.max_angle / turn, 0.5))
        return min(max(taken * factor, self.settings.min_step), self.settings.max_step)


def _shrink(turn: float, aim: float) -> float:
    """The factor on a refused step of one smooth piece that turned by ``turn`` (rad).

    The turn grows with the step (in proportion where the branch's curvature is smooth): the
    factor aims at a turn of ``aim`` (rad); it at least halves the step, as a refusal always
    did, and at most divides it by 10.
    """
    return min(max(aim / turn, 0.1), 0.5)


def tangent_of(jacobian: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    """The unit null vector of ``jacobian`` (n x n+1), its projection on ``orientation`` > 0."""
    system = np.vstack([jacobian, orientation])
    rhs = np.zeros(len(orientation))
    rhs[-1] = 1.0
    tangent = np.linalg.solve(system, rhs)
    return tangent / np.linalg.norm(tangent)


def _newton_step(system: np.ndarray, residual: np.ndarray, direction: np.ndarray,
                 offset: np.ndarray) -> np.ndarray | None:
    """The correction solving ``system`` delta = -(residual, direction . offset).

    ``residual``: the scaled r; ``offset``: x~ minus the predicted point. None where the
    system or the right-hand side is not finite, or the system is singular.
    """
    rhs = np.append(residual, direction @ offset)
    if not np.all(np.isfinite(system)) or not np.all(np.isfinite(rhs)):
        return None
    try:
        return np.linalg.solve(system, -rhs)
    except np.linalg.LinAlgError:
        return None


def _turn(start: Point, point: Point) -> float:
    """How far a step from ``start`` to ``point`` turned (rad): its tangent's and its secant's.

    The secant's too: a step that Newton carried across a tight fold onto the branch's way
    back has a tangent parallel to the start's (oriented like it), but a secant across the
    two strands.
    """
    secant = (point.x - start.x) / np.linalg.norm(point.x - start.x)
    return max(angle(point.tangent, start.tangent), angle(secant, start.tangent))


def angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (rad) between two unit vectors."""
    return math.acos(min(1.0, max(-1.0, float(a @ b))))


def oriented(point: Point, forward: np.ndarray) -> Point:
    """``point`` with its tangent turned, if need be, to have a positive part along ``forward``."""
    if point.tangent @ forward >= 0:
        return point
    return dataclasses.replace(point, tangent=-point.tangent)


def same_piece(a: Point, b: Point) -> bool:
    """Whether two points lie on one smooth piece: the same contacts and episodes per orbit.

    (The grazing value alone may change sign between two orbits of one contact sequence: it
    is whichever of a free-flight minimum and the shallowest contact is nearer 0.)
    """
    return (a.evaluation.contacts, a.evaluation.episodes) == (b.evaluation.contacts,
                                                              b.evaluation.episodes)


def crosses(before: float, values: tuple[float, ...]) -> bool:
    """Whether a grazing value changes sign from ``before`` to any of ``values``."""
    return math.isfinite(before) and any(
        math.isfinite(v) and (v > 0) != (before > 0) for v in values)

