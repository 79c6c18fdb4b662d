"""A contact at any point along the beams, from below or from above (issue 33, item 3).

Against independent references (tests/point_reference.py: textbook modes in long double, the
closed-form Green's function, DOP853 on the modal equations; tests/fe_reference.py's beam
elements for the static flexibility): the static flexibility at a point, the first impact of a
contact at mid-span from below and from above, the first contacts of a stop at mid-span and of
two beams touching at offset points, the mirror symmetry of the two sides, and the refusals.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from impactbeams import Params, simulate
from impactbeams.contact import build_free_phase, spring_contact
from impactbeams.modes import beam
from impactbeams.params import ParameterError
from impactbeams.structure import Spring
from point_reference import Beam, PointContact

STOP = Params(counterpart="stop")
MID = 0.5 * STOP.l1  # mid-span of beam 1 (m)


def reference_beam(params: Params, which: int, n: int) -> Beam:
    i = str(which)
    return Beam(getattr(params, "EI" + i), getattr(params, "rhoA" + i), getattr(params, "l" + i),
                n)


# --- static flexibility at a point ------------------------------------------------------------


@pytest.mark.parametrize("x", [0.01, 0.03, MID, 0.09, STOP.l1])
def test_static_flexibility_at_a_point_is_x_cubed_over_3_EI_and_the_fe_solve(x):
    """G(x, x) of the bare beam: x^3 / (3 EI) to 2 ulp, and the static solve K u = e of a
    beam-element model (Hermite cubics hold a static point-load deflection exactly, so the FE
    nodal value is exact to its solve's round-off, which grows with K's condition number, ~n^4:
    2e7 at 10 elements; measured <= 4.5e-13 relative, asserted 1e-11). The free phase carries it as
    ``point_compliance`` and the modes' share of it converges to it (what the static correction
    adds: r_N = G - sum Y^2 / omega^2 > 0, falling like N^-3 at mid-span, checked as
    r_40 < r_10 / 30)."""
    from fe_reference import beam_matrices

    G = beam(STOP, 1).flexibility(x, x)
    assert G == pytest.approx(x**3 / (3.0 * STOP.EI1), rel=4e-16, abs=0)
    n_elements = 10
    K, _ = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, n_elements)
    node = round(x / STOP.l1 * n_elements)
    load = np.zeros(K.shape[0])
    load[2 * (node - 1)] = 1.0
    assert np.linalg.solve(K, load)[2 * (node - 1)] == pytest.approx(G, rel=1e-11, abs=0)
    params = STOP.replace(contact_position1=x)
    residual = [G - np.sum(build_free_phase(params, n).point1**2
                           / build_free_phase(params, n).frequencies**2) for n in (10, 40)]
    assert build_free_phase(params, 10).point_compliance == (G, 0.0)
    assert 0.0 < residual[1] < residual[0] / 30.0


def test_static_flexibility_with_a_spring_to_ground_against_the_fe_solve():
    """With a spring to ground (50 N/m at 0.08 m), G(x, x) at x = 0.03 from structure/ (the
    Green's function with Woodbury) against the beam elements' static solve with the spring
    added to K: 1e-11 relative (10 elements, as above); the free phase carries it."""
    from fe_reference import beam_matrices

    params = STOP.replace(attachments1=(Spring(position=0.08, stiffness=50.0),))
    n_elements, x = 10, 0.03
    K, _ = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, n_elements)
    spring = 2 * (round(0.08 / STOP.l1 * n_elements) - 1)
    K[spring, spring] += 50.0
    at = 2 * (round(x / STOP.l1 * n_elements) - 1)
    load = np.zeros(K.shape[0])
    load[at] = 1.0
    got = beam(params, 1).flexibility(x, x)
    assert np.linalg.solve(K, load)[at] == pytest.approx(got, rel=1e-11, abs=0)
    assert got < x**3 / (3.0 * STOP.EI1)  # the spring stiffens the beam
    assert build_free_phase(params.replace(contact_position1=x), 4).point_compliance[0] == got


# --- the first impact at a point ----------------------------------------------------------------


def _first_root(gap, t_end: float, points: int) -> float:
    """The first zero of ``gap`` on [0, t_end]: the first sign change on a fine grid, brentq.

    ``gap`` takes an array of times (the grid) or one time (brentq).
    """
    t = np.linspace(0.0, t_end, points)
    first = np.flatnonzero(gap(t) <= 0.0)[0]
    return brentq(lambda s: float(gap(np.array([s]))[0]), t[first - 1], t[first], xtol=1e-16,
                  rtol=1e-15)


@pytest.mark.filterwarnings("ignore:n_modes = 6 does not resolve:RuntimeWarning")
def test_first_impact_at_mid_span_of_the_free_vibration():
    """A stop below mid-span, beam 1 released from a static tip uplift (F0 = 0): the first
    impact is the first zero of clearance + sum_n delta Y_n(l) Y_n(x) / (c omega_n^2)
    cos(omega_n t) (closed form with the textbook modes, the same 6 modes): to 1e-11 s
    (measured 5e-18 s: both are the same series to round-off)."""
    n, uplift, clearance = 6, 3e-5, 4e-6
    params = STOP.replace(force_amplitude=0.0, uplift1=uplift, clearance=clearance,
                          contact_position1=MID)
    ref = PointContact(reference_beam(params, 1, n), None, MID, 0.0, 1.0, 1e4, clearance, 0.0,
                       0.0, uplift)
    eta0, shapes = ref.initial_state()[:n], ref.beam1.shapes(MID)

    def gap(t: np.ndarray) -> np.ndarray:
        return clearance + (shapes * eta0) @ np.cos(np.outer(ref.frequencies, t))

    expected = _first_root(gap, 0.01, 100001)
    ds = simulate(params, 0.01, n_modes=n, dt_output=1e-3)
    assert float(ds.impact_onset_time[0]) == pytest.approx(expected, abs=1e-11)


@pytest.mark.filterwarnings("ignore:n_modes = 5 does not resolve:RuntimeWarning")
@pytest.mark.parametrize("side", ["below", "above"])
def test_first_impact_at_mid_span_of_the_forced_response(side):
    """The tip force F0 sin(Omega t) from rest, a stop at mid-span below or above beam 1: the
    first impact is the first zero of clearance + s y(x, t) with the mode-acceleration form
    y = -R_N(x, l) F + sum_n Y_n(x) eta_n, eta_n = -Y_n(l) F0 (sin(Omega t) - (Omega / omega_n)
    sin(omega_n t)) / (omega_n^2 - Omega^2) (closed form, textbook modes, the closed-form
    Green's function): to 1e-11 s (measured below 1e-17 s)."""
    n, clearance, force, omega = 5, 3e-6, 1e-3, 400.0
    params = STOP.replace(force_amplitude=force, omega=omega, clearance=clearance,
                          contact_position1=MID, contact_side=side)
    s = 1.0 if side == "below" else -1.0
    ref = PointContact(reference_beam(params, 1, n), None, MID, 0.0, s, 1e4, clearance, force,
                       omega)
    w, tip = ref.frequencies[:, None], ref.beam1.shapes(STOP.l1)[:, None]

    def gap(t: np.ndarray) -> np.ndarray:
        eta = (-tip * force * (np.sin(omega * t) - omega / w * np.sin(w * t))
               / (w**2 - omega**2))
        return clearance + s * ref.point_deflection(t, eta)

    expected = _first_root(gap, 0.05, 200001)
    ds = simulate(params, 0.05, n_modes=n, times=np.array([0.0, expected]))
    assert float(ds.impact_onset_time[0]) == pytest.approx(expected, abs=1e-11)
    # beam 1 moves down onto a stop below it, up onto one above: y(x) = -s clearance there
    assert float(ds.contact_deflection_1[1]) == pytest.approx(-s * clearance, rel=1e-9)
    assert float(ds.impact_velocity[0]) < 0.0  # the gap closes


# --- contacts through the dynamics against DOP853 ---------------------------------------------


def _engine_contacts(ds, count):
    onset = ds.impact_onset_time.values[:count]
    return {"onset": onset, "release": onset + ds.impact_duration.values[:count],
            "peak": ds.impact_peak_force.values[:count]}


def _compare(got, expected, time_tolerance, force_tolerance):
    count = expected["release"].size
    assert count >= 3
    for key in ("onset", "release"):
        np.testing.assert_allclose(got[key][:count], expected[key][:count], rtol=0,
                                   atol=time_tolerance, err_msg=key)
    np.testing.assert_allclose(got["peak"][:count], expected["peak"], rtol=force_tolerance)


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
@pytest.mark.parametrize("side", ["below", "above"])
def test_contacts_at_mid_span_against_dop853(side):
    """A stop at mid-span (k = 1e4 N/m), 4 modes, forced: the first contacts (onset, release,
    peak force) against DOP853 on the same modal equations with the contact force at that
    point (point_reference.PointContact, rtol 1e-13). DOP853's own error, estimated by the
    same run at rtol 1e-11: 4e-15 s in the event times, 5e-12 relative in the peaks (the peak
    is located on its dense output); measured against the engine: 2e-16 s and 7e-14. Asserted
    1e-12 s and 1e-9: DOP853's error at rtol 1e-11 with a margin of 100."""
    n = 4
    params = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=3e-6, contact_stiffness=1e4,
                          contact_position1=MID, contact_side=side)
    s = 1.0 if side == "below" else -1.0
    ref = PointContact(reference_beam(params, 1, n), None, MID, 0.0, s, 1e4, 3e-6, 1e-3, 400.0)
    expected = ref.contacts(0.04, 4)
    ds = simulate(params, 0.04, n_modes=n, dt_output=1e-2)
    _compare(_engine_contacts(ds, 4), expected, 1e-12, 1e-9)


@pytest.mark.filterwarnings("ignore:n_modes = 3 does not resolve:RuntimeWarning")
def test_two_beams_touching_at_offset_points_against_dop853():
    """Beam 1 at x1 = 0.07 m onto beam 2 at x2 = 0.05 m below it (3 modes per beam, k = 1e4
    N/m): the first contacts against DOP853 on the two beams' modal equations, as above
    (measured 2e-16 s and 7e-13)."""
    n = 3
    params = Params(force_amplitude=1e-3, omega=300.0, clearance=3e-6, contact_stiffness=1e4,
                    contact_position1=0.07, contact_position2=0.05)
    ref = PointContact(reference_beam(params, 1, n), reference_beam(params, 2, n), 0.07, 0.05,
                       1.0, 1e4, 3e-6, 1e-3, 300.0)
    expected = ref.contacts(0.04, 4)
    ds = simulate(params, 0.04, n_modes=n, dt_output=1e-2)
    _compare(_engine_contacts(ds, 4), expected, 1e-12, 1e-9)


def _against_fe(params: Params, t_max: float, count: int) -> dict:
    """`fe_spring.mesh_deviations` of the first ``count`` contacts of 20 modes against the FE
    model at 20 and 40 elements (the gap at the contact node, exact time integration)."""
    from fe_spring import fe_spring_contacts, mesh_deviations

    coarse, fine = (fe_spring_contacts(params, params.contact_stiffness, t_max=t_max,
                                       n_elements=(n, n), n_contacts=count) for n in (20, 40))
    ds = simulate(params, t_max, n_modes=20, dt_output=t_max / 3)
    got = {"onset": ds.impact_onset_time, "duration": ds.impact_duration,
           "impulse": ds.impact_impulse, "peak": ds.impact_peak_force}
    return mesh_deviations({key: value.values[:count] for key, value in got.items()}, coarse,
                           fine)


@pytest.mark.parametrize("side", ["below", "above"])
def test_contacts_at_mid_span_against_the_fe_model(side):
    """A stop at mid-span (k = 1e4 N/m, forced): the first three contacts of 20 modes against
    the finite-element model of the beam with its gap at the mid-span node (tests/fe_spring.py,
    exact time integration of the FE system; 20 and 40 elements). Bound, as for the tip stop
    (tests/test_stop.py): the FE's own error, estimated by |f_40 - f_20| (its convergence is not
    monotone, so no Richardson order is trusted), plus the modal truncation at 20 modes with the
    static correction (1e-6); onsets relative to the shortest duration. Measured: at most
    3.8e-5 relative (the third peak below, whose FE estimate is 5.6e-4), 1.9e-7 for the first
    onset above (FE estimate 3e-8, within the 1e-6 allowance)."""
    params = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=3e-6,
                          contact_stiffness=1e4, contact_position1=MID, contact_side=side)
    for key, (deviation, fe_error) in _against_fe(params, 0.03, 3).items():
        assert np.all(deviation <= fe_error + 1e-6), (key, deviation, fe_error)
        assert deviation.max() < 5e-5, key


@pytest.mark.parametrize("side", ["below", "above"])
def test_first_contact_at_mid_span_of_a_beam_with_attachments_against_the_fe_model(side):
    """Beam 1 with a 2 g tip mass and a 30 N/m spring to ground at 0.08 m, a stop at mid-span:
    the first contact (onset, duration, impulse, peak force) at 20 modes (the attachments' exact
    modes, the Green's function with the spring at the point) against the FE model with the
    same attachments lumped on its nodes, as above: within |f_40 - f_20| + 1e-6 (measured at
    most 3.5e-6 relative; later contacts, after the first rattle, drift past the FE estimate,
    which is not monotone there)."""
    from impactbeams import PointMass

    parts = (PointMass(position=STOP.l1, mass=2e-3), Spring(position=0.08, stiffness=30.0))
    params = STOP.replace(force_amplitude=1e-3, omega=300.0, clearance=3e-6,
                          contact_stiffness=1e4, contact_position1=MID, contact_side=side,
                          attachments1=parts)
    for key, (deviation, fe_error) in _against_fe(params, 0.04, 1).items():
        assert np.all(deviation <= fe_error + 1e-6), (key, deviation, fe_error)


# --- the two sides mirror each other ------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:n_modes = 5 does not resolve:RuntimeWarning")
def test_contact_from_above_mirrors_contact_from_below():
    """A stop above the point 0.06 m with beam 1 released from a downward uplift -delta is the
    mirror image of a stop below with +delta: the same impacts, gaps, forces and energies,
    and the deflections negated, bit for bit (every weight and state flips its sign exactly,
    and the contact phase's rank-one update sees only w w^T; measured: identical)."""
    base = STOP.replace(force_amplitude=0.0, clearance=4e-6, contact_stiffness=1e5,
                        contact_position1=0.06)
    below = simulate(base.replace(uplift1=3e-5), 0.02, n_modes=5, dt_output=1e-4)
    above = simulate(base.replace(uplift1=-3e-5, contact_side="above"), 0.02, n_modes=5,
                     dt_output=1e-4)
    assert below.impact.size > 3
    for name in ("impact_onset_time", "impact_duration", "impact_peak_force", "impact_velocity",
                 "impact_impulse", "gap", "contact_force", "energy"):
        np.testing.assert_array_equal(above[name], below[name], err_msg=name)
    for name in ("tip_deflection_1", "contact_deflection_1", "tip_velocity_1"):
        np.testing.assert_array_equal(above[name], -below[name], err_msg=name)


@pytest.mark.filterwarnings("ignore:n_modes = 5 does not resolve:RuntimeWarning")
def test_a_sign_flipped_tip_force_mirrors_the_forced_response():
    """The forced case of the mirror: a stop above with the tip force -F0 sin(Omega t) against
    a stop below with +F0 sin(Omega t), damped: bit for bit mirrored (measured: identical).
    `Params` takes only F0 >= 0 (an amplitude), so the test sets -F0 past its check: what is
    shown is the symmetry of the drive's, the gap's and the contact's terms in the code."""
    base = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=3e-6, damping_ratio=0.01,
                        contact_stiffness=1e4, contact_position1=0.06)
    below = simulate(base, 0.06, n_modes=5, dt_output=1e-4)
    flipped = base.replace(contact_side="above")
    object.__setattr__(flipped, "force_amplitude", -base.force_amplitude)
    above = simulate(flipped, 0.06, n_modes=5, dt_output=1e-4)
    assert below.impact.size >= 3
    for name in ("impact_onset_time", "impact_duration", "impact_peak_force", "impact_impulse",
                 "gap", "contact_force", "energy"):
        np.testing.assert_array_equal(above[name], below[name], err_msg=name)
    for name in ("tip_deflection_1", "contact_deflection_1", "tip_velocity_1"):
        np.testing.assert_array_equal(above[name], -below[name], err_msg=name)


# --- where the tips stay the tips -------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_the_tip_stays_the_tip_and_the_gap_is_at_the_contact_point():
    """With a stop at mid-span the outputs that say tip are the tip's (the tip's static
    response to R through what the modes miss, R_N(l, x) R), the gap is the contact point's:
    g = clearance + y(x) in every sample, the stop stays at -clearance, and the energy
    balances (work of F and the stored energy, to 1e-12 of the energy)."""
    params = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=3e-6,
                          contact_stiffness=1e4, contact_position1=MID)
    ds = simulate(params, 0.03, n_modes=4, dt_output=1e-5, energy_balance=True)
    assert ds.impact.size > 2
    np.testing.assert_allclose(ds.gap, params.clearance + ds.contact_deflection_1, rtol=0,
                               atol=1e-20)
    np.testing.assert_array_equal(ds.tip_deflection_2.values, -params.clearance)
    assert float(np.abs(ds.tip_deflection_1).max()) > 1.5 * float(
        np.abs(ds.contact_deflection_1).max())  # the tip swings further than mid-span
    balance = ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force
    assert float(np.abs(balance - balance[0]).max()) < 1e-12 * float(np.abs(ds.energy).max())


def test_the_spring_contact_at_a_point_uses_the_point_flexibility():
    """k_e = k / (1 + k r) with r = G(x, x) - sum_n Y_n(x)^2 / omega_n^2 at the point (the
    textbook modes and the closed form: 1e-12), and the tip shift R_N(l, x) likewise."""
    params = STOP.replace(contact_position1=0.04, contact_stiffness=1e5)
    free = build_free_phase(params, 5)
    spring = spring_contact(free, free.point_compliance, 0.0, 1e5)
    ref = Beam(params.EI1, params.rhoA1, params.l1, 5)
    assert spring.residual == pytest.approx(ref.residual(0.04, 0.04), rel=1e-10)
    assert spring.tip_shift1 == pytest.approx(ref.residual(params.l1, 0.04), rel=1e-10)
    above = build_free_phase(params.replace(contact_side="above"), 5)
    assert spring_contact(above, above.point_compliance, 0.0, 1e5).tip_shift1 == pytest.approx(
        -spring.tip_shift1, rel=1e-15)


# --- parameters -------------------------------------------------------------------------------


def test_the_default_contact_is_at_the_tips_from_below():
    p = Params()
    assert p.contact_point == (p.l1, p.l2) and p.at_tips and p.side.sign == 1.0
    assert "contact_position1" not in p.as_dict() and "contact_side" not in p.as_dict()
    q = STOP.replace(contact_position1=0.05, contact_side="above")
    assert q.contact_point == (0.05, 0.0) and not q.at_tips
    assert q.as_dict()["contact_position1"] == 0.05 and q.as_dict()["contact_side"] == "above"
    r = Params(contact_position1=0.05, contact_position2=0.1, contact_side="above")
    assert Params.from_mapping(r.as_dict()) == r
    free, tip = build_free_phase(p, 3), build_free_phase(p.replace(contact_position1=p.l1), 3)
    np.testing.assert_array_equal(free.gap_weights, free.tip1 - free.tip2)
    np.testing.assert_array_equal(tip.gap_weights, free.gap_weights)
    assert free.gap_compliance == p.tip_compliance[0] == tip.gap_compliance


@pytest.mark.parametrize(("changes", "fragment"), [
    ({"contact_position1": 0.0}, "contact_position1 = 0.0 is not allowed: must be > 0 and <= l1"),
    ({"contact_position1": 0.2}, "contact_position1 = 0.2 is not allowed: must be > 0 and <= l1"),
    ({"contact_position1": math.nan}, "contact_position1 = nan is not allowed"),
    ({"contact_position2": 0.13}, "contact_position2 = 0.13 is not allowed: must be > 0 and <= l2"),
    ({"contact_side": "left"}, "contact_side = 'left' is not allowed: must be one of 'below'"),
    ({"contact_law": "tied", "contact_position1": 0.05},
     "contact_position1 = 0.05 is not allowed: contact_law = 'tied' (the paper's law) ties"),
    ({"contact_law": "tied", "contact_position2": 0.05}, "contact_position2 = 0.05 is not"),
    ({"contact_law": "tied", "contact_side": "above"}, "contact_side = 'above' is not allowed"),
    ({"counterpart": "stop", "contact_position2": 0.05},
     "contact_position2 = 0.05 is not allowed: counterpart = 'stop' has no beam 2"),
    ({"counterpart": "stop", "contact_position1": 0.05, "uplift1": -4e-5},
     "uplift1 = -4e-05 is not allowed: the initial gap at the contact point, clearance + "
     "(0.3125 uplift1 - 1 uplift2)"),
])
def test_contact_point_refusals(changes, fragment):
    with pytest.raises(ParameterError, match=None) as error:
        Params(**changes)
    assert fragment in str(error.value)
    assert "\n" not in str(error.value)


def test_the_tied_law_at_the_tip_given_explicitly_is_allowed():
    p = Params(contact_law="tied", contact_position1=0.1, contact_position2=0.12)
    assert p.at_tips


def test_command_line_and_toml(tmp_path, capsys):
    from impactbeams.cli import main

    path = tmp_path / "p.toml"
    path.write_text('[params]\ncounterpart = "stop"\ncontact_position1 = 0.05\n'
                    'contact_side = "above"\n')
    p = Params.from_toml(path)
    assert p.contact_point == (0.05, 0.0) and p.side.sign == -1.0
    assert main(["modes", "--counterpart", "stop", "--contact-position1", "0.05",
                 "--contact-side", "above", "--json"]) == 0
    capsys.readouterr()
    assert main(["modes", "--contact-position1", "0.5"]) == 2
    err = capsys.readouterr().err
    assert "contact_position1 = 0.5 is not allowed" in err and "Traceback" not in err


# --- every run kind on a contact at a point ------------------------------------------------------

POINT_SWEEP = {"t_max": 0.05, "n_modes": 4,
               "params": {"counterpart": "stop", "contact_stiffness": 1e4, "clearance": 3e-6,
                          "contact_position1": 0.06, "contact_side": "above"}}


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_maps_of_a_contact_at_a_point_equal_single_runs():
    """A first-impact map (the column kernel along Omega) and a dynamics map of a stop above
    the point 0.06 m: every cell's first impact equals simulate()'s to 1e-12 s (both certified
    to round-off), its count and peak force bit for bit; the point and side are the Dataset's
    attributes and part of the fingerprint."""
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    axes = {"omega": {"min": 100.0, "max": 500.0, "num": 3},
            "force_amplitude": {"min": 5e-4, "max": 1e-3, "num": 2}}
    first = sweep_from_mapping({**POINT_SWEEP, "observables": ["first_impact_time"],
                                "axes": axes}, source="point columns")
    dynamics = sweep_from_mapping({**POINT_SWEEP, "axes": axes, "observables": [
        "first_impact_time", "impact_count", "max_contact_force"]}, source="point map")
    assert not first.needs_dynamics
    at_tip = {**POINT_SWEEP, "params": {**POINT_SWEEP["params"], "contact_position1": 0.1}}
    assert sweep_from_mapping({**at_tip, "observables": ["first_impact_time"], "axes": axes}
                              ).fingerprint() != first.fingerprint()
    columns, cells = run_sweep(first, parallel=False), run_sweep(dynamics, parallel=False)
    assert cells.attrs["contact_position1"] == 0.06 and cells.attrs["contact_side"] == "above"
    assert np.isfinite(columns.first_impact_time.values).sum() >= 4
    for i, omega in enumerate(cells.omega.values):
        for j, force in enumerate(cells.force_amplitude.values):
            params = Params(**POINT_SWEEP["params"], omega=float(omega),
                            force_amplitude=float(force))
            run = simulate(params, 0.05, n_modes=4, dt_output=0.05)
            expected = float(run.impact_onset_time[0]) if run.impact.size else math.nan
            cell = cells.isel(omega=i, force_amplitude=j)
            assert float(cell.first_impact_time) == pytest.approx(expected, abs=1e-12, nan_ok=True)
            assert float(columns.first_impact_time.isel(omega=i, force_amplitude=j)) == (
                pytest.approx(expected, abs=1e-12, nan_ok=True))
            assert int(cell.impact_count) == run.impact.size
            if run.impact.size:
                assert float(cell.max_contact_force) == float(run.impact_peak_force.max())


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_maps_along_the_contact_position_equal_single_runs():
    """contact_position1 as an axis (a geometry: each position its own gap weights and static
    correction), beside omega, up to the tip: every cell of a first-impact map and of a
    dynamics map is simulate() of Params with that position, as above (first impact to
    1e-12 s, count and peak force bit for bit)."""
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    fixed = {name: value for name, value in POINT_SWEEP["params"].items()
             if name != "contact_position1"}
    axes = {"omega": {"min": 100.0, "max": 500.0, "num": 2},
            "contact_position1": {"min": 0.04, "max": 0.1, "num": 3}}
    first, dynamics = (run_sweep(sweep_from_mapping(
        {**POINT_SWEEP, "params": fixed, "axes": axes, "observables": observables}),
        parallel=False) for observables in (["first_impact_time"], [
            "first_impact_time", "impact_count", "max_contact_force"]))
    assert dynamics.contact_position1.attrs["units"] == "m"
    assert "contact_position1" not in dynamics.attrs
    assert np.isfinite(first.first_impact_time.values).all()
    for i, omega in enumerate(dynamics.omega.values):
        for j, position in enumerate(dynamics.contact_position1.values):
            params = Params(**fixed, omega=float(omega), contact_position1=float(position))
            run = simulate(params, 0.05, n_modes=4, dt_output=0.05)
            cell = dynamics.isel(omega=i, contact_position1=j)
            expected = float(run.impact_onset_time[0])
            assert float(cell.first_impact_time) == pytest.approx(expected, abs=1e-12)
            assert float(first.first_impact_time[i, j]) == pytest.approx(expected, abs=1e-12)
            assert int(cell.impact_count) == run.impact.size
            assert float(cell.max_contact_force) == float(run.impact_peak_force.max())


def test_a_contact_position_axis_beyond_the_beam_is_refused_in_one_line(tmp_path, capsys):
    from impactbeams.cli import main

    path = tmp_path / "sweep.toml"
    path.write_text('t_max = 0.05\nn_modes = 4\n[params]\ncounterpart = "stop"\n'
                    "[axes.contact_position1]\nmin = 0.04\nmax = 0.3\nnum = 3\n")
    assert main(["run", str(path), "-o", str(tmp_path / "out.nc")]) == 2
    assert capsys.readouterr().err == (
        f"impactbeams: error: at the grid point contact_position1 = 0.3 of {path}: "
        "contact_position1 = 0.3 is not allowed: must be > 0 and <= l1 = 0.1 (m: a point of "
        "beam 1, its distance from the clamp)\n")
    assert list(tmp_path.iterdir()) == [path]


@pytest.mark.filterwarnings("ignore:n_modes = 6 does not resolve:RuntimeWarning")
def test_periodic_orbit_and_continuation_of_a_contact_at_a_point():
    """A damped stop at mid-span: the periodic orbit found by shooting is a fixed point of the
    dynamics (one forcing period of simulate() from it returns to it: 1e-9 relative in the
    energy norm's coordinates, the orbit's tolerance being 1e-11), with contacts; a short
    continuation in Omega starts on it."""
    from impactbeams import Continuation, continue_orbits, periodic_orbit

    params = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=3e-6, damping_ratio=0.05,
                          contact_stiffness=1e4, contact_position1=MID)
    orbit = periodic_orbit(params, 6)
    assert orbit.contacts > 0
    period = 2.0 * math.pi / params.omega
    run = simulate(params, period, n_modes=6, dt_output=period, initial_state=orbit.state)
    end = np.concatenate([run.final_displacement.values, run.final_velocity.values])
    scale = np.abs(orbit.state).max()
    np.testing.assert_allclose(end, orbit.state, rtol=0, atol=1e-9 * scale)
    branches = continue_orbits(Continuation(params, "omega", 395.0, 405.0, start=400.0,
                                            n_modes=6, max_points=4))
    assert branches.sizes["branch_point"] >= 2 and branches.attrs["contact_position1"] == MID
    assert np.all(branches.contacts_per_orbit.values > 0)


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_long_time_samples_of_a_contact_at_a_point_equal_simulate():
    """A long-time sweep of a damped stop above the point 0.06 m: the kernel's stroboscopic
    tip samples (Numba) against simulate()'s series at the same times (NumPy, the same events):
    to 1e-13 of the largest sample, as tests/test_longtime.py; the contacts happen."""
    from impactbeams import LongTime
    from impactbeams.sweep import LONG_TIME_OBSERVABLES, run_sweep, sweep_from_mapping

    fixed = {**POINT_SWEEP["params"], "damping_ratio": 0.02, "force_amplitude": 1e-3}
    sweep = sweep_from_mapping({
        "n_modes": 4, "observables": list(LONG_TIME_OBSERVABLES), "transient_periods": 5,
        "sampled_periods": 4, "params": fixed,
        "axes": {"omega": {"min": 300.0, "max": 500.0, "num": 2}}})
    ds = run_sweep(sweep, progress=False)
    setting = LongTime(sampled_periods=4)
    for i, omega in enumerate(ds.omega.values):
        run = simulate(Params(**fixed, omega=float(omega)), float(setting.horizon(omega, 5)),
                       n_modes=4, times=setting.sample_times(omega, 5), transient_periods=5,
                       long_time=setting)
        assert run.impact.size > 0
        cell = ds.isel(omega=i)
        for name, series in (("poincare_deflection1", "tip_deflection_1"),
                             ("poincare_velocity1", "tip_velocity_1")):
            scale = np.max(np.abs(cell[name].values))
            assert np.max(np.abs(cell[name].values - run[series].values)) <= 1e-13 * scale


@pytest.mark.parametrize("side", ["below", "above"])
def test_the_linear_gap_of_a_contact_at_a_point(side):
    """The no-contact steady gap per unit F0 (`orbits.grazing.LinearGap`, the grazing curves'
    phasor) at a point of beam 1 against the mode-acceleration form with the textbook modes:
    G_F = -s R_N(x, l) - s sum_n Y_n(x) Y_n(l) / (omega_n^2 - Omega^2) (undamped), to 1e-12
    relative; per unit U0 of a shaker on beam 1's clamp (the stop stays) likewise."""
    from impactbeams.orbits.grazing import LinearGap

    s = 1.0 if side == "below" else -1.0
    params = STOP.replace(contact_position1=0.03, contact_side=side, shaker="beam1")
    omega = np.array([50.0, 400.0, 3000.0])
    force, base = LinearGap(params, 5).per_unit(omega)
    ref = Beam(params.EI1, params.rhoA1, params.l1, 5)
    w = ref.frequencies[:, None]
    expected = -s * ref.residual(0.03, params.l1) - s * np.sum(
        (ref.shapes(0.03) * ref.shapes(params.l1))[:, None] / (w**2 - omega**2), axis=0)
    np.testing.assert_allclose(force.real, expected, rtol=1e-12)
    assert np.all(force.imag == 0.0)
    # the shaker: s (1 + sum_n Y_n(x) Gamma_n Omega^2 / (omega_n^2 - Omega^2)), Gamma_n =
    # rhoA int Y_n by 200-point Gauss-Legendre (exact to round-off for these smooth shapes)
    nodes, weights = np.polynomial.legendre.leggauss(200)
    x = 0.5 * params.l1 * (nodes + 1.0)
    gamma = params.rhoA1 * 0.5 * params.l1 * np.array([ref.shapes(xi) for xi in x]).T @ weights
    expected = s * (1.0 + np.sum((ref.shapes(0.03) * gamma)[:, None] * omega**2
                                 / (w**2 - omega**2), axis=0))
    np.testing.assert_allclose(base.real, expected, rtol=1e-12)


def test_the_reduced_model_refuses_a_contact_elsewhere():
    from impactbeams.packing import reduced_model

    with pytest.raises(ParameterError, match="reduced_model: contact_position1 = 0.05"):
        reduced_model(STOP.replace(contact_position1=0.05), 4)
    with pytest.raises(ParameterError, match="reduced_model: contact_side = 'above'"):
        reduced_model(STOP.replace(contact_side="above"), 4)


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
@pytest.mark.parametrize("side", ["below", "above"])
def test_the_trajectory_plot_draws_the_contact_point(side, tmp_path):
    """The run's plot shows beam 1 at its contact point and the stop where it touches,
    y2(x2) - s clearance (-s clearance for a fixed stop), over the tip; the figure is written."""
    import matplotlib.pyplot as plt

    from impactbeams.plotting.trajectories import plot_run, plot_tips

    params = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=3e-6,
                          contact_stiffness=1e4, contact_position1=MID, contact_side=side)
    ds = simulate(params, 0.03, n_modes=4, dt_output=1e-4)
    figure, axis = plt.subplots()
    plot_tips(axis, ds)
    lines = {line.get_label(): line for line in axis.get_lines()}
    np.testing.assert_array_equal(lines[r"$y_1(x_1)$, contact point"].get_ydata(),
                                  ds.contact_deflection_1 * 1e6)
    s = 1.0 if side == "below" else -1.0
    np.testing.assert_allclose(lines[r"counterpart, $y_2(x_2) - s\Delta$"].get_ydata(),
                               -s * 3.0, rtol=1e-12)
    plt.close(figure)
    plot_run(ds, tmp_path / "run.png")
    assert (tmp_path / "run.png").stat().st_size > 0
