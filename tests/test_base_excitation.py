"""Base (shaker) excitation: the drive seam's second drive (docs/model.md, "Base excitation").

References written here or in tests/spring_modal_reference.py: the continuous beam's exact
steady response (undamped), a 200-mode modal sum with participation factors by quadrature
(damped), the modal spring law integrated by DOP853, and the one-cell first-impact search.
"""

import numpy as np
import pytest

from impactbeams import Params, simulate
from impactbeams.cli import build_parser, params_from_args
from impactbeams.contact import build_tied_model
from impactbeams.drive import contact_participation, drive_summary, participation
from impactbeams.kernels import first_impact as fi
from impactbeams.kernels.layout import CELL_U0, CONTACT
from impactbeams.modes import free_modes
from impactbeams.packing import pack_run
from impactbeams.params import ParameterError
from impactbeams.sweep.definition import sweep_from_mapping
from impactbeams.sweep.plan import (
    build_plan,
    check_contact_phases,
    chunk_cells,
    first_impact_columns,
)
from references import gauss_rule
from spring_modal_reference import spring_modal_contacts
from test_dynamics import energy_check_times, segment_of, trajectory

U0 = 1e-6  # m
FAR = 0.04  # m, a clearance the tips never close: no contact
TIMES = np.linspace(0.0, 0.2, 9)


def clamped_response(EI, rhoA, length, omega):
    """Exact tip amplitude Y(l) of an undamped cantilever whose clamp moves as sin(Omega t).

    EI Y'''' = rhoA Omega^2 Y, Y(0) = 1, Y'(0) = 0, Y''(l) = Y'''(l) = 0, with
    Y = a cosh + b sinh + c cos + d sin of beta x (the absolute motion per unit U0).
    """
    beta = (rhoA * omega**2 / EI) ** 0.25
    z = beta * length
    ch, sh, c, s = np.cosh(z), np.sinh(z), np.cos(z), np.sin(z)
    system = np.array([[1, 0, 1, 0], [0, 1, 0, 1], [ch, sh, -c, -s], [sh, ch, s, -c]])
    a, b, cc, d = np.linalg.solve(system, [1.0, 0.0, 0.0, 0.0])
    return a * ch + b * sh + cc * c + d * s


def modal_sum(EI, rhoA, length, omega, zeta, n=200):
    """Complex relative tip amplitude W (per unit U0): sum Y_n(l) Gamma_n Omega^2 / D_n.

    Gamma_n = rhoA int Y_n by Gauss quadrature of the shapes (the package uses -Y'''(0)/k^4).
    """
    modes = free_modes(EI, rhoA, length, n)
    x, w = gauss_rule(length, panels=2000)
    gamma = rhoA * (modes.shapes(x) @ w)
    detuning = modes.frequencies**2 - omega**2 + 2j * zeta * modes.frequencies * omega
    return np.sum(modes.shapes.tip() * gamma * omega**2 / detuning)


def steady_run(omega, zeta, n_modes=100):
    params = Params(clearance=FAR, force_amplitude=0.0, base_amplitude=U0, omega=omega,
                    damping_ratio=zeta, start="steady")
    return params, simulate(params, float(TIMES[-1]), n_modes=n_modes, times=TIMES)


def test_participation_factors_equal_the_quadrature():
    """Gamma_n = -rhoA Y_n'''(0) / k_n^4 (closed form) = rhoA int Y_n (quadrature), 60 modes."""
    p = Params()
    modes = free_modes(p.EI1, p.rhoA1, p.l1, 60)
    x, w = gauss_rule(p.l1, panels=2000)
    quadrature = p.rhoA1 * (modes.shapes(x) @ w)
    # both to round-off of sums of terms of size ~sqrt(rhoA l): 1e-12 of the largest
    np.testing.assert_allclose(participation(modes.shapes, p.rhoA1), quadrature, rtol=0,
                               atol=1e-12 * np.max(np.abs(quadrature)))


@pytest.mark.parametrize("omega", [50.0, 400.0, 3000.0])
def test_undamped_steady_response_equals_the_continuous_beam(omega):
    """Absolute and relative tip motion on the steady state, both beams, against the exact
    continuous solution. The relative motion's modal sum converges like N^-5 (measured at
    Omega = 3000 rad/s: 3.3e-6 relative at 40 modes, 3.3e-8 at 100): 100 modes per beam."""
    p, ds = steady_run(omega, 0.0)
    clamp = U0 * np.sin(omega * TIMES)
    # tip_deflection_2 is y2(l2) - clearance (as in the paper's Fig. 3a)
    for absolute, (EI, rhoA, length) in (
            (ds.tip_deflection_1.values, (p.EI1, p.rhoA1, p.l1)),
            (ds.tip_deflection_2.values + p.clearance, (p.EI2, p.rhoA2, p.l2))):
        amplitude = U0 * clamped_response(EI, rhoA, length, omega)
        np.testing.assert_allclose(absolute, amplitude * np.sin(omega * TIMES), rtol=0,
                                   atol=1e-6 * abs(amplitude))
        relative = absolute - clamp
        np.testing.assert_allclose(relative, (amplitude - U0) * np.sin(omega * TIMES), rtol=0,
                                   atol=1e-6 * abs(amplitude - U0))
    assert np.all(ds.impact_onset_time.size == 0)


def test_damped_steady_response_equals_the_modal_sum():
    """Several zeta and Omega, one at beam 1's first resonance: 100 modes against 200."""
    p = Params()
    first = free_modes(p.EI1, p.rhoA1, p.l1, 1).frequencies[0]
    for omega, zeta in ((50.0, 0.02), (first, 0.01), (first, 0.05), (2500.0, 0.03)):
        _, ds = steady_run(omega, zeta)
        relative = U0 * modal_sum(p.EI1, p.rhoA1, p.l1, omega, zeta)
        expected = np.imag((U0 + relative) * np.exp(1j * omega * TIMES))
        np.testing.assert_allclose(ds.tip_deflection_1.values, expected, rtol=0,
                                   atol=1e-6 * abs(U0 + relative))
        clamp = U0 * np.sin(omega * TIMES)
        np.testing.assert_allclose(ds.tip_deflection_1.values - clamp,
                                   np.imag(relative * np.exp(1j * omega * TIMES)), rtol=0,
                                   atol=1e-6 * abs(relative))


def test_rest_start_settles_on_the_steady_state():
    """Started at rest, the damped response reaches the steady start's within its decay."""
    params = Params(clearance=FAR, force_amplitude=0.0, base_amplitude=U0, omega=300.0,
                    damping_ratio=0.2)
    times = np.array([3.0])  # 0.2 * 110 rad/s * 3 s = 66 time constants of the slowest mode
    rest = simulate(params, 3.0, n_modes=32, times=times)
    steady = simulate(params.replace(start="steady"), 3.0, n_modes=32, times=times)
    scale = abs(float(steady.tip_deflection_1[0])) + U0
    assert abs(float(rest.tip_deflection_1[0] - steady.tip_deflection_1[0])) < 1e-12 * scale


@pytest.mark.parametrize("changes", [
    {"shaker": "beam1", "base_amplitude": 2e-5, "force_amplitude": 0.0, "omega": 200.0},
    {"shaker": "beam2", "base_amplitude": 2e-5, "force_amplitude": 0.0, "omega": 80.0},
    {"shaker": "both", "base_amplitude": 3e-6, "force_amplitude": 1e-3, "omega": 400.0,
     "damping_ratio": 0.01},
], ids=["beam1", "beam2", "both-with-force"])
def test_spring_contacts_equal_dop853(changes):
    """The first five contacts against DOP853 on the same modal equations (12 modes, k = 1e4):
    onsets to 2e-12 s, durations and impulses to 1e-8 (the reference's own tolerance, as in
    tests/test_spring.py)."""
    params = Params(contact_stiffness=1e4, **changes)
    ds = simulate(params, 0.05, n_modes=12)
    ref = spring_modal_contacts(params, 12, params.contact_stiffness, n_contacts=5, t_max=0.05)
    count = min(5, ref["duration"].size)
    assert count >= 2
    np.testing.assert_allclose(ds.impact_onset_time.values[:count], ref["onset"][:count],
                               rtol=0, atol=2e-12)
    np.testing.assert_allclose(ds.impact_duration.values[:count], ref["duration"][:count],
                               rtol=1e-8)
    np.testing.assert_allclose(ds.impact_impulse.values[:count], ref["impulse"][:count],
                               rtol=1e-8)


@pytest.mark.parametrize("dashpot", [0.0, 0.5])
@pytest.mark.parametrize("shaker", ["beam1", "beam2", "both"])
def test_energy_balance_closes_with_the_base_drive(shaker, dashpot):
    """E - U - (work of F and of the shaker) + dissipation is constant over a damped run with
    contacts, with and without a dashpot (energies relative to the clamps; measured 2e-14 to
    7e-12 of the energy, 1e-10 required as for the tip force alone in tests/test_dynamics.py)."""
    params = Params(contact_stiffness=1e4, shaker=shaker, base_amplitude=2e-5, omega=80.0,
                    damping_ratio=0.01, contact_damping=dashpot, force_amplitude=1e-3)
    times = np.linspace(0.0, 0.05, 5001)
    ds = simulate(params, 0.05, n_modes=12, times=times, energy_balance=True)
    assert ds.impact_onset_time.size >= 2
    assert ds.attrs["energy_frame"] == "relative"
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force
               + ds.damping_dissipation).values
    assert np.max(np.abs(balance - balance[0])) < 1e-10 * float(np.max(ds.energy))


@pytest.mark.parametrize("shaker", ["beam1", "beam2", "both"])
def test_first_impact_map_over_omega_and_u0_equals_the_one_cell_search(shaker):
    """A sweep over (Omega, U0), F0 = 0: columns along U0 (the gap is affine in U0), each cell
    against its own search from t = 0."""
    sweep = sweep_from_mapping({
        "t_max": 0.3, "n_modes": 8,
        "params": {"force_amplitude": 0.0, "shaker": shaker, "damping_ratio": 0.01},
        "axes": {"omega": {"min": 30.0, "max": 700.0, "num": 12},
                 "base_amplitude": {"min": 1e-6, "max": 1e-4, "num": 16, "scale": "log"}}})
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, sweep.size)
    columns = first_impact_columns(sweep, 0, sweep.size)
    assert columns.key == CELL_U0 and columns.bounds.size - 1 == 12
    by_column, by_cell = np.empty(sweep.size), np.empty(sweep.size)
    fi.first_impact_map_serial(cells, columns.bounds, columns.key, plan.tables, plan.geometry,
                               sweep.t_max, by_column)
    fi.first_impact_cells(cells, plan.tables, plan.geometry, sweep.t_max, by_cell)
    assert np.array_equal(np.isnan(by_column), np.isnan(by_cell))
    hit = ~np.isnan(by_cell)
    assert 0.2 < hit.mean() < 1.0
    # one root, two evaluations of the same gap (the column's response to U0 = 1 m scaled,
    # or the cell's own): round-off of the gap over its slope, as in tests/test_columns.py;
    # measured at most 1.0e-14 relative
    np.testing.assert_allclose(by_column[hit], by_cell[hit], rtol=1e-13, atol=0)
    # the map's cells are the runs': a few against simulate's first onset
    for k in np.flatnonzero(hit)[::37]:
        i, j = np.unravel_index(k, sweep.shape)
        params = sweep.params_at({"omega": sweep.axes[0].value(i),
                                  "base_amplitude": sweep.axes[1].value(j),
                                  "contact_stiffness": 1e3})
        run = simulate(params, sweep.t_max, n_modes=8, times=[0.0])
        assert abs(float(run.impact_onset_time[0]) - by_cell[k]) <= 1e-12 * by_cell[k]


def test_steady_start_at_an_undamped_resonance_is_refused():
    p = Params()
    first = float(free_modes(p.EI1, p.rhoA1, p.l1, 1).frequencies[0])
    with pytest.raises(ParameterError, match="start = 'steady' is not allowed: omega = .* is a "
                                             "natural frequency and damping_ratio = 0"):
        simulate(Params(omega=first, start="steady", base_amplitude=U0, force_amplitude=0.0),
                 0.01, n_modes=32)


def test_fields_are_absolute():
    """The deflection surfaces carry the clamp's motion: at the clamp, y = u_b."""
    params = Params(clearance=FAR, force_amplitude=0.0, base_amplitude=U0, omega=300.0,
                    shaker="beam1")
    ds = simulate(params, 0.01, n_modes=32, times=TIMES[:3] / 20, fields=True)
    clamp = U0 * np.sin(300.0 * TIMES[:3] / 20)
    np.testing.assert_allclose(ds.deflection_1.values[:, 0], clamp, rtol=0, atol=1e-20)
    np.testing.assert_allclose(ds.deflection_2.values[:, 0], 0.0, rtol=0, atol=1e-20)
    np.testing.assert_allclose(ds.deflection_1.values[:, -1], ds.tip_deflection_1.values,
                               rtol=1e-12, atol=0)


def test_unknown_shaker_and_start_are_refused():
    with pytest.raises(ParameterError, match="shaker = 'table' is not allowed: must be one of"):
        Params(shaker="table")
    with pytest.raises(ParameterError, match="start = 'now' is not allowed"):
        Params(start="now")


def test_tied_contact_participation_equals_the_quadrature():
    """sum_i rhoA_i int Z_im of the tied contact modes (closed form from the shears) against
    Gauss quadrature of the shapes on both beams; round-off of the sums: 1e-12."""
    params = Params(contact_law="tied")
    model = build_tied_model(params, 8)
    x1, w1 = gauss_rule(params.l1, panels=2000)
    x2, w2 = gauss_rule(params.l2, panels=2000)
    quadrature = (params.rhoA1 * (model.contact.beam1(x1) @ w1)
                  + params.rhoA2 * (model.contact.beam2(x2) @ w2))
    np.testing.assert_allclose(contact_participation(model), quadrature, rtol=0,
                               atol=1e-12 * np.max(np.abs(quadrature)))


@pytest.mark.parametrize("damping_ratio", [0.0, 0.02])
def test_tied_law_energy_balance_within_every_phase_with_both_clamps_shaken(damping_ratio):
    """Tied law, both clamps on the shaker, tip force too: d(E - U) = dW - dD within each phase
    (the tied law loses energy only at onsets), 1e-10 of the energy as in
    tests/test_dynamics.py; the contact modes' own participation factors carry the drive."""
    params = Params(contact_law="tied", base_amplitude=5e-6, force_amplitude=1e-3, omega=230.0,
                    damping_ratio=damping_ratio)
    t_max = 0.3
    packed, traj = trajectory(params, t_max)
    assert np.count_nonzero(traj.phase == CONTACT) >= 3
    times = energy_check_times(traj, t_max, 30_001)
    ds = simulate(params, t_max, n_modes=5, times=times, energy_balance=True)
    k = segment_of(traj, times)
    start = np.searchsorted(times, traj.time)
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force
               + ds.damping_dissipation).values
    assert np.max(np.abs(balance - balance[start[k]])) < 1e-10 * float(np.max(ds.energy))
    # the tied tips: the gap is 0 throughout each contact, in the absolute frame
    in_contact = ds.in_contact.values == 1
    assert np.max(np.abs(ds.gap.values[in_contact])) < 1e-9 * params.clearance


@pytest.mark.parametrize("shaker", ["beam1", "beam2"])
def test_tied_law_refuses_one_moving_clamp(shaker):
    with pytest.raises(ParameterError, match="with contact_law = 'tied' the shaker must carry "
                                             "both clamps"):
        Params(contact_law="tied", base_amplitude=1e-6, shaker=shaker)
    assert Params(contact_law="tied", base_amplitude=1e-6, shaker="both").mount.carries_both_clamps


def test_tied_contact_modes_carry_the_static_inertial_response():
    """Quasi-static limit: the tied pair under a uniform acceleration a of both clamps.

    Each free tip would deflect by d_i = rhoA_i l_i^4 / (8 EI_i) per unit -a; tied, they share
    (c2 d1 + c1 d2) / (c1 + c2). The contact modes' static sum ``sum Z_m(l) Gamma_m / omega_m^2``
    must give it (measured 1e-8 at 20 modes per beam, 5e-12 at 50). And the contact phase's
    drive amplitudes of a run are ``Gamma_m U0 Omega^2`` plus the tip force's."""
    params = Params(contact_law="tied", base_amplitude=U0, force_amplitude=1e-3, omega=300.0)
    c1, c2 = params.tip_compliance
    d1 = params.rhoA1 * params.l1**4 / (8 * params.EI1)
    d2 = params.rhoA2 * params.l2**4 / (8 * params.EI2)
    model = build_tied_model(params, 50)
    gamma = contact_participation(model)
    static = np.sum(model.contact_tip * gamma / model.contact.frequencies**2)
    assert abs(static / ((c2 * d1 + c1 * d2) / (c1 + c2)) - 1) < 1e-10
    packed = pack_run(params, 5, 0.1, 0.1)
    without = pack_run(params.replace(base_amplitude=0.0), 5, 0.1, 0.1)
    gamma = contact_participation(build_tied_model(params, 5))
    np.testing.assert_allclose(packed.forces[CONTACT] - without.forces[CONTACT],
                               gamma * U0 * 300.0**2, rtol=1e-14, atol=0)


def test_a_sweep_starting_steady_at_an_undamped_resonance_is_refused_before_work():
    """A cell driving an undamped mode exactly at resonance has no steady state to start on.

    The grid hits beam 1's first natural frequency exactly (an axis from it); one line names it.
    """
    first = float(free_modes(Params().EI1, Params().rhoA1, Params().l1, 1).frequencies[0])
    mapping = {"t_max": 0.01, "n_modes": 3, "observables": ["first_impact_time"],
               "params": {"start": "steady", "base_amplitude": U0, "force_amplitude": 1e-3},
               "axes": {"omega": {"min": first, "max": 2 * first, "num": 3}}}
    with pytest.raises(ParameterError, match="is a natural frequency and damping_ratio = 0"):
        check_contact_phases(sweep_from_mapping(mapping))
    mapping["params"]["damping_ratio"] = 0.01  # damped: a steady state exists
    check_contact_phases(sweep_from_mapping(mapping))
    mapping["params"] |= {"damping_ratio": 0.0, "start": "rest"}
    check_contact_phases(sweep_from_mapping(mapping))


@pytest.mark.parametrize("name", ["shaker", "start"])
def test_the_shaker_and_the_start_are_not_axes(name):
    """Names, not numbers (found by the input fuzz: a numeric axis of them was a KeyError)."""
    mapping = {"t_max": 0.01, "n_modes": 3, "observables": ["first_impact_time"],
               "axes": {name: {"min": 1e-3, "max": 1e-2, "num": 3, "scale": "log"}}}
    with pytest.raises(ParameterError, match=f"{name} is not sweepable: give it in"):
        sweep_from_mapping(mapping)


def test_a_study_that_names_its_shaker_has_no_tip_force_unless_it_names_one(tmp_path):
    """The paper's 1 mN tip force is the default drive only of a study without a shaker: one
    that gives base_amplitude (keywords, a file's [params], a sweep's axis, a copy's change,
    the command line, even at 0) is driven by its shaker alone unless it gives
    force_amplitude too."""
    assert Params().force_amplitude == 1e-3 and Params().base_amplitude == 0.0
    assert Params(base_amplitude=1e-5).force_amplitude == 0.0
    assert Params(base_amplitude=0.0).force_amplitude == 0.0
    assert Params(base_amplitude=1e-5, force_amplitude=2e-4).force_amplitude == 2e-4
    assert Params.from_mapping({"base_amplitude": 1e-5}).force_amplitude == 0.0
    # a copy resolves a default again, as if built with its changes; a given value stays
    assert Params().replace(base_amplitude=1e-5) == Params(base_amplitude=1e-5)
    assert Params().replace(omega=80.0).force_amplitude == 1e-3
    assert Params(force_amplitude=1e-3).replace(base_amplitude=1e-5).force_amplitude == 1e-3
    assert Params(base_amplitude=1e-5).replace(omega=80.0).force_amplitude == 0.0
    assert Params(base_amplitude=1e-5).replace(base_amplitude=0.0).force_amplitude == 0.0
    (tmp_path / "p.toml").write_text("[params]\nbase_amplitude = 1e-5\n")
    assert Params.from_toml(tmp_path / "p.toml").force_amplitude == 0.0
    sweep = sweep_from_mapping({"t_max": 0.01, "n_modes": 3, "params": {"counterpart": "stop"},
                                "axes": {"base_amplitude": {"min": 0.0, "max": 1e-5,
                                                            "num": 3}}})
    assert {sweep.params_at({"base_amplitude": u}).force_amplitude
            for u in (0.0, 5e-6, 1e-5)} == {0.0}
    parser = build_parser()
    for argv, force in ((["--base-amplitude", "1e-5"], 0.0), ([], 1e-3),
                        (["--base-amplitude", "1e-5", "--force-amplitude", "1e-3"], 1e-3),
                        (["--params", str(tmp_path / "p.toml"), "--omega", "80"], 0.0)):
        args = parser.parse_args(["simulate", "--t-max", "0.01", "-o", "run.nc", *argv])
        assert params_from_args(args).force_amplitude == force, argv


def test_the_drives_are_named_in_one_line():
    assert drive_summary(Params()) == "drives: tip force F0 = 0.001 N; Omega = 50 rad/s"
    stop = Params(counterpart="stop", base_amplitude=1e-5, omega=200.0)
    assert drive_summary(stop) == (
        "drives: base motion U0 = 1e-05 m on beam 1's clamp and the stop (the stop moves with "
        "the shaker: shaker = 'beam1' keeps it fixed); Omega = 200 rad/s")
    assert drive_summary(stop.replace(shaker="beam1", force_amplitude=2e-4)) == (
        "drives: tip force F0 = 0.0002 N; base motion U0 = 1e-05 m on beam 1's clamp; "
        "Omega = 200 rad/s")
    assert drive_summary(Params(base_amplitude=0.0)) == "drives: none; Omega = 50 rad/s"
