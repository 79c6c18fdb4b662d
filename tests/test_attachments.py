"""Attachments on a beam in the engine (issue 33): Params, the modal data, runs and refusals.

References: the closed-form characteristic equation of a cantilever with a tip mass and rotary
inertia (references.py), the FE model of tests/fe_spring.py with the mass lumped at its tip
node (its own error shown by refining the mesh), Hermite FE matrices for the static shape's
kinetic norm, and the textbook cantilever's results of today's closed forms.
"""

import json
import math

import numpy as np
import pytest
import xarray as xr

import impactbeams as ib
from fe_spring import build_pair, fe_spring_contacts
from impactbeams import simulate
from impactbeams.cli import main
from impactbeams.contact import build_free_phase
from impactbeams.drive import base_participation
from impactbeams.modes import beam
from impactbeams.params import ParameterError, Params
from impactbeams.structure import PointMass, Spring
from impactbeams.sweep import run_sweep, sweep_from_mapping
from references import gauss_rule, tip_mass_roots
from test_structure_modes import fe_model

TIP_MASS = PointMass(0.1, 1e-3, 1e-7)  # kg, kg m^2: 0.54 of beam 1's mass, a 1 g bolt
STOP = Params(counterpart="stop", contact_stiffness=1e4, attachments1=(TIP_MASS,))
PAIR = Params(contact_stiffness=1e4, attachments1=(TIP_MASS,),
              attachments2=(PointMass(0.12, 5e-4, 0.0),))
# masses and a spring (both stiffnesses) inside the span, a lighter mass at the tip
INTERIOR = Params(counterpart="stop", contact_stiffness=1e4, attachments1=(
    PointMass(0.05, 2e-3, 1e-7), Spring(0.025, 300.0, 0.4), PointMass(0.1, 5e-4, 0.0)))
# the textbook cantilever given as a structure: one segment, a massless "mass" at the tip
WEIGHTLESS = {"attachments1": (PointMass(0.1, 0.0),), "attachments2": (PointMass(0.12, 0.0),)}


@pytest.mark.parametrize(("mu", "eta"), [(0.1, 1e-3), (1.0, 1e-2), (10.0, 0.1)])
def test_modes_with_a_tip_mass_solve_the_characteristic_equation(capsys, tmp_path, mu, eta):
    """`impactbeams modes` of a parameters file with a tip mass (a TOML table), and the free
    phase the kernels read, against the roots of the closed-form equation.

    Measured: 7e-16 at worst; 1e-10 allowed (the issue's bound).
    """
    p = Params(counterpart="stop")
    mass, inertia = mu * p.rhoA1 * p.l1, eta * p.rhoA1 * p.l1**3
    path = tmp_path / "rig.toml"
    path.write_text('[params]\ncounterpart = "stop"\nattachments1 = [{position = 0.1, '
                    f"mass = {mass!r}, rotary_inertia = {inertia!r}}}]\n")
    assert main(["modes", "--n", "10", "--json", "--params", str(path)]) == 0
    listed = np.array(json.loads(capsys.readouterr().out)["free"]["beam1"])
    free = build_free_phase(p.replace(attachments1=(PointMass(p.l1, mass, inertia),)), 10)
    expected = math.sqrt(p.EI1 / p.rhoA1) * (tip_mass_roots(mu, eta, 10) / p.l1) ** 2
    assert np.array_equal(listed, free.frequencies)
    assert np.abs(free.frequencies / expected - 1.0).max() < 1e-10


def test_a_sweep_file_and_the_command_line_take_attachments(capsys, tmp_path):
    """A sweep file's [params] table names a tip mass and a spring: the same map as from
    Python; the tied law with them is refused in one line, exit code 2."""
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        't_max = 0.05\nn_modes = 10\nobservables = ["first_impact_time"]\n[params]\n'
        'counterpart = "stop"\ncontact_stiffness = 1e4\nattachments1 = [{position = 0.1, '
        "mass = 1e-3, rotary_inertia = 1e-7}, {position = 0.05, stiffness = 50.0}]\n"
        "[axes.omega]\nmin = 40.0\nmax = 60.0\nnum = 3\n")
    assert main(["run", str(sweep), "-o", str(tmp_path / "out.nc"), "--quiet"]) == 0
    parts = (TIP_MASS, Spring(0.05, 50.0))
    with xr.open_dataset(tmp_path / "out.nc") as ds:
        assert ds.attrs["attachments1"] == "; ".join(map(repr, parts))
        mapped = ds.first_impact_time.values
    fixed = {"counterpart": "stop", "contact_stiffness": 1e4, "attachments1": parts}
    python = run_sweep(sweep_from_mapping({
        "t_max": 0.05, "n_modes": 10, "observables": ["first_impact_time"], "params": fixed,
        "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3}}}), parallel=False)
    assert np.array_equal(mapped, python.first_impact_time.values)
    params = tmp_path / "rig.toml"
    params.write_text("[params]\nattachments1 = [{position = 0.1, mass = 1e-3}]\n")
    assert main(["modes", "--params", str(params), "--contact-law", "tied"]) == 2
    assert "supports the paper's uniform beams only" in capsys.readouterr().err


@pytest.mark.parametrize("params", [STOP, PAIR, INTERIOR], ids=["stop", "two beams", "interior"])
def test_first_contacts_with_attachments_agree_with_the_fe_model(params):
    """The first two contacts of 40 modes per beam against the FE model, parts on its nodes.

    The FE's onsets converge as h^4 (16x per halving; at least 8x asserted), so |f160 - f320|
    bounds the 320-element run's error 15 times over; ours must lie within it. Measured (stop):
    first onset 1.4e-16 s from f320 (|f160 - f320| = 2.3e-15 s), second 2.9e-14 s (4.1e-13 s);
    durations and peaks within 1e-9 relative (|f160 - f320| 3e-10, 2e-10); interior parts:
    onsets 9e-16 s and 8e-14 s from f320 (|f160 - f320| 1.4e-14 s, 1.2e-12 s).
    """
    fe = {n: fe_spring_contacts(params, 1e4, t_max=0.05, n_elements=(n, n), n_contacts=2,
                                mode_rtol=1e-9) for n in (40, 80, 160, 320)}
    ds = simulate(params, 0.05, n_modes=40)
    ours = {"onset": ds.impact_onset_time.values[:2], "duration": ds.impact_duration.values[:2],
            "peak": ds.impact_peak_force.values[:2]}
    for key, values in ours.items():
        f40, f80, f160, f320 = (fe[n][key] for n in (40, 80, 160, 320))
        if key == "onset":  # the rate: durations and peaks reach round-off earlier
            assert np.all(np.abs(f40 - f80) >= 8 * np.abs(f80 - f160)), (f40, f80, f160)
        scale = 1.0 if key == "onset" else np.abs(f320)
        bound = np.abs(f160 - f320) / scale + 4e-16 * np.abs(f320) / scale + 1e-12 * (
            key != "onset")
        assert np.all(np.abs(values - f320) / scale <= bound), (key, values - f320, bound)


@pytest.mark.parametrize("counterpart", ["beam", "stop"])
def test_a_uniform_beam_given_as_a_structure_gives_todays_first_impact(counterpart):
    """One segment and a massless tip mass: Wittrick-Williams modes in place of the closed
    forms give today's first contacts: onsets to 1e-13 relative (measured 3e-14 over the
    first 10), durations to 1e-13 of the release time (they are differences of two such
    times: 6e-16 s measured), peak forces to 1e-10 (measured 2e-11)."""
    today = Params(counterpart=counterpart, contact_stiffness=1e4)
    keys = WEIGHTLESS if counterpart == "beam" else {"attachments1": WEIGHTLESS["attachments1"]}
    structured = today.replace(**keys)
    assert not beam(structured, 1).closed_form and beam(today, 1).closed_form
    assert_todays_contacts(*(simulate(p, 0.05, n_modes=20) for p in (structured, today)))


def assert_todays_contacts(got, expected):
    """The first 10 contacts of ``got`` are ``expected``'s to round-off: onsets to 1e-13
    relative, durations to 1e-13 of the release time, peak forces to 1e-10."""
    onsets = expected.impact_onset_time.values[:10]
    np.testing.assert_allclose(got.impact_onset_time.values[:10], onsets, rtol=1e-13, atol=0)
    durations = expected.impact_duration.values[:10]
    assert np.all(np.abs(got.impact_duration.values[:10] - durations)
                  <= 1e-13 * (onsets + durations))
    np.testing.assert_allclose(got.impact_peak_force.values[:10],
                               expected.impact_peak_force.values[:10], rtol=1e-10, atol=0)


def _sweep(observable, params, n_modes=10):
    return sweep_from_mapping({
        "t_max": 0.05, "n_modes": n_modes, "observables": [observable], "params": params,
        "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3},
                 "clearance": {"min": 1e-5, "max": 2e-5, "num": 2}}}, source="attachments")


def test_a_first_impact_map_with_a_tip_mass_equals_single_runs():
    """The map's column kernel against simulate()'s event search, cell by cell (1e-12 s, both
    certified to round-off), and the map says what the beam carries."""
    fixed = {"counterpart": "stop", "contact_stiffness": 1e4, "attachments1": (TIP_MASS,)}
    ds = run_sweep(_sweep("first_impact_time", fixed), parallel=False)
    assert ds.attrs["attachments1"] == repr(TIP_MASS)
    for i, omega in enumerate(ds.omega.values):
        for j, clearance in enumerate(ds.clearance.values):
            run = simulate(STOP.replace(omega=float(omega), clearance=float(clearance)), 0.05,
                           n_modes=10, dt_output=0.05)
            assert float(ds.first_impact_time[i, j]) == pytest.approx(
                float(run.impact_onset_time[0]), abs=1e-12)


def test_a_long_time_sweep_with_attachments_equals_single_runs():
    """Impact counts of the dynamics map equal simulate()'s with the same modes."""
    fixed = {"contact_stiffness": 1e4, "attachments1": (TIP_MASS, Spring(0.05, 50.0))}
    ds = run_sweep(_sweep("impact_count", fixed, n_modes=12), parallel=False)
    params = Params(**fixed)
    for i, omega in enumerate(ds.omega.values):
        run = simulate(params.replace(omega=float(omega), clearance=1e-5), 0.05, n_modes=12,
                       dt_output=0.05)
        assert int(ds.impact_count[i, 0]) == run.impact.size


def test_base_participation_with_attachments_is_the_mass_weighted_integral():
    """Gamma_n = int rhoA Y_n + sum m Y_n(x_m) (the [Y''']/k^4 identity per piece) against
    Gauss quadrature of the shapes (measured 3e-15 of the largest)."""
    parts = (PointMass(0.06, 2e-3, 1e-7), PointMass(0.1, 5e-4), Spring(0.03, 80.0, 0.5))
    p = Params(counterpart="stop", shaker="beam1", base_amplitude=1e-6, attachments1=parts)
    free = build_free_phase(p, 12)
    x, w = gauss_rule(p.l1)
    shapes = free.beam1.shapes
    quadrature = p.rhoA1 * shapes(x) @ w + 2e-3 * shapes(0.06)[:, 0] + 5e-4 * shapes(0.1)[:, 0]
    gamma = base_participation(p, free)
    assert np.abs(gamma - quadrature).max() < 1e-12 * np.abs(quadrature).max()


def test_the_static_shape_and_its_kinetic_norm_equal_the_fe_models():
    """u = w / w(L) under a tip force and <u, u> with masses, rotary inertia and springs,
    against Hermite FE matrices with the parts on nodes (cubics hold u exactly between them:
    the same numbers to round-off, measured 1e-15), and the tip compliance against K^-1."""
    parts = (PointMass(0.1, 1e-3, 1e-7), PointMass(0.05, 2e-3, 3e-8), Spring(0.025, 300.0, 0.4))
    p = Params(counterpart="stop", attachments1=parts)
    K, M, nodes = fe_model([(p.l1, p.EI1, p.rhoA1)], parts, per_metre=40)  # 4 elements
    column = np.linalg.solve(K, np.eye(len(K))[:, -2])  # unit tip force
    u = column / column[-2]
    modal = beam(p, 1)
    assert modal.tip_compliance == pytest.approx(column[-2], rel=1e-12)
    np.testing.assert_allclose(modal.unit_tip_shape(nodes[1:]), u[0::2], rtol=0, atol=1e-12)
    norm = modal.static_mass_per_length * modal.length * 33.0 / 140.0
    assert norm == pytest.approx(u @ M @ u, rel=1e-12)


def test_energy_balances_with_masses_springs_and_a_compliant_clamp():
    """Energy - work of F - unresolved kinetic energy stays constant without damping
    (measured 2e-14 of the energy), and the field's tip is the tip (1e-11 m: the residual)."""
    parts = (TIP_MASS, Spring(0.05, 50.0, 0.2), Spring(0.0, rotational_stiffness=20.0))
    p = Params(counterpart="stop", contact_stiffness=1e4, force_amplitude=2e-3,
               attachments1=parts)
    ds = simulate(p, 0.05, n_modes=20, energy_balance=True, fields=True)
    assert ds.impact.size > 3
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force).values
    assert np.abs(balance - balance[0]).max() < 1e-12 * np.abs(ds.energy.values).max()
    assert np.abs(ds.deflection_1.values[:, -1] - ds.tip_deflection_1.values).max() < 1e-11


def test_a_run_says_what_its_beams_carry():
    ds = simulate(STOP, 0.02, n_modes=10)
    assert ds.attrs["attachments1"] == repr(TIP_MASS)
    assert "attachments1" not in simulate(STOP.replace(attachments1=()), 0.01, n_modes=12).attrs


@pytest.mark.parametrize(("build", "message"), [
    (lambda: Params(contact_law="tied", attachments1=(TIP_MASS,)),
     "contact_law = 'tied' supports the paper's uniform beams only"),
    (lambda: Params(attachments1=(PointMass(0.2, 1e-3),)),
     r"attachments1\[0\].position = 0.2 is not allowed: must lie on the beam"),
    (lambda: Params(attachments1=3), "attachments1 = 3 is not allowed: must be a tuple"),
    (lambda: Params(attachments1=(1e-3,)),
     r"attachments1\[0\] = 0.001 is not allowed: must be a PointMass or a Spring"),
    (lambda: Params(counterpart="stop", attachments2=(TIP_MASS,)),
     "counterpart = 'stop' has no beam 2"),
    (lambda: Params(attachments1=(Spring(0.0),)), "must be > 0"),
    (lambda: Params(counterpart="stop", force_amplitude=0.1,
                    attachments1=(Spring(0.0, rotational_stiffness=0.05),)),  # a loose clamp
     r"force_amplitude = 0.1 is not allowed: its static tip deflection F0 c1 \(c1 with beam "
     r"1's attachments\) = 0.0237 m must be <= 0.2 l1"),
    (lambda: Params.from_mapping({"attachments1": [{"position": 0.1}]}),
     r"attachments1\[0\] = \{'position': 0.1\} is not allowed: a point mass is a table of"),
])
def test_bad_attachments_are_refused_in_one_line(build, message):
    with pytest.raises(ParameterError, match=message):
        build()


def test_what_cannot_take_attachments_refuses_them():
    from impactbeams.contact import build_tied_model

    with pytest.raises(ParameterError, match="the tied law supports the paper's uniform beams"):
        build_tied_model(STOP, 5)

    with pytest.raises(ParameterError, match="attachments1 is not sweepable"):
        sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                            "axes": {"attachments1": {"min": 0.0, "max": 1.0, "num": 2}}})
    # the grid's first point has the shortest beam (axes run from min to max)
    with pytest.raises(ParameterError, match=r"attachments1\[0\].position = 0.1 is not allowed: "
                                             r"must lie on the beam, 0 < x <= 0.05"):
        sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                            "params": {"counterpart": "stop", "attachments1": (TIP_MASS,)},
                            "axes": {"l1": {"min": 0.05, "max": 0.1, "num": 2}}})


def test_the_preflight_bounds_the_highest_frequency_of_a_beam_with_springs():
    """Stiff springs raise the frequencies past the uniform beam's (the check would pass runs
    it should refuse); the bound by interlacing, mode n + springs of the uniform beam, holds."""
    from impactbeams.preflight import highest_frequency

    parts = (PointMass(0.1, 1e-3), Spring(0.05, 1e9, 1e6), Spring(0.0, rotational_stiffness=3.0))
    p = Params(counterpart="stop", attachments1=parts)
    assert p.grounded_springs == 2
    for n in (5, 20):
        highest = beam(p, 1).free_modes(n).frequencies[-1]
        assert highest_frequency(p.numeric(), n) < highest  # the uniform beam's: too low
        assert highest <= highest_frequency(p.numeric(), n, p.grounded_springs)


@pytest.mark.parametrize("omega", [100.0, 500.0, 3000.0])
def test_the_shakers_steady_response_with_a_tip_mass_agrees_with_the_fe_model(omega):
    """The non-impacting steady gap under base motion of beam 1's clamp (the participation
    factors with the tip mass, the tip's absolute motion) against the FE model's
    (K - Omega^2 M) x = Omega^2 U0 M r, solved through the closed-form flexibility F.

    The FE converges as h^3 here (8x per halving, at least 6x asserted); its Richardson limit
    agrees with 80 modes to 2e-9 relative (measured 2e-12 to 1.8e-9), and 80 modes lie within
    |f160 - f320| of f320.
    """
    p = Params(counterpart="stop", shaker="beam1", base_amplitude=1e-6, omega=omega,
               clearance=1e-3, attachments1=(TIP_MASS,))
    ours = ib.steady_gap(p, 80).phasor.real
    fe = {}
    for n in (80, 160, 320):
        pair = build_pair(p, (n,))
        rigid = np.zeros(len(pair.M))
        rigid[0::2] = 1.0  # the clamp's translation: every deflection, no slope
        FM = pair.F @ pair.M
        x = np.linalg.solve(np.eye(len(FM)) - omega**2 * FM, FM @ rigid * 1e-6 * omega**2)
        fe[n] = x[pair.tip1] + 1e-6  # the gap sees the tip's absolute motion
    assert abs(fe[80] - fe[160]) >= 6 * abs(fe[160] - fe[320])
    assert abs(ours - fe[320]) <= abs(fe[160] - fe[320])
    limit = fe[320] + (fe[320] - fe[160]) / 7.0
    assert ours == pytest.approx(limit, rel=2e-9)
