"""Smooth bifurcations are labelled only where their test crosses 0 continuously (issue 31).

A Neimark-Sacker test follows a complex pair's |mu| - 1. Where that pair meets the real axis
(two real multipliers from then on) the test takes the next pair's |mu| - 1 instead: it jumps,
and a root of regula falsi lies at the jump. On the stiff stop-and-shaker branch going down
(issue 31; a step not sampled for hidden crossings) main labelled such a jump a Neimark-Sacker
point at 124.963 rad/s (a pair at |mu| 2.37 turning real), and located one at 168.0963 rad/s
with |mu| = 1.00406 (a jump) instead of the crossing at 168.0984 (|mu| = 1.00000).

Here synthetic multipliers along a line s in [0, 1] (x~ = (0, s), the parameter s), corrected
exactly by a stand-in follower, are searched by the branch's own `_between`.
"""

import math
import types

import numpy as np
import pytest

from impactbeams.continuation.arclength import Point, Settings
from impactbeams.continuation.branch import _between
from impactbeams.continuation.events import (
    NEIMARK_SACKER,
    PERIOD_DOUBLING,
    continuous_root,
    detected,
    locate,
)
from impactbeams.continuation.problem import Evaluation

TURNS_REAL = 0.5  # where the pair outside the circle meets the real axis
CROSSES = 0.75  # where another pair crosses the circle (a Neimark-Sacker point)


def pair(modulus, argument):
    return [modulus * np.exp(1j * argument), modulus * np.exp(-1j * argument)]


def outside_pair_turning_real(s):
    """A pair at |mu| 2.35 (argument 0.15 -> 0) that turns real (2.35 +- ...) at TURNS_REAL;
    two real multipliers near 0 meet there and leave the axis as a tiny pair."""
    if s < TURNS_REAL:
        return [*pair(2.35 + 0.1 * s, 0.3 * (TURNS_REAL - s)), 2e-3, 1e-3]
    split = 0.3 * np.sqrt(s - TURNS_REAL)
    return [2.35 + 0.1 * s + split, 2.35 + 0.1 * s - split, *pair(1.5e-3, 1.5)]


def line(multipliers, rate=1.0):
    """A stand-in follower whose point at s carries ``multipliers(s)``, its points, the ends.

    The line x~ = s (sqrt(1 - rate^2), rate): the parameter (x~'s last) changes at ``rate``.
    """
    tangent = np.array([math.sqrt(1.0 - rate ** 2), rate])

    def point_at(s, guess=None):
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)),
                                np.array(multipliers(s), complex))
        return Point(s * tangent, tangent, evaluation, 1)

    follower = types.SimpleNamespace(
        settings=Settings(),
        correct=lambda x, normal, _, start=None: types.SimpleNamespace(
            point=point_at(float(x @ tangent))))
    return follower, point_at, point_at(0.0), point_at(1.0)


def labelled(points):
    return [(point.label, float(np.linalg.norm(point.x)), point.evaluation.multipliers)
            for point in points if point.label]


def test_a_pair_outside_turning_real_is_no_neimark_sacker():
    """The pair at 2.35 is matched with the tiny one (the only pair at s = 1): the detection
    sees a pair cross the circle; its test jumps from +1.40 to -1.00 at TURNS_REAL. Main
    labelled the jump; it is no bifurcation: nothing crosses the circle."""
    follower, point_at, a, b = line(outside_pair_turning_real)
    ((label, test),) = detected(a, b)
    assert label == NEIMARK_SACKER and test(a) > 1.3 and test(b) < -0.99
    jump = locate(point_at, a, 1.0, b, test, 1e-11)
    assert jump.s < TURNS_REAL <= float(jump.beyond.x[1])  # pinned at the jump
    assert not continuous_root(test, a, b, jump, 1e-11)
    assert labelled(_between(follower, a, b)) == []


def with_a_crossing(s):
    """The pair turning real, and another pair (argument 2) crossing the circle at CROSSES."""
    return [*outside_pair_turning_real(s), *pair(1.0 + 0.1 * (s - CROSSES), 2.0)]


def test_a_crossing_beside_a_jump_is_located_and_the_jump_is_not():
    """Both pairs are seen to cross (the tiny pair is matched with the one at 2.35, the
    crossing pair with itself): the crossing at CROSSES is located on the circle, the jump at
    TURNS_REAL is no label (main labelled both)."""
    follower, _, a, b = line(with_a_crossing)
    assert [label for label, _ in detected(a, b)] == [NEIMARK_SACKER] * 2
    ((label, s, mu),) = labelled(_between(follower, a, b))
    assert label == NEIMARK_SACKER and s == pytest.approx(CROSSES, abs=1e-11)
    assert np.abs(np.abs(mu[np.abs(np.angle(mu) - 2.0) < 0.1]) - 1.0).max() <= 1e-9


@pytest.mark.parametrize("rate", [0.05, 0.5, 2.0])
def test_a_true_neimark_sacker_is_located_on_the_circle(rate):
    """A pair whose |mu| - 1 = rate (s - 0.3): one label, |mu| = 1 to 1e-9 (the parameter to
    locate_tolerance 1e-11 times the rate), the root continuous at every rate."""
    follower, _, a, b = line(lambda s: [*pair(1.0 + rate * (s - 0.3), 0.9), 0.2, -0.1])
    assert [label for label, _ in detected(a, b)] == [NEIMARK_SACKER]
    ((label, s, mu),) = labelled(_between(follower, a, b))
    assert label == NEIMARK_SACKER and s == pytest.approx(0.3, abs=1e-11)
    assert np.abs(np.abs(mu[mu.imag != 0]) - 1.0).max() <= 1e-9


def test_a_period_doubling_where_the_branch_is_vertical_is_located_on_the_circle():
    """The parameter changes at 1e-13 of the arclength (a branch vertical in it, as the stiff
    stop's period-2 branch going down at 160.40 rad/s): the step's ends already pin the
    parameter to 1e-11, and main labelled the step's start, |mu| 0.97 (on the beams, 0.456).
    The bracket is now narrowed until the multiplier is on the circle: to 1e3 times its mean
    slope (0.1) times the arclength tolerance 1e-11. (The other multipliers far from the circle:
    the step is not sampled.)"""
    follower, _, a, b = line(lambda s: [-(0.97 + 0.1 * s), 0.3, 0.2], rate=1e-13)
    ((label, s, mu),) = labelled(_between(follower, a, b))
    assert label == PERIOD_DOUBLING and s == pytest.approx(0.3, abs=1e-8)
    assert abs(abs(mu[0]) - 1.0) <= 1e-9


def test_a_bracket_narrowed_to_round_off_is_continuous_and_a_jump_there_is_not():
    # a period doubling on the small model (245.43 rad/s at 0.8 of the drive, Newton-Picard):
    # the bracket's ends 4e-17 apart in x~, the test -5.2e-14 and +4.9e-15 there (the
    # multiplier's round-off), the step's mean slope 0.077: a crossing. A jump of the test at
    # the same ends (to another multiplier, 0.5 away) stays one
    from impactbeams.continuation.events import Located

    tangent = np.array([0.0, 1.0])
    values = {}

    def point(s, value):
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.zeros(0, complex))
        made = Point(s * tangent, tangent, evaluation, 1)
        values[id(made)] = value
        return made

    def test(p):
        return values[id(p)]

    start, end = point(0.0, -0.0387), point(1.0, 0.0387)
    before, beyond = point(0.5, -5.2e-14), point(0.5 + 4e-17, 4.9e-15)
    tolerance = Settings().locate_tolerance
    assert continuous_root(test, start, end, Located(0.5, before, beyond, True), tolerance)
    jumped = point(0.5 + 4e-17, 0.5)
    assert not continuous_root(test, start, end, Located(0.5, before, jumped, True), tolerance)
