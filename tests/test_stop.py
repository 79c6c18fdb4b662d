"""Beam 1 against a fixed rigid stop (``counterpart = "stop"``) against independent references.

The spring law's contact frequencies against the exact characteristic equation of a cantilever
with a tip spring (written here), the tied law's against the clamped-pinned roots, the first
impact against the closed-form modal series, the first five spring contacts against an FE model
of the one beam (tests/data/stop_spring_fe.json from fe_spring.py), the energy invariant, and
the parameter refusals that a stop brings.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.optimize import brentq

from fe_spring import mesh_deviations
from impactbeams import Params, simulate
from impactbeams.contact import build_free_phase, build_tied_model, spring_contact
from impactbeams.contact.spring import recommended_modes
from impactbeams.modes import cantilever_roots, pinned_roots
from impactbeams.params import ParameterError

STOP = Params(counterpart="stop")
FE_DATA = Path(__file__).parent / "data" / "stop_spring_fe.json"


def tip_spring_determinant(b: float, EI: float, length: float, k: float) -> float:
    """det of the 4x4 boundary system of a cantilever with a tip spring k, at b = s l.

    y = A1 cosh sx + A2 sinh sx + A3 cos sx + A4 sin sx with y(0) = y'(0) = 0, y''(l) = 0 and
    EI y'''(l) = k y(l) (the spring pushes the tip back). Rows 3 and 4 are divided by cosh b
    and row 4 by EI s^3 + k, so that every entry is O(1).
    """
    s = b / length
    sh, c, si = math.tanh(b), math.cos(b) / math.cosh(b), math.sin(b) / math.cosh(b)
    e, f = EI * s**3 / (EI * s**3 + k), k / (EI * s**3 + k)
    return np.linalg.det(np.array([
        [1.0, 0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0, 1.0],
        [1.0, sh, -c, -si],
        [e * sh - f, e - f * sh, e * si - f * c, -e * c - f * si]]))


def tip_spring_roots(EI: float, length: float, k: float, n: int) -> np.ndarray:
    """b of the first n modes: each between the cantilever's and the clamped-pinned root."""
    return np.array([brentq(tip_spring_determinant, lo, hi, args=(EI, length, k), xtol=1e-15,
                            rtol=1e-15) for lo, hi in zip(cantilever_roots(n), pinned_roots(n),
                                                          strict=True)])


def beam1_frequencies(b: np.ndarray) -> np.ndarray:
    return math.sqrt(STOP.EI1 / STOP.rhoA1) * (b / STOP.l1) ** 2


# --- contact frequencies ------------------------------------------------------------------


def test_pinned_roots_solve_tan_equal_tanh():
    """tan b = tanh b, in a form without poles: sin b - cos b tanh b = 0 to round-off of b
    (its slope is ~1, so the residual is the root's absolute error); and b_j -> (j + 1/4) pi."""
    b = pinned_roots(8)
    assert np.all(np.abs(np.sin(b) - np.cos(b) * np.tanh(b)) < 4 * np.finfo(float).eps * b)
    assert b[0] == pytest.approx(3.926602312047919, rel=1e-15)
    assert abs(b[-1] - 8.25 * np.pi) < 1e-12


@pytest.mark.parametrize("k", [1e1, 1e3, 1e5, 1e7, 1e9])
def test_spring_stop_frequencies_solve_the_tip_spring_equation(k):
    """Spring law against a stop: the undamped contact frequencies at 100 modes are the roots
    of the 4x4 characteristic equation to 1e-10 relative (measured <= 2.4e-11: with the static
    correction the truncated modes' dynamic remainder, which falls with the number of modes;
    at 40 modes it is 1e-8 for the 5th mode)."""
    exact = beam1_frequencies(tip_spring_roots(STOP.EI1, STOP.l1, k, 5))
    free = build_free_phase(STOP, 100)
    got = spring_contact(free, STOP.tip_compliance, 0.0, k).frequencies[:5]
    np.testing.assert_allclose(got, exact, rtol=1e-10)


def test_stiff_spring_approaches_the_clamped_pinned_roots():
    """As k grows the tip-spring roots go to tan b = tanh b, the distance falling like 1 / k."""
    distances = [np.max(np.abs(tip_spring_roots(STOP.EI1, STOP.l1, k, 5) / pinned_roots(5) - 1))
                 for k in (1e5, 1e7, 1e9)]
    assert distances[0] > distances[1] > distances[2]
    assert distances[2] < 2e-6
    assert distances[1] / distances[2] == pytest.approx(100, rel=0.05)


def test_tied_stop_contact_modes_are_the_clamped_pinned_beam():
    """Tied law: as many contact modes as free coordinates (n, beam 1's), at the clamped-pinned
    frequencies to 1e-10 (measured ~1e-16), with zero tip deflection and unit mass (quadrature,
    1e-12); no shapes on beam 2."""
    model = build_tied_model(STOP.replace(contact_law="tied"), 12)
    contact = model.contact
    assert contact.frequencies.size == model.free.frequencies.size == 12
    np.testing.assert_allclose(contact.frequencies, beam1_frequencies(pinned_roots(12)),
                               rtol=1e-10)
    assert np.all(np.abs(contact.beam1.tip() * np.sqrt(STOP.rhoA1 * STOP.l1)) < 1e-12)
    assert contact.beam2.k.size == 0 and not np.any(model.contact_tip)
    x = np.linspace(0.0, STOP.l1, 20001)
    shapes = contact.beam1(x)
    gram = np.trapezoid(shapes[:, None, :] * shapes[None, :, :] * STOP.rhoA1, x, axis=2)
    np.testing.assert_allclose(gram, np.eye(12), atol=5e-7)  # trapezoid rule: h^2 error
    # the contact force of each shape is beam 1's tip shear, -EI1 Z'''(l1)
    np.testing.assert_array_equal(model.contact_shear2, -STOP.EI1 * contact.beam1.tip(3))
    assert not np.any(model.contact_drive) and not np.any(model.contact_unit2)


def test_tied_stop_projections_of_the_static_shape():
    """<u_1, Z_m> from the boundary identity (EI1 Z'''(l1) / omega_m^2, since Z(l1) = 0)
    equals Gauss-Legendre quadrature to 1e-12 of the largest; the static shift is c1 <u_1, Z>."""
    from impactbeams.contact import quadrature, unit_tip_shape

    model = build_tied_model(STOP.replace(contact_law="tied"), 8)
    x, w = quadrature(STOP.l1, model.contact.beam1.k[-1])
    by_quadrature = (model.contact.beam1(x) * STOP.rhoA1 * w) @ unit_tip_shape(STOP.l1, x)
    scale = np.max(np.abs(by_quadrature))
    np.testing.assert_allclose(model.contact_unit1, by_quadrature, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(model.contact_static_shift,
                                  STOP.tip_compliance[0] * model.contact_unit1)


# --- first impact, energy -------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:n_modes = 10 does not resolve:RuntimeWarning")
@pytest.mark.parametrize("law", ["tied", "spring"])
def test_first_impact_of_the_free_vibration_is_the_closed_form_series(law):
    """F0 = 0 from a static uplift delta: y1(l1, t) = delta sum_n (12 / b_n^4) cos(omega_n t)
    (mass-normalised tip values Y_n(l)^2 = 4 / (rhoA l), so <u_1, Y_n> Y_n(l) = 12 / b_n^4;
    the sum is 1 at t = 0). With the same 10 modes the first impact solves
    clearance + y1(l1, t) = 0 to round-off of the time (1e-12 s)."""
    n, uplift = 10, 3e-5
    params = STOP.replace(force_amplitude=0.0, uplift1=uplift, contact_law=law)
    b = cantilever_roots(n)
    w = beam1_frequencies(b)
    assert np.sum(12 / b**4) == pytest.approx(1.0, abs=1e-4)  # the series' tail beyond 10

    def gap(t: float) -> float:
        return params.clearance + uplift * np.sum(12 / b**4 * np.cos(w * t))

    t = np.linspace(0.0, 0.02, 200001)
    first = np.flatnonzero(np.array([gap(s) for s in t]) < 0)[0]
    expected = brentq(gap, t[first - 1], t[first], xtol=1e-16, rtol=1e-15)
    ds = simulate(params, 0.02, n_modes=n, dt_output=1e-3)
    assert float(ds.impact_onset_time[0]) == pytest.approx(expected, abs=1e-12)
    # against the stop: tip 2 is the stop's position, -clearance, at every time
    np.testing.assert_array_equal(ds.tip_deflection_2.values, -params.clearance)


def test_spring_stop_energy_is_constant_without_force_and_damping():
    """F0 = 0, c = 0, zeta = 0: kinetic + bending + k_e g^2 / 2 is an exact invariant (exact
    propagation, identity switches): constant to 1e-12 relative over many contacts."""
    params = STOP.replace(force_amplitude=0.0, uplift1=3e-5, contact_stiffness=1e5)
    ds = simulate(params, 0.2, n_modes=recommended_modes(params), dt_output=1e-5)
    assert ds.impact.size > 20
    energy = ds.energy.values
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-12
    # the initial energy is the uplift's strain energy 3 EI1 delta^2 / (2 l1^3)
    assert energy[0] == pytest.approx(1.5 * STOP.EI1 * 3e-5**2 / STOP.l1**3, rel=1e-12)


# --- the spring law against the FE model of one beam ------------------------------------------


def test_first_five_spring_contacts_agree_with_the_fe_model_of_one_beam():
    """40 modes against the FE model of beam 1 alone with the same law (Fig. 3 forcing,
    k = 1e4 N/m; tests/data/stop_spring_fe.json at 40, 80, 160 elements).

    Bound: the FE's own error, estimated conservatively by |f_160 - f_80| (its convergence in
    these contact quantities is erratic, so no Richardson order is trusted), plus the modal
    truncation at 40 modes with the static correction (1e-6); onsets relative to the shortest
    duration. Measured: at most 1.7e-5 relative (the 4th contact, a 0.17 ms micro-contact whose
    FE values still move by 1e-4 from 80 to 160 elements), below 5e-6 on the other four; the FE
    error estimate is never approached by more than 0.9 of itself.
    """
    data = json.loads(FE_DATA.read_text())
    params = Params(**data["params"])
    fe80, fe160 = ({key: np.array(value) for key, value in data["fe_by_mesh"][n].items()}
                   for n in ("80", "160"))
    ds = simulate(params, 0.05, n_modes=40)
    got = {"onset": ds.impact_onset_time.values[:5], "duration": ds.impact_duration.values[:5],
           "impulse": ds.impact_impulse.values[:5], "peak": ds.impact_peak_force.values[:5]}
    for key, (deviation, fe_error) in mesh_deviations(got, fe80, fe160).items():
        assert np.all(deviation <= fe_error + 1e-6), (key, deviation, fe_error)
        assert deviation.max() < 2e-5, key


# --- parameters, sweeps and the command line -------------------------------------------------


@pytest.mark.parametrize(("argv", "fragment"), [
    (["modes", "--counterpart", "stop", "--l2", "0.2"], "--l2 in the command line"),
    (["modes", "--counterpart", "stop", "--E2", "7e10"], "--E2 in the command line"),
    (["modes", "--counterpart", "stop", "--uplift2", "1e-6"], "uplift2 = 1e-06 is not allowed"),
    (["modes", "--counterpart", "wall"], "invalid choice: 'wall'"),
])
def test_a_stop_refuses_beam_2_on_the_command_line(capsys, argv, fragment):
    from impactbeams.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    # one line, after the usage line if an argument itself is wrong
    lines = err.splitlines()
    assert len(lines) == 1 or (len(lines) == 2 and lines[0].startswith("usage: impactbeams modes"))
    assert fragment in lines[-1] and "Traceback" not in err


def test_params_of_a_stop():
    """Beam 2's keys: refused when given (TOML, mappings, keywords off their defaults); a
    two-beam Params becomes a stop by replace, beam 2's values dropped; c2 = 0."""
    assert STOP.tip_compliance[1] == 0.0 and STOP.tip_compliance[0] == Params().tip_compliance[0]
    assert Params(l2=0.3).replace(counterpart="stop") == STOP
    assert STOP.replace(counterpart="beam") == Params()
    with pytest.raises(ParameterError, match=r"^l2 = 0.3 is not allowed: counterpart = 'stop'"):
        Params(counterpart="stop", l2=0.3)
    with pytest.raises(ParameterError, match=r"^rhoA2 in parameters is not allowed"):
        Params.from_mapping({"counterpart": "stop", "rhoA2": Params().rhoA2})
    with pytest.raises(ParameterError, match=r"^thickness2 in parameters is not allowed"):
        Params.from_mapping({"counterpart": "stop", "thickness2": 1e-3})
    with pytest.raises(ParameterError, match=r"^uplift2 = -1e-06 is not allowed: must be 0"):
        Params(counterpart="stop", uplift2=-1e-6)
    with pytest.raises(ParameterError, match=r"^counterpart = 'wall' is not allowed"):
        Params(counterpart="wall")
    # beam 1 alone closes the clearance: at most 0.2 l1 (two beams: 0.2 (l1 + l2))
    Params(clearance=0.03)
    with pytest.raises(ParameterError, match=r"^clearance = 0.03 is not allowed.*0.2 l1"):
        Params(counterpart="stop", clearance=0.03)


def _sweep_text(body):
    return ('t_max = 0.05\nn_modes = 5\nobservables = ["first_impact_time", "impact_count", '
            '"max_contact_force"]\n' + body)


@pytest.mark.parametrize(("body", "fragment"), [
    ('[params]\ncounterpart = "stop"\nl2 = 0.2\n[axes.omega]\nmin = 50.0\nmax = 60.0\nnum = 2\n',
     "l2 in [params] of "),
    ('[params]\ncounterpart = "stop"\n[axes.EI2]\nmin = 0.01\nmax = 0.02\nnum = 2\n',
     "EI2 in [axes] of "),
    ('[axes.counterpart]\nmin = 0\nmax = 1\nnum = 2\n', "counterpart is not sweepable"),
])
def test_a_stop_sweep_refuses_beam_2(tmp_path, capsys, body, fragment):
    from impactbeams.cli import main

    (tmp_path / "s.toml").write_text(_sweep_text(body))
    assert main(["run", str(tmp_path / "s.toml"), "-o", str(tmp_path / "s.nc")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err and "Traceback" not in err
    assert "counterpart" in err
    assert not (tmp_path / "s.nc").exists()


@pytest.fixture(scope="module")
def stop_map():
    """A first-impact and dynamics map of the stop over Omega and F0, both laws."""
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    sweep = sweep_from_mapping({
        "t_max": 0.05, "n_modes": 6,
        "observables": ["first_impact_time", "impact_count", "max_contact_force"],
        "params": {"counterpart": "stop", "contact_stiffness": 1e4},
        "axes": {"omega": {"min": 40.0, "max": 300.0, "num": 3},
                 "force_amplitude": {"min": 5e-4, "max": 2e-3, "num": 2},
                 "contact_law": {"values": ["spring", "tied"]}}}, source="stop map")
    return sweep, run_sweep(sweep, parallel=False)


@pytest.mark.filterwarnings("ignore:n_modes = 6 does not resolve:RuntimeWarning")
def test_stop_map_cells_equal_single_runs(stop_map):
    """Every cell of the map (the column algorithm for the first impact, the dynamics kernels
    for the counts and forces) equals simulate() of its parameters, bit for bit; the counterpart
    is recorded and is part of the sweep's fingerprint."""
    from impactbeams.sweep import sweep_from_mapping

    sweep, ds = stop_map
    assert ds.attrs["counterpart"] == "stop"
    beam = sweep_from_mapping({**sweep.definition(), "params": {"contact_stiffness": 1e4}})
    assert beam.fingerprint() != sweep.fingerprint()
    assert np.all(np.isfinite(ds.first_impact_time.values))
    for i, omega in enumerate(ds.omega.values):
        for j, force in enumerate(ds.force_amplitude.values):
            for k, law in enumerate(ds.contact_law.values):
                params = STOP.replace(omega=float(omega), force_amplitude=float(force),
                                      contact_law=str(law), contact_stiffness=1e4)
                run = simulate(params, 0.05, n_modes=6, dt_output=0.05)
                cell = ds.isel(omega=i, force_amplitude=j, contact_law=k)
                assert float(cell.first_impact_time) == float(run.impact_onset_time[0])
                assert int(cell.impact_count) == run.impact.size
                assert float(cell.max_contact_force) == float(run.impact_peak_force.max())


@pytest.fixture(scope="module")
def long_run():
    """A damped, forced stop run with episodes, long-time samples and two exponents."""
    from impactbeams import LongTime

    params = STOP.replace(contact_stiffness=1e4, damping_ratio=0.01, omega=200.0,
                          force_amplitude=2e-3)
    return simulate(params, 1.0, n_modes=12, lyapunov=2, transient_periods=10,
                    long_time=LongTime(sampled_periods=20))


def test_long_run_against_a_stop(long_run):
    """Everything a run offers works against a stop: the Lyapunov spectrum of the state
    (q, q') of beam 1's 12 modes (dimension 24, two exponents, the largest first), the
    long-time samples, the episodes; beam 2's parameters are not in the attributes (ignored
    defaults) and tip 2 is the stop."""
    ds = long_run
    assert ds.attrs["counterpart"] == "stop" and "l2" not in ds.attrs and "EI2" not in ds.attrs
    assert ds.impact.size > 20
    spectrum = ds.lyapunov_spectrum.values
    assert spectrum.size == 2 and np.all(np.isfinite(spectrum)) and spectrum[0] >= spectrum[1]
    assert np.all(ds.tip_deflection_2.values == -STOP.clearance)
    assert np.all(ds.gap.values[ds.in_contact.values == 0] > -1e-9)
    assert ds.sizes["episode"] > 0 and ds.sizes["period"] == 20


def test_fields_of_a_stop():
    """Beam 1's field ends at its tip deflection; beam 2's field is zero (there is none)."""
    params = STOP.replace(contact_law="tied", force_amplitude=2e-3)
    ds = simulate(params, 0.03, n_modes=5, dt_output=1e-3, fields=True, n_points=11)
    np.testing.assert_allclose(ds.deflection_1.values[:, -1], ds.tip_deflection_1.values,
                               rtol=0, atol=1e-15)
    assert not np.any(ds.deflection_2.values)


def test_lyapunov_count_is_bounded_by_beam_1_alone():
    from impactbeams.trajectory.lyapunov import check_request

    """The state (q, q') has 2 n_modes coordinates against a stop (4 n_modes for two beams)."""
    check_request(STOP, 6, 1.0, 12, 0)
    with pytest.raises(ParameterError, match=r"from 1 to 12 \(2 n_modes\)"):
        check_request(STOP, 6, 1.0, 13, 0)


def test_plots_of_a_stop_name_it(long_run, tmp_path):
    import matplotlib.pyplot as plt

    from impactbeams.plotting.trajectories import plot_tips

    figure, axis = plt.subplots()
    plot_tips(axis, long_run)
    assert [line.get_label() for line in axis.get_lines()][1] == r"stop, $-\Delta$"
    plt.close(figure)


def test_modes_command_of_a_stop(capsys):
    from impactbeams.cli import main

    assert main(["modes", "--n", "3", "--json", "--counterpart", "stop", "--contact-law",
                 "tied"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert set(result["free"]) == {"beam1"} and result["counterpart"] == "stop"
    np.testing.assert_allclose(result["contact"], beam1_frequencies(pinned_roots(3)), rtol=1e-13)


# --- the old names --------------------------------------------------------------------------


def test_old_names_still_work_and_warn(monkeypatch):
    """build_model is build_tied_model (DeprecationWarning once per process); ``omega`` of the
    natural frequencies is ``frequencies`` (``omega`` names the forcing frequency)."""
    import impactbeams as ib
    import impactbeams.contact.tied as tied
    from impactbeams.model import build_model

    monkeypatch.setattr(tied, "_warned", set())
    with pytest.warns(DeprecationWarning, match="build_tied_model"):
        old = build_model(Params(), 3)
    new = ib.build_tied_model(Params(), 3)
    np.testing.assert_array_equal(old.overlap, new.overlap)
    build_model(Params(), 3)  # once: no second warning (warnings are errors in the tests)
    with pytest.warns(DeprecationWarning, match="frequencies"):
        np.testing.assert_array_equal(new.free.omega, new.free.frequencies)
    with pytest.warns(DeprecationWarning, match="frequencies"):
        np.testing.assert_array_equal(new.contact.omega, new.contact.frequencies)
    with pytest.warns(DeprecationWarning, match="frequencies"):
        np.testing.assert_array_equal(new.free.beam1.omega, new.free.beam1.frequencies)


def test_first_impact_map_of_a_stop_uses_the_column_algorithm():
    """A first-impact map (the column kernel over Omega at each F0) against the one-cell event
    search of simulate(): the same first impact to 1e-12 s (both certified to round-off)."""
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    sweep = sweep_from_mapping({
        "t_max": 0.1, "n_modes": 5, "observables": ["first_impact_time"],
        "params": {"counterpart": "stop", "contact_law": "tied"},
        "axes": {"force_amplitude": {"min": 2e-4, "max": 1e-3, "num": 3},
                 "omega": {"min": 30.0, "max": 400.0, "num": 5}}}, source="stop columns")
    ds = run_sweep(sweep, parallel=False)
    assert not sweep.needs_dynamics and ds.attrs["counterpart"] == "stop"
    for j, force in enumerate(ds.force_amplitude.values):
        for i, omega in enumerate(ds.omega.values):
            run = simulate(STOP.replace(omega=float(omega), force_amplitude=float(force),
                                        contact_law="tied"), 0.1, n_modes=5, dt_output=0.1)
            expected = float(run.impact_onset_time[0]) if run.impact.size else math.nan
            got = float(ds.first_impact_time[j, i])
            assert got == pytest.approx(expected, abs=1e-12, nan_ok=True), (force, omega)


SHIPPED = Path(__file__).resolve().parents[1] / "sweeps"
# the README's stop-and-shaker commands on reduced grids (the full ones take about 90 s):
# every 25th Omega of the map, and 6 Omega values over 50 + 20 periods for the diagram
REDUCED = {"stop-shaker-omega-amplitude.toml": {"num = 1000": "num = 40"},
           "stop-shaker-bifurcation.toml": {"num = 400": "num = 6",
                                            "transient_periods = 500": "transient_periods = 50",
                                            "sampled_periods = 200": "sampled_periods = 20"}}


@pytest.mark.parametrize("name", sorted(REDUCED))
def test_the_readme_stop_and_shaker_commands_run(name, tmp_path, monkeypatch):
    """The shipped sweeps run and plot; the map's first impact never comes later for a larger U0.

    Along U0 the gap is the clearance plus U0 times one response (affine): a larger U0 closes it
    no later, and a cell that impacts stays impacting as U0 grows.
    """
    from impactbeams.cli import main

    text = (SHIPPED / name).read_text()
    for old, new in REDUCED[name].items():
        assert old in text
        text = text.replace(old, new)
    monkeypatch.chdir(tmp_path)
    Path(name).write_text(text)
    assert main(["run", name, "-o", "out.nc", "--quiet"]) == 0
    assert main(["plot", "out.nc", "-o", "out.png"]) == 0
    assert Path("out.png").stat().st_size > 10_000
    with xr.open_dataset("out.nc") as result:
        assert result.attrs["counterpart"] == "stop" and result.attrs["shaker"] == "both"
        if "first_impact_time" in result:
            t_star = result.first_impact_time.transpose("omega", "base_amplitude").values
            impacting = ~np.isnan(t_star)
            assert impacting.any() and not impacting.all()
            assert np.all(np.diff(impacting.astype(int), axis=1) >= 0)  # impacting as U0 grows
            both = impacting[:, 1:] & impacting[:, :-1]
            assert np.all(np.diff(np.where(impacting, t_star, 0.0), axis=1)[both] <= 1e-12)
        else:
            assert (result.steady_impact_rate > 0).any()


# --- shaker = "both" moves the stop: said once per run, only where it was not asked for ------


def _moving_stop_warnings(record):
    return [w for w in record if "moves the stop with beam 1's clamp" in str(w.message)]


def test_a_stop_on_a_shaker_left_at_both_is_told_once_per_simulate(recwarn):
    """One line per call (not per window or phase); none where the shaker is named, where it
    carries beam 1 only, where nothing shakes, or for two beams; kept through ``replace``."""
    import warnings

    unasked = Params(counterpart="stop", base_amplitude=1e-6)
    assert unasked.moving_stop() == unasked.replace(omega=100.0, force_amplitude=1e-4
                                                    ).moving_stop() is not None
    for quiet in (Params(counterpart="stop", base_amplitude=1e-6, shaker="both"),
                  Params.from_mapping({"counterpart": "stop", "base_amplitude": 1e-6,
                                       "shaker": "both"}).replace(omega=80.0),
                  Params(counterpart="stop", base_amplitude=1e-6, shaker="beam1"),
                  Params(counterpart="stop"), Params(base_amplitude=1e-6)):
        assert quiet.moving_stop() is None
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        simulate(unasked, 0.05, n_modes=3, dt_output=0.01)
        assert len(_moving_stop_warnings(recwarn)) == 1
        simulate(unasked.replace(shaker="both"), 0.05, n_modes=3, dt_output=0.01)
    assert len(_moving_stop_warnings(recwarn)) == 1


def test_a_sweep_tells_it_once_and_the_shipped_sweeps_not_at_all(tmp_path, capsys):
    """A map of 2 x 3 cells along U0 from 0: one warning line from ``run`` (per sweep, not per
    cell); the shipped stop-and-shaker sweeps name their shaker and say nothing."""
    from impactbeams.cli import main
    from impactbeams.sweep import load_sweep
    from impactbeams.sweep.run import _warn_moving_stop

    path = tmp_path / "shaken.toml"
    path.write_text('t_max = 0.05\nn_modes = 3\n[params]\ncounterpart = "stop"\n'
                    "[axes.omega]\nmin = 100.0\nmax = 200.0\nnum = 2\n"
                    "[axes.base_amplitude]\nmin = 0.0\nmax = 1e-6\nnum = 3\n")
    assert main(["run", str(path), "-o", str(tmp_path / "shaken.nc"), "--quiet"]) == 0
    assert capsys.readouterr().err == (
        f"impactbeams: warning: {path}: shaker = 'both' (the default) moves the stop with beam "
        "1's clamp, as on one shaker table: set shaker = 'beam1' for a fixed stop, or shaker = "
        "'both' to say so\n")
    shipped = sorted((Path(__file__).parents[1] / "sweeps").glob("*shaker*.toml"))
    assert len(shipped) == 3
    for sweep in shipped:
        _warn_moving_stop(load_sweep(sweep))  # pytest turns a warning into an error
