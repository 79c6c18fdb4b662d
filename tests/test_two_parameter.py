"""Bifurcation curves in two parameters (issue 34, item 1): grazing, fold, codimension two.

Each continued curve is checked against an independent computation: the grazing curve of the
non-impacting orbit against the closed form through the modal sums (`grazing_curve`), its
turning point against the maximum of the closed form's |G(Omega)|, a fold curve against the
folds that one-parameter branches locate at five drive levels, the cusp where two fold curves
meet against one-parameter branches on both sides of it (two folds above its drive, none
below).
"""

import numpy as np
import pytest
import xarray as xr
from scipy.optimize import minimize_scalar

import impactbeams as ib
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.continuation.twoparameter import BifurcationCurve, continue_curve
from impactbeams.orbits.grazing import LinearGap
from impactbeams.params import ParameterError
from impactbeams.variables import BIFURCATIONS, CURVE_EVENTS, validate

# the continuation tests' small model: two beams, a stiff spring, 3 modes per beam
SMALL = ib.Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5,
                  clearance=1.1e-5)
# the shipped example's soft stop, 3 modes: a hysteresis band between two folds at 1e-4 N
STOP = ib.Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                 force_amplitude=1e-4)
FOLD = BIFURCATIONS.index("fold")
# a curve point solves the augmented system to Newton's 1e-10 of the scaled unknowns (the
# parameters per their ranges, O(1) here), and a one-parameter branch locates an event to
# 1e-11 of its range: the brief's 1e-9 relative
AGREE = 1e-9


def event(curve, label):
    return np.flatnonzero(curve.curve_event.values == CURVE_EVENTS.index(label))


@pytest.fixture(scope="module")
def small_branch():
    """The small model's non-impacting orbits up to its first grazing (234.73 rad/s)."""
    continuation = Continuation(SMALL, "omega", 225.0, 240.0, n_modes=3, max_branches=1,
                                max_points=20)
    return continuation, continue_orbits(continuation)


@pytest.fixture(scope="module")
def stop_branch():
    continuation = Continuation(STOP, "omega", 195.0, 330.0, n_modes=3, subspace=4,
                                max_branches=1)
    return continuation, continue_orbits(continuation)


@pytest.fixture(scope="module")
def small_grazing(small_branch):
    """The small model's grazing curve in F0 from 3e-5 up to 4e-5 N (Omega from 234.73 down
    to 230.15 rad/s)."""
    return continue_curve(BifurcationCurve.from_branch(*small_branch, "grazing",
                                                       "force_amplitude", 2e-5, 4e-5,
                                                       max_step=0.02))


def test_grazing_curve_is_the_closed_form_at_every_point(small_grazing):
    curve = small_grazing
    validate(curve)
    assert curve.branch_point.size >= 20 and curve.attrs["curve_ending"] == "bound"
    closed = ib.grazing_curve(SMALL, 3, "force_amplitude", curve.omega.values)
    np.testing.assert_allclose(curve.force_amplitude.values, closed.force_amplitude.values,
                               rtol=AGREE, atol=0.0)
    # it starts at the branch's located grazing and moves along the curve (Omega falls)
    assert curve.force_amplitude.values[0] == SMALL.force_amplitude
    assert np.all(np.diff(curve.omega.values) < 0.0)
    assert curve.force_amplitude.values[-1] == 4e-5  # ended on the box's edge
    assert list(event(curve, "end")) == [curve.branch_point.size - 1]


def test_grazing_curve_turns_where_the_closed_forms_clearance_is_largest(small_branch):
    """In (Omega, clearance) the grazing curve is Delta = |G(Omega)|: it turns at the
    resonance, the maximum of |G| (found by Brent's method on the closed form)."""
    curve = continue_curve(BifurcationCurve.from_branch(
        *small_branch, "grazing", "clearance", 5e-6, 5e-5, box=(200.0, 300.0)))
    (turn,) = event(curve, "turning_point")
    linear = LinearGap(SMALL, 3)
    peak = minimize_scalar(lambda omega: -abs(complex(linear.phasor(omega))),
                           bracket=(240.0, 246.0, 250.0), tol=1e-12)
    # the clearance is flat at the turn: known to the corrector's tolerance; Omega there to
    # the square root of it (the turn is located where the tangent's part vanishes)
    assert float(curve.clearance[turn]) == pytest.approx(-peak.fun, rel=AGREE)
    assert float(curve.omega[turn]) == pytest.approx(peak.x, rel=1e-6)
    # located until F0 is pinned to 1e-11 of its range: the tangent's part, ~ the arclength
    # from the turn, to ~1e-11 over the parameter's rate there (~1e-3)
    assert abs(float(curve.curve_tangent_2[turn])) < 1e-6
    assert float(curve.clearance.max()) == float(curve.clearance[turn])


def _located(params, omega, state, label="fold", width=1.0):
    """The ``label`` event the one-parameter branch locates going up from ``omega - width``
    to ``omega + width`` (its only one there)."""
    branch = continue_orbits(Continuation(params, "omega", omega - width, omega + width,
                                          state=state, n_modes=3, subspace=4,
                                          max_branches=1, transient_periods=0))
    (located,) = branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index(label)]
    return float(located)


def _curve_to_level(started, kind, level):
    """The drive level times the start's and the curve's end there (on the range's edge)."""
    continuation, branch = started
    start = continuation.params.force_amplitude
    force = level * start
    low, high, direction = (force, start, "down") if level < 1 else (start, force, "up")
    curve = continue_curve(BifurcationCurve.from_branch(continuation, branch, kind,
                                                        "force_amplitude", low, high,
                                                        direction=direction))
    end = curve.isel(branch_point=-1)
    assert curve.attrs["curve_ending"] == "bound" and float(end.force_amplitude) == force
    return force, end


@pytest.mark.parametrize("level", [0.6, 0.8, 1.2, 1.4, 1.6])
def test_fold_curve_passes_through_the_one_parameter_folds(stop_branch, level):
    """The fold curve from the upper fold at 1e-4 N, ended on the drive level's edge, is at
    the fold a one-parameter branch in Omega locates at that level (started from the curve's
    orbit 1 rad/s below: the guess only, the fold is the branch's own)."""
    force, end = _curve_to_level(stop_branch, "fold", level)
    assert abs(float(end.curve_condition)) < 1e-9
    located = _located(STOP.replace(force_amplitude=force), float(end.omega),
                       end.section_state.values)
    assert float(end.omega) == pytest.approx(located, rel=AGREE, abs=0.0)


@pytest.fixture(scope="module")
def doubling_branch():
    """The small model's impacting orbits (one contact) from 244 rad/s up: they double their
    period at 244.73 rad/s."""
    continuation = Continuation(SMALL, "omega", 236.0, 246.0, start=244.0, n_modes=3,
                                max_branches=1, max_points=60, transient_periods=600)
    return continuation, continue_orbits(continuation)


@pytest.mark.parametrize("level", [0.8, 0.9, 1.1, 1.2, 1.3])
def test_period_doubling_curve_passes_through_the_one_parameter_doublings(doubling_branch,
                                                                          level):
    """As the fold curve's test: the period-doubling curve (a multiplier at -1) ended on the
    drive level's edge, against the doubling a one-parameter branch locates there."""
    force, end = _curve_to_level(doubling_branch, "period_doubling", level)
    mu = end.multiplier_modulus.values * np.exp(1j * end.multiplier_argument.values)
    assert np.min(np.abs(mu + 1.0)) < 1e-9  # the eigenvalues of M: a multiplier at -1
    located = _located(SMALL.replace(force_amplitude=force), float(end.omega),
                       end.section_state.values, "period_doubling", width=0.2)
    assert float(end.omega) == pytest.approx(located, rel=AGREE, abs=0.0)


@pytest.fixture(scope="module")
def torus_branch():
    """The small model's one-contact orbits from 244 rad/s down: a complex pair of
    multipliers leaves the unit circle at 243.83 rad/s (Neimark-Sacker)."""
    continuation = Continuation(SMALL, "omega", 236.0, 246.0, start=244.0, direction="down",
                                n_modes=3, max_branches=1, max_points=60,
                                transient_periods=600)
    return continuation, continue_orbits(continuation)


@pytest.mark.parametrize("level", [0.7, 0.85, 1.1, 1.2, 1.3])
def test_neimark_sacker_curve_passes_through_the_one_parameter_ones(torus_branch, level):
    """As the fold curve's test, for a pair on the unit circle (the bialternate product's
    test function): its end on the drive level against the one-parameter branch's."""
    force, end = _curve_to_level(torus_branch, "neimark_sacker", level)
    mu = end.multiplier_modulus.values * np.exp(1j * end.multiplier_argument.values)
    pair = mu[mu.imag > 0]
    assert np.min(np.abs(np.abs(pair) - 1.0)) < 1e-9  # the eigenvalues of M: |mu| = 1
    located = _located(SMALL.replace(force_amplitude=force), float(end.omega),
                       end.section_state.values, "neimark_sacker", width=0.2)
    assert float(end.omega) == pytest.approx(located, rel=AGREE, abs=0.0)


def test_neimark_sacker_curve_ends_where_its_orbits_contacts_change(torus_branch):
    """Followed down in the contact stiffness, the Neimark-Sacker curve turns, then its orbit
    gains a contact (a free-flight minimum of the gap reaches 0): the monodromy jumps there,
    so the curve ends, labelled (the old code stepped across and went on to 1e7 N/m on the
    orbits of two contacts). Its end is the one-parameter branch's Neimark-Sacker at the
    end's stiffness (started 0.3 rad/s above from the end's orbit)."""
    curve = continue_curve(BifurcationCurve.from_branch(
        *torus_branch, "neimark_sacker", "contact_stiffness", 1e2, 1e7, direction="down",
        box=(150.0, 400.0), max_points=300))
    assert curve.attrs["curve_ending"] == "grazing"
    assert list(event(curve, "grazing")) == [curve.branch_point.size - 1]
    assert np.all(curve.contacts_per_orbit.values == 1)
    gaps = np.abs(curve.grazing_gap.values)
    assert gaps[-1] <= 1e-3 * gaps.max()  # the gap's minimum at zero depth (ZERO_DEPTH)
    found = _coming_down_to(curve.isel(branch_point=-1), "contact_stiffness")
    assert found[0][0] == "neimark_sacker"
    assert found[0][1] == pytest.approx(float(curve.omega[-1]), rel=AGREE, abs=0.0)


def _coming_down_to(end, second, factor=1.0):
    """The events of the small model's branch in Omega at ``factor`` times the curve end's
    ``second`` parameter, coming down from 0.3 rad/s above the end from its orbit."""
    omega = float(end.omega)
    return _branch_events(SMALL.replace(**{second: factor * float(end[second])}), omega,
                          end.section_state.values, start=omega + 0.3, direction="down")


@pytest.fixture(scope="module")
def torus_clearance(torus_branch):
    """The Neimark-Sacker curve followed down in the clearance: it turns twice, then ends
    where its orbit grazes (234.858 rad/s, 3.732 um), a second contact beyond."""
    return continue_curve(BifurcationCurve.from_branch(
        *torus_branch, "neimark_sacker", "clearance", 1e-6, 1.1e-5, direction="down",
        box=(200.0, 300.0), max_points=300))


def test_neimark_sacker_curve_ends_at_its_grazing_from_any_start(torus_clearance):
    """Started on the curve 1 um above its grazing with long steps, the steps creep up to
    the grazing (no point past it): the end is labelled a grazing where its gap is at zero
    depth (the old code ended it 'min_step', unlabelled), at the curve's own end."""
    whole = torus_clearance
    assert whole.attrs["curve_ending"] == "grazing"
    i = int(np.argmax(whole.clearance.values < whole.clearance.values[-1] + 1e-6))
    start = whole.isel(branch_point=i)
    clearance = float(start.clearance)
    curve = continue_curve(BifurcationCurve(
        SMALL.replace(clearance=clearance), "neimark_sacker", "omega", float(start.omega),
        start.section_state.values, "clearance", 1e-6, clearance, 200.0, 300.0, 3,
        direction="down", step=0.05, max_step=0.05, max_points=60))
    assert curve.attrs["curve_ending"] == "grazing"
    assert list(event(curve, "grazing")) == [curve.branch_point.size - 1]
    for name in ("omega", "clearance"):
        assert float(curve[name][-1]) == pytest.approx(float(whole[name][-1]), rel=1e-8)


def test_past_the_neimark_sacker_grazing_point_the_one_contact_torus_is_gone(
        torus_clearance):
    """At the end's clearance the branch in Omega coming down locates the Neimark-Sacker at
    the end's frequency and its grazing 2e-9 below it (a pair outside on the two-contact
    side: the multipliers jump there); 1e-4 below that clearance, past the end, the orbits
    there have two contacts and the Neimark-Sacker points nearest the end's frequency are the
    two-contact orbit's own, 0.02 rad/s away: the curve does not go on across."""
    end = torus_clearance.isel(branch_point=-1)
    omega = float(end.omega)
    found = _coming_down_to(end, "clearance")
    assert found[0][0] == "neimark_sacker"
    assert found[0][1] == pytest.approx(omega, rel=AGREE, abs=0.0)
    assert found[1][0] == "grazing" and 0.0 < omega - found[1][1] < 1e-8 * omega
    past = _coming_down_to(end, "clearance", 1 - 1e-4)
    torus = [value for label, value in past if label == "neimark_sacker"]
    assert torus and min(abs(value - omega) for value in torus) > 1e-2

@pytest.mark.slow
def test_two_fold_curves_meet_at_a_cusp(stop_branch):
    """Both folds' curves, followed down in the drive, reach the same cusp, and go on as the
    other fold's; one-parameter branches 1 % above its drive have two folds, 1 % below none."""
    cusps = []
    for which in (0, 1):
        curve = continue_curve(BifurcationCurve.from_branch(
            *stop_branch, "fold", "force_amplitude", 1e-6, 2e-4, which=which,
            direction="down", max_points=400))
        (cusp,) = event(curve, "cusp")
        cusps.append((float(curve.omega[cusp]), float(curve.force_amplitude[cusp])))
        assert curve.attrs["curve_ending"] == "bound"
        assert abs(float(curve.curve_tangent_1[cusp])) < 1e-3
    assert cusps[0] == pytest.approx(cusps[1], rel=1e-9)
    omega, force = cusps[0]
    for factor, folds in ((1.01, 2), (0.99, 0)):
        branch = continue_orbits(Continuation(
            STOP.replace(force_amplitude=factor * force), "omega", omega - 8.0,
            omega + 8.0, n_modes=3, subspace=4, max_branches=1))
        assert np.count_nonzero(branch.bifurcation.values == FOLD) == folds


@pytest.mark.parametrize(("changes", "message"), [
    ({"kind": "hopf"}, "kind = 'hopf' is not allowed: must be one of 'grazing', 'fold'"),
    ({"second": "omega"}, "second = 'omega' is not allowed: must differ from parameter"),
    ({"state": np.zeros(3)}, "state = (3,) is not allowed: must be 6 finite numbers"),
    ({"low": 2e-4}, "force_amplitude = 0.0001 is not allowed: (the start's, from params)"),
    ({"max_step": 1.0, "step": 2.0}, "step = 2.0 is not allowed: must lie from min_step"),
])
def test_bad_input_in_one_line(changes, message):
    values = {"params": STOP, "kind": "fold", "parameter": "omega", "value": 300.0,
              "state": np.zeros(6), "second": "force_amplitude", "low": 5e-5, "high": 3e-4,
              "parameter_low": 200.0, "parameter_high": 400.0, "n_modes": 3, **changes}
    with pytest.raises(ParameterError) as error:
        BifurcationCurve(**values)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_a_start_off_the_bifurcation_is_refused(stop_branch):
    continuation, branch = stop_branch
    curve = BifurcationCurve.from_branch(continuation, branch, "fold", "force_amplitude",
                                         5e-5, 2e-4)
    far = BifurcationCurve(**{**curve.__dict__, "value": 250.0})
    with pytest.raises(ParameterError, match="did not converge to a fold"):
        continue_curve(far)


def test_an_event_the_branch_does_not_have_is_named(stop_branch):
    """A kind the branch located none of is refused naming the kind and what it located
    (not ``which = 0``, which the user may not have set); a ``which`` past its events names
    how many there are."""
    continuation, branch = stop_branch
    with pytest.raises(ParameterError, match=r"^kind = 'period_doubling' is not allowed: the "
                       r"branch located no period_doubling \(it located 2 fold, 2 grazing\)$"):
        BifurcationCurve.from_branch(continuation, branch, "period_doubling",
                                     "force_amplitude", 5e-5, 2e-4)
    with pytest.raises(ParameterError, match=r"^which = 2 is not allowed: the branch located "
                       r"2 fold event\(s\): must be below 2$"):
        BifurcationCurve.from_branch(continuation, branch, "fold", "force_amplitude", 5e-5,
                                     2e-4, which=2)


@pytest.fixture(scope="module")
def stiff_branch():
    """The small model's branch from 261.5 rad/s down: it folds back and forth four times,
    two of its folds just past grazings (the stiff spring's impacting orbits)."""
    continuation = Continuation(SMALL, "omega", 255.0, 268.0, start=261.5, direction="down",
                                n_modes=3, max_branches=1, max_points=150,
                                transient_periods=600)
    return continuation, continue_orbits(continuation)


def _branch_events(params, omega, state, **range_):
    branch = continue_orbits(Continuation(params, "omega", omega - 0.3, omega + 0.3,
                                          state=state, transient_periods=0, n_modes=3,
                                          max_branches=1, **range_))
    return [(BIFURCATIONS[code], float(branch.omega[i]))
            for i, code in enumerate(branch.bifurcation.values) if code]


@pytest.fixture(scope="module")
def fold_to_grazing(stiff_branch):
    """The fold at 266.05 rad/s followed down in F0: it turns, then ends where its orbit
    grazes (a third contact appears past it, and the fold has no smooth continuation)."""
    return continue_curve(BifurcationCurve.from_branch(*stiff_branch, "fold",
                                                       "force_amplitude", 1e-5, 6e-5,
                                                       which=3, direction="down"))


@pytest.mark.slow
def test_fold_curve_ends_where_its_fold_meets_the_grazing(fold_to_grazing):
    """At the curve's end drive, the one-parameter branch in Omega (started 0.3 rad/s above
    from the end's orbit) locates its fold and a grazing at the curve's end frequency."""
    curve = fold_to_grazing
    assert curve.attrs["curve_ending"] == "grazing"
    assert list(event(curve, "grazing")) == [curve.branch_point.size - 1]
    end = curve.isel(branch_point=-1)
    omega = float(end.omega)
    found = _branch_events(SMALL.replace(force_amplitude=float(end.force_amplitude)), omega,
                           end.section_state.values, start=omega + 0.3, direction="down")
    near = {label: [value for name, value in found if name == label and abs(value - omega)
                    < 1e-3] for label in ("fold", "grazing")}
    # (the orbit of three contacts past the grazing folds there too)
    assert near["fold"] and near["grazing"]
    np.testing.assert_allclose(near["fold"] + near["grazing"], omega, rtol=AGREE, atol=0.0)


@pytest.mark.slow
def test_past_the_fold_grazing_point_the_fold_is_gone(fold_to_grazing):
    """1e-6 below the end's drive, the branch coming down in Omega folds first, 1.4e-5 rad/s
    short of its grazing; 1e-6 above, it reaches the grazing first (its fold lay past it,
    where the contacts differ: the orbit of three contacts folds there on its own)."""
    end = fold_to_grazing.isel(branch_point=-1)
    omega, force = float(end.omega), float(end.force_amplitude)
    for factor, first in ((1 - 1e-6, "fold"), (1 + 1e-6, "grazing")):
        found = _branch_events(SMALL.replace(force_amplitude=factor * force), omega,
                               end.section_state.values, start=omega + 0.3, direction="down")
        near = [(label, value) for label, value in found if abs(value - omega) < 1e-3]
        assert near[0][0] == first
        if first == "fold":
            assert near[1][0] == "grazing" and 0.0 < near[1][1] - near[0][1] < 1e-7 * omega


@pytest.mark.slow
def test_a_jump_of_the_grazing_value_is_not_a_grazing(stiff_branch):
    """The fold at 261.03 rad/s followed down: its orbit's grazing value changes sign by a
    jump (another gap minimum becomes the nearest to 0, never at 0): no grazing labelled."""
    curve = continue_curve(BifurcationCurve.from_branch(*stiff_branch, "fold",
                                                       "force_amplitude", 1e-5, 6e-5,
                                                       which=1, direction="down"))
    gaps = curve.grazing_gap.values
    assert gaps.min() < 0.0 < gaps.max()
    assert np.abs(gaps).min() > 1e-3 * np.abs(gaps).max()
    assert event(curve, "grazing").size == 0 and curve.attrs["curve_ending"] == "bound"


STOP_CURVE_FILE = """n_modes = 3
[params]
counterpart = "stop"
contact_stiffness = 100.0
damping_ratio = 0.02
force_amplitude = 1e-4
[continuation]
parameter = "omega"
min = 195.0
max = 330.0
subspace = 4
max_branches = 1
[curve]
kind = "fold"
second = "force_amplitude"
min = 1e-4
max = 1.2e-4
"""


def test_the_command_writes_the_curve_and_plot_draws_it(stop_branch, tmp_path, capsys):
    from impactbeams.cli import main

    path, out = tmp_path / "fold.toml", tmp_path / "fold.nc"
    path.write_text(STOP_CURVE_FILE)
    assert main(["continue", str(path), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "the fold of the branch along omega from 195 to 330 (event 0), followed in " \
        "force_amplitude from 0.0001 to 0.00012" in err
    assert f"wrote {out}: " in err and "fold curve (ended: bound); end at omega = " in err
    assert "branch of period 1, point 20: " in err  # the progress lines
    with xr.open_dataset(out) as written:
        validate(written)
        expected = continue_curve(BifurcationCurve.from_branch(*stop_branch, "fold",
                                                               "force_amplitude", 1e-4, 1.2e-4))
        np.testing.assert_array_equal(written.omega.values, expected.omega.values)
        assert written.attrs["curve_kind"] == "fold"
    assert main(["plot", str(out), "-o", str(tmp_path / "fold.png")]) == 0
    assert (tmp_path / "fold.png").stat().st_size > 0
    assert main(["plot", str(out), "--var", "omega"]) == 2
    assert "variable (--var) = 'omega' is not allowed: a bifurcation curve is drawn in its " \
        "parameters' plane; --var chooses what a map under it (--over) shows" \
        in capsys.readouterr().err


@pytest.mark.parametrize(("change", "message"), [
    (('second = "force_amplitude"', 'second = "omega"'),
     "second = 'omega' is not allowed: must differ from parameter = 'omega'"),
    (("max = 1.2e-4", "mx = 1.2e-4"), "unknown key 'mx' in [curve] of"),
    (('kind = "fold"', 'kind = "cusp"'), "kind = 'cusp' is not allowed: must be one of"),
    (("min = 1e-4\n", "min = 2e-4\n"),
     "high = 0.00012 is not allowed: the range [0.0002, 0.00012] is empty"),
])
def test_a_bad_curve_table_is_one_line_before_any_compute(tmp_path, capsys, change, message):
    from impactbeams.cli import main

    path, out = tmp_path / "fold.toml", tmp_path / "fold.nc"
    path.write_text(STOP_CURVE_FILE.replace(*change))
    assert main(["continue", str(path), "-o", str(out)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert message in line and line.startswith("impactbeams: error: ")
    assert not out.exists()


# the curves over a map of their plane (issue 34, item 1: `impactbeams plot CURVE --over MAP`)

@pytest.fixture(scope="module")
def steady_map():
    """A first-impact map of the small model over (Omega, F0) started on the non-impacting
    steady response (``start = "steady"``): a cell impacts within its first period iff that
    response reaches the gap, i.e. above the grazing curve. Cells of 0.5 rad/s and 1 uN."""
    from impactbeams.sweep import sweep_from_mapping

    fixed = {key: SMALL.as_dict()[key] for key in ("contact_stiffness", "damping_ratio",
                                                   "clearance")}
    return ib.run_sweep(sweep_from_mapping({
        "n_modes": 3, "t_max": 0.1, "params": {**fixed, "start": "steady"},
        "axes": {"omega": {"min": 225.0, "max": 236.0, "num": 23},
                 "force_amplitude": {"min": 2e-5, "max": 4e-5, "num": 21}}}))


def test_the_closed_form_grazing_curve_bounds_the_first_impact_map(steady_map):
    """The independent check of what the figure shows: in every column of the map, the cells
    above the closed-form grazing force impact and those below do not (the map's event
    search on the linear response against the modal sums' closed form)."""
    closed = ib.grazing_curve(SMALL, 3, "force_amplitude", steady_map.omega.values)
    forces = steady_map.force_amplitude.values
    impacts = steady_map.impacted.transpose("omega", "force_amplitude").values == 1
    inside = 0
    for column, force in zip(impacts, closed.force_amplitude.values, strict=True):
        np.testing.assert_array_equal(column, forces > force)
        inside += forces[0] < force < forces[-1]
    assert inside >= 10  # the curve crosses the map in 10 of its 23 columns at least


def _drawn(axes):
    """The map's image (its extent in data coordinates) and the curves' lines, by label."""
    from matplotlib.image import BboxImage

    (image,) = [a for a in axes.get_children() if isinstance(a, BboxImage)]
    (x0, y0), (x1, y1) = axes.transData.inverted().transform(image.get_window_extent())
    lines = {line.get_label(): line for line in axes.get_lines()}
    return (x0, x1, y0, y1), lines


def test_the_curve_is_drawn_over_the_map_in_the_same_units(small_grazing, steady_map):
    from matplotlib.figure import Figure

    from impactbeams.plotting.curves import draw_curves

    figure = Figure(layout="constrained")
    axes = figure.subplots()
    draw_curves(axes, [small_grazing], steady_map)
    extent, lines = _drawn(axes)
    # the map's cells from edge to edge, in the curve's units (F0 in uN: both below 1e-4 N)
    np.testing.assert_allclose(extent, (224.75, 236.25, 19.5, 40.5), rtol=1e-12)
    curve = lines["grazing curve"]
    np.testing.assert_array_equal(curve.get_xdata(), small_grazing.omega.values)
    np.testing.assert_array_equal(curve.get_ydata(), 1e6 * small_grazing.force_amplitude.values)
    assert axes.get_xlim() == pytest.approx((224.75, 236.25), rel=1e-12)
    assert axes.get_ylim() == pytest.approx((19.5, 40.5), rel=1e-12)
    assert axes.get_ylabel() == "$F_0$ (µN)" and len(figure.axes) == 2  # and its colour bar
    # a map that covers part of the curve: the limits reach the curve's end, the map stays
    figure = Figure(layout="constrained")
    axes = figure.subplots()
    draw_curves(axes, [small_grazing], steady_map.isel(force_amplitude=slice(0, 11)))
    extent, _ = _drawn(axes)
    np.testing.assert_allclose(extent, (224.75, 236.25, 19.5, 30.5), rtol=1e-12)
    assert axes.get_ylim() == pytest.approx((19.5, 40.0), rel=1e-12)


def test_the_curve_is_drawn_over_a_map_on_a_log_axis(small_grazing, steady_map):
    """A map swept on a log scale (as sweeps/fig5a-omega-force.toml's F0): the curve is drawn
    on its log axis, at its own values (the tick formatter is the log axis's, which has no
    offset to switch off: this raised AttributeError)."""
    from matplotlib.figure import Figure

    from impactbeams.plotting.curves import draw_curves

    force = steady_map.force_amplitude
    logged = steady_map.assign_coords(force_amplitude=force.assign_attrs(scale="log"))
    axes = Figure(layout="constrained").subplots()
    draw_curves(axes, [small_grazing], logged)
    assert axes.get_yscale() == "log" and axes.get_xscale() == "linear"
    (line,) = [line for line in axes.get_lines() if line.get_label() == "grazing curve"]
    np.testing.assert_array_equal(line.get_ydata(), 1e6 * small_grazing.force_amplitude.values)


def test_a_stepped_sweeps_direction_is_sliced(small_grazing, steady_map):
    """A long-time sweep of the plane has more dimensions (a stepped sweep's directions):
    sliced to the curve's plane, or refused in one line."""
    from matplotlib.figure import Figure

    from impactbeams.plotting.curves import draw_curves

    stepped = xr.concat([steady_map, steady_map.fillna(1.0)], dim=xr.DataArray(
        ["up", "down"], dims="sweep_direction", name="sweep_direction",
        attrs={"units": "1"}))  # as a stepped sweep's file has it
    axes = Figure().subplots()
    notes = draw_curves(axes, [small_grazing], stepped, "first_impact_time",
                        values={"sweep_direction": "down"})
    # a named choice is found, not the nearest; no unit "1" after it
    assert notes == ["slice sweep_direction = down (index 1 of 0..1)"]
    with pytest.raises(ParameterError) as error:
        draw_curves(Figure().subplots(), [small_grazing], stepped)
    assert str(error.value) == (
        "the map's (--over) first_impact_time is also over sweep_direction: slice it (--slice "
        "NAME=VALUE or --slice-index NAME=I) to a map of the curve's parameters (omega, "
        "force_amplitude)")


def _over_clearance(plane):
    """``plane`` as though its second axis were the clearance (its attributes too)."""
    from impactbeams.variables import parameter_attributes

    plane = plane.rename(force_amplitude="clearance")
    return plane.assign_coords(clearance=plane.clearance.assign_attrs(
        parameter_attributes("clearance")))


@pytest.mark.parametrize(("change", "message"), [
    (_over_clearance,
     "the map (--over) is not over the curve's parameters (omega, force_amplitude): its "
     "first_impact_time is over (omega, clearance), without force_amplitude"),
    (lambda m: m.assign_coords(force_amplitude=m.force_amplitude.assign_attrs(units="mN")),
     "the map's (--over) force_amplitude is in 'mN', the curve's in 'N': draw a map of the "
     "same units"),
])
def test_a_map_of_another_plane_is_refused(small_grazing, steady_map, change, message):
    from matplotlib.figure import Figure

    from impactbeams.plotting.curves import draw_curves

    axes = Figure().subplots()
    with pytest.raises(ParameterError) as error:
        draw_curves(axes, [small_grazing], change(steady_map))
    assert str(error.value) == message
    assert not axes.artists and not axes.lines  # refused before anything is drawn


def test_plot_draws_a_curve_over_a_map_from_the_command_line(small_grazing, steady_map,
                                                               tmp_path, capsys):
    from impactbeams.cli import main
    from impactbeams.io import write_netcdf

    curve, plane, other = tmp_path / "curve.nc", tmp_path / "map.nc", tmp_path / "other.nc"
    write_netcdf(small_grazing, curve)
    write_netcdf(steady_map, plane)
    write_netcdf(_over_clearance(steady_map), other)
    assert main(["plot", str(curve), "--over", str(plane), "-o", str(tmp_path / "a.png"),
                 "--contours", "3"]) == 0
    assert (tmp_path / "a.png").stat().st_size > 0
    capsys.readouterr()
    assert main(["plot", str(curve), "--over", str(other), "-o", str(tmp_path / "b.png")]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line == ("impactbeams: error: the map (--over) is not over the curve's parameters "
                    "(omega, force_amplitude): its first_impact_time is over (omega, "
                    "clearance), without force_amplitude")
    assert not (tmp_path / "b.png").exists()
    assert main(["plot", str(curve), "--slice", "omega=230", "-o", str(tmp_path / "c.png")]) == 2
    assert "values (--slice) = {'omega': '230'} is not allowed: a bifurcation curve without a " \
        "map under it (--over)" in capsys.readouterr().err


def test_plot_draws_several_curves_of_one_plane_from_the_command_line(
        small_branch, small_grazing, steady_map, tmp_path, capsys, monkeypatch):
    """``--with CURVE.nc`` (repeatable) draws more curves of IN.nc's plane on the same axes,
    over the map if given (as `draw_curves` does from Python); a file that is no curve, a
    curve of another plane, or IN.nc not a curve: one line, exit 2, no figure."""
    from impactbeams.cli import main
    from impactbeams.io import write_netcdf
    from impactbeams.plotting import curves as plotted

    down = continue_curve(BifurcationCurve.from_branch(*small_branch, "grazing",
                                                       "force_amplitude", 2e-5, 4e-5,
                                                       direction="down", max_points=6))
    names = {name: tmp_path / f"{name}.nc" for name in ("up", "down", "map", "other")}
    other = _over_clearance(small_grazing).assign_attrs(curve_parameters="omega clearance")
    for name, dataset in (("up", small_grazing), ("down", down), ("map", steady_map),
                          ("other", other)):
        write_netcdf(dataset, names[name])
    drawn = []
    original = plotted.draw_curves
    monkeypatch.setattr(plotted, "draw_curves", lambda axes, curves, *rest, **options: (
        drawn.append(curves), original(axes, curves, *rest, **options))[1])
    assert main(["plot", str(names["up"]), "--with", str(names["down"]), "--over",
                 str(names["map"]), "-o", str(tmp_path / "both.png")]) == 0
    (curves,) = drawn
    assert [curve.branch_point.size for curve in curves] == [small_grazing.branch_point.size,
                                                               down.branch_point.size]
    np.testing.assert_array_equal(curves[1].omega.values, down.omega.values)
    assert (tmp_path / "both.png").stat().st_size > 0
    capsys.readouterr()
    for first, also, message in (
            ("up", "map", "--with file '{}' is not a curve in a plane of two parameters: a "
                          "bifurcation curve (impactbeams continue with a [curve]) or a "
                          "closed-form grazing curve (impactbeams grazing PARAMETER)"),
            ("up", "other", "curve 1 is in (omega, clearance), not in the first one's plane "
                            "(omega, force_amplitude): draw them apart"),
            ("map", "up", "--with is not allowed: it adds bifurcation curves to a bifurcation "
                          "curve's plot, and this Dataset is none")):
        assert main(["plot", str(names[first]), "--with", str(names[also]), "-o",
                     str(tmp_path / "no.png")]) == 2
        (line,) = capsys.readouterr().err.splitlines()
        assert line == f"impactbeams: error: {message.format(names[also])}"
        assert not (tmp_path / "no.png").exists()


def test_plot_draws_the_closed_form_grazing_curve_with_a_continued_one(
        small_grazing, tmp_path, capsys, monkeypatch):
    """``plot CURVE.nc --with GRAZING.nc``, GRAZING.nc written by ``impactbeams grazing``: one
    figure with the continued curve and the closed-form one (dotted, its own legend entry),
    each line's points those of its file; the grazing frequencies of one drive (no plane):
    one line, exit 2."""
    from impactbeams.cli import main
    from impactbeams.io import write_netcdf
    from impactbeams.plotting import curves as plotted

    model = ["--contact-stiffness", "1e4", "--damping-ratio", "0.02", "--clearance", "1.1e-5",
             "--n-modes", "3"]
    curve, closed, frequencies = (tmp_path / f"{name}.nc" for name in
                                  ("curve", "closed", "frequencies"))
    write_netcdf(small_grazing, curve)
    assert main(["grazing", "force_amplitude", "--omega-min", "230", "--omega-max", "235",
                 "--points", "11", *model, "-o", str(closed), "--quiet"]) == 0
    assert main(["grazing", "omega", "--omega-min", "230", "--omega-max", "240",
                 "--force-amplitude", "3e-5", *model, "-o", str(frequencies), "--quiet"]) == 0
    drawn = []
    original = plotted.draw_curves
    monkeypatch.setattr(plotted, "draw_curves", lambda axes, curves, *rest, **options: (
        drawn.append(axes), original(axes, curves, *rest, **options))[1])
    image = tmp_path / "both.png"
    assert main(["plot", str(curve), "--with", str(closed), "-o", str(image)]) == 0
    assert image.stat().st_size > 0
    (axes,) = drawn
    legend = [text.get_text() for text in axes.get_legend().get_texts()]
    assert "grazing curve" in legend
    assert "closed-form grazing curve (linear response)" in legend
    with xr.open_dataset(closed) as written:
        dotted = [line for line in axes.get_lines() if line.get_linestyle() == ":"]
        (line,) = dotted
        np.testing.assert_array_equal(line.get_xdata(), written.omega.values)
        # drawn in the continued curve's units (uN): the file's force amplitudes scaled
        ratio = line.get_ydata() / written.force_amplitude.values
        np.testing.assert_allclose(ratio, 1e6, rtol=1e-15)
    solid = np.concatenate([line.get_xdata() for line in axes.get_lines()
                            if line.get_linestyle() == "-" and len(line.get_xdata()) > 1])
    assert set(small_grazing.omega.values) <= set(solid)
    capsys.readouterr()
    assert main(["plot", str(curve), "--with", str(frequencies), "-o",
                 str(tmp_path / "no.png")]) == 2
    (message,) = capsys.readouterr().err.splitlines()
    assert "is not a curve in a plane of two parameters" in message
    assert not (tmp_path / "no.png").exists()


def test_a_curve_cut_at_max_points_exits_3_unless_allowed(tmp_path, capsys):
    """As a branch short of its range: a curve that stops at ``max_points`` (short of its
    box, no event ending it) warns, naming where it stopped, and exits 3; with
    ``--allow-incomplete`` it exits 0. A curve that ends on its box exits 0."""
    from impactbeams.cli import main

    path = tmp_path / "fold.toml"
    path.write_text(STOP_CURVE_FILE + "max_points = 3\n")
    assert main(["continue", str(path), "-o", str(tmp_path / "a.nc"), "--quiet"]) == 3
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("impactbeams: warning: the fold curve stopped at max_points = 3, at "
                           "omega = ") and "raise max_points" in line
    with xr.open_dataset(tmp_path / "a.nc") as written:
        assert written.attrs["curve_ending"] == "max_points" and written.branch_point.size == 3
    assert main(["continue", str(path), "-o", str(tmp_path / "b.nc"), "--quiet",
                 "--allow-incomplete"]) == 0
