"""`simulate` of several contacts (issue 33, item 5): energy balance, episodes, initial state,
progress and the command line.

The energy balance against its invariant (energy + dissipation - work constant to round-off:
the energy is evaluated from the sampled states, the work and dissipation integrate the drives'
and dampers' powers) and against the single contact's own quadrature
(`kernels.reductions.work_of_force`) where the second contact never closes; the episodes
against the single contact's table (`trajectory.episodes`) likewise; a restart from a run's
final state against the whole run.
"""

import math

import numpy as np
import pytest
import xarray as xr

from impactbeams import Contact, Params, simulate, two_sided_stop
from impactbeams.cli import main
from impactbeams.params import ParameterError

STOP = Params(counterpart="stop", contact_stiffness=1e4)
MID = 0.5 * STOP.l1  # m
FORCED = STOP.replace(force_amplitude=1e-3, omega=400.0)
EPISODE_COLUMNS = ("episode_onset_time", "episode_duration", "episode_contact_count",
                   "episode_impulse", "episode_peak_force", "episode_restitution",
                   "episode_dissipated_energy", "episode_energetic_restitution")


@pytest.mark.parametrize("params", [
    FORCED.replace(damping_ratio=0.01, contacts=(Contact(MID, clearance=1e-6),
                                                 Contact(clearance=2e-6))),
    FORCED.replace(damping_ratio=0.01, contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                                                 Contact(clearance=2e-6, damping=0.5))),
    STOP.replace(base_amplitude=2e-6, omega=400.0, damping_ratio=0.01,
                 contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                           Contact(clearance=2e-6, damping=0.5))),
    FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6)),
], ids=["forced", "dashpots", "shaker", "two-sided"])
def test_energy_balance_of_several_contacts_holds_to_round_off(params):
    """energy - unresolved kinetic energy - work + dissipation stays its initial value within
    1e-12 of the largest energy over 0.03 s (measured 2.6e-15 to 1.3e-14; the quadratures'
    own error is ~1e-18, the damped contact modes' eigenvalues ~1e-14), with the work and,
    where there is damping, the dissipation both a sizeable share of it (so both are checked);
    the dissipation never decreases by more than round-off (the springs given up at the
    dashpots' switches included)."""
    ds = simulate(params, 0.03, n_modes=12, dt_output=1e-5, energy_balance=True)
    assert ds.attrs["status"] == "complete" and ds.sizes["impact"] >= 3
    assert set(ds.impact_contact.values) == {0, 1}
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force
               + ds.damping_dissipation).values
    scale = float(np.abs(ds.energy).max())
    assert np.max(np.abs(balance - balance[0])) < 1e-12 * scale
    assert float(np.abs(ds.work_of_force).max()) > 0.1 * scale
    dissipation = ds.damping_dissipation.values
    if params.damping_ratio > 0.0:
        assert dissipation[-1] > 0.1 * scale
    assert np.all(np.diff(dissipation) >= -1e-14 * scale)


def _alone_and_beside_a_far_stop(clearance, t_max, dt_output):
    """Runs (12 modes, zeta = 0.01, forced, the energy balance) of a tip stop ``clearance`` m
    away alone and beside a mid-span stop 1 mm away, which never closes."""
    params = FORCED.replace(damping_ratio=0.01)
    alone = simulate(params.replace(clearance=clearance), t_max, n_modes=12,
                     dt_output=dt_output, energy_balance=True)
    both = simulate(params.replace(contacts=(Contact(clearance=clearance),
                                             Contact(MID, clearance=1e-3))),
                    t_max, n_modes=12, dt_output=dt_output, energy_balance=True)
    return alone, both


def test_a_contact_that_never_closes_leaves_the_single_contacts_balance_and_episodes():
    """A tip stop (zeta = 0.01, forced) beside a mid-span stop 1 mm away that never closes,
    against simulate of the tip stop alone (its own kernel quadrature and episode table):
    energy, work and dissipation to 1e-12 of the largest energy (measured 1.2e-14), the
    episodes of all contacts and the tip stop's own episodes, column by column, to 1e-12
    relative (measured 8.6e-14, a restitution)."""
    alone, both = _alone_and_beside_a_far_stop(2e-6, 0.06, 1e-5)
    scale = float(alone.energy.max())
    for name in ("energy", "work_of_force", "damping_dissipation"):
        np.testing.assert_allclose(both[name].values, alone[name].values, rtol=0,
                                   atol=1e-12 * scale)
    assert alone.sizes["episode"] == both.sizes["episode"] == both.sizes["contact_episode"] > 2
    assert both.attrs["episode_separation"] == alone.attrs["episode_separation"]
    np.testing.assert_array_equal(both.contact_episode_contact.values, 0)
    for name in EPISODE_COLUMNS:
        for got in (both[name].values, both["contact_" + name].values):
            np.testing.assert_allclose(got, alone[name].values, rtol=1e-12, atol=0)


def test_a_run_in_which_no_contact_closes_is_the_single_contacts():
    """Two stops 1 mm away, neither reached: no impacts, no episodes (the episode table of no
    impacts used to fail: a ValueError), the tips and the energy balance those of the single
    far stop to 1e-12 of their largest (measured 3e-15)."""
    alone, both = _alone_and_beside_a_far_stop(1e-3, 0.02, 1e-4)
    assert both.sizes["impact"] == both.sizes["episode"] == both.sizes["contact_episode"] == 0
    for name in ("tip_deflection_1", "energy", "work_of_force"):
        reference = alone[name].values
        assert np.abs(both[name].values - reference).max() <= 1e-12 * np.abs(reference).max()


def test_the_energetic_restitution_with_a_dashpot_is_the_single_contacts():
    """A tip stop with a dashpot (c = 0.3 N s/m) beside a mid-span stop that never closes:
    the episodes' energetic restitution (R's work on the physical gap, whose rate has the
    dashpot's R' = -k g' - c g'' through the flexibility the modes miss) is the single
    contact's (its own quadrature on the same panels) to 1e-12 (measured 1.5e-14), and below
    1 (measured 0.77 to 0.85)."""
    params = FORCED.replace(damping_ratio=0.01)
    alone = simulate(params.replace(clearance=2e-6, contact_damping=0.3), 0.06, n_modes=12,
                     dt_output=1e-4, energy_balance=True)
    both = simulate(params.replace(contacts=(Contact(clearance=2e-6, damping=0.3),
                                             Contact(MID, clearance=1e-3))),
                    0.06, n_modes=12, dt_output=1e-4, energy_balance=True)
    expected = alone.episode_energetic_restitution.values
    assert expected.size > 2 and np.all(expected < 0.9)
    for name in ("episode_energetic_restitution", "contact_episode_energetic_restitution"):
        np.testing.assert_allclose(both[name].values, expected, rtol=1e-12, atol=0)


def test_impacts_energy_columns_beside_a_contact_that_never_closes_are_the_single_contacts():
    """A tip stop with a dashpot (c = 0.3 N s/m) beside a mid-span stop that never closes:
    each impact's energy loss at onset (the dashpot's force jumps there), its gap and force
    just after release and its restitution are the single contact's (its own kernel's
    states and energy): the losses to 1e-12 of the largest energy (measured 1.5e-15, where
    they reach 1.9e-5 of it), the gaps to 1e-12 of the clearance (measured 3.4e-14), the
    restitutions to 1e-11 relative (measured 3.8e-13); the kinetic energy loss is 0 (the
    single contact's round-off of its contact coordinates, < 1e-12 of the energy). Its
    release energy change differs by design: one contact's energy keeps the spring's while
    the gap reopens (0), several contacts' give it up at the release (< 0: the springs
    given up, `test_impacts_energy_columns_close_the_energy_balance`)."""
    params = FORCED.replace(damping_ratio=0.01)
    alone = simulate(params.replace(clearance=2e-6, contact_damping=0.3), 0.06, n_modes=12,
                     dt_output=1e-3)
    both = simulate(params.replace(contacts=(Contact(clearance=2e-6, damping=0.3),
                                             Contact(MID, clearance=1e-3))),
                    0.06, n_modes=12, dt_output=1e-3)
    assert both.sizes["impact"] == alone.sizes["impact"] > 2
    scale = float(alone.energy.max())
    # an energy loss is a difference of two energies: to their round-off
    for name, tolerance in (("impact_energy_loss", 1e-12 * scale),
                            ("release_gap", 1e-12 * 2e-6)):
        expected = alone[name].values
        assert np.nanmax(np.abs(expected)) > 1e3 * tolerance, name
        np.testing.assert_allclose(both[name].values, expected, rtol=0, atol=tolerance,
                                   err_msg=name)
    # a ratio of two gap rates, each to round-off of itself: a slow approach amplifies it
    np.testing.assert_allclose(both.restitution_coefficient.values,
                               alone.restitution_coefficient.values, rtol=1e-11, atol=0)
    peak = float(alone.impact_peak_force.max())
    for values in (alone.release_contact_force.values, both.release_contact_force.values):
        assert np.nanmax(np.abs(values)) < 1e-12 * peak  # a release: R = 0 to round-off
    np.testing.assert_array_equal(both.impact_kinetic_energy_loss.values, 0.0)
    assert np.abs(alone.impact_kinetic_energy_loss.values).max() < 1e-12 * scale
    assert np.abs(alone.release_energy_change.values).max() < 1e-12 * scale
    assert np.all(both.release_energy_change.values < -1e-9 * scale)


def test_impacts_energy_columns_close_the_energy_balance():
    """Two stops with dashpots (the tip stop alone, then both closed), over 0.03 s: the energy's
    change (less the unresolved kinetic energy) is the drives' work minus the modal damping's
    and the dashpots' dissipation, each integrated within the phases only (12-point
    Gauss-Legendre; the tip force's work on beam 1's tip rate with the closed forces' rates
    through the flexibility the modes miss, not integrated by parts), plus the energy's jumps
    at the switches: minus each onset's ``impact_energy_loss`` plus each release's
    ``release_energy_change``, to 1e-12 of the largest energy (measured 5.3e-15), where the
    jumps sum to 3.7e-3 of it (without them the balance misses by that)."""
    from impactbeams.active_phases import (
        contact_quantities,
        force_rates,
        pack_contacts,
        run_contacts,
        sample,
    )
    from impactbeams.trajectory.several_run import _powers

    params = FORCED.replace(damping_ratio=0.01, contacts=(
        Contact(MID, clearance=1e-6, damping=0.5), Contact(clearance=2e-6, damping=0.5)))
    t_max, n_modes = 0.03, 12
    ds = simulate(params, t_max, n_modes, times=np.array([0.0, t_max]))
    packed = pack_contacts(params, n_modes, t_max, t_max)
    run = run_contacts(packed, 100_000)
    assert run.time.size == ds.attrs["n_phases"] and {2, 3} <= set(run.mask.tolist())
    nodes, weights = np.polynomial.legendre.leggauss(12)
    fastest = max(float(np.max(phase.frequencies)) for phase in packed.contacts.sets.values())
    shift1 = np.array([each.dynamics.spring.tip_shift1 for each in packed.runs])
    integral = 0.0
    for t0, t1 in zip(run.time, np.append(run.time[1:], run.t_end), strict=True):
        edges = np.linspace(t0, t1, max(1, math.ceil((t1 - t0) * fastest / math.pi)) + 1)
        half = 0.5 * np.diff(edges)[:, None]
        t = (0.5 * (edges[:-1] + edges[1:])[:, None] + half * nodes).ravel()
        power, dissipation = _powers(packed, run, t)  # the power but -F s_1 . R', +F' s_1 . R
        q, v, mask = sample(packed, run, t)
        forces = contact_quantities(packed, t, q, v, mask)["contact_force"]
        force = params.force_amplitude * np.sin(params.omega * t)
        force_rate = params.force_amplitude * params.omega * np.cos(params.omega * t)
        power -= force_rate * (forces @ shift1) + force * (force_rates(packed, t, q, v, mask)
                                                           @ shift1)
        integral += float(np.sum((half * weights).ravel() * (power - dissipation)))
    jumps = (-np.nansum(ds.impact_energy_loss.values)
             + np.nansum(ds.release_energy_change.values))
    energy = (ds.energy - ds.unresolved_kinetic_energy).values
    scale = float(np.abs(energy).max())
    assert abs(jumps) > 1e-3 * scale
    assert abs(energy[1] - energy[0] - integral - jumps) < 1e-12 * scale


def test_episodes_of_all_contacts_and_of_each():
    """Stops at mid-span and at the tip, closed together at times: every contact belongs to one
    episode of all contacts and to one of its own contact's; the counts, impulses and peaks
    add up; an episode whose contacts are of both stops has no restitution (a gap's), one of a
    single stop's has its own."""
    params = FORCED.replace(contacts=(Contact(MID, clearance=1e-6), Contact(clearance=2e-6)))
    ds = simulate(params, 0.06, n_modes=12, dt_output=1e-4, episode_separation=1e-3)
    impacts, joint = ds.sizes["impact"], ds.sizes["episode"]
    assert ds.attrs["episode_separation"] == 1e-3 and 1 < joint < impacts
    assert int(ds.episode_contact_count.sum()) == int(ds.contact_episode_contact_count.sum()) \
        == impacts
    for prefix in ("", "contact_"):
        np.testing.assert_allclose(float(ds[prefix + "episode_impulse"].sum()),
                                   float(ds.impact_impulse.sum()), rtol=1e-14)
        assert float(ds[prefix + "episode_peak_force"].max()) == float(
            ds.impact_peak_force.max())
    for j in (0, 1):
        own = ds.contact_episode_contact.values == j
        assert int(ds.contact_episode_contact_count[own].sum()) == int(
            np.count_nonzero(ds.impact_contact.values == j))
    mixed = np.isnan(ds.episode_restitution.values)
    assert mixed.any() and np.all(np.isfinite(ds.contact_episode_restitution.values))


def test_a_run_restarted_from_its_final_state_continues_it():
    """Soft stops with dashpots (zeta = 0.01, Omega = 100 rad/s): a run of 8 forcing periods
    against one of k periods continued from its Dataset for 8 - k, with both stops closed at
    the restart (k = 2) or one (k = 6): the series to 1e-9 of their largest values (measured
    1.6e-11, the forces; the restart's section t = 0 against k T), the onsets after the
    restart to 1e-12 s (measured 1.4e-13 s), and the contacts closed at the start counted
    with their start as onset (no approach: NaN impact velocity)."""
    omega = 100.0
    period = 2.0 * math.pi / omega
    params = STOP.replace(contact_stiffness=1e3, force_amplitude=3e-3, omega=omega,
                          damping_ratio=0.01, contacts=(
                              Contact(MID, clearance=1e-6, damping=0.05),
                              Contact(clearance=2e-6, damping=0.05)))
    dt = period / 200
    whole = simulate(params, 8 * period, n_modes=10, dt_output=dt)
    for turns, closed in ((2, [0, 1]), (6, [0])):
        first = simulate(params, turns * period, n_modes=10, dt_output=dt)
        assert list(np.flatnonzero(first.contact_forces.values[-1] > 0.0)) == closed
        rest = simulate(params, (8 - turns) * period, n_modes=10, dt_output=dt,
                        initial_state=first)
        later = whole.sel(time=slice(turns * period * (1 + 1e-9), None))
        tail = rest.isel(time=slice(rest.sizes["time"] - later.sizes["time"], None))
        for name in ("tip_deflection_1", "contact_forces", "contact_gaps", "energy"):
            np.testing.assert_allclose(tail[name].values, later[name].values, rtol=0,
                                       atol=1e-9 * float(np.abs(later[name]).max()))
        onsets = whole.impact_onset_time.values
        after = onsets[onsets > turns * period]
        np.testing.assert_allclose(rest.impact_onset_time.values[len(closed):] + turns * period,
                                   after, rtol=0, atol=1e-12)
        assert list(rest.impact_contact.values[:len(closed)]) == closed
        assert np.all(rest.impact_onset_time.values[:len(closed)] == 0.0)
        assert np.all(np.isnan(rest.impact_velocity.values[:len(closed)]))


def test_a_start_that_no_set_of_contacts_fits_is_refused():
    """A tip overlapping a dashpot's stop while moving away fast enough that its force would
    pull (-k g - c g' < 0): no closed set fits; refused in one line before the run. The
    refusals of start and uplifts are the single contact's."""
    from impactbeams.active_phases import pack_contacts

    params = FORCED.replace(contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                                      Contact(clearance=2e-6, damping=0.5)))
    free = pack_contacts(params, 8, 0.01, 0.01).runs[0].dynamics.free
    z = np.zeros(16)
    z[0] = -5e-6 / free.tip1[0]  # the tip 5 um down: both stops overlap
    z[8] = 0.5 * free.frequencies[0] * 5e-6 / abs(free.tip1[0]) * 1e3  # moving up, fast
    with pytest.raises(ParameterError, match="^initial_state is not allowed: no set of closed"):
        simulate(params, 0.01, n_modes=8, initial_state=z)
    with pytest.raises(ParameterError, match="^initial_state replaces params.start"):
        simulate(params.replace(uplift1=1e-6), 0.01, n_modes=8, initial_state=np.zeros(16))


def test_progress_reports_windows_of_the_same_run(capsys, monkeypatch):
    """progress=True runs the kernel in windows of PROGRESS_WINDOW phases, each resumed at the
    last phase of the one before (its early releases restored): with windows of 3 phases on
    dashpots that release early and close again, every variable is the one-call run's, bit
    for bit; the expected time and the bars are on stderr."""
    from impactbeams import active_phases

    params = FORCED.replace(contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                                      Contact(clearance=2e-6, damping=0.5)))
    plain = simulate(params, 0.03, n_modes=12, dt_output=1e-5)
    monkeypatch.setattr(active_phases, "PROGRESS_WINDOW", 3)
    shown = simulate(params, 0.03, n_modes=12, dt_output=1e-5, progress=True)
    assert plain.attrs["n_phases"] > 12  # several windows
    for name in plain.variables:
        np.testing.assert_array_equal(shown[name].values, plain[name].values)
    err = capsys.readouterr().err
    assert "simulate: 2 contacts, 12 modes of beam 1" in err and "s simulated" in err


def test_fields_beside_a_contact_that_never_closes_are_the_single_contacts():
    """The deflection fields (41 points per beam) of a tip stop with a dashpot beside a
    mid-span stop that never closes, against the tip stop alone: to 1e-12 of their largest
    (measured 4.8e-15). At the tip the field is the tip series where no contact is closed
    (to 1e-12 of the tip's largest), and the modes' tip while one is, without what the
    closed force moves it by through the flexibility the modes miss (as one contact's
    fields: up to 1.1e-8 m here)."""
    alone = simulate(FORCED.replace(clearance=2e-6, contact_damping=0.3), 0.03, n_modes=12,
                     dt_output=1e-5, fields=True)
    both = simulate(FORCED.replace(contacts=(Contact(clearance=2e-6, damping=0.3),
                                             Contact(MID, clearance=1e-3))),
                    0.03, n_modes=12, dt_output=1e-5, fields=True)
    for name in ("deflection_1", "x1"):
        np.testing.assert_allclose(both[name].values, alone[name].values, rtol=0,
                                   atol=1e-12 * float(np.abs(alone[name]).max()))
    assert both.deflection_1.shape == (both.sizes["time"], 41)
    tip = both.tip_deflection_1.values
    apart = np.abs(both.deflection_1.values[:, -1] - tip)
    open_ = np.all(both.contact_forces.values == 0.0, axis=1)
    assert np.max(apart[open_]) < 1e-12 * np.max(np.abs(tip))
    assert 1e-9 < np.max(apart[~open_]) < 1e-7


# a tip stop with a dashpot (zeta = 0.02, Omega = 300 rad/s: a period-2 response after 100
# forcing periods), alone and beside a mid-span stop 1 mm away that never closes
LONG = STOP.replace(force_amplitude=1e-3, omega=300.0, damping_ratio=0.02)
ALONE = LONG.replace(clearance=2e-6, contact_damping=0.2)
BESIDE = LONG.replace(contacts=(Contact(clearance=2e-6, damping=0.2),
                                Contact(MID, clearance=1e-3)))


def test_long_time_and_tip_velocities_beside_a_contact_that_never_closes():
    """simulate with long_time (16 periods after 100) of `BESIDE` against `ALONE` (the single
    contact's run and sampling): the response period (2) and the steady impact and episode
    rates equal, the stroboscopic tip deflections and velocities to 1e-11 of their largest
    (measured 2.5e-13 and 1.7e-12), the tip velocity series, whose closed dashpot's force rate
    -k g' - c g'' moves the tip through the flexibility the modes miss, to 1e-11 (measured
    1.2e-12)."""
    from impactbeams import LongTime

    period = 2.0 * math.pi / LONG.omega
    long_time = LongTime(sampled_periods=16)
    runs = [simulate(params, 116 * period, n_modes=12, dt_output=period / 8,
                     long_time=long_time, transient_periods=100) for params in (ALONE, BESIDE)]
    alone, beside = runs
    assert int(beside.response_period) == int(alone.response_period) == 2
    for name in ("steady_impact_rate", "steady_episode_rate"):
        assert float(beside[name]) == float(alone[name]) > 0.0
    for name in ("poincare_deflection1", "poincare_velocity1", "tip_velocity_1"):
        np.testing.assert_allclose(beside[name].values, alone[name].values, rtol=0,
                                   atol=1e-11 * float(np.abs(alone[name]).max()))
    assert beside.attrs["transient_periods"] == 100


def test_a_long_time_sweep_of_several_contacts_is_simulate_and_the_single_contacts_map():
    """A long-time map over Omega of `BESIDE` (unstepped): each cell is simulate's long_time of
    its parameters bit for bit, and the single contact's map of `ALONE` (its stroboscope
    kernel) to round-off: the response periods and rates equal, the samples to 1e-11 of their
    largest (measured 1.3e-13 and 1.5e-12)."""
    from impactbeams import LongTime
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    observables = ["poincare_deflection1", "poincare_velocity1", "response_period",
                   "steady_impact_rate", "steady_episode_rate"]
    mapping = {"axes": {"omega": {"min": 300.0, "max": 400.0, "num": 2}}, "t_max": 0.01,
               "n_modes": 12, "sampled_periods": 16, "transient_periods": 100,
               "observables": observables}
    common = {"counterpart": "stop", "force_amplitude": 1e-3, "contact_stiffness": 1e4,
              "damping_ratio": 0.02}
    sweep = sweep_from_mapping({**mapping, "params": {**common, "contacts": [
        {"clearance": 2e-6, "damping": 0.2}, {"position1": MID, "clearance": 1e-3}]}})
    several = run_sweep(sweep)
    single = run_sweep(sweep_from_mapping({**mapping, "params": {
        **common, "clearance": 2e-6, "contact_damping": 0.2}}))
    assert list(single.response_period.values) == list(several.response_period.values) == [2, 1]
    for name in ("steady_impact_rate", "steady_episode_rate"):
        np.testing.assert_array_equal(several[name].values, single[name].values)
    for name in ("poincare_deflection1", "poincare_velocity1"):
        np.testing.assert_allclose(several[name].values, single[name].values, rtol=0,
                                   atol=1e-11 * float(np.abs(single[name]).max()))
    for omega in several.omega.values:
        period = 2.0 * math.pi / omega
        run = simulate(sweep.params_at({"omega": omega}), 116 * period, n_modes=12,
                       dt_output=period, long_time=LongTime(sampled_periods=16),
                       transient_periods=100)
        for name in observables:
            np.testing.assert_array_equal(several[name].sel(omega=omega).values,
                                          run[name].values)


def test_the_command_line_simulates_several_contacts(tmp_path, capsys):
    """``impactbeams simulate --params FILE`` with ``[[params.contacts]]``: the library's Dataset
    (the same contacts, bit for bit) in the netCDF file, the contacts as its attributes;
    ``--lyapunov`` the library's exponent too."""
    path = tmp_path / "two.toml"
    path.write_text('[params]\ncounterpart = "stop"\nforce_amplitude = 1e-3\nomega = 400.0\n'
                    "contact_stiffness = 1e4\n[[params.contacts]]\nposition1 = 0.05\n"
                    "clearance = 1e-6\n[[params.contacts]]\nclearance = 2e-6\n")
    out = tmp_path / "run.nc"
    assert main(["simulate", "--params", str(path), "--t-max", "0.03", "--n-modes", "12",
                 "--energy-balance", "--quiet", "-o", str(out)]) == 0
    params = FORCED.replace(contacts=(Contact(MID, clearance=1e-6), Contact(clearance=2e-6)))
    expected = simulate(params, 0.03, n_modes=12, energy_balance=True)
    with xr.open_dataset(out) as written:
        for name in ("impact_onset_time", "impact_contact", "contact_forces", "work_of_force"):
            np.testing.assert_array_equal(written[name].values, expected[name].values)
        assert "clearance=2e-06" in written.attrs["contacts"]
        assert "clearance" not in written.attrs  # each contact gives its own
    capsys.readouterr()
    assert main(["simulate", "--params", str(path), "--t-max", "0.03", "--n-modes", "12",
                 "--lyapunov", "1", "--quiet",
                 "-o", str(tmp_path / "lyapunov.nc")]) == 0
    expected = simulate(params, 0.03, n_modes=12, lyapunov=1)
    with xr.open_dataset(tmp_path / "lyapunov.nc") as written:
        assert float(written.lyapunov_exponent) == float(expected.lyapunov_exponent)


# --- sweeps of the full dynamics of several contacts --------------------------------------------


def _union_length(onset: np.ndarray, end: np.ndarray) -> float:
    """The length (s) of the union of the intervals [onset, end]."""
    total, reach = 0.0, -math.inf
    for a, b in sorted(zip(onset, end, strict=True)):
        total += max(0.0, b - max(a, reach))
        reach = max(reach, b)
    return total


def test_a_dynamics_sweep_of_several_contacts_is_simulate_cell_by_cell():
    """A forcing frequency by the tip stop's clearance (a mid-span stop beside it, one with
    dashpots): every cell against simulate of that cell's parameters: the impact count, the
    first contact and its onset, the largest force, each contact's impacts and largest force
    bit for bit, the mean restitution (the
    separation over the approach speeds of the contacts simulate lists) to 1e-14 and the
    contact fraction (the union of the contacts' intervals over t_max) to 1e-12 (measured
    0 and 0: the same numbers); parallel, serial and in chunks of one cell the same bits; the
    first impact as the first-impact map of the same grid gives it (each contact's own map,
    its own kernel) to 1e-12 s (measured 6.9e-18 s)."""
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    mapping = {"params": {"counterpart": "stop", "force_amplitude": 1e-3,
                          "contact_stiffness": 1e4, "contacts": [
                              {"position1": MID, "clearance": 1e-6, "damping": 0.2}, {}]},
               "axes": {"omega": {"min": 300.0, "max": 500.0, "num": 3},
                        "contacts.1.clearance": {"min": 1e-6, "max": 3e-6, "num": 2}},
               "t_max": 0.03, "n_modes": 12,
               "observables": ["first_impact_time", "impact_count", "max_contact_force",
                               "mean_restitution", "contact_fraction", "contact_impact_count",
                               "contact_max_force"]}
    sweep = sweep_from_mapping(mapping)
    ds = run_sweep(sweep)
    for other in (run_sweep(sweep, parallel=False), run_sweep(sweep, chunk_cells=1)):
        for name in ds.data_vars:
            np.testing.assert_array_equal(other[name].values, ds[name].values)
    first = run_sweep(sweep_from_mapping({**mapping, "observables": ["first_impact_time"]}))
    np.testing.assert_allclose(ds.first_impact_time.values, first.first_impact_time.values,
                               rtol=0, atol=1e-12)
    np.testing.assert_array_equal(ds.first_contact.values, first.first_contact.values)
    assert np.all(ds.dynamics_status.values == 0) and ds.impact_count.values.min() >= 3
    for omega in ds.omega.values:
        for clearance in ds["contacts.1.clearance"].values:
            cell = ds.sel({"omega": omega, "contacts.1.clearance": clearance})
            run = simulate(sweep.params_at({"omega": omega, "contacts.1.clearance": clearance}),
                           0.03, n_modes=12, dt_output=1e-3)
            assert int(cell.impact_count) == run.sizes["impact"]
            assert int(cell.first_contact) == int(run.impact_contact[0])
            assert float(cell.first_impact_time) == float(run.impact_onset_time[0])
            assert float(cell.max_contact_force) == float(run.impact_peak_force.max())
            for j in (0, 1):  # each contact's share
                own = run.impact_contact.values == j
                assert int(cell.contact_impact_count[j]) == np.count_nonzero(own)
                assert float(cell.contact_max_force[j]) == float(
                    run.impact_peak_force.values[own].max(initial=0.0))
            approach = run.impact_velocity.values
            separated = np.isfinite(run.separation_velocity.values) & (approach < 0)
            restitution = (run.separation_velocity.values[separated].sum()
                           / -approach[separated].sum())
            assert float(cell.mean_restitution) == pytest.approx(restitution, rel=1e-14)
            onset = run.impact_onset_time.values
            end = np.where(np.isnan(run.impact_duration.values), 0.03,
                           onset + run.impact_duration.values)
            assert float(cell.contact_fraction) == pytest.approx(
                _union_length(onset, end) / 0.03, rel=1e-12)


def test_what_sweeps_of_several_contacts_refuse_in_one_line():
    """Each contact's share with one contact."""
    from impactbeams.sweep import sweep_from_mapping

    omega = {"omega": {"min": 300.0, "max": 400.0, "num": 2}}
    with pytest.raises(ParameterError, match=r"^observables in sweep = \['contact_impact_count'"
                                             r"\] is not allowed: each contact's share"):
        sweep_from_mapping({"params": {"counterpart": "stop"}, "axes": omega, "t_max": 0.1,
                            "observables": ["contact_impact_count"]})
