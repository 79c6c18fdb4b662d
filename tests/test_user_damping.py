"""A user structure's own damping: a damping matrix C diagonal in its modes, or modal ratios.

Independent checks: Rayleigh damping's modal ratios in closed form; the damped FE equations
with the contact spring integrated directly (scipy DOP853 on M x'' + C x' + K x = f, each phase
to its event) against the engine's first contacts; the steady response without contact
against the direct solve (K - Omega^2 M + i Omega C) x = f and against the modal sum with
per-mode ratios; per-mode ratios all equal to ``damping_ratio`` give today's run bit for bit.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from fe_reference import beam_matrices, tip_dof
from impactbeams import Continuation, MatrixStructure, ModalStructure, simulate, two_sided_stop
from impactbeams.modes import beam
from impactbeams.orbits.grazing import LinearGap
from impactbeams.params import ParameterError, Params
from impactbeams.structure.user import read_structure
from impactbeams.sweep import sweep_from_mapping
from test_user_structure import analytic_modal_data

STOP = Params(counterpart="stop", contact_stiffness=1e4)
ELEMENTS = 6  # 12 DOFs: every mode in the engine, so that its model is the FE model itself
K6, M6 = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, ELEMENTS)
TIP = tip_dof(ELEMENTS)
OMEGA_MAX = float(np.sqrt(scipy.linalg.eigh(K6, M6, eigvals_only=True)[-1]))
# alpha: 2 % on the fundamental (170.9 rad/s); beta: 25 % on the highest FE mode
ALPHA, BETA = 2 * 0.02 * 170.9, 0.5 / OMEGA_MAX
C6 = ALPHA * M6 + BETA * K6


def rayleigh(**keys) -> MatrixStructure:
    return MatrixStructure(M6, K6, contact_dof=TIP, length=STOP.l1, damping=C6, **keys)


def test_rayleigh_damping_gives_its_closed_form_ratios():
    """zeta_n = alpha / (2 omega_n) + beta omega_n / 2 for every mode of the 6- and the
    40-element FE cantilevers (dense), the 10 lowest (sparse): within 1e-8 (measured 3e-12
    at 6 elements, 2.4e-9 on the highest of 40 elements' 80 modes, which the flexibility's
    eigenproblem computes to eps cond(K) only; the low modes' to 1e-12)."""
    for elements in (6, 40):
        K, M = beam_matrices(STOP.EI1, STOP.rhoA1, STOP.l1, elements)
        for sparse in (False, True):
            matrices = [scipy.sparse.csr_matrix(a) if sparse else a
                        for a in (M, K, ALPHA * M + BETA * K / 1e3)]
            structure = MatrixStructure(*matrices[:2], contact_dof=tip_dof(elements),
                                        length=STOP.l1, damping=matrices[2])
            n = 2 * elements if not sparse else 10
            modes = structure.modes(n)
            expected = ALPHA / (2 * modes.frequencies) + BETA / 1e3 * modes.frequencies / 2
            np.testing.assert_allclose(modes.damping_ratios, expected, rtol=1e-8, atol=0)
            np.testing.assert_array_equal(beam(STOP.replace(structure1=structure),
                                               1).own_damping_ratios(n), modes.damping_ratios)


def _phase(M, C, K, force, t0, y0, t_max, event):
    """One smooth phase of M x'' + C x' + K x = force(t) from y0 = (x, x') at t0, to ``event``."""
    size = M.shape[0]
    factor = scipy.linalg.cho_factor(M)

    def rate(t, y):
        return np.concatenate([y[size:], scipy.linalg.cho_solve(
            factor, force(t) - C @ y[size:] - K @ y[:size])])

    event.terminal = True
    return solve_ivp(rate, (t0, t_max), y0, method="DOP853", rtol=1e-13, atol=1e-20,
                     events=event, dense_output=True)


def ode_contacts(params: Params, t_max: float, count: int) -> dict[str, np.ndarray]:
    """The first ``count`` contacts of the damped FE model against the stop, by DOP853.

    Free: M x'' + C x' + K x = -F0 sin(Omega t) e; contact: + k e e^T x = -k clearance e
    (R = -k g, g = clearance + x_tip); onset g falls through 0, release g rises through 0.
    """
    size, k = K6.shape[0], params.contact_stiffness
    e = np.zeros(size)
    e[TIP] = 1.0
    clearance, F0, omega = params.clearance, params.force_amplitude, params.omega

    def load(spring):
        return lambda t: -F0 * np.sin(omega * t) * e - spring * clearance * e

    def gap(t, y):
        return clearance + y[TIP]

    t, y, out = 0.0, np.zeros(2 * size), {"onset": [], "duration": [], "peak": []}
    while len(out["duration"]) < count:
        gap.direction = -1.0
        free = _phase(M6, C6, K6, load(0.0), t, y, t_max, gap)
        t, y = free.t_events[0][0], free.y_events[0][0]
        gap.direction = 1.0
        contact = _phase(M6, C6, K6 + k * np.outer(e, e), load(k), t, y, t_max, gap)
        release = contact.t_events[0][0]
        # the force's largest sample, then its maximum between that sample's neighbours
        samples = np.linspace(t, release, 401)
        force = -k * (clearance + contact.sol(samples)[TIP])
        best = int(np.argmax(force))
        peak = minimize_scalar(lambda s, c=contact: k * gap(s, c.sol(s)),
                               bounds=(samples[max(best - 1, 0)], samples[min(best + 1, 400)]),
                               method="bounded", options={"xatol": 1e-14})
        out["onset"].append(t)
        out["duration"].append(release - t)
        out["peak"].append(-peak.fun)
        t, y = release, contact.y_events[0][0]
    return {key: np.array(value) for key, value in out.items()}


@pytest.mark.slow  # the DOP853 reference takes 6 s; the ratios and the steady state are fast
def test_rayleigh_damped_fe_model_against_its_equations_integrated_directly():
    """Three contacts of the 12-DOF FE cantilever with Rayleigh C (zeta from 0.5 % to 25 %)
    against a stop, all 12 modes, against DOP853 on M x'' + C x' + K x = f (rtol 1e-13):
    onsets within 1e-13 s, durations and peak forces within 1e-10 relative (measured 6e-16 s,
    3.2e-13 and 8.1e-13: the integrator's tolerance)."""
    params = STOP.replace(structure1=rayleigh())
    got = simulate(params, 0.05, n_modes=2 * ELEMENTS)
    reference = ode_contacts(STOP, 0.05, 3)
    np.testing.assert_allclose(got.impact_onset_time.values[:3], reference["onset"], rtol=0,
                               atol=1e-13)
    np.testing.assert_allclose(got.impact_duration.values[:3], reference["duration"],
                               rtol=1e-10)
    np.testing.assert_allclose(got.impact_peak_force.values[:3], reference["peak"], rtol=1e-10)
    # the damping matters here: the undamped model's third peak is 8 % off the damped one's
    undamped = simulate(STOP.replace(structure1=MatrixStructure(M6, K6, contact_dof=TIP,
                                                                length=STOP.l1)),
                        0.05, n_modes=2 * ELEMENTS)
    assert np.abs(undamped.impact_peak_force.values[2] / reference["peak"][2] - 1) > 0.05


def test_the_energy_balance_closes_with_a_structures_own_damping():
    """E - U - work of F + dissipation (2 zeta_n omega_n per mode) is constant over the
    Rayleigh-damped FE model's first 6 contacts: within 1e-11 of the largest energy (measured
    6.2e-14, the quadratures' round-off) while the dissipation grows to 35 % of it."""
    times = np.linspace(0.0, 0.02, 201)
    ds = simulate(STOP.replace(structure1=rayleigh()), 0.02, n_modes=2 * ELEMENTS, times=times,
                  energy_balance=True)
    assert ds.impact.size >= 3
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force
               + ds.damping_dissipation).values
    scale = float(np.max(ds.energy))
    assert np.max(np.abs(balance - balance[0])) < 1e-11 * scale
    assert float(ds.damping_dissipation[-1]) > 0.1 * scale


def _tip_phasor_samples(run, omega: float) -> np.ndarray:
    """The tip deflection's samples of ``run`` as Im(X e^(i Omega t)) fits: X (m)."""
    t = run.time.values
    design = np.column_stack([np.sin(omega * t), np.cos(omega * t)])
    (real, imag), *_ = np.linalg.lstsq(design, run.tip_deflection_1.values, rcond=None)
    return complex(real, imag)


OMEGA = 300.0  # rad/s, between the first two modes (170.9 and 1071 rad/s)
NO_CONTACT = {"clearance": 1e-2, "omega": OMEGA, "start": "steady"}


def test_a_rayleigh_damped_steady_response_is_the_direct_solve():
    """Started on its steady state and never touching the stop, the 12-DOF FE model with
    Rayleigh C stays on x = Im(X e^(i Omega t)), X = (K - Omega^2 M + i Omega C)^-1 (-F0 e):
    the tip's samples fit X within 5e-12 relative, and the linear gap's phasor (grazing) too
    (measured 4.6e-13 both: the computed modes' round-off, cond(K) eps, against a dense
    solve)."""
    params = STOP.replace(structure1=rayleigh(), **NO_CONTACT)
    e = np.zeros(K6.shape[0])
    e[TIP] = 1.0
    direct = np.linalg.solve(K6 - OMEGA**2 * M6 + 1j * OMEGA * C6,
                             -params.force_amplitude * e)[TIP]
    run = simulate(params, 0.02, n_modes=2 * ELEMENTS, dt_output=1e-3)
    assert run.impact.size == 0
    assert abs(_tip_phasor_samples(run, OMEGA) / direct - 1) <= 5e-12
    gap_per_newton = LinearGap(params, 2 * ELEMENTS).per_unit(OMEGA)[0]
    assert abs(gap_per_newton * params.force_amplitude / direct - 1) <= 5e-12


def test_per_mode_ratios_give_the_modal_sum_steady_response():
    """Modal data with its own ratio per mode (30 % down to 1 %): the steady tip response is
    -F0 [c - sum Y_n^2 / omega_n^2 + sum Y_n^2 / (omega_n^2 - Omega^2 + 2 i zeta_n omega_n
    Omega)] (the residual flexibility quasi-static), within 1e-12 relative from the samples
    and the linear gap's phasor (measured 2.8e-16 and 4.4e-16: round-off)."""
    ratios = np.linspace(0.3, 0.01, 12)
    structure = analytic_modal_data(12, damping_ratios=ratios)
    params = STOP.replace(structure1=structure, **NO_CONTACT)
    w, Y = structure.frequencies, structure.contact_values
    closed = -params.force_amplitude * (structure.tip_compliance - np.sum(Y**2 / w**2) + np.sum(
        Y**2 / (w**2 - OMEGA**2 + 2j * ratios * w * OMEGA)))
    run = simulate(params, 0.02, n_modes=12, dt_output=1e-3)
    assert run.impact.size == 0
    assert abs(_tip_phasor_samples(run, OMEGA) / closed - 1) <= 1e-12
    gap_per_newton = LinearGap(params, 12).per_unit(OMEGA)[0]
    assert abs(gap_per_newton * params.force_amplitude / closed - 1) <= 1e-12
    # the last mode's ratio for all: not this response (the ratios are read per mode)
    uniform = analytic_modal_data(12, damping_ratios=np.full(12, ratios[-1]))
    assert abs(LinearGap(STOP.replace(structure1=uniform, **NO_CONTACT), 12).per_unit(OMEGA)[0]
               * params.force_amplitude / closed - 1) > 1e-3


def _first_impacts(params: dict):
    from impactbeams.sweep import run_sweep
    return run_sweep(sweep_from_mapping({
        "t_max": 0.05, "n_modes": 12, "observables": ["first_impact_time"], "params": params,
        "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3},
                 "clearance": {"min": 1e-5, "max": 2e-5, "num": 2}}}, source="user"),
        parallel=False).first_impact_time.values


def test_ratios_all_equal_to_damping_ratio_give_todays_runs_bit_for_bit():
    """Each mode's own ratio 2 %, against today's beam with damping_ratio = 0.02: the
    contacts of a run (the spring law's complex modes) and a first-impact map (the column
    kernel) bit for bit."""
    today = STOP.replace(damping_ratio=0.02)
    own = STOP.replace(structure1=analytic_modal_data(20, damping_ratios=np.full(20, 0.02)))
    expected, got = (simulate(p, 0.05, n_modes=20) for p in (today, own))
    assert expected.impact.size >= 2
    for name in ("impact_onset_time", "impact_duration", "impact_peak_force", "impact_impulse",
                 "tip_deflection_1"):
        np.testing.assert_array_equal(got[name].values, expected[name].values, err_msg=name)
    fixed = {"counterpart": "stop", "contact_stiffness": 1e4}
    maps = [_first_impacts({**fixed, "damping_ratio": 0.02}), _first_impacts(
        {**fixed, "structure1": analytic_modal_data(12, damping_ratios=np.full(12, 0.02))})]
    assert np.isfinite(maps[0]).any()
    np.testing.assert_array_equal(maps[1], maps[0])


def test_a_damped_structure_in_an_npz_file():
    """``damping`` (dense or COO triplets) and ``damping_ratios`` read back as given."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "s.npz"
        rows, cols = np.nonzero(C6)
        np.savez(path, mass=M6, stiffness=K6, contact_dof=TIP, length=STOP.l1,
                 damping_rows=rows, damping_cols=cols, damping_values=C6[rows, cols],
                 size=C6.shape[0])
        sparse = read_structure(path)
        np.savez(path, frequencies=[1.0, 2.0], contact_values=[1.0, 1.0], tip_compliance=2.0,
                 static_mass=1.0, length=0.1, damping_ratios=[0.1, 0.2])
        modal = read_structure(path)
    np.testing.assert_array_equal(sparse.damping.toarray(), C6)
    np.testing.assert_allclose(sparse.modes(12).damping_ratios, rayleigh().modes(12).damping_ratios,
                               rtol=1e-12)
    np.testing.assert_array_equal(modal.modes(2).damping_ratios, [0.1, 0.2])
    assert "damped" in repr(modal)


def _coupling():
    tip = np.zeros_like(C6)  # a dashpot at the tip alone couples the modes
    tip[TIP, TIP] = 1.0
    return MatrixStructure(M6, K6, contact_dof=TIP, length=STOP.l1, damping=tip).modes(12)


def _own_ratios(ratio: float) -> ModalStructure:
    """Today's beam 1 as 12 modes' data, each mode damped by its own ``ratio``."""
    return analytic_modal_data(12, damping_ratios=np.full(12, ratio))


@pytest.mark.parametrize(("build", "message"), [
    (lambda: MatrixStructure(M6, K6, contact_dof=TIP, length=0.1, damping=C6 + np.triu(
        C6, 1) * 1e-6), r"structure1.damping = 'a matrix with max \|A - A\^T\| = .*' is not "
     "allowed: must be symmetric"),
    (lambda: MatrixStructure(M6, K6, contact_dof=TIP, length=0.1, damping=-C6),
     "structure1.damping = 'a matrix with diagonal entry .*' is not allowed: must be positive "
     "semidefinite"),
    (lambda: MatrixStructure(M6, K6, contact_dof=TIP, length=0.1, damping=C6[:4, :4]),
     "structure1.damping = '4 x 4' is not allowed: must have the mass matrix's shape, 12 x 12"),
    (_coupling, "structure1.damping = 'a matrix coupling the modes by .*' is not allowed: must "
                "be diagonal in the modes"),
    (lambda: MatrixStructure(M6, K6, contact_dof=TIP, length=0.1, damping=100 * C6).modes(12),
     r"structure1.damping = 'its modal damping ratios .* up to .*' is not allowed: must "
     r"satisfy 0 <= zeta_n < 1"),
    (lambda: MatrixStructure(M6, K6, contact_dof=TIP, length=0.1, damping=C6,
                             damping_ratios=[0.1]),
     "structure1.damping_ratios = 'given with damping' is not allowed: give either"),
    (lambda: analytic_modal_data(3, damping_ratios=[0.1, 1.0, 0.2]),
     r"structure1.damping_ratios = 1.0 is not allowed: must satisfy 0 <= zeta_n < 1"),
    (lambda: analytic_modal_data(3, damping_ratios=[0.1, -0.1, 0.2]),
     r"structure1.damping_ratios = -0.1 is not allowed: must satisfy 0 <= zeta_n < 1"),
    (lambda: analytic_modal_data(3, damping_ratios=[0.1, 0.2]),
     "structure1.damping_ratios = .* is not allowed: must be a real vector of 3 values"),
    (lambda: simulate(STOP.replace(structure1=MatrixStructure(
        M6, K6, contact_dof=TIP, length=0.1, damping_ratios=[0.1, 0.2])), 0.01, n_modes=3),
     "n_modes = 3 is not allowed: structure1 has 2 modes"),
    (lambda: STOP.replace(structure1=rayleigh(), damping_ratio=0.01),
     "damping_ratio = 0.01 is not allowed: structure1 has damping of its own"),
    (lambda: sweep_from_mapping({"t_max": 0.05, "observables": ["first_impact_time"],
                                 "params": {"counterpart": "stop", "structure1": rayleigh()},
                                 "axes": {"damping_ratio": {"min": 0.0, "max": 0.1,
                                                            "num": 2}}}),
     "damping_ratio = 0.1 is not allowed: structure1 has damping of its own"),
    (lambda: Continuation(STOP.replace(structure1=rayleigh()), "damping_ratio", 0.0, 0.1),
     "damping_ratio = 0.1 is not allowed: structure1 has damping of its own"),
    (lambda: simulate(STOP.replace(structure1=_own_ratios(0.02), contact_damping=1e6), 0.01,
                      n_modes=12),
     r"contact_damping = 1000000.0 is not allowed: with contact_stiffness = 10000 N/m and "
     r"structure1's own damping \(zeta_n up to 0.02; damping_ratio is 0 with it\), it "
     "overdamps the contact phase"),
])
def test_bad_damping_is_refused_in_one_line(build, message):
    with pytest.raises(ParameterError, match=message) as error:
        build()
    assert "\n" not in str(error.value)


def test_a_periodic_orbit_with_ratios_all_equal_to_damping_ratio_is_todays():
    """The period map and its Floquet multipliers with each mode's own ratio 1 %: the orbit
    of damping_ratio = 0.01, bit for bit."""
    from impactbeams import periodic_orbit

    today = STOP.replace(damping_ratio=0.01, omega=200.0, force_amplitude=3e-3)
    own = today.replace(damping_ratio=0.0, structure1=analytic_modal_data(
        12, damping_ratios=np.full(12, 0.01)))
    orbits = [periodic_orbit(p, n_modes=12) for p in (today, own)]
    assert orbits[0].contacts >= 1
    np.testing.assert_array_equal(orbits[1].state, orbits[0].state)
    np.testing.assert_array_equal(orbits[1].multipliers, orbits[0].multipliers)


def test_a_first_impact_map_with_per_mode_ratios_equals_single_runs():
    """The Rayleigh-damped FE model (zeta_n from 0.5 % to 25 %): a first-impact map (the
    column kernel reads each mode's ratio) against simulate()'s event search, cell by cell,
    within 1e-12 s (the two searches' tolerance; measured 5e-18 s). Undamped, the map moves
    by 1.3e-4 s: the ratios are read."""
    fixed = {"counterpart": "stop", "contact_stiffness": 1e4, "structure1": rayleigh()}
    first = _first_impacts(fixed)
    assert np.isfinite(first).all()
    undamped = _first_impacts({**fixed, "structure1": MatrixStructure(
        M6, K6, contact_dof=TIP, length=STOP.l1)})
    assert np.abs(undamped - first).max() > 1e-5
    params = Params(**fixed)
    for i, omega in enumerate((40.0, 50.0, 60.0)):
        for j, clearance in enumerate((1e-5, 2e-5)):
            run = simulate(params.replace(omega=omega, clearance=clearance), 0.05,
                           n_modes=12, dt_output=0.05)
            assert first[i, j] == pytest.approx(float(run.impact_onset_time[0]), abs=1e-12)


def _long_runs(**damping) -> list:
    """Against the stop with ``damping``, 12 modes: an impact-count and peak-force map of the
    full dynamics, simulate()'s Lyapunov exponent (40 periods after 20) and the contacts of
    a two-sided stop at the tip (2 and 1 um: each side closes within 20 ms)."""
    from impactbeams.sweep import run_sweep
    fixed = {"counterpart": "stop", "contact_stiffness": 1e4, **damping}
    maps = run_sweep(sweep_from_mapping({
        "t_max": 0.05, "n_modes": 12, "observables": ["impact_count", "max_contact_force"],
        "params": fixed, "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 2}}},
        source="user"), parallel=False)
    params = Params(**fixed)
    period = 2 * np.pi / params.omega
    lyapunov = simulate(params, 60 * period, n_modes=12, dt_output=period, lyapunov=True,
                        transient_periods=20)
    backlash = simulate(params.replace(force_amplitude=1e-3, omega=400.0,
                                       contacts=two_sided_stop(None, 2e-6, 1e-6)),
                        0.02, n_modes=12)
    return [maps.impact_count.values, maps.max_contact_force.values,
            lyapunov.lyapunov_exponent.values, backlash.impact_contact.values,
            backlash.impact_onset_time.values, backlash.impact_peak_force.values,
            backlash.contact_forces.values]


def test_ratios_all_equal_to_damping_ratio_give_todays_long_runs_bit_for_bit():
    """Each mode's own ratio 5 % against damping_ratio = 0.05: a map of the full dynamics
    (impact count, peak force), the Lyapunov exponent of simulate() and a run with two
    contacts (a two-sided stop, both sides closing) bit for bit; own ratios of 3 % change
    the peak forces, the exponent (-21 to -7 s^-1) and the contacts (the damping is read)."""
    today, own, other = (_long_runs(**damping) for damping in (
        {"damping_ratio": 0.05}, {"structure1": _own_ratios(0.05)},
        {"structure1": _own_ratios(0.03)}))
    assert np.all(today[0] > 0) and set(today[3]) == {0, 1}
    for name, expected, got, changed in zip(
            ("impact_count", "max_contact_force", "lyapunov_exponent", "impact_contact",
             "impact_onset_time", "impact_peak_force", "contact_forces"), today, own, other,
            strict=True):
        np.testing.assert_array_equal(got, expected, err_msg=name)
        if name not in ("impact_count", "impact_contact"):  # counts may coincide
            assert changed.shape != expected.shape or np.any(changed != expected), name
