"""Bifurcation curves in two parameters: `continue_curve` from a one-parameter branch's event.

A grazing, fold, period doubling or Neimark-Sacker point located on a branch of ``parameter`` (p1)
is followed in the plane (p1, ``second``) by the one-parameter engine on the augmented system of
`impactbeams.continuation.curves` (p2 the engine's parameter, p1 part of its state): the same
predictor, corrector and step control, and the same Illinois location of events (`events.locate`).
Lengths: p2 in units of its range, p1 in units of its box, the state as in `continue_orbits` (its
``state_scale``).

Codimension-two points met on the way, each located to ``locate_tolerance`` and labelled in
``curve_event``:

- ``turning_point``: p2 turns back along the curve (the tangent's p2 part changes sign; on a
  fold curve the cusp is such a point, where the tangent's p1 part vanishes as well:
  ``cusp`` when it is below ``CUSP_TANGENT`` there);
- ``grazing``: the curve's orbit touches: its grazing value passes through 0 along a fold,
  period-doubling or Neimark-Sacker curve (a sign change by a jump, where another contact or
  gap minimum becomes the nearest to 0, is not one: `_at_zero_depth`). The monodromy jumps
  there (the far side's has the new contact's saltation), so the curve ends there
  (``curve_ending`` "grazing"; the last point carries the label): where no point is found
  beyond it, where Newton's iterates at a point whose orbit touches meet another contact
  sequence, or where a step lands on an orbit of other contacts;
- ``contact_merge``, ``contact_split``: a multiplier's orbit loses or gains a contact with
  no contact at zero depth (bisected on its contacts): the curve ends there as well
  (``curve_ending`` "contact_change");
- on a Neimark-Sacker curve, ``resonance_1_1``, ``resonance_1_2``, ``resonance_1_3``,
  ``resonance_1_4``: the pair's cosine (`curves.pair_cosine`) passes 1, -1, -1/2, 0; at 1:1
  and 1:2 the pair turns real and the curve ends (``curve_ending`` "pair_real");
  ``fold_neimark_sacker``, ``flip_neimark_sacker``: a real multiplier but the pair passes
  +1 or -1 (the curve goes on);
- ``end``: the curve's last point otherwise: at the edge of the box (``curve_ending``
  "bound", corrected onto it) or where the corrector finds no point (the orbit stops
  existing, or turns within less than ``min_step``: "min_step").
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.blas import one_blas_thread
from impactbeams.continuation.arclength import (
    Follower,
    Point,
    Scaling,
    Settings,
    crosses,
    oriented,
    same_piece,
)
from impactbeams.continuation.branch import (
    INTERRUPTED,
    ZERO_DEPTH,
    Branch,
    ContinuationInterrupted,
    Course,
    Position,
    Steps,
    merge_or_split,
)
from impactbeams.continuation.checkpoint import CourseLog, checkpointed
from impactbeams.continuation.curves import (
    CONDITIONS,
    KINDS,
    PAIR_TURNS_REAL,
    RESONANCES,
    CurveProblem,
    other_multipliers,
    pair_cosine,
)
from impactbeams.continuation.events import Located, continuous_root, grazing_test, locate
from impactbeams.continuation.output import branches_dataset
from impactbeams.continuation.run import (
    DIRECTIONS,
    STATE_SCALE_CLEARANCES,
    Continuation,
    check_continued,
    least_clearance,
    mode_count,
)
from impactbeams.params import (
    MAX_MODES,
    ParameterError,
    Params,
    check_parameter,
    is_path,
    named_attributes,
    parameter_value,
    require,
    require_finite,
    require_integer,
    require_type,
)
from impactbeams.variables import (
    BIFURCATIONS,
    CURVE_EVENTS,
    attributes,
    global_attributes,
)

if TYPE_CHECKING:
    import xarray as xr

# how a curve ended (`curve_ending`): at the box's edge, at its orbit's grazing (a multiplier's
# curve), at another change of its orbit's contacts (a merge or split), where the corrector
# found no point (the orbit ends), too long
BOUND, GRAZED, CONTACT_CHANGE, MIN_STEP, MAX_POINTS = (
    "bound", "grazing", "contact_change", "min_step", "max_points")
# ... and a Neimark-Sacker curve at a strong resonance 1:1 or 1:2, where its pair turns real
PAIR_REAL = "pair_real"
# a p2 turning point is a cusp where the unit tangent's p1 part (scaled) is also this small:
# the curve's tangent then lies in the state space (the parameter plane's curve has a cusp)
CUSP_TANGENT = 1e-3


@dataclasses.dataclass(frozen=True)
class BifurcationCurve:
    """The curve in two parameters of a grazing, fold, period doubling or Neimark-Sacker.

    ``kind``: "grazing", "fold", "period_doubling" or "neimark_sacker". It starts at
    ``params`` with ``parameter`` (p1) = ``value`` and the orbit's section state
    ``state`` (the located event's, e.g. `from_branch`), and follows ``second`` (p2) from its
    value in ``params`` ``direction`` "up" or "down" within [``low``, ``high``], p1 within
    [``parameter_low``, ``parameter_high``] (the box; units of each parameter). ``period``:
    forcing periods of the orbit; ``n_modes`` per beam. Steps are fractions of the arclength
    unit (p2's range): ``step`` (default 0.02), ``min_step`` (1e-9), ``max_step`` (0.05);
    ``state_scale`` (m) as in `Continuation`.
    """

    params: Params
    kind: str
    parameter: str
    value: float
    state: np.ndarray
    second: str
    low: float
    high: float
    parameter_low: float
    parameter_high: float
    n_modes: int
    direction: str = "up"
    period: int = 1
    step: float = 0.02
    min_step: float = 1e-9
    max_step: float = 0.05
    max_points: int = 200
    state_scale: float | None = None

    def __post_init__(self) -> None:
        require_type("params", self.params, isinstance(self.params, Params),
                     "an impactbeams.Params")
        require("kind", self.kind, self.kind in KINDS,
                f"must be one of {', '.join(map(repr, KINDS))}")
        for name in ("parameter", "second"):
            check_continued(self.params, name, getattr(self, name))
        require("second", self.second, self.second != self.parameter,
                f"must differ from parameter = {self.parameter!r}")
        for name, parameter in (("low", self.second), ("high", self.second),
                                ("parameter_low", self.parameter),
                                ("parameter_high", self.parameter)):
            check_parameter(parameter, require_finite(name, getattr(self, name)))
        require("high", self.high, self.high > self.low,
                f"the range [{self.low!r}, {self.high!r}] is empty: need high > low")
        require("parameter_high", self.parameter_high,
                self.parameter_high > self.parameter_low,
                f"the box [{self.parameter_low!r}, {self.parameter_high!r}] is empty")
        start = parameter_value(self.params, self.second)
        require(self.second, start, self.low <= start <= self.high,
                f"(the start's, from params) must lie in [{self.low!r}, {self.high!r}]")
        require("value", self.value, self.parameter_low <= require_finite("value", self.value)
                <= self.parameter_high,
                f"must lie in [{self.parameter_low!r}, {self.parameter_high!r}]")
        require("direction", self.direction, self.direction in DIRECTIONS,
                f"must be one of {', '.join(map(repr, DIRECTIONS))}")
        require_integer("n_modes", self.n_modes, 1, MAX_MODES)
        require_integer("period", self.period, 1)
        require_integer("max_points", self.max_points, 2)
        Settings(step=self.step, min_step=self.min_step, max_step=self.max_step)  # checks
        state = np.asarray(self.state, dtype=float)
        size = 2 * self.params.partner.beams * self.n_modes
        require("state", state.shape, state.shape == (size,) and bool(np.all(np.isfinite(
            state))), f"must be {size} finite numbers (the orbit's section state)")

    @classmethod
    def from_branch(cls, continuation: Continuation, branch: xr.Dataset, kind: str,
                    second: str, low: float, high: float, which: int = 0,
                    box: tuple[float, float] | None = None,
                    **options: object) -> BifurcationCurve:
        """The curve through the ``which``-th ``kind`` event of ``branch``.

        ``branch``: `continue_orbits`(``continuation``)'s Dataset; the start is its located
        event's orbit, p1's box ``box`` (default the continuation's range).
        """
        if box is not None:
            continuation = dataclasses.replace(continuation, low=box[0], high=box[1])
        plan = CurvePlan(continuation, kind, second, low, high, which,
                         **options)  # type: ignore[arg-type]
        return plan.from_branch(branch)

    def settings(self) -> Settings:
        """The engine's settings (steps in units of the second parameter's range)."""
        return Settings(step=self.step, min_step=self.min_step, max_step=self.max_step,
                        max_points=self.max_points, max_branches=1)


@dataclasses.dataclass(frozen=True)
class CurvePlan:
    """A curve to follow from the ``which``-th ``kind`` event of ``continuation``'s branch.

    Checked when made, before the branch is computed (`impactbeams continue` with a
    ``[curve]`` table): all but whether the branch has that event. ``options``: the
    remaining `BifurcationCurve` fields (steps, direction, max_points).
    """

    continuation: Continuation
    kind: str
    second: str
    low: float
    high: float
    which: int = 0
    direction: str = "up"
    step: float = 0.02
    min_step: float = 1e-9
    max_step: float = 0.05
    max_points: int = 200

    def __post_init__(self) -> None:
        require_integer("which", self.which, 0)
        c = self.continuation
        self.start(c.first, np.zeros(2 * c.params.partner.beams * mode_count(c)),
                   c.period)  # every check of the curve, on a stand-in start

    def start(self, value: float, state: np.ndarray, period: int) -> BifurcationCurve:
        """The curve from the orbit ``state`` of ``period`` at ``parameter`` = ``value``."""
        c = self.continuation
        return BifurcationCurve(
            c.params, self.kind, c.parameter, value, state, self.second, self.low, self.high,
            c.low, c.high, mode_count(c), direction=self.direction, period=period,
            step=self.step, min_step=self.min_step, max_step=self.max_step,
            max_points=self.max_points, state_scale=c.state_scale)

    def from_branch(self, branch: xr.Dataset) -> BifurcationCurve:
        """The curve through the planned event of ``branch`` (ParameterError if it has none)."""
        codes = branch.bifurcation.values
        at = np.flatnonzero(codes == BIFURCATIONS.index(self.kind))
        if not at.size:  # not the user's ``which``: the kind itself is not on the branch
            found = np.unique(codes[codes > 0], return_counts=True)
            located = ", ".join(f"{count} {BIFURCATIONS[code]}" for code, count in zip(
                *found, strict=True)) or "no event"
            raise ParameterError(f"kind = {self.kind!r} is not allowed: the branch located no "
                                 f"{self.kind} (it located {located})")
        require("which", self.which, self.which < at.size,
                f"the branch located {at.size} {self.kind} event(s): must be below {at.size}")
        i = int(at[self.which])
        return self.start(float(branch[self.continuation.parameter][i]),
                          np.asarray(branch.section_state[i].values),
                          int(branch.orbit_period[i]))


Progress = Callable[[Branch, Point], None]


@one_blas_thread
def continue_curve(curve: BifurcationCurve, progress: Progress | None = None,
                   output: str | Path | None = None) -> xr.Dataset:
    """Follow ``curve`` and return its Dataset (written to netCDF ``output`` if given).

    With ``output`` the curve checkpoints every step under ``OUTPUT.partial/``, as
    `continue_orbits` does (`impactbeams.continuation.checkpoint`): killed or interrupted,
    the same call resumes from its last step and writes the same file, bit for bit; the
    partial run of another curve or other code is refused. On Ctrl-C raises
    `ContinuationInterrupted` whose ``dataset`` holds the points computed (with ``output``,
    also written to ``OUTPUT.partial/OUTPUT``). ParameterError if the start does not
    converge on the augmented system (the state is not at such a bifurcation).
    ``progress(branch, point)`` is called with each point kept.
    """
    require_type("curve", curve, isinstance(curve, BifurcationCurve),
                 "an impactbeams.continuation.BifurcationCurve")
    require_type("output", output, output is None or is_path(output),
                 "None or the path of a netCDF file (str or pathlib.Path)")
    problem = CurveProblem(curve.params, curve.parameter, curve.second, curve.n_modes,
                           curve.period, CONDITIONS[curve.kind](),
                           (curve.parameter_low, curve.parameter_high))
    problem.start(np.asarray(curve.state, dtype=float), curve.value)
    if output is None:
        return _interrupted_with_dataset(curve, problem, lambda: follow(problem, curve,
                                                                        progress))
    return checkpointed(Path(output), curve, lambda log: _interrupted_with_dataset(
        curve, problem, lambda: follow(problem, curve, progress, log)))


def _interrupted_with_dataset(curve: BifurcationCurve, problem: CurveProblem,
                              followed: Callable[[], Branch]) -> xr.Dataset:
    """The Dataset of ``followed()``; a `ContinuationInterrupted` from it gets the points'."""
    try:
        return curve_dataset(followed(), curve, problem.followed_contact)
    except ContinuationInterrupted as interrupted:
        interrupted.dataset = curve_dataset(interrupted.branches[0], curve,
                                            problem.followed_contact)
        raise


def follow(problem: CurveProblem, curve: BifurcationCurve, progress: Progress | None = None,
           log: CourseLog | None = None) -> Branch:
    """The curve's points from its start to its end, events located and labelled.

    ``log``: the checkpoints, saved at the top of every step and resumed from if it holds
    some. `ContinuationInterrupted` (with the points so far) on Ctrl-C past the start.
    """
    settings = curve.settings()
    resume = None if log is None else log.restore(problem, settings)
    if resume is None:
        follower, followed = _started(problem, curve, settings, progress)
        at = Position(followed.points[-1], settings.step, Steps())
    else:  # the condition as it was at that step: bordered at the last point kept
        follower, followed, at = resume.follower, resume.branches[0], resume.position
        last = followed.points[-1]
        problem.border(*follower.scaling.unscaled(last.x), last.evaluation)
    save = None if log is None else (lambda position: log(Course(
        [followed], follower, 0, position, [])))
    try:
        _steps(follower, followed, _box(curve, follower.scaling), progress, at, save)
    except KeyboardInterrupt:
        followed.ending = INTERRUPTED
        raise ContinuationInterrupted([followed]) from None
    end = followed.points[-1]
    followed.points[-1] = dataclasses.replace(end, label=end.label or "end")
    return followed


def _started(problem: CurveProblem, curve: BifurcationCurve, settings: Settings,
             progress: Progress | None) -> tuple[Follower, Branch]:
    """The engine on ``problem`` and the curve of its first point, corrected at the start."""
    p2 = parameter_value(curve.params, curve.second)
    scaling = _scaling(problem, curve, p2)
    follower = Follower(problem, scaling, settings)
    orientation = np.zeros(scaling.state.size + 1)
    orientation[-1] = 1.0 if curve.direction == "up" else -1.0
    y0 = np.append(np.asarray(curve.state, dtype=float), curve.value)
    first = follower.at_parameter(scaling.scaled(y0, p2), orientation).point
    if first is None:
        raise ParameterError(f"the start at {curve.parameter} = {curve.value!r}, "
                             f"{curve.second} = {p2!r} did not converge to a {curve.kind}: "
                             "give the state and value of a located one (from_branch)")
    followed = Branch([], curve.period, scaling)
    _keep(follower, followed, [first], progress)
    return follower, followed


def _scaling(problem: CurveProblem, curve: BifurcationCurve, p2: float) -> Scaling:
    """x~: p2 per its range, p1 per its box, the state as `continue_orbits`' (state_scale)."""
    orbits = problem.orbits(p2)
    z = np.asarray(curve.state, dtype=float)
    weights = orbits.state_weights()
    tip = orbits.period_map(curve.value)(z, measures=True).max_tip1
    size = float(np.linalg.norm(weights * z))
    scale = curve.state_scale or STATE_SCALE_CLEARANCES * least_clearance(curve.params)
    per_metre = size / tip if tip > 0 and size > 0 else 1.0
    return Scaling(np.append(weights / (per_metre * scale),
                             1.0 / (curve.parameter_high - curve.parameter_low)),
                   1.0 / (curve.high - curve.low))


def _box(curve: BifurcationCurve, scaling: Scaling) -> np.ndarray:
    """The box in x~: rows (low, high) of p1 (index -2) and p2 (index -1)."""
    return np.array([[curve.parameter_low, curve.parameter_high],
                     [curve.low, curve.high]]) * np.array(
        [[scaling.state[-1]], [scaling.parameter]])


def _steps(follower: Follower, curve: Branch, box: np.ndarray, progress: Progress | None,
           at: Position, save: Callable[[Position], None] | None = None) -> None:
    """Step ``curve`` from ``at`` to its end (``curve.ending``).

    ``save`` is called with the `Position` at the top of every step (the step's start and
    length: all the loop carries from step to step).
    """
    settings = follower.settings
    current, ds = at.current, at.ds
    while len(curve.points) < settings.max_points:
        if save is not None:
            save(Position(current, ds, Steps([current])))
        if _ended_past_edge(follower, curve, current, ds, box, progress):
            return
        point, taken, grazing = follower.step(current, ds)
        if point is None:
            if crosses(current.evaluation.grazing, grazing):
                if taken / 2.0 >= settings.min_step:
                    ds = taken / 2.0  # an iterate crossed: nearer first
                    continue
                _end_at_grazing(follower, curve, current, taken, progress)
                return
            # no point beyond: the orbit ends here, at a grazing if it touches (the fold of
            # an impacting orbit that meets its grazing has no smooth continuation): the
            # steps then creep up to it, its gap falling to ~0 against the curve's
            grazes = _at_zero_depth(current, *curve.points)
            curve.ending = GRAZED if grazes else MIN_STEP
            if grazes:
                curve.points[-1] = dataclasses.replace(current, label="grazing")
            return
        outside = _outside(point, box)
        if outside is not None:
            end = _at_edge(follower, current, point, box, outside)
            if end is None and taken / 2.0 >= settings.min_step:
                ds = taken / 2.0
                continue
            points = _events(follower, current, end) if end is not None else []
            _keep(follower, curve, points, progress)
            curve.ending = BOUND
            return
        points = _events(follower, current, point)
        if not (follower.problem.condition.smooth_across_contacts
                or same_piece(current, point)):
            _end_at_contact_change(follower, curve, current, point, points, progress)
            return
        turns_real = [i for i, p in enumerate(points) if p.label in PAIR_TURNS_REAL]
        if turns_real:  # the Neimark-Sacker curve ends where its pair meets on the real axis
            _keep(follower, curve, points[:turns_real[0] + 1], progress)
            curve.ending = PAIR_REAL
            return
        _keep(follower, curve, points, progress)
        if point.crossed and _at_zero_depth(point, *curve.points):
            # Newton's iterates met another contact sequence at a point whose orbit touches:
            # the monodromy jumps there (the far side's has the new contact's saltation), so
            # the curve of this side's bifurcation ends at the grazing
            curve.points[-1] = dataclasses.replace(curve.points[-1], label="grazing")
            curve.ending = GRAZED
            return
        current, ds = point, follower.next_step(taken, current, point)
    curve.ending = MAX_POINTS


def _keep(follower: Follower, curve: Branch, points: list[Point],
          progress: Progress | None) -> None:
    """Append ``points`` with their measures and own multipliers; the condition adapts."""
    for point in points:
        z, p = follower.scaling.unscaled(point.x)
        point = follower.kept(dataclasses.replace(point, evaluation=dataclasses.replace(
            point.evaluation, multipliers=follower.problem.multipliers(z, p))))
        curve.points.append(point)
        if progress is not None:
            progress(curve, point)
    if points:
        z, p = follower.scaling.unscaled(points[-1].x)
        follower.problem.border(z, p, points[-1].evaluation)


def _outside(point: Point, box: np.ndarray) -> tuple[int, float] | None:
    """(index in x~, bound) of the box's edge ``point`` is past, None inside."""
    for index, (low, high) in zip((-2, -1), box, strict=True):
        if not low <= point.x[index] <= high:
            return index, low if point.x[index] < low else high
    return None


def _ended_past_edge(follower: Follower, curve: Branch, current: Point, ds: float,
                     box: np.ndarray, progress: Progress | None) -> bool:
    """End the curve on the box's edge where the step ``ds`` from ``current`` aims past it.

    Only where the aim's parameters are refused: past an edge at a parameter's smallest
    allowed value (a mass, a drive of 0) every iterate's are, so no step lands outside the
    box, as past another edge, and the steps would creep up to it, halved until they fail.
    The edge's point is corrected onto it from the aim instead, accepted as a step's point
    would be (within ``max_angle`` of the tangent: not another part of the curve) and
    unless a multiplier's curve would reach it across a change of its orbit's contacts
    (it is stepped up to that, as before).
    """
    aim = dataclasses.replace(current, x=current.x + ds * current.tangent)
    outside = _outside(aim, box)
    if outside is None or _allowed(follower, aim):
        return False
    end = _at_edge(follower, current, aim, box, outside)
    if end is None or not follower.turns_within(current, end) or not (
            follower.problem.condition.smooth_across_contacts or same_piece(current, end)):
        return False  # (a multiplier's curve ends at a change of its contacts before it)
    _keep(follower, curve, _events(follower, current, end), progress)
    curve.ending = BOUND
    return True


def _allowed(follower: Follower, point: Point) -> bool:
    """Whether both parameters of ``point`` are allowed values (`check_parameter`)."""
    y, p2 = follower.scaling.unscaled(point.x)
    problem = follower.problem
    try:
        check_parameter(problem.first, float(y[-1]))
        check_parameter(problem.second, p2)
    except ParameterError:
        return False
    return True


def _at_edge(follower: Follower, a: Point, b: Point, box: np.ndarray,
             edge: tuple[int, float]) -> Point | None:
    """The curve's point on the box's edge between ``a`` (inside) and ``b`` (past it)."""
    index, bound = edge
    weight = (bound - a.x[index]) / (b.x[index] - a.x[index])
    guess = a.x + weight * (b.x - a.x)
    guess[index] = bound
    along = np.zeros_like(guess)
    along[index] = 1.0
    end = follower.correct(guess, along, a.tangent).point
    if end is None or _outside(end, box) is not None and not np.isclose(end.x[index], bound):
        return None
    return oriented(end, end.x - a.x)


def _events(follower: Follower, a: Point, b: Point) -> list[Point]:
    """The codimension-two points between ``a`` and ``b``, located and labelled, then ``b``."""
    found = []
    if (a.tangent[-1] > 0) != (b.tangent[-1] > 0):
        found.append(_turning(follower, a, b))
    if crosses(a.evaluation.grazing, (b.evaluation.grazing,)):
        located = _located(follower, a, b, grazing_test, may_jump=True)
        if located.root and _at_zero_depth(located.before, a, b):
            found.append(dataclasses.replace(located.before, label="grazing"))
    if follower.problem.condition.label == "neimark_sacker":
        found += _pair_events(follower, a, b)
    found.sort(key=lambda point: float(a.tangent @ (point.x - a.x)))
    return [*found, b]


def _pair_events(follower: Follower, a: Point, b: Point) -> list[Point]:
    """A Neimark-Sacker curve's strong resonances and fold- or flip-Neimark-Sacker points.

    A resonance where the pair's cosine (`pair_cosine`) passes its value (`RESONANCES`); a
    fold (flip) where a real multiplier but the pair passes +1 (-1): the parity of those
    beyond it changes (a complex pair meeting on the real axis changes their number by 2),
    located at the root of that multiplier minus +1 (-1).
    """
    tests = []
    cosines = [pair_cosine(point.evaluation.multipliers) for point in (a, b)]
    for label, cosine in RESONANCES.items():
        if (cosines[0] > cosine) != (cosines[1] > cosine):
            tests.append((label, lambda point, c=cosine: pair_cosine(
                point.evaluation.multipliers) - c))
    for sigma, label in ((1.0, "fold_neimark_sacker"), (-1.0, "flip_neimark_sacker")):
        outside = [int(np.count_nonzero(_real_beyond(point, sigma) > 1.0)) for point in (a, b)]
        if (outside[0] - outside[1]) % 2:
            rank = min(outside)
            tests.append((label, lambda point, s=sigma, r=rank: _crossing(point, s, r)))
    found = []
    for label, test in tests:
        # (a test that jumps, where the pair or multiplier it follows changed, is none)
        located = _located(follower, a, b, test)
        if continuous_root(test, a, b, located, follower.settings.locate_tolerance):
            found.append(dataclasses.replace(located.before, label=label))
    return found


def _real_beyond(point: Point, sigma: float) -> np.ndarray:
    """|mu| of the real multipliers of ``sigma``'s sign but the pair, largest first.

    (Those beyond ``sigma`` are outside the unit circle.)
    """
    mu = other_multipliers(np.asarray(point.evaluation.multipliers))
    mu = mu[(mu.imag == 0.0) & (np.sign(mu.real) == sigma)]
    return np.sort(np.abs(mu))[::-1]


def _crossing(point: Point, sigma: float, rank: int) -> float:
    """|mu| - 1 of the ``rank``-th largest real multiplier of ``sigma``'s sign but the pair."""
    moduli = _real_beyond(point, sigma)
    return float(moduli[rank]) - 1.0 if rank < moduli.size else -1.0


def _turning(follower: Follower, a: Point, b: Point) -> Point:
    """The p2 turning point between ``a`` and ``b``: a cusp if the p1 part vanishes too."""
    located = _located(follower, a, b, lambda point: float(point.tangent[-1]))
    point = located.before
    cusp = abs(point.tangent[-2]) < CUSP_TANGENT and follower.problem.condition.label == "fold"
    return dataclasses.replace(point, label="cusp" if cusp else "turning_point")


def _located(follower: Follower, a: Point, b: Point, test: Callable[[Point], float],
             may_jump: bool = False) -> Located:
    """The root of ``test`` between ``a`` and ``b`` on ``a``'s secant planes."""
    # Newton from the tangent's point on each plane: a curve's corrector is not given the
    # bracket's guess (`events.guess_at`), with which curves ended otherwise (test_curve_resonances)
    return locate(lambda s, _: follower.at_arclength(a, s).point, a, float(
        a.tangent @ (b.x - a.x)), b, test, follower.settings.locate_tolerance,
        may_jump=may_jump)


def _at_zero_depth(point: Point, *ends: Point) -> bool:
    """Whether ``point``'s grazing value is ~0 against those at ``ends``: the orbit touches.

    The grazing value (the smallest free-flight gap, or minus the shallowest overlap) also
    changes sign by a jump, where another contact or minimum becomes the nearest to 0: no
    grazing (`ZERO_DEPTH`, as the one-parameter branches tell the two apart).
    """
    scale = max(abs(end.evaluation.grazing) for end in ends)
    return abs(point.evaluation.grazing) <= ZERO_DEPTH * scale


def _end_at_contact_change(follower: Follower, curve: Branch, current: Point, point: Point,
                           located: list[Point], progress: Progress | None) -> None:
    """End a multiplier's curve where its orbit's contacts change from ``current`` to ``point``.

    ``located``: the events `_events` found between them, then ``point``. There the
    monodromy jumps (the far side's has the new contact's saltation: its dashpot's force
    starts with it), so the bifurcation of one side does not continue into the other's: a
    curve stepped across would go on as the far side's own bifurcation (or as points that
    solve neither side's condition to the tolerance). The end is the located grazing, or
    else the last point of ``current``'s contacts, bisected on them (a merge or split, or a
    contact that comes in where the grazing value jumps).
    """
    grazings = [p for p in located if p.label == "grazing"]
    if grazings:
        end = grazings[0]
    else:
        before = _located(follower, current, point,
                          lambda q: 1.0 if same_piece(current, q) else -1.0).before
        label = "grazing" if _at_zero_depth(before, current, point) else merge_or_split(
            current, point)
        end = dataclasses.replace(before, label=label)
    along = float(current.tangent @ (end.x - current.x))
    if along <= 0.0:  # no point of current's contacts past it: current is the end
        curve.points[-1] = dataclasses.replace(current, label=end.label)
    else:
        _keep(follower, curve, [p for p in located if p.label and p.label != "grazing"
                                and float(current.tangent @ (p.x - current.x)) < along]
              + [end], progress)
    curve.ending = GRAZED if end.label == "grazing" else CONTACT_CHANGE


def _end_at_grazing(follower: Follower, curve: Branch, current: Point, taken: float,
                    progress: Progress | None) -> None:
    """End the curve at the grazing ahead of ``current``, located (no point found past it)."""
    located = locate(lambda s, _: follower.at_arclength(current, s).point, current, taken, None,
                     grazing_test, follower.settings.locate_tolerance, may_jump=True)
    end = located.before if located.root else current
    # (against the whole curve's values: the steps may have crept up to the grazing, the
    # last point's gap already at zero depth, none nearer found)
    if not _at_zero_depth(end, *curve.points):
        curve.ending = MIN_STEP
        return
    if end is current:
        curve.points[-1] = dataclasses.replace(current, label="grazing")
    else:
        _keep(follower, curve, [dataclasses.replace(end, label="grazing")], progress)
    curve.ending = GRAZED


def curve_dataset(curve: Branch, spec: BifurcationCurve, contact: int | None = None,
                  ) -> xr.Dataset:
    """The curve's points along ``branch_point``: both parameters as coordinates.

    The variables of a one-parameter branch (the orbit's measures, multipliers, contacts,
    grazing gap, section state) and ``curve_condition`` (the bifurcation's test function at
    the point: ~0, to the corrector's tolerance), ``curve_tangent_1`` and ``curve_tangent_2``
    (the unit tangent's parameter parts, scaled: their zeros are the turning points),
    ``curve_event`` (the codimension-two points), ``curve_stable`` (in place of ``stable``,
    which the critical multiplier at round-off from the circle would decide). Attributes: the
    kind, the parameters (``curve_parameters``), the ending (``curve_ending``); with several
    contacts, ``curve_contact``: ``contact``, the one whose grazing a grazing curve follows.
    """
    unlabelled = [dataclasses.replace(point, label="") for point in curve.points]
    attrs = global_attributes(
        f"{spec.kind} curve of periodic orbits in ({spec.parameter}, {spec.second})",
        f"continue a {spec.kind} in {spec.second} from {spec.low!r} to {spec.high!r}",
        {name: value for name, value in spec.params.as_dict().items()
         if name not in (spec.parameter, spec.second)},
        n_modes=spec.n_modes, start_period=spec.period,
        curve_kind=spec.kind, curve_parameters=f"{spec.parameter} {spec.second}",
        curve_ending=curve.ending,
        locate_tolerance=spec.settings().locate_tolerance * (spec.high - spec.low),
        newton_tolerance=spec.settings().tolerance,
        **({} if contact is None else {"curve_contact": contact}))
    dataset = branches_dataset([Branch(unlabelled, spec.period, curve.scaling)], spec.second,
                               attrs)
    dataset = dataset.drop_vars(["bifurcation", "branch", "stable"])
    dataset["curve_stable"] = ("branch_point", np.array(
        [_stable_but_critical(point, spec.kind) for point in curve.points], dtype=np.int8))
    states = dataset.section_state.values
    dataset = dataset.isel(state=slice(0, states.shape[1] - 1))
    dataset = dataset.assign_coords({spec.parameter: ("branch_point", states[:, -1])})
    dataset[spec.parameter].attrs.update(named_attributes(spec.parameter))
    dataset["curve_condition"] = ("branch_point", np.array(
        [point.evaluation.residual[-1] for point in curve.points]))
    for name, index in (("curve_tangent_1", -2), ("curve_tangent_2", -1)):
        dataset[name] = ("branch_point", np.array([point.tangent[index]
                                                   for point in curve.points]))
    dataset["curve_event"] = ("branch_point", np.array(
        [CURVE_EVENTS.index(point.label or "none") for point in curve.points], dtype=np.int8))
    names = ["curve_condition", "curve_tangent_1", "curve_tangent_2", "curve_event",
             "curve_stable"]
    if spec.kind == "neimark_sacker":
        dataset["curve_pair_cosine"] = ("branch_point", np.array(
            [pair_cosine(np.asarray(point.evaluation.multipliers)) for point in curve.points]))
        names.append("curve_pair_cosine")
    for name in names:
        dataset[name].attrs.update(attributes(name))
    dataset.attrs.pop("branch_endings")
    dataset.attrs.pop("branch_origins")
    return dataset



def _stable_but_critical(point: Point, kind: str) -> bool:
    """Whether every multiplier but the critical ones (+1, -1, the pair on the circle) is in."""
    mu = np.asarray(point.evaluation.multipliers)
    distance = {"fold": np.abs(mu - 1.0), "period_doubling": np.abs(mu + 1.0),
                "neimark_sacker": np.abs(np.abs(mu) - 1.0) + np.where(mu.imag == 0, np.inf, 0.0)}
    if kind in distance:
        mu = np.delete(mu, np.argsort(distance[kind])[:2 if kind == "neimark_sacker" else 1])
    return bool(np.all(np.abs(mu) < 1.0))
