"""Bifurcations along a branch: detected between consecutive points, located by Illinois.

Each kind has an integer signature, whose change between two points detects it, and a test
function, continuous near the crossing, whose root locates it:

=================  ============================================  ===============================
label              detected by a change of                       located at the root of
=================  ============================================  ===============================
fold               the sign of the tangent's parameter part, and  that part (a multiplier at +1)
                   the parity of the real multipliers > 1
period_doubling    the parity of the real multipliers < -1       |mu| - 1 of that real mu < 0
neimark_sacker     the complex pairs outside the unit circle     |mu| - 1 of that pair
grazing            the sign of the orbit's smallest free gap     that gap
branch_point       the parity of the real multipliers > 1, the   mu - 1 of that real mu > 0
                   tangent's parameter part keeping its sign
=================  ============================================  ===============================

A real multiplier through +1 is a fold where the branch turns back in the parameter, else a
branch point, where another branch crosses (e.g. the symmetry-breaking pitchfork of a
symmetric orbit, docs/continuation.md).

The root is sought on the secant plane of the first point (`Follower.at_arclength`), by the
Illinois variant of regula falsi, until the parameter is known to ``locate_tolerance``: the
arclength bracket times the largest parameter rate |t_p| at its ends. It is a bifurcation only
if the test is continuous across it (`continuous_root`): a test whose multiplier changes kind
in the step (a pair turned real) jumps there instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from impactbeams.continuation.arclength import Point
from impactbeams.variables import BIFURCATIONS

FOLD, PERIOD_DOUBLING, NEIMARK_SACKER, GRAZING, BRANCH_POINT = (
    "fold", "period_doubling", "neimark_sacker", "grazing", "branch_point")
# nonsmooth events that are not grazings: a free interval between two contacts closes (merge)
# or opens (split), in the direction the branch is followed; ``chatter``: the contact sequence
# changed within an episode between the previous point and this one, not located
# (``micro_contacts = "summarise"``)
CONTACT_MERGE, CONTACT_SPLIT, CHATTER = "contact_merge", "contact_split", "chatter"
NONSMOOTH = (GRAZING, CONTACT_MERGE, CONTACT_SPLIT, CHATTER)
LABELS = BIFURCATIONS  # the registry's flags: "none", then the labels above, codes 0, 1, ...
MAX_LOCATING = 60  # corrector solves per located event (bisection from 1 to 1e-18 of a step)


def _real_negative(point: Point) -> np.ndarray:
    mu = point.evaluation.multipliers
    return np.sort(np.abs(mu[(mu.imag == 0) & (mu.real < 0)]))[::-1]


def _real_positive(point: Point) -> np.ndarray:
    mu = point.evaluation.multipliers
    return np.sort(np.abs(mu[(mu.imag == 0) & (mu.real > 0)]))[::-1]


def _complex_pairs(point: Point) -> np.ndarray:
    mu = point.evaluation.multipliers
    return np.sort(np.abs(mu[mu.imag > 0]))[::-1]


def _outside(moduli: np.ndarray) -> int:
    return int(np.count_nonzero(moduli > 1.0))


def _real_crossing(moduli: Callable[[Point], np.ndarray], a: Point, b: Point) -> int:
    """+1 (-1) if a real multiplier of ``moduli``'s kind left (entered) the circle, else 0.

    A crossing changes the parity of the real ones outside; a complex pair that meets on the
    real axis, or leaves it, changes their number by 2.
    """
    change = _outside(moduli(b)) - _outside(moduli(a))
    return int(np.sign(change)) if change % 2 else 0


def _all_outside(point: Point) -> int:
    return _outside(np.abs(point.evaluation.multipliers))


def _crossing_modulus(moduli: Callable[[Point], np.ndarray], a: Point, b: Point,
                      missing: float = math.nan) -> Callable[[Point], float]:
    """|mu| - 1 of the multiplier that crosses: the (k+1)-th largest, k outside on both ends.

    ``missing``: the value where there is no such multiplier (NaN: not located).
    """
    rank = min(_outside(moduli(a)), _outside(moduli(b)))

    def test(point: Point) -> float:
        values = moduli(point)
        return float(values[rank]) - 1.0 if rank < len(values) else missing

    return test


def detected(a: Point, b: Point) -> list[tuple[str, Callable[[Point], float]]]:
    """The smooth bifurcations between two points of a branch, with their test functions."""
    found: list[tuple[str, Callable[[Point], float]]] = []
    turned = (a.tangent[-1] > 0) != (b.tangent[-1] > 0)
    plus, minus = _real_crossing(_real_positive, a, b), _real_crossing(_real_negative, a, b)
    if turned and plus:
        # (a tangent that turns without a real multiplier through +1 is not a fold: its
        # orientation flipped, as it can at a point just past a grazing, where the far side's
        # Jacobian is singular)
        found.append((FOLD, lambda point: float(point.tangent[-1])))
    if plus and not turned:
        # a real multiplier through +1 without the branch turning
        found.append((BRANCH_POINT, _crossing_modulus(_real_positive, a, b)))
    if minus:
        # a real multiplier < 0 may be born in the step from a complex pair meeting on the
        # negative axis inside the circle: before that, none is outside (-1 = |mu| of 0)
        found.append((PERIOD_DOUBLING, _crossing_modulus(_real_negative, a, b, missing=-1.0)))
    pairs = _pair_crossings(a, b)
    found += [(NEIMARK_SACKER, test) for test in pairs]
    if not pairs and _all_outside(b) - _all_outside(a) != plus + minus:
        # more multipliers left (or entered) the circle than the real crossings account for: a
        # complex pair crossed it, one born or gone on the real axis within the step. Counting
        # complex pairs outside would also count two real multipliers outside that meet on the
        # real axis and leave it as a pair: no crossing.
        found.append((NEIMARK_SACKER, _crossing_modulus(_complex_pairs, a, b)))
    return found


def _pair_crossings(a: Point, b: Point) -> list[Callable[[Point], float]]:
    """|mu| - 1 of each complex pair that crosses the circle from ``a`` to ``b``.

    The pairs (mu with Im mu > 0) of both ends are matched by nearness, so that one pair
    leaving and another entering in the same step are two crossings, not none. The test
    function of a crossing follows its pair by the argument of the matched ends.
    """
    from scipy.optimize import linear_sum_assignment

    mu_a, mu_b = (point.evaluation.multipliers for point in (a, b))
    mu_a, mu_b = mu_a[mu_a.imag > 0], mu_b[mu_b.imag > 0]
    if mu_a.size == 0 or mu_b.size == 0:
        return []
    rows, columns = linear_sum_assignment(np.abs(mu_a[:, None] - mu_b[None, :]))
    tests = []
    for i, j in zip(rows, columns, strict=True):
        if (abs(mu_a[i]) > 1.0) != (abs(mu_b[j]) > 1.0):
            tests.append(_pair_modulus(0.5 * (np.angle(mu_a[i]) + np.angle(mu_b[j]))))
    return tests


def _pair_modulus(argument: float) -> Callable[[Point], float]:
    """|mu| - 1 of a point's complex multiplier whose argument is nearest ``argument``."""

    def test(point: Point) -> float:
        mu = point.evaluation.multipliers
        mu = mu[mu.imag > 0]
        if mu.size == 0:
            return math.nan
        return float(abs(mu[np.argmin(np.abs(np.angle(mu) - argument))])) - 1.0

    return test


def grazing_test(point: Point) -> float:
    """The orbit's smallest free-flight gap (its sign changes at a grazing)."""
    return point.evaluation.grazing


def interval_test(point: Point) -> float:
    """The gap's maximum between contacts nearest 0 (its sign changes at a merge or split)."""
    return point.evaluation.interval


# ``point_at(s, guess)``: the corrected point on the plane at arclength s (None if Newton
# fails), Newton started from ``guess`` (a point near the branch there) if not None
PointAt = Callable[[float, "np.ndarray | None"], "Point | None"]
# an unbracketed end (no corrected point beyond) is a root if the test's value there is within
# this many times the secant's slope from the start times the bracket's width (a root in it)
ROOT_MARGIN = 1e3
# a far end whose test value is this many times the near end's says nothing of the root: the
# test jumps between them (`_next_arclength`)
JUMP_RATIO = 1e3
# how far beside a one-sided secant's root a solve lands, against the root's distance from
# the near end (`_beside_secant`): more than the secant's error there
BESIDE = 1e-2


class Located(NamedTuple):
    """A root bracketed by `locate`.

    ``s`` and ``before``: the last point on the start's side; ``beyond``: the first corrected
    point past it (None if none was found); ``root``: whether the root lies within the bracket.
    """

    s: float
    before: Point
    beyond: Point | None
    root: bool


def locate(point_at: PointAt, start: Point, s_end: float, end: Point | None,
           test: Callable[[Point], float], tolerance: float,
           value_tolerance: float = math.inf, may_jump: bool = False,
           one_sided: bool = False) -> Located:
    """The points on both sides of the root of ``test`` between ``start`` and ``end``.

    ``start`` is at s = 0, ``end`` at s = ``s_end`` (None if the corrector failed there: it
    then counts as beyond). ``point_at(s, guess)``: the corrected point at s (None if Newton
    fails), from the branch interpolated through the points corrected so far (`guess_at`).
    The bracket pins the parameter to ``tolerance`` in x~. A failed corrector inside the
    bracket counts as beyond the root, as at ``end``: it happens past a grazing, where the
    period map is not smooth, but also where the branch turns back across the planes (a fold
    between: the planes along ``start``'s tangent reach no farther than where the branch's
    tangent is orthogonal to it). Without a corrected point beyond, the bracket holds a root
    only if the test's value at its near end is as small as the secant from ``start``
    predicts over the bracket's width (``ROOT_MARGIN``): at a fold's reach it is not.
    ``value_tolerance``: the bracket also needs the test's value at its near end this small
    (a grazing's gap: where the branch crosses the grazing surface slantwise, the parameter
    pinned leaves the gap less well known). ``may_jump``: the test may jump (a grazing value,
    where a free-flight minimum of the gap vanishes): a bracket whose ends' values stay far
    from 0 as it narrows is then no root either, and the search ends there. ``one_sided``:
    the test may go to 0 on one side of the root only (the other side's value stays away,
    another contact's standing in there): each solve lands beside the secant root of the end
    nearer 0 (`_beside_secant`), and no end's value is halved (Illinois's rule, for a test
    continuous across its root).
    """
    low: Bracket = (0.0, test(start), start)
    high: Bracket = (s_end, test(end) if end is not None else math.nan, end)
    before: list[Bracket | None] = [None, None]  # each end's previous place (its secant)
    side = 0  # which end kept its place last (Illinois halves its value the second time)
    widths = (math.inf, math.inf)  # the bracket's widths before the last two solves
    corrected = [(0.0, start)] + ([(s_end, end)] if end is not None else [])
    for _ in range(MAX_LOCATING):
        if _known(low, high, tolerance) and abs(test(low[2])) <= value_tolerance:
            break
        if low[0] > 0.0 and (may_jump or high[2] is None) and not _pinned(low, high, start,
                                                                          test):
            # the test is too far from 0 at both ends for a root within the bracket: it jumps
            # there (e.g. a free-flight minimum of the gap vanishes), or the corrector fails
            # beyond it (a fold's reach); narrowing the bracket cannot change that
            break
        s = _next_arclength(low, high, *before, one_sided)
        width = high[0] - low[0]
        if width > 0.5 * widths[0]:
            # two solves did not halve the bracket (a secant creeps from one end): the middle,
            # as in Dekker's method
            s = low[0] + 0.5 * width
        widths = (widths[1], width)
        point = point_at(s, guess_at(low, high, s, tuple(corrected)))
        if point is not None:
            corrected.append((s, point))
        value = test(point) if point is not None else math.nan
        if point is not None and math.isfinite(value) and (value > 0) == (low[1] > 0):
            low, before[0] = (s, value, point), _true(low, test)
            if side == -1 and not one_sided:
                high = (high[0], high[1] / 2.0, high[2])
            side = -1
        else:
            high, before[1] = (s, value, point), _true(high, test)
            if side == 1 and not one_sided:
                low = (low[0], low[1] / 2.0, low[2])
            side = 1
    return Located(low[0], low[2], high[2],
                   _pinned(low, high, start, test) if may_jump or high[2] is None else True)


# the round-off of a test function, relative to the quantity it is the distance of from its
# root (|mu| for |mu| - 1; 1 for a unit tangent's parameter part): the eigenvalues of the
# monodromy are backward stable, their moduli carry a few hundred epsilon (5.2e-14 = 234 eps
# at a bracket narrowed to 4e-17 of x~ on the small model,
# tests/test_continuation_jumps.py); four times that
TEST_ROUND_OFF = 1024 * float(np.finfo(float).eps)


def near_zero(test: Callable[[Point], float], start: Point, end: Point,
              tolerance: float) -> float:
    """How near 0 a smooth bifurcation's ``test`` must be where it is located.

    ``ROOT_MARGIN`` times the test's mean slope over the step from ``start`` to ``end`` times
    ``tolerance`` (x~): the multiplier on the circle, or the tangent's parameter part at 0, as
    a bracket of that arclength puts it. (Where the branch is nearly vertical in the parameter,
    a bracket far wider already pins the parameter, and its near end's multiplier may be far
    from the circle: e.g. |mu| 0.456 for a period doubling on the stiff stop's period-2 branch
    going down at 160.40 rad/s, the step's other end at 1.26.) Not below the test's own
    round-off (``TEST_ROUND_OFF`` of 1 + its larger end's magnitude): where it changes slowly
    over the step (a multiplier that grazes the circle), a value asked for below its
    round-off is met by no bracket, and the root was not labelled.
    """
    scale = 1.0 + max(abs(test(start)), abs(test(end)))
    return max(ROOT_MARGIN * _mean_slope(test, start, end) * tolerance,
               TEST_ROUND_OFF * scale)


def _mean_slope(test: Callable[[Point], float], start: Point, end: Point) -> float:
    """|test(end) - test(start)| over the distance between them in x~."""
    step = float(np.linalg.norm(end.x - start.x))
    return abs(test(end) - test(start)) / step if step > 0.0 else math.inf


def continuous_root(test: Callable[[Point], float], start: Point, end: Point,
                    located: Located, tolerance: float) -> bool:
    """Whether the root of a smooth bifurcation's ``test`` that `locate` bracketed is one.

    ``start`` and ``end``: the step searched (``test`` changes sign between them). A
    multiplier that crosses the unit circle, or a tangent's parameter part through 0, makes
    a test continuous across its root: as the bracket narrows, the test's values at its ends
    go to 0 with it. The jump between them must then be within ``ROOT_MARGIN`` times the
    step's mean slope times the bracket's width (both in x~ norms), and the near end's value
    within `near_zero` (``tolerance``: the arclength's, x~), as is a jump within it (a
    bracket narrowed to round-off: the test's own rounding). Where the multiplier the test
    follows changes kind instead (a complex pair outside the circle meets on the real axis:
    the test jumps from that pair's |mu| - 1 to another pair's), the jump stays as the
    bracket narrows: no bifurcation. Without a corrected point beyond, the near end's value
    alone must be that small.
    """
    before, beyond = located.before, located.beyond
    slope = _mean_slope(test, start, end)
    if beyond is None:
        width = float(np.linalg.norm(end.x - start.x) - np.linalg.norm(before.x - start.x))
        jump = abs(test(before))
    else:
        width = float(np.linalg.norm(beyond.x - before.x))
        jump = abs(test(beyond) - test(before))
    # both ends within near_zero of 0 is continuous too: a bracket narrowed to round-off
    # leaves the test's own round-off (1e-14 of a multiplier) as its jump (False for a NaN)
    close = near_zero(test, start, end, tolerance)
    return bool(jump <= max(ROOT_MARGIN * slope * width, close)
                and abs(test(before)) <= close)


def _pinned(low: Bracket, high: Bracket, start: Point, test: Callable[[Point], float]) -> bool:
    """Whether the test's value at an end of the bracket is small enough for a root in it.

    At least one end's value must be within ``ROOT_MARGIN`` times the bracket's width times
    the secant's slope from ``start`` to ``low`` (an end without a value, where the corrector
    failed, does not count): a continuous test with a simple root satisfies this as the
    bracket narrows, a test that jumps does not.
    """
    (s0, f0, _), (s1, f1, _) = low, high
    if s0 <= 0.0:  # no step from the start: a root anywhere up to a valued end
        return math.isfinite(f1)
    if not math.isfinite(f0):
        return False
    slope = abs(test(start) - f0) / s0
    ends = [abs(f0)] + ([abs(f1)] if math.isfinite(f1) else [])
    return min(ends) <= ROOT_MARGIN * slope * (s1 - s0)


Bracket = tuple[float, float, Point | None]
# a third point bends the guess between a bracket's ends only this far out of the bracket at
# least, in its widths (nearer, round-off in its weights would grow as the width over it)
BEND_DISTANCE = 1e-3


def guess_at(low: Bracket, high: Bracket, s: float,
             corrected: tuple[tuple[float, Point], ...] = ()) -> np.ndarray | None:
    """The branch at arclength ``s`` within a bracket, interpolated between its corrected ends.

    Bent by the parabola through the nearest of the ``corrected`` points (s, point) at least
    ``BEND_DISTANCE`` widths outside the bracket, if any. As the bracket narrows the guess
    nears the branch like its width cubed (squared without a third point; like the width
    where the branch kinks between the ends, at a change of the contacts), and Newton starts
    within its tolerance: one or two linearisations a solve, not three. None without a
    point at both ends (Newton then starts from the plane's point on the line of the search).
    """
    (s0, _, low_point), (s1, _, high_point) = low, high
    if low_point is None or high_point is None or not s0 < s1:
        return None
    width = s1 - s0
    weight = min(max((s - s0) / width, 0.0), 1.0)
    guess = (1.0 - weight) * low_point.x + weight * high_point.x
    outside = [(max(s0 - place, place - s1), place, point) for place, point in corrected]
    outside = [known for known in outside if known[0] > BEND_DISTANCE * width]
    if outside:
        _, place, point = min(outside, key=lambda known: known[0])
        # the parabola's part that vanishes at both ends, through the third point
        line = low_point.x + (place - s0) / width * (high_point.x - low_point.x)
        guess += (s - s0) / (place - s0) * ((s - s1) / (place - s1)) * (point.x - line)
    return guess


def _known(low: Bracket, high: Bracket, tolerance: float) -> bool:
    """Whether the bracket pins the parameter to ``tolerance`` (x~ units).

    Without a corrected point beyond, the parameter's rate there is unknown: the bound 1 of a
    unit tangent's part stands for it (the bracket then ends unbracketed, see `locate`).
    """
    ends = [point for _, _, point in (low, high) if point is not None]
    rate = max(abs(point.tangent[-1]) for point in ends) if len(ends) == 2 else 1.0
    return (high[0] - low[0]) * rate <= tolerance


def _next_arclength(low: Bracket, high: Bracket, low_before: Bracket | None = None,
                    high_before: Bracket | None = None, one_sided: bool = False) -> float:
    """Regula falsi between the ends, or one end's secant (off the ends by a margin).

    Where one end has no value (the corrector failed there: past a grazing, or beyond a
    fold's reach) or one ``JUMP_RATIO`` times the other's (the test jumps on that side), that
    end says nothing of the root: the other end's secant (through its previous place,
    ``low_before`` or ``high_before``) is extrapolated to 0, doubled so that the solve lands
    past the root (a root is then bracketed from one side's slope in a few solves, not crept
    up on, or bisected from a step down to the tolerance); with ``one_sided`` the secant of the
    end nearer 0 always, the solve just beside its root (`_beside_secant`). Without such a
    secant inside the bracket, regula falsi (its next solve gives that end a previous place),
    or the middle where the far end has no value.
    """
    (s0, f0, _), (s1, f1, _) = low, high
    if not math.isfinite(f0):
        return 0.5 * (s0 + s1)
    secant = None
    if one_sided:  # the end nearer 0 is the side whose value vanishes
        secant = (_beside_secant(low, low_before, s1) if not math.isfinite(f1)
                  or abs(f0) <= abs(f1) else _beside_secant(high, high_before, s0))
    elif not math.isfinite(f1) or abs(f1) > JUMP_RATIO * abs(f0):
        secant = _doubled_secant(low, low_before, (s0, s1))
    elif abs(f0) > JUMP_RATIO * abs(f1):
        secant = _doubled_secant(high, high_before, (s0, s1))
    if secant is not None:
        return secant
    if not math.isfinite(f1) or f0 == f1:
        return 0.5 * (s0 + s1)
    s = s0 - f0 * (s1 - s0) / (f1 - f0)
    # kept off the ends by a margin, not sent to the middle: a root close to an end (where
    # the other end's value is large, e.g. at a grazing reached by a step much longer than
    # the gap's curvature allows) is then bracketed a thousand times closer in one solve
    margin = 1e-3 * (s1 - s0)
    return min(max(s, s0 + margin), s1 - margin)


def _true(end: Bracket, test: Callable[[Point], float]) -> Bracket | None:
    """``end`` with its test value as read (Illinois may have halved it); None without one."""
    s, _, point = end
    value = test(point) if point is not None else math.nan
    return (s, value, point) if math.isfinite(value) else None


def _doubled_secant(end: Bracket, previous: Bracket | None, bracket: tuple[float, float],
                    ) -> float | None:
    """``end``'s secant through ``previous`` to 0, doubled; None if none, or not within."""
    if previous is None or previous[1] == end[1]:
        return None
    s = end[0] - 2.0 * end[1] * (previous[0] - end[0]) / (previous[1] - end[1])
    margin = 1e-3 * (bracket[1] - bracket[0])
    return s if bracket[0] + margin < s < bracket[1] - margin else None


def _beside_secant(near: Bracket, previous: Bracket | None, far: float) -> float | None:
    """``near``'s secant through ``previous`` to 0, put just beside it; None if none.

    Just past the root (``BESIDE`` of its distance from ``near``, toward the ``far`` end)
    while the far end is farther than twice that, else just short of it: the far end then
    comes within that margin of the root and the near end next, so that a bracket whose far
    side jumps shrinks by about ``BESIDE`` every two solves (from a step to 1e-11 of it in
    some ten, where bisection takes 35). None without a secant, or one outside the bracket.
    """
    if previous is None or previous[1] == near[1]:
        return None
    root = near[0] - near[1] * (previous[0] - near[0]) / (previous[1] - near[1])
    toward = math.copysign(1.0, far - near[0])
    margin = BESIDE * abs(root - near[0])
    s = root + (toward if abs(far - root) > 2.0 * margin else -toward) * margin
    return s if min(near[0], far) < s < max(near[0], far) else None
