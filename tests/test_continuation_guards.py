"""Guards of the continuation (issue 31's defects): each located event stored once, a step
that lands on another strand refused, smooth bifurcations located inside a step that turned
back by more than 90 degrees, a floor under `near_zero`.
"""

import dataclasses
import math

import numpy as np
import pytest

import continuation_toys as toys
from impactbeams.continuation.arclength import Follower, Point, Scaling, Settings
from impactbeams.continuation.branch import Branch, _append, _between
from impactbeams.continuation.events import TEST_ROUND_OFF, detected, near_zero
from impactbeams.continuation.problem import Evaluation
from test_continuation_jumps import labelled, line

SETTINGS = Settings(step=0.05, max_step=0.1)


def point(p, state, contacts, label=""):
    """A point at x~ = (state, p), measured (so that `_append` keeps it as it is)."""
    x = np.array([state, p])
    evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.array([0.5]), grazing=0.0,
                            contacts=contacts, measures={"amplitude": abs(state)})
    return Point(x, np.array([0.0, 1.0]), evaluation, 2, label=label)


def twin_branch():
    """A branch whose last point is a grazing labelled on its near side (7 contacts)."""
    follower = Follower(toys.grazing(), Scaling(np.ones(1), 1.0), SETTINGS)
    near = point(0.5, 1.0, 7, "grazing")
    return follower, Branch([point(0.4, 0.8, 7), near], 1, follower.scaling)


def test_the_far_side_of_a_located_event_does_not_label_it_again():
    # the far side's first point, 1e-13 away in the parameter (5e-15 of the stiff stop's
    # range, as 1e-12 rad/s there) but 1e-6 away in the state (a branch steep in the
    # parameter): the same grazing, stored once, on the point that carried it first
    follower, branch = twin_branch()
    far = point(0.5 + 1e-13, 1.0 + 1e-6, 8, "grazing")
    _append(follower, branch, [far], None)
    assert [p.label for p in branch.points] == ["", "grazing"]
    assert branch.points[-1].evaluation.contacts == 7


def test_the_far_side_relabelled_keeps_no_second_label():
    # the far side's first point appended unlabelled, then relabelled (`_cross_grazing`
    # where the grazing located ahead of it is that point itself)
    follower, branch = twin_branch()
    far = point(0.5 + 1e-13, 1.0 + 1e-6, 8)
    _append(follower, branch, [far], None)
    _append(follower, branch, [dataclasses.replace(far, label="grazing")], None)
    assert [p.label for p in branch.points] == ["", "grazing", ""]
    assert branch.points[-1].evaluation.measures == far.evaluation.measures


def test_two_events_of_a_kind_apart_are_both_stored():
    # beyond the location tolerance (1e-11 of the range), or not neighbours: two events
    follower, branch = twin_branch()
    _append(follower, branch, [point(0.5 + 1e-9, 1.0 + 1e-6, 8, "grazing")], None)
    _append(follower, branch, [point(0.6, 1.2, 8), point(0.6 + 1e-13, 1.2 + 1e-6, 9,
                                                         "grazing")], None)
    assert [p.label for p in branch.points] == ["", "grazing", "grazing", "", "grazing"]
    assert not math.isnan(branch.points[-1].x[0])


class Staircase:
    """z -> (z + p) / 2, the branch z = p; a contact per orbit for each 0.1 of z (no grazing
    or interval value: each change is located by bisection on the contacts)."""

    period = 1

    def evaluate(self, z, p, jacobian=True, grazing=True):
        contacts = int(np.floor(10.0 * z[0]))
        return Evaluation(0.5 * (z + p) - z, -0.5 * np.eye(1) if jacobian else np.empty((0, 0)),
                          np.array([0.5]) if jacobian else np.empty(0), contacts=contacts)

    def measures(self, z, p):
        return {"amplitude": float(abs(z[0]))}

    def iterated(self, times):
        raise NotImplementedError


def test_a_step_onto_another_strand_is_refused_and_retried_shorter(monkeypatch):
    # the corrector of the step from z = 0.23 "converges" 0.35 further along (3 contacts
    # more, as main's from 149.57 to 151.37 rad/s on the stiff stop, 5 to 2 contacts): that
    # step is refused, a shorter one taken from the same point; the branch then crosses each
    # change of the contacts in a step of its own, each located
    from impactbeams.continuation import branch as branch_module

    jumps, steps = [], []

    class Jumping(Follower):
        def step(self, start, ds):
            steps.append((start.x[-1], ds))
            if 0.22 < start.x[-1] < 0.24 and not jumps:
                far = self.at_parameter(start.x + 0.35, start.tangent).point
                jumps.append(len(steps))
                return far, ds, ()
            return super().step(start, ds)

    monkeypatch.setattr(branch_module, "Follower", Jumping)
    (branch,) = branch_module.continue_branches(
        Staircase(), np.array([0.05]), 0.05, branch_module.Span(0.0, 1.0),
        Scaling(np.ones(1), 1.0), Settings(step=0.01, max_step=0.01, max_branches=1))
    assert len(jumps) == 1 and branch.ending == "bound"
    (start, ds), retried = steps[jumps[0] - 1], steps[jumps[0]]
    assert retried == (start, ds / 2.0)
    contacts = np.array([p.evaluation.contacts for p in branch.points])
    assert np.all(np.abs(np.diff(contacts)) <= 1)
    assert contacts[0] == 0 and contacts[-1] == 10
    changes = [p.x[-1] for p in branch.points if p.label == "contact_split"]
    assert changes == pytest.approx(np.arange(1, 11) / 10.0, abs=2e-11)


class OneSided(Staircase):
    """The staircase's branch z = p with one change of the contacts, 3 to 4 at p = 0.5, whose
    interval value goes to 0 on the near side only ((0.5 - p) / 100 m, linear) and stays
    2e-3 on the far side, and whose grazing value is 5e-3 on both: neither changes sign (a
    shallow contact beside another's release on the stiff stop). ``solves`` counts the
    evaluations."""

    def __init__(self):
        self.solves = 0

    def evaluate(self, z, p, jacobian=True, grazing=True):
        self.solves += 1
        near = p < 0.5
        evaluation = super().evaluate(z, p, jacobian, grazing)
        return dataclasses.replace(evaluation, contacts=3 if near else 4, grazing=5e-3,
                                   interval=(0.5 - p) / 100.0 if near else 2e-3)


def test_a_change_no_sign_shows_is_located_from_the_side_whose_value_vanishes():
    # bisection on the contacts from the step of 0.05 to 1e-11 takes 31 corrector solves (124
    # evaluations); the near side's value, signed by the side (`_sided`), a secant beside its
    # root (`_beside_secant`) each: 11 solves, 36 evaluations
    from impactbeams.continuation import branch as branch_module
    from impactbeams.continuation.branch import _located_change

    problem = OneSided()
    follower = branch_module.Follower(problem, Scaling(np.ones(1), 1.0), SETTINGS)
    a, b = (follower.at_parameter(np.array([p, p]), np.array([0.0, 1.0])).point
            for p in (0.48, 0.53))
    problem.solves = 0
    located = _located_change(follower, a, b, a.tangent, branch_module._contacts_of(a))
    assert located.before.evaluation.contacts == 3 and located.beyond.evaluation.contacts == 4
    assert located.before.x[-1] <= 0.5 <= located.beyond.x[-1]
    assert located.beyond.x[-1] - located.before.x[-1] <= SETTINGS.locate_tolerance
    assert problem.solves <= 40  # (measured: 36)


def test_near_zero_has_the_test_functions_round_off_as_its_floor():
    # a multiplier that crosses -1 slowly (|mu| - 1 = 1e-6 (s - 0.3) over a step of 1 in
    # x~), its modulus off by 5e-14 of round-off that does not shrink with the bracket (as
    # the monodromy's eigenvalues are: -5.2e-14 and +4.9e-15 at ends 4e-17 apart on the
    # small model): main asked the root's test to be within 1e3 x 1e-6 x 1e-11 = 1e-14 of 0,
    # below that round-off, which no bracket meets: the doubling was not labelled. Now
    # within the round-off floor: located, on the circle to it
    def multipliers(s):
        noise = math.copysign(5e-14, s - 0.3)
        return [-(1.0 + 1e-6 * (s - 0.3) + noise), 0.3, 0.2]

    follower, _, a, b = line(multipliers)
    test = lambda p: float(abs(p.evaluation.multipliers[0].real)) - 1.0  # noqa: E731
    floor = near_zero(test, a, b, follower.settings.locate_tolerance)
    assert floor == pytest.approx(TEST_ROUND_OFF * (1.0 + 7e-7), rel=1e-6)
    assert 5e-14 < floor < 1e-12
    ((label, s, mu),) = labelled(_between(follower, a, b))
    assert label == "period_doubling"
    assert abs(abs(mu[0]) - 1.0) <= floor
    assert s == pytest.approx(0.3, abs=(floor + 5e-14) / 1e-6)
    # a test that changes fast keeps its slope's bound, far above the floor
    follower, _, a, b = line(lambda s: [-(1.0 + 0.1 * (s - 0.3)), 0.3, 0.2])
    assert near_zero(test, a, b, 1e-11) == pytest.approx(1e3 * 0.1 * 1e-11, rel=1e-9)


def arc_follower(multipliers):
    """A stand-in follower on the unit circle x~ = (cos theta, sin theta), the parameter
    sin theta: it turns back in the parameter at theta = pi / 2. A point on a plane is the
    circle's crossing nearest the plane's point (as Newton from it); ``multipliers(theta)``."""
    import types

    from scipy.optimize import brentq

    def point_at(theta):
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)),
                                np.array(multipliers(theta), complex))
        return Point(np.array([math.cos(theta), math.sin(theta)]),
                     np.array([-math.sin(theta), math.cos(theta)]), evaluation, 2)

    def correct(x, normal, _, start=None):
        def across(theta):
            return float(normal @ (np.array([math.cos(theta), math.sin(theta)]) - x))

        guess = math.atan2(x[1], x[0])
        grid = np.linspace(-math.pi, math.pi, 4001)
        roots = [brentq(across, t0, t1, xtol=1e-15)
                 for t0, t1 in zip(grid[:-1], grid[1:], strict=True)
                 if across(t0) * across(t1) < 0]
        theta = min(roots, key=lambda root: abs(root - guess))
        return types.SimpleNamespace(point=point_at(theta))

    return types.SimpleNamespace(settings=Settings(), correct=correct), point_at


def test_smooth_bifurcations_inside_a_step_that_turns_back_are_located():
    # from theta = 0.2 to 2.4 the branch turns by 126 degrees, back in the parameter at a
    # fold (theta = pi / 2, a multiplier through +1) and through a period doubling on the
    # way back (theta = 2, a multiplier through -1); planes along the start's tangent reach
    # no farther than theta = 1.14 (main labelled neither: the tests jumped at their reach)
    def multipliers(theta):
        # slow, as the beams' near their crossings: the step is not sampled (no other
        # multiplier near the circle), its ends only are searched between
        return [1.0 + 0.01 * (theta - math.pi / 2), -(1.0 + 0.01 * (theta - 2.0)), 0.2]

    follower, point_at = arc_follower(multipliers)
    a, b = point_at(0.2), point_at(2.4)
    assert sorted(label for label, _ in detected(a, b)) == ["fold", "period_doubling"]
    found = labelled(_between(follower, a, b))
    assert [label for label, *_ in found] == ["fold", "period_doubling"]
    (_, _, fold), (_, _, doubling) = found
    assert fold[0].real == pytest.approx(1.0, abs=1e-9)
    assert doubling[1].real == pytest.approx(-1.0, abs=1e-9)


def test_the_stiff_stops_grazing_at_163_3051438_is_stored_once(captured, tmp_path):
    # issue 31's stiff stop going down at its default Hertz contact and modes, to its 160th
    # point (4 s of CPU): main labelled the grazing at 163.3051438 rad/s on the near side's
    # last point (7 contacts per orbit) and again on the far side's first (8), 1.1e-12 rad/s
    # apart; its summary counted 14 grazings, the plot's legend 15. Now one label, on the near
    # side, and both count the same
    import re

    import impactbeams as ib
    from impactbeams.cli import _branch_summary
    from impactbeams.continuation import Continuation, continue_orbits
    from impactbeams.plotting import plot_dataset
    from impactbeams.variables import BIFURCATIONS

    keys = {"l1": 0.2, "width1": 0.02, "thickness1": 0.001, "counterpart": "stop",
            "clearance": 5e-4, "shaker": "beam1", "base_amplitude": 1e-4,
            "force_amplitude": 0.0, "damping_ratio": 0.01}
    dataset = continue_orbits(Continuation(ib.Params.from_mapping(keys), "omega", 65.6, 262.5,
                                           direction="down", max_points=160, max_branches=1))
    omega, codes = dataset.omega.values, dataset.bifurcation.values
    at = np.flatnonzero(np.abs(omega - 163.3051438) < 1e-6)
    assert at.size == 2 and list(dataset.contacts_per_orbit.values[at]) == [7, 8]
    assert [BIFURCATIONS[code] for code in codes[at]] == ["grazing", "none"]
    tolerance = 1e-11 * (262.5 - 65.6)  # locate_tolerance of the range
    neighbours = (codes[:-1] > 0) & (codes[:-1] == codes[1:])
    assert not np.any(neighbours & (np.abs(np.diff(omega)) <= tolerance))
    plot_dataset(dataset, tmp_path / "down.png")
    legend = [text.get_text() for text in captured[0].axes[0].get_legend().get_texts()]
    summary = _branch_summary(dataset)
    for entry in legend:
        kind = re.match(r"^[A-Z]+: ([a-z ]+) \((\d+)", entry)
        if kind:
            assert f"{kind.group(2)} {kind.group(1).replace(' ', '_')}" in summary
    # each stored label once: the summary's count is the labels' (13 or 14 as the steps land)
    grazings = sum(BIFURCATIONS[code] == "grazing" for code in codes)
    assert f"{grazings} grazing" in summary
