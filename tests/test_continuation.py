"""The continuation engine on small problems with exact answers (tests/continuation_toys.py)."""

import dataclasses
import math

import numpy as np
import pytest

import continuation_toys as toys
from impactbeams.continuation import arclength
from impactbeams.continuation.arclength import Point, Scaling, Settings
from impactbeams.continuation.branch import (
    ContinuationInterrupted,
    Span,
    continue_branches,
)
from impactbeams.continuation.events import grazing_test, locate
from impactbeams.continuation.output import branches_dataset
from impactbeams.continuation.problem import Evaluation, parameter_derivative
from impactbeams.params import ParameterError

SETTINGS = Settings(step=0.05, max_step=0.1)
# the location stops when the parameter is known to locate_tolerance (1e-11 at unit scaling);
# the Newton corrector's own error (tolerance 1e-10 on the correction, quadratic: ~1e-20) is
# far below
LOCATED = 2e-11


def follow(problem, z0, p0, low, high, direction=1, settings=SETTINGS):
    return continue_branches(problem, np.asarray(z0, float), p0, Span(low, high, direction),
                             Scaling(np.ones(len(z0)), 1.0), settings)


def labelled(branch, label):
    return [point for point in branch.points if point.label == label]


def test_fold_located_where_the_determinant_vanishes():
    branches = follow(toys.fold(), [1.0, 0.4], 1.04, -1.0, 2.0, direction=-1,
                      settings=Settings(step=0.05, max_step=0.1, max_branches=1))
    (fold,) = labelled(branches[0], "fold")
    assert fold.x[-1] == pytest.approx(-4e-4, abs=LOCATED)
    assert not labelled(branches[0], "branch_point")  # its multiplier at +1 is the fold's
    assert fold.x[0] == pytest.approx(-0.02, abs=1e-5)  # p is quadratic in z1 there
    # the branch turned back: it ends at the upper bound on the other side (z1 < 0)
    end = branches[0].points[-1]
    assert branches[0].ending == "bound" and end.x[-1] == pytest.approx(2.0, abs=1e-12)
    assert end.x[0] == pytest.approx(-0.02 - math.sqrt(4e-4 + 2.0), abs=1e-9)
    # every point solves r = 0 to Newton's tolerance
    for point in branches[0].points:
        assert np.max(np.abs(point.x[0] ** 2 + 0.04 * point.x[0] - point.x[-1])) < 1e-12


def test_period_doubling_located_and_switched_to_the_period_2_orbit():
    main, doubled = follow(toys.period_doubling(), [0.0, 0.0], -0.5, -0.5, 0.5)
    (doubling,) = labelled(main, "period_doubling")
    assert doubling.x[-1] == pytest.approx(0.0, abs=LOCATED)
    assert doubled.period == 2 and doubled.origin == (0, main.points.index(doubling))
    assert doubled.ending == "bound" and doubled.points[-1].x[-1] == pytest.approx(0.5)
    for point in doubled.points:  # the exact period-2 orbit z1^2 = p, z2 = 2 p
        z1, z2, p = point.x
        assert z1**2 == pytest.approx(p, abs=1e-13) and z2 == pytest.approx(2 * p, abs=1e-13)
    # not the period-1 orbit: a single application of the map moves the state
    z1, _, p = doubled.points[0].x
    once = toys.period_doubling().residual(doubled.points[0].x[:2], p)
    assert abs(z1) > 1e-4 and abs(once[0]) > 1e-4


def test_branch_point_located_where_a_multiplier_crosses_plus_1_without_a_fold():
    """The symmetric branch z = 0 of the pitchfork: a real multiplier through +1 at p = 0
    while the branch goes on in p: labelled branch_point (not fold), located to 1e-11."""
    (branch,) = follow(toys.pitchfork(), [0.0, 0.0], -0.5, -0.5, 0.5)
    (point,) = labelled(branch, "branch_point")
    assert point.x[-1] == pytest.approx(0.0, abs=LOCATED)
    assert np.max(point.evaluation.multipliers.real) == pytest.approx(1.0, abs=LOCATED)
    assert not labelled(branch, "fold") and branch.ending == "bound"
    assert all(abs(p.x[0]) < 1e-12 for p in branch.points)  # stays on the symmetric branch


def test_neimark_sacker_located():
    (branch,) = follow(toys.neimark_sacker(), [0.0, 0.0], -0.5, -0.5, 0.5)
    (point,) = labelled(branch, "neimark_sacker")
    assert point.x[-1] == pytest.approx(0.0, abs=LOCATED)
    assert np.abs(point.evaluation.multipliers) == pytest.approx([1.0, 1.0], abs=LOCATED)
    assert abs(np.angle(point.evaluation.multipliers[0])) == pytest.approx(toys.THETA)


@pytest.mark.parametrize("stiffness", [100.0, 1e4])
def test_grazing_is_an_event_of_the_branch(stiffness):
    """The multiplier jumps from 1/2 to 1 within 1/(54 K^2) of the grazing (1.9e-6 and
    1.9e-10 in p): located as events, in a bounded number of points."""
    (branch,) = follow(toys.grazing(stiffness), [0.0], 0.0, -1.0, 2.0)
    (grazing,) = labelled(branch, "grazing")
    assert grazing.x[-1] == pytest.approx(0.5, abs=LOCATED)
    assert grazing.evaluation.contacts == 0
    after = branch.points[branch.points.index(grazing) + 1]
    assert after.evaluation.contacts == 1
    (fold,) = labelled(branch, "fold")
    assert fold.x[-1] == pytest.approx(0.5 + 1 / (54 * stiffness**2), abs=LOCATED)
    assert branch.ending == "bound" and len(branch.points) < 120


@pytest.mark.parametrize(("offset", "slant", "step"), [
    (0.4, 0.0, 1.5), (0.4, 5.0, 1.5), (0.2, 0.0, 1.5), (0.3, 0.0, 2.0), (0.4, 0.0, 1.0)])
def test_grazing_just_past_a_fold_is_located_on_the_branch(offset, slant, step):
    """Coming down p = z^2 from z = 1 with a step that overshoots the fold (z = p = 0): the
    secant planes of the points before the fold reach no farther than z = -1/(4 z_0), short of
    the grazing at z = -offset. The grazing is labelled at p = offset^2 (not at the end of the
    planes' reach, as before: a point still in contact, its gap offset - 1/(4 z_0) < 0), once,
    with the contacts changing across it; the fold is located at p = 0."""
    (branch,) = follow(toys.fold_then_grazing(offset, slant), [1.0], 1.0, -1.0, 30.0,
                       direction=-1, settings=Settings(step=step, max_step=step))
    (grazing,) = labelled(branch, "grazing")
    assert grazing.x[-1] == pytest.approx(offset ** 2, abs=LOCATED)
    assert abs(grazing.evaluation.grazing) < LOCATED
    after = branch.points[branch.points.index(grazing) + 1]
    assert (grazing.evaluation.contacts, after.evaluation.contacts) == (1, 0)
    (fold,) = labelled(branch, "fold")
    assert fold.x[-1] == pytest.approx(0.0, abs=LOCATED)
    assert branch.ending == "bound"


def test_measures_are_read_at_the_kept_points_only():
    """A corrector's iterates, a located event's search and the samples of a step read no
    measures (the beams' tip maxima cost 12 times a run at 16 modes): each kept point reads
    them once, and every kept point has them."""
    problem = toys.fold()
    read = []
    measures = problem.measures
    problem.measures = lambda z, p: read.append(p) or measures(z, p)
    branches = follow(problem, [1.0, 0.4], 1.04, -1.0, 2.0, direction=-1,
                      settings=Settings(step=0.05, max_step=0.1, max_branches=1))
    points = branches[0].points
    assert labelled(branches[0], "fold")  # a located event's search ran
    assert len(read) == len(points)
    assert all(point.evaluation.measures["amplitude"] > 0 for point in points)


def test_dataset_along_branch_points(tmp_path):
    branches = follow(toys.period_doubling(), [0.0, 0.0], -0.5, -0.5, 0.5)
    dataset = branches_dataset(branches, "omega", {"title": "toy"})
    points = sum(len(branch.points) for branch in branches)
    assert dataset.sizes == {"branch_point": points, "multiplier": 2, "state": 2, "section": 2}
    assert dataset.bifurcation.attrs["flag_meanings"].split()[2] == "period_doubling"
    assert (dataset.bifurcation == 2).sum() == 1  # the period-2 orbit's (1 - 2p)^2 stays > -1
    assert set(dataset.orbit_period.values) == {1, 2}
    before = dataset.where(dataset.omega < -1e-9, drop=True)
    assert (before.stable == 1).all() and before.multiplier_modulus.max() < 1
    # a period-p orbit's p section samples; NaN past a period-1 orbit's one
    sections = dataset.section_deflection_1
    assert sections.dims == ("branch_point", "section")
    single, double = (sections[dataset.orbit_period == p] for p in (1, 2))
    assert np.isnan(single[:, 1]).all() and np.isfinite(single[:, 0]).all()
    np.testing.assert_array_equal(double[:, 0], dataset.section_state[dataset.orbit_period == 2, 0])
    np.testing.assert_allclose(double[:, 1], -double[:, 0], atol=1e-9)  # z1 = +-sqrt(p)
    dataset.to_netcdf(tmp_path / "branch.nc")


def test_interrupt_keeps_the_points():
    seen = []

    def progress(branch, point):
        seen.append(point)
        if len(seen) == 5:
            raise KeyboardInterrupt

    with pytest.raises(ContinuationInterrupted) as caught:
        continue_branches(toys.fold(), np.array([1.0, 0.4]), 1.04, Span(-1, 2, -1),
                          Scaling(np.ones(2), 1.0), SETTINGS, progress)
    (branch,) = caught.value.branches
    assert branch.ending == "interrupted" and len(branch.points) == 6  # the start and 5


@pytest.mark.parametrize("changes, message", [
    ({"step": 0.0}, "step = 0.0 is not allowed"),
    ({"step": 1.0, "max_step": 0.5}, "step = 1.0 is not allowed: must lie from min_step"),
    ({"max_points": 0}, "max_points = 0 is not allowed"),
])
def test_settings_refused_in_one_line(changes, message):
    with pytest.raises(ParameterError, match=message):
        Settings(**changes)


def test_start_that_does_not_converge():
    with pytest.raises(ParameterError, match="did not converge"):
        follow(toys.fold(), [1.0, 0.4], -1.0, -2.0, 2.0)  # no solution at p = -1


def test_period_doubling_just_after_a_collision_in_the_same_step():
    """The complex pair meets on the negative axis (p = 0) and a multiplier crosses -1
    (p = 0.01) within one step of 0.05: still located."""
    (branch,) = follow(toys.colliding_pair(), [0.0, 0.0], -0.21, -0.21, 0.2,
                       settings=Settings(step=0.05, max_step=0.1, max_branches=1))
    (point,) = labelled(branch, "period_doubling")
    assert point.x[-1] == pytest.approx(0.01, abs=LOCATED)
    before = branch.points[branch.points.index(point) - 1]
    assert before.x[-1] < 0 and np.all(before.evaluation.multipliers.imag != 0)


def test_branches_drawn_as_a_frequency_response(tmp_path):
    """Every branch, stability runs and labels drawn from the saved Dataset; the bad --var and
    a diagram under a file without branches refused in one line."""
    import xarray as xr

    from impactbeams.plotting import plot_dataset

    branches = follow(toys.period_doubling(), [0.0, 0.0], -0.5, -0.5, 0.5)
    branches_dataset(branches, "omega", {"title": "toy"}).to_netcdf(tmp_path / "b.nc")
    with xr.open_dataset(tmp_path / "b.nc") as dataset:
        assert plot_dataset(dataset, tmp_path / "b.png", "amplitude") == []
        with pytest.raises(ParameterError, match="'grazing_ga' is not a variable along"):
            plot_dataset(dataset, tmp_path / "c.png", "grazing_ga")
        with pytest.raises(ParameterError, match="for a continuation's file only"):
            plot_dataset(dataset.drop_dims("branch_point"), tmp_path / "d.png",
                         diagram=dataset)
    assert (tmp_path / "b.png").stat().st_size > 10_000


@pytest.mark.parametrize(("reach", "root", "located"), [(0.6, 0.6, True), (0.6, 1.0, False)])
def test_locate_without_a_corrected_point_beyond(reach, root, located):
    """The corrector fails past ``reach``: past a grazing where the map is not smooth (the
    root is located, ``root`` True, its near end at it) or where the branch turns back across
    the planes before the grazing (no root: the search ends near the reach as soon as the
    test's value there is too large for a root within the bracket, ROOT_MARGIN = 1e3 times
    its width times the slope, 1: within 0.4 / 1e3 of it, in a dozen solves, not 60)."""
    solves = []

    def point_at(s, guess=None):
        solves.append(s)
        if s > reach:
            return None
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.ones(1), grazing=s - root)
        return Point(np.array([0.0, s]), np.array([0.0, 1.0]), evaluation, 1)

    found = locate(point_at, point_at(0.0), 2.0, None, grazing_test, 1e-11)
    assert found.beyond is None and found.root == located
    if located:
        assert found.s == pytest.approx(root, abs=1e-11)
    else:
        assert reach - 0.4e-3 <= found.s <= reach and len(solves) <= 15


def test_locate_stops_where_the_test_jumps():
    """A grazing value that jumps from -1 to +1 at s = 0.3 (a free-flight minimum of the gap
    vanishes, no contact at zero depth): with ``may_jump`` the search ends once the bracket's
    ends stay far from 0 as it narrows (no root); without, it pins the jump as a root."""
    def point_at(s, guess=None):
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.ones(1),
                                grazing=(0.5 - s) if s < 0.3 else -1.0)
        return Point(np.array([0.0, s]), np.array([0.0, 1.0]), evaluation, 1)

    jump = locate(point_at, point_at(0.0), 1.0, point_at(1.0), grazing_test, 1e-11,
                  may_jump=True)
    assert not jump.root and jump.s < 0.3 < jump.beyond.x[-1]
    pinned = locate(point_at, point_at(0.0), 1.0, point_at(1.0), grazing_test, 1e-11)
    assert pinned.root and pinned.beyond.x[-1] - pinned.s <= 1e-11


def _located_on_a_line(test_value):
    """``locate`` on points s in [0, 1] of a line whose test is ``test_value(s)``; its solves."""
    solves = []

    def point_at(s, guess=None):
        solves.append(s)
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.ones(1),
                                grazing=test_value(s))
        return Point(np.array([0.0, s]), np.array([0.0, 1.0]), evaluation, 1)

    found = locate(point_at, point_at(0.0), 1.0, point_at(1.0), grazing_test, 1e-11)
    return found, len(solves) - 2


@pytest.mark.parametrize(("test_value", "solves"), [
    (lambda s: 0.3 - s if s < 0.3 else -1e6, 10),  # a jump past the root: 7 solves
    (lambda s: 0.3 - s if s < 0.3 else 1e4 * (0.3 - s), 10),  # a kink, steep past it: 7
    (lambda s: 1e4 * (0.3 - s) if s < 0.3 else 0.3 - s, 58),  # steep before it: 56
    (lambda s: 1e6 if s < 0.3 else 0.3 - s, 55),  # a jump before it: 51
    (lambda s: (0.3 - s) * (1 + 3 * s), 16),  # smooth (concave): 16
])
def test_locate_where_the_test_jumps_or_kinks_at_the_root(test_value, solves):
    """A test continuous on one side of its root and jumping, or a thousand times steeper,
    on the other (a merge's interval value where another contact's rise stands in; a grazing
    value where the near side's minimum is another contact's): the root pinned to the
    tolerance within the solves measured (+- a few). Main 018dd4a crept from one end by
    regula falsi and stopped at its 60-solve cap 1e-3, 6e-6, 6e-6 and 4e-4 short of it."""
    found, used = _located_on_a_line(test_value)
    assert abs(found.s - 0.3) <= 1e-11 and found.beyond.x[-1] - found.s <= 1e-11
    assert used <= solves


def test_a_gaps_value_tolerance_is_not_below_its_round_off():
    """From a start 5.8e-10 m from a merge, 1e-11 of it (5.8e-21 m) is below a gap's round-off
    (1e-19 m at 5e-4 m): no bracket met it, and each such search ran to its cap of 60 solves.
    The beams' problem gives its round-off, 1e3 eps of the clearance."""
    import impactbeams as ib
    from impactbeams.continuation.arclength import Follower
    from impactbeams.continuation.beams import BeamOrbits
    from impactbeams.continuation.branch import _value_tolerance

    params = ib.Params(clearance=5e-4, omega=200.0)
    problem = BeamOrbits(params, "omega", n_modes=3)
    assert problem.gap_round_off == pytest.approx(1e3 * np.finfo(float).eps * 5e-4, rel=1e-15)
    near = Point(np.zeros(2), np.array([0.0, 1.0]),
                 Evaluation(np.zeros(1), np.zeros((1, 1)), np.ones(1), grazing=5.8e-10), 1)
    follower = Follower(problem, Scaling(np.ones(12), 1.0), Settings())
    assert _value_tolerance(follower, grazing_test, near) == problem.gap_round_off
    far = dataclasses.replace(near, evaluation=dataclasses.replace(near.evaluation,
                                                                   grazing=1e-3))
    assert _value_tolerance(follower, grazing_test, far) == pytest.approx(1e-14)


@pytest.mark.parametrize(("other", "sampled"), [(0.5, False), (0.9, True), (1.1, True)])
def test_a_step_is_sampled_for_hidden_crossings_where_another_multiplier_is_near(other,
                                                                                  sampled):
    """A step where one multiplier crosses (1.02 to 0.98: moduli change 0.04 at most) is
    searched in pieces only if another lies within 4 x 0.04 of the circle at an end: only
    such a one could leave and return within the step unseen at its ends."""
    from impactbeams.continuation.branch import _may_hide_crossings

    def point(moduli):
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.array(moduli, complex))
        return Point(np.zeros(2), np.array([0.0, 1.0]), evaluation, 1)

    a, b = point([1.02, other, 0.3]), point([0.98, other, 0.3])
    assert _may_hide_crossings(a, b, crossings=1) == sampled


@pytest.mark.parametrize(("second", "sampled"), [(None, False), (0.95, True)])
def test_a_complex_pair_is_one_multiplier_near_the_circle(second, sampled):
    """A pair crossing the circle (a Neimark-Sacker point, moduli 1.02 to 0.98) is one
    crossing: its conjugate is not another multiplier that could hide a crossing (main
    counted it, and sampled every step over a Neimark-Sacker point in 16 pieces); a second
    pair within 4 x 0.04 of the circle is."""
    from impactbeams.continuation.branch import _may_hide_crossings

    def point(modulus):
        pairs = [modulus] + ([] if second is None else [second])
        angles = (0.7, 2.1)[:len(pairs)]
        mu = [r * np.exp(s * 1j * angle) for r, angle in zip(pairs, angles, strict=True)
              for s in (1, -1)]
        evaluation = Evaluation(np.zeros(1), np.zeros((1, 1)), np.array([*mu, 0.3], complex))
        return Point(np.zeros(2), np.array([0.0, 1.0]), evaluation, 1)

    assert _may_hide_crossings(point(1.02), point(0.98), crossings=1) == sampled


@pytest.mark.parametrize(("options", "refused"), [
    (["--slice", "omega=200"], "values (--slice) = {'omega': '200'} is not allowed"),
    (["--slice", "bogus=1"], "values (--slice) = {'bogus': '1'} is not allowed"),
    (["--slice-index", "branch_point=0"], "indices (--slice-index) = {'branch_point': '0'}"),
    (["--log"], "scale (--log / --linear) = 'log' is not allowed"),
    (["--contours", "3"], "contours (--contours) = 3 is not allowed"),
])
def test_options_a_continuation_plot_would_ignore_are_refused(tmp_path, capsys, options,
                                                              refused):
    """--slice, --slice-index, a colour scale and contours mean nothing to the branches drawn
    whole along their parameter: refused in one line, not silently ignored."""
    from impactbeams.cli import main

    branches = follow(toys.period_doubling(), [0.0, 0.0], -0.5, -0.5, 0.5)
    branches_dataset(branches, "omega", {"title": "toy"}).to_netcdf(tmp_path / "cont.nc")
    assert main(["plot", str(tmp_path / "cont.nc"), "--var", "amplitude", *options]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"impactbeams: error: {refused}")
    assert line.endswith("a continuation's branches, drawn whole along their parameter, "
                         "take none")
    assert not (tmp_path / "cont.png").exists()


def test_plot_draws_next_to_its_input_by_default(tmp_path, capsys):
    """Without -o the figure is IN.png beside IN.nc (plot had no default output)."""
    from impactbeams.cli import main

    branches = follow(toys.period_doubling(), [0.0, 0.0], -0.5, -0.5, 0.5)
    branches_dataset(branches, "omega", {"title": "toy"}).to_netcdf(tmp_path / "cont.nc")
    assert main(["plot", str(tmp_path / "cont.nc"), "--var", "amplitude"]) == 0
    assert capsys.readouterr().err == f"wrote {tmp_path / 'cont.png'}\n"
    assert (tmp_path / "cont.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["plot", str(tmp_path / "cont.nc"), "--var", "amplitude", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


EPS = np.finfo(float).eps


class _Counted(toys.Map):
    """A toy map that counts its runs: evaluations at another (z, p) than the one before.

    As the beams' period map, which keeps its last run (a Jacobian there costs no new run).
    """

    runs, last = 0, None

    def evaluate(self, z, p, jacobian=True, grazing=True):
        key = (z.tobytes(), p)
        type(self).runs += key != type(self).last
        type(self).last = key
        return super().evaluate(z, p, jacobian, grazing)


@pytest.mark.parametrize("chord_check", [1e-6, 0.0])
def test_the_chord_check_finds_newtons_point_with_a_run_less(chord_check, monkeypatch):
    # the fold toy's branch z1^2 + 0.04 z1 = p, z2 = 0.4 z1: from a step of 0.05 Newton's
    # third correction is below the tolerance. With the chord check the second one's run
    # confirms it (a chord step with the second Jacobian), dr/dz is taken there, and the point
    # is as exact (round-off of values near 1: a few eps)
    toy = toys.fold()
    problem = _Counted(toy.step, toy.jac)
    from impactbeams.continuation import arclength

    monkeypatch.setattr(arclength, "CHORD_CHECK", chord_check)
    follower = arclength.Follower(problem, Scaling(np.ones(2), 1.0), SETTINGS)
    start = follower.at_parameter(np.array([1.0, 0.4, 1.04]), np.array([0.0, 0.0, 1.0])).point
    _Counted.runs = 0
    point = follower.at_arclength(start, 0.05).point
    z1, z2, p = point.x
    assert abs(z1 ** 2 + 0.04 * z1 - p) <= 4 * EPS and abs(z2 - 0.4 * z1) <= 4 * EPS
    # the multipliers are the point's own (those of dP/dz at its z1), not an iterate's
    exact = np.sort(np.linalg.eigvals(np.eye(2) + np.array([[2 * z1, 0.1], [0.2, -0.5]])))
    assert np.sort(point.evaluation.multipliers) == pytest.approx(exact, abs=1e-13)
    # Newton: 3 iterates with dr/dp each (a run more), and the point's run: 7 runs. With the
    # check: 2 iterates with dr/dp, and the check's run, where dr/dz is taken and which is the
    # point's too (the chord is round-off here): 5
    assert point.iterations == 3
    assert _Counted.runs == (5 if chord_check else 7)


def test_a_step_that_turned_too_far_reads_its_points_grazing_value_not_its_iterates():
    # on the fold toy a step of 0.5 from z1 = 0.2 turns the tangent by more than max_angle
    # (0.25 rad) round the fold at z1 = -0.02: the step is halved, and whether a grazing lies
    # ahead is read from the turned point's own grazing value (no iterate is run again)
    from impactbeams.continuation import arclength

    toy = toys.fold()
    problem = toys.Map(toy.step, toy.jac, gap=lambda z, p: z[0] + 1.0)  # no grazing near
    follower = arclength.Follower(problem, Scaling(np.ones(2), 1.0), SETTINGS)
    start = follower.at_parameter(np.array([0.2, 0.08, 0.048]),
                                  np.array([0.0, 0.0, -1.0])).point
    turned = follower.at_arclength(start, 0.5).point
    assert turned is not None and arclength._turn(start, turned) > SETTINGS.max_angle

    def refused(correction):
        raise AssertionError("a converged point's iterates were run again")

    follower.grazing_values = refused
    point, taken, grazing = follower.step(start, 0.5)
    assert point is not None and taken < 0.5 and grazing == ()
    assert arclength._turn(start, point) <= SETTINGS.max_angle


def test_the_chord_check_keeps_to_the_iterations_allowed():
    # the step of 0.05 on the fold toy takes Newton 3 iterations: with 2 allowed it fails, the
    # chord check (Newton's third correction in effect) included
    from impactbeams.continuation import arclength

    toy = toys.fold()
    settings = dataclasses.replace(SETTINGS, max_iterations=2)
    follower = arclength.Follower(toy, Scaling(np.ones(2), 1.0), settings)
    start = follower.at_parameter(np.array([1.0, 0.4, 1.04]), np.array([0.0, 0.0, 1.0])).point
    assert arclength.Follower(toy, Scaling(np.ones(2), 1.0), SETTINGS).at_arclength(
        start, 0.05).point.iterations == 3
    assert follower.at_arclength(start, 0.05).point is None


@pytest.mark.parametrize("turn_aim", [None, 0.8])
def test_steps_that_aim_at_a_turn_are_seldom_refused(monkeypatch, turn_aim):
    """On a circle of radius 1 a step ds turns the tangent by ds: a step grown by 1.5 after
    each quick correction (a loose tolerance: two or three iterations) is refused for its turn
    at every other step or so (the old control: 20 of 45); aiming at 0.8 max_angle, never,
    with steps of 0.8 max_angle, and the same folds (p = +-1)."""
    refused, corrections = [], []
    turn = arclength._turn

    def counted(start, point):
        angle = turn(start, point)
        refused.append(angle > SETTINGS.max_angle)
        return angle

    correct = arclength.Follower.correct
    monkeypatch.setattr(arclength, "_turn", counted)
    monkeypatch.setattr(arclength.Follower, "correct",
                        lambda *a, **k: corrections.append(1) or correct(*a, **k))
    settings = Settings(step=0.01, max_step=1.0, max_angle=0.25, max_branches=1,
                        tolerance=1e-6, turn_aim=turn_aim)
    (branch,) = follow(toys.circle(), [math.sqrt(1.0 - 0.9**2), 0.0], 0.9, -2.0, 2.0,
                       settings=settings)
    folds = [point.parameter(Scaling(np.ones(2), 1.0)) for point in labelled(branch, "fold")]
    assert folds == pytest.approx([1.0, -1.0], abs=LOCATED)
    refusals = sum(refused)
    if turn_aim is None:
        assert refusals >= 0.3 * len(branch.points)
    else:
        assert refusals == 0
        steps = np.linalg.norm(np.diff([point.x for point in branch.points], axis=0), axis=1)
        assert np.median(steps) == pytest.approx(0.8 * 0.25, rel=0.01)


def test_turn_aim_is_a_fraction_of_max_angle():
    for bad in (0.0, 1.0, -0.5, 2.0):
        with pytest.raises(ParameterError, match=f"turn_aim = {bad!r} is not allowed"):
            Settings(turn_aim=bad)


def test_a_difference_narrowed_to_the_end_is_divided_by_its_own_step():
    """dr/dp where every narrowed step still straddles a change of the contacts (a contact
    at p itself): the last difference over its own step. The old loop narrowed the step once
    more after its last run: dr/dp came out 1000 times too large."""
    class Straddled:
        def evaluate(self, z, p, jacobian=True, grazing=True):
            return Evaluation(np.array([3.0 * p]), np.empty((0, 0)), np.empty(0),
                              contacts=int(p > 2.0))

    problem = Straddled()
    rate = parameter_derivative(problem, np.zeros(1), 2.0, 1.0, problem.evaluate(None, 2.0))
    # (the last step is 3e-14 of p: its difference carries eps |r| / h ~ 1 % of round-off)
    assert rate == pytest.approx([3.0], rel=0.05)


def _on_parabola(s):
    """A stand-in point at s of the branch x~(s) = (s^2, 1 - 3 s^2, s)."""
    evaluation = Evaluation(np.zeros(2), np.zeros((2, 2)), np.ones(2))
    return Point(np.array([s * s, 1.0 - 3.0 * s * s, s]), np.array([0.0, 0.0, 1.0]),
                 evaluation, 1)


def test_a_solves_guess_is_the_branch_through_the_brackets_ends():
    """Between the ends 0.2 and 0.3 of a bracket, a point at 0.5 makes the guess the branch
    itself (a parabola, to round-off); without it, or with it nearer the bracket than
    BEND_DISTANCE widths (its weights would amplify round-off), the chord between the ends;
    without a corrected point at an end, no guess."""
    from impactbeams.continuation.events import BEND_DISTANCE, guess_at

    low, high = ((s, 0.0, _on_parabola(s)) for s in (0.2, 0.3))
    far, near = ((s, _on_parabola(s)) for s in (0.5, 0.3 + 0.5 * BEND_DISTANCE * 0.1))
    bent = guess_at(low, high, 0.26, (far,))
    np.testing.assert_allclose(bent, _on_parabola(0.26).x, rtol=0, atol=4e-16)
    chord = 0.4 * low[2].x + 0.6 * high[2].x
    np.testing.assert_allclose(guess_at(low, high, 0.26, (near,)), chord, rtol=0, atol=4e-16)
    np.testing.assert_allclose(guess_at(low, high, 0.26), chord, rtol=0, atol=4e-16)
    assert np.abs(chord - _on_parabola(0.26).x).max() > 1e-3  # the bend is not round-off
    assert guess_at(low, (0.3, math.nan, None), 0.26, (far,)) is None


def test_located_solves_start_from_the_guess(monkeypatch):
    """The fold of test_fold_located_where_the_determinant_vanishes, located with each solve
    started from the guess between the bracket's ends and from the tangent's point: the same
    fold to the location tolerance, in fewer linearisations (measured: 190 against 205 over
    the whole branch, whose steps are the same)."""
    from impactbeams.continuation import events

    def followed():
        problem, linearised = toys.fold(), []
        evaluate = problem.evaluate
        problem.evaluate = lambda z, p, jacobian=True, grazing=True: (
            linearised.append(jacobian) or evaluate(z, p, jacobian, grazing))
        (branch, *_) = follow(problem, [1.0, 0.4], 1.04, -1.0, 2.0, direction=-1,
                              settings=Settings(step=0.05, max_step=0.1, max_branches=1))
        (fold,) = labelled(branch, "fold")
        return fold.x[-1], sum(linearised)

    guessed, with_guess = followed()
    monkeypatch.setattr(events, "guess_at", lambda *_: None)
    tangent, without = followed()
    assert guessed == pytest.approx(-4e-4, abs=LOCATED)
    assert tangent == pytest.approx(-4e-4, abs=LOCATED)
    assert with_guess < without
