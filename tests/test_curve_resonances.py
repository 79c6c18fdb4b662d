"""Codimension-two points of Neimark-Sacker curves (issue 34): strong resonances, fold-NS.

The beam models within reach have Neimark-Sacker curves whose pair's argument stays away from
0 and pi (the small model's, followed in Omega and the force, clearance, damping or contact
stiffness, have cos theta between -0.07 and 0.9 before their orbits graze): the 1:1, 1:2 and
1:3 resonances, where the curve ends, are checked on a constructed map
(`continuation_toys.resonant_torus`) whose curve and points are known exactly, followed by
the curves' own step loop; the 1:4 resonance and the fold- and flip-Neimark-Sacker points
that the small model's curves meet are checked against one-parameter branches.
"""

import math

import numpy as np
import pytest

import impactbeams as ib
from continuation_toys import CurveMap, resonant_torus
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.continuation.arclength import Follower, Scaling, Settings
from impactbeams.continuation.branch import MIN_STEP, Branch, Position, Steps
from impactbeams.continuation.curves import UnitPair, pair_cosine
from impactbeams.continuation.twoparameter import (
    PAIR_REAL,
    BifurcationCurve,
    _keep,
    _steps,
    continue_curve,
)
from impactbeams.params import ParameterError
from impactbeams.variables import BIFURCATIONS, CURVE_EVENTS, validate

# the toy's curve points solve the system to Newton's 1e-10 (x~ = the unknowns themselves),
# its events are located until p2 is known to the engine's locate_tolerance, 1e-11
LOCATED = 1e-9


def follow_toy(fold_at, p2, direction, ends_at=math.inf):
    """The toy's Neimark-Sacker curve from (p1, p2) = (0, ``p2``), on its fixed points of
    x > 0, followed ``direction`` (+1 up, -1 down in p2) within |p1| <= 1, |p2| <= 2; past
    p2 = ``ends_at`` the map has no orbit (its evaluation raises, as a beam run that stops)."""
    step, jacobian = resonant_torus(fold_at)

    def existing(function):
        def where_it_exists(z, p1, p2):
            if p2 > ends_at:
                raise RuntimeError("no orbit beyond ends_at")
            return function(z, p1, p2)
        return where_it_exists

    problem = CurveMap(existing(step), existing(jacobian), UnitPair())
    scaling = Scaling(np.ones(4), 1.0)
    settings = Settings(step=0.02, min_step=1e-9, max_step=0.05, max_points=400,
                        max_branches=1)
    follower = Follower(problem, scaling, settings)
    orientation = np.zeros(5)
    orientation[-1] = direction
    start = np.array([0.0, 0.0, math.sqrt(p2 - fold_at), 0.0, p2])
    first = follower.at_parameter(start, orientation).point
    curve = Branch([], 1, scaling)
    _keep(follower, curve, [first], None)
    _steps(follower, curve, np.array([[-1.0, 1.0], [-2.0, 2.0]]), None,
           Position(first, settings.step, Steps()))
    return curve


def labelled(curve):
    return [(point.label, float(point.x[-1]), point) for point in curve.points if point.label]


def test_a_curve_whose_orbit_stops_existing_ends_there():
    """Past p2 = 0.5 the toy has no orbit: the steps shrink against it to min_step and the
    curve ends there ("min_step"), its last point within 100 min_step (1e-9) of p2 = 0.5 (a
    failed step is halved, a taken one lengthened again: measured 1.5e-8 short), with no
    event labelled on the way (cos theta = p2 runs from 0.2 to 0.5: no strong resonance)."""
    curve = follow_toy(-1.2, 0.2, +1, ends_at=0.5)
    assert curve.ending == MIN_STEP
    last = float(curve.points[-1].x[-1])
    assert 0.5 - 1e-7 < last <= 0.5
    assert labelled(curve) == []


def test_the_pair_turning_real_ends_the_curve_at_1_1():
    """Up from cos theta = 0.9: the pair meets at +1 at p2 = 1 (1:1); the curve ends there."""
    curve = follow_toy(-1.2, 0.9, +1)
    assert curve.ending == PAIR_REAL
    ((label, p2, point),) = labelled(curve)
    assert label == "resonance_1_1" and point is curve.points[-1]
    assert p2 == pytest.approx(1.0, abs=LOCATED)
    assert abs(point.x[-2]) < LOCATED  # on the curve p1 = 0
    # the pair on the circle at every point (the last within its Newton correction of it)
    assert all(abs(pair_cosine(p.evaluation.multipliers)) <= 1.0 + LOCATED
               for p in curve.points)


def test_resonances_down_to_1_2_where_the_curve_ends():
    """Down from cos theta = 0.9: 1:4 at p2 = 0; a flip-Neimark-Sacker point at p2 = -0.2
    (x = 1: its multiplier 1 - 2 x at -1); 1:3 at -1/2; then the pair meets at -1 (1:2) at
    p2 = -1, where the curve ends; every point's pair on the circle."""
    curve = follow_toy(-1.2, 0.9, -1)
    assert curve.ending == PAIR_REAL
    found = labelled(curve)
    assert [label for label, _, _ in found] == ["resonance_1_4", "flip_neimark_sacker",
                                               "resonance_1_3", "resonance_1_2"]
    for (label, p2, point), exact in zip(found, (0.0, -0.2, -0.5, -1.0), strict=True):
        assert p2 == pytest.approx(exact, abs=LOCATED)
        mu = point.evaluation.multipliers
        assert np.min(np.abs(np.abs(mu) - 1.0)) < LOCATED
        if label == "flip_neimark_sacker":
            assert np.min(np.abs(mu + 1.0)) < LOCATED
        else:
            cosine = {"resonance_1_4": 0.0, "resonance_1_3": -0.5, "resonance_1_2": -1.0}
            assert pair_cosine(mu) == pytest.approx(cosine[label], abs=LOCATED)
    assert found[-1][2] is curve.points[-1]
    moduli = [np.sort(np.abs(np.abs(p.evaluation.multipliers) - 1.0))[:2].max()
              for p in curve.points]
    assert max(moduli) < 1e-9  # the pair on the unit circle at every point


def test_a_fold_neimark_sacker_point_where_the_curve_turns():
    """With the fold of x at p2 = 0.3: down from 0.9 the curve meets the fold (a real
    multiplier 1 - 2 x through +1, the curve turning back in p2) at p2 = 0.3, then returns
    on the fixed points x < 0 up to the 1:1 point."""
    curve = follow_toy(0.3, 0.9, -1)
    found = labelled(curve)
    names = [label for label, _, _ in found]
    assert names[-1] == "resonance_1_1" and curve.ending == PAIR_REAL
    assert sorted(names[:-1]) == ["fold_neimark_sacker", "turning_point"]
    for _, p2, point in found[:-1]:
        assert p2 == pytest.approx(0.3, abs=LOCATED)
        assert abs(point.x[2]) < 1e-5  # x = sqrt(p2 - 0.3): to the square root of it
    fold = next(point for label, _, point in found if label == "fold_neimark_sacker")
    mu = fold.evaluation.multipliers
    assert np.min(np.abs(mu - 1.0)) < 1e-5


SMALL = ib.Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5,
                  clearance=1.1e-5)


@pytest.fixture(scope="module")
def torus_branch_down():
    """The small model's one-contact orbits from 244 rad/s down: a Neimark-Sacker at 243.83."""
    continuation = Continuation(SMALL, "omega", 236.0, 246.0, start=244.0, direction="down",
                                n_modes=3, max_branches=1, max_points=60,
                                transient_periods=600)
    return continuation, continue_orbits(continuation)


@pytest.fixture(scope="module")
def torus_in_force(torus_branch_down):
    """The small model's Neimark-Sacker curve followed down in F0: it turns at 12.98 uN, then
    meets two fold-Neimark-Sacker points and a 1:4 resonance before its orbit grazes."""
    curve = continue_curve(BifurcationCurve.from_branch(
        *torus_branch_down, "neimark_sacker", "force_amplitude", 1e-6, 3e-4,
        direction="down", box=(150.0, 400.0), max_points=300))
    validate(curve)
    return curve


def test_the_small_models_curve_meets_a_1_4_resonance(torus_in_force):
    """At the resonance's force the one-parameter branch in Omega locates its
    Neimark-Sacker at the resonance's frequency, and its multipliers there (`periodic_orbit`'s
    orbit, the eigenvalues of its monodromy) have the pair at +-i."""
    curve = torus_in_force
    names = [CURVE_EVENTS[code] for code in curve.curve_event.values if code]
    assert names == ["turning_point", "fold_neimark_sacker", "resonance_1_4",
                     "fold_neimark_sacker", "grazing"]
    (i,) = np.flatnonzero(curve.curve_event.values == CURVE_EVENTS.index("resonance_1_4"))
    assert abs(float(curve.curve_pair_cosine[i])) < 1e-9
    omega, force = float(curve.omega[i]), float(curve.force_amplitude[i])
    branch = continue_orbits(Continuation(
        SMALL.replace(force_amplitude=force), "omega", omega - 0.3, omega + 0.3,
        start=omega + 0.3, direction="down", state=curve.section_state.values[i],
        transient_periods=0, n_modes=3, max_branches=1))
    at = np.flatnonzero(branch.bifurcation.values == BIFURCATIONS.index("neimark_sacker"))
    located = branch.omega.values[at]
    j = at[np.argmin(np.abs(located - omega))]
    assert float(branch.omega[j]) == pytest.approx(omega, rel=1e-9, abs=0.0)
    orbit = ib.periodic_orbit(SMALL.replace(force_amplitude=force, omega=float(branch.omega[j])),
                              3, guess=branch.section_state.values[j], method="newton")
    assert np.min(np.abs(orbit.multipliers - 1j)) < 1e-6


def _branch_to_fold(force, omega, state):
    """The branch in Omega at ``force`` towards ``omega`` from 0.05 rad/s on the side of it
    where the orbits (folding at ``omega``) exist: started from the fold's ``state``."""
    for start in (omega - 0.05, omega + 0.05):
        try:
            return continue_orbits(Continuation(
                SMALL.replace(force_amplitude=force), "omega", omega - 0.3, omega + 0.3,
                start=start, direction="up" if start < omega else "down", state=state,
                transient_periods=0, n_modes=3, max_branches=1))
        except ParameterError:  # no orbit there: the fold's other side
            continue
    raise AssertionError(f"no orbit 0.05 rad/s on either side of {omega}")


def test_the_small_models_fold_neimark_sacker_points(torus_in_force):
    """At each fold-Neimark-Sacker point's force, the one-parameter branch in Omega (started
    0.05 rad/s from it on the side where its orbits exist) locates a fold and a
    Neimark-Sacker, both at the point's frequency."""
    curve = torus_in_force
    for i in np.flatnonzero(curve.curve_event.values == CURVE_EVENTS.index(
            "fold_neimark_sacker")):
        omega = float(curve.omega[i])
        branch = _branch_to_fold(float(curve.force_amplitude[i]), omega,
                                 curve.section_state.values[i])
        for label in ("fold", "neimark_sacker"):
            located = branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index(label)]
            assert np.min(np.abs(located - omega)) <= 1e-9 * omega


def test_the_curves_codimension_two_points_are_drawn_and_labelled(torus_in_force):
    """`draw_curve` marks the resonance and the fold-Neimark-Sacker points, labelled R4 and
    LPNS, at their points."""
    from matplotlib.figure import Figure

    from impactbeams.plotting.curves import draw_curve

    axes = Figure().subplots()
    draw_curve(axes, torus_in_force)
    texts = sorted(text.get_text() for text in axes.texts)
    assert texts == ["G", "LPNS", "LPNS", "R4", "T"]
    (i,) = np.flatnonzero(torus_in_force.curve_event.values == CURVE_EVENTS.index(
        "resonance_1_4"))
    stars = [line for line in axes.lines if line.get_marker() == "*"]
    assert len(stars) == 1 and stars[0].get_xdata()[0] == float(torus_in_force.omega[i])


def test_the_small_models_flip_neimark_sacker_points(torus_branch_down):
    """The same curve followed down in the contact stiffness meets two flip-Neimark-Sacker
    points (a real multiplier through -1) before its orbit grazes: at each one's stiffness
    the one-parameter branch in Omega locates a Neimark-Sacker and a period doubling at its
    frequency."""
    curve = continue_curve(BifurcationCurve.from_branch(
        *torus_branch_down, "neimark_sacker", "contact_stiffness", 1e2, 1e7,
        direction="down", box=(150.0, 400.0), max_points=300))
    flips = np.flatnonzero(curve.curve_event.values == CURVE_EVENTS.index(
        "flip_neimark_sacker"))
    assert flips.size == 2
    for i in flips:
        omega = float(curve.omega[i])
        mu = curve.multiplier_modulus.values[i] * np.exp(1j * curve.multiplier_argument.values[i])
        assert np.min(np.abs(mu + 1.0)) < 1e-6
        branch = continue_orbits(Continuation(
            SMALL.replace(contact_stiffness=float(curve.contact_stiffness[i])), "omega",
            omega - 0.3, omega + 0.3, state=curve.section_state.values[i],
            transient_periods=0, n_modes=3, max_branches=1, start=omega - 0.3))
        for label in ("neimark_sacker", "period_doubling"):
            located = branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index(label)]
            assert np.min(np.abs(located - omega)) <= 1e-9 * omega
