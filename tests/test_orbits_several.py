"""Periodic orbits with several contacts (issue 33, item 5): the period map of the active sets'
phases, its exact monodromy (each phase's tangent flow, the saltation at every switch), and
shooting on it.

The runs: a stop at mid-span and one at the tip, both below (closed together), with and
without dashpots, and a two-sided stop at mid-span (`tests/test_several_contacts.py`'s), at
k = 1e4 N/m, zeta = 0.05 and 8 modes: stable period-1 orbits.
"""

import re

import numpy as np
import pytest

from impactbeams import Contact, ParameterError, Params, simulate, two_sided_stop
from impactbeams.active_phases import contact_quantities, sample
from impactbeams.continuation import Continuation, continue_orbits
from impactbeams.kernels.layout import FREE, ROW_EVENT, TIP_V1, TIP_Y1
from impactbeams.orbits import PeriodMap, periodic_orbit
from impactbeams.orbits.contacts_map import ContactsPeriodMap
from impactbeams.trajectory.start import phase_state
from impactbeams.variables import BIFURCATIONS
from orbit_reference import central_jacobian, settled
from orbit_reference import map_energy_scale as energy_scale

N_MODES = 8
STOP = Params(counterpart="stop", contact_stiffness=1e4, damping_ratio=0.05)
MID = 0.5 * STOP.l1  # m
FORCED = STOP.replace(force_amplitude=1e-3, omega=400.0)
TWO_SIDED = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6))
TOGETHER = FORCED.replace(contacts=(Contact(MID, clearance=1e-6), Contact(clearance=2e-6)))
DASHPOTS = FORCED.replace(contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                                    Contact(clearance=2e-6, damping=0.5)))
RUNS = {"two-sided": TWO_SIDED, "together": TOGETHER, "dashpots": DASHPOTS}


def in_energy(period_map, jacobian):
    scale = energy_scale(period_map)
    return scale[:, None] * jacobian / scale[None, :]


@pytest.fixture(scope="module")
def orbits():
    """Each run's orbit by Newton from 50 transient periods, with its map."""
    return {name: (periodic_orbit(params, N_MODES, method="newton"),
                   ContactsPeriodMap(params, N_MODES)) for name, params in RUNS.items()}


@pytest.mark.parametrize("name", list(RUNS))
def test_monodromy_of_several_contacts_matches_finite_differences(name):
    """The carried Jacobian against central differences of the map (relative steps 1e-4 and
    1e-5 in the energy norm), 40 periods after rest (not yet on the orbit). The difference is
    the differences' own truncation, O(h^2): it falls 100-fold from 1e-4 to 1e-5 (measured
    2.5e-7 -> 2.5e-9 two-sided, 1.2e-7 -> 1.2e-9 together, 1.6e-7 -> 1.6e-9 with dashpots),
    so at 1e-5 it is below 1e-8. The runs switch sets: both sides of the two-sided stop, the
    two stops closing together; with dashpots the forces jump at the closings (the saltation
    matrix: without it the difference is 1.06) and two early releases' gaps open."""
    period_map = ContactsPeriodMap(RUNS[name], N_MODES)
    z = settled(period_map, 40)
    result = period_map(z, directions="all", measures=False)
    run = result.trajectory
    assert set(run.mask.tolist()) == ({0, 1, 2} if name == "two-sided" else {0, 2, 3})
    if name == "dashpots":  # the early releases' openings: functions n + f
        assert {2, 3} <= set(run.switched.tolist())
    carried = in_energy(period_map, result.jacobian)
    errors = []
    for step in (1e-4, 1e-5):
        reference = in_energy(period_map, central_jacobian(
            lambda x: period_map(x, measures=False).state, z, energy_scale(period_map), step))
        errors.append(np.linalg.norm(carried - reference, 2) / np.linalg.norm(reference, 2))
    assert errors[1] < 1e-8
    assert 50 < errors[0] / errors[1] < 200  # h^2: the tangent is exact


@pytest.mark.parametrize("damping", [0.0, 0.5])
def test_one_contact_beside_one_that_never_closes_is_the_single_contacts_map(damping):
    """A tip stop (with or without a dashpot) beside a mid-span one 1 mm away: the state, the
    monodromy, the counts and the contacts' measures of the single contact's PeriodMap, to
    round-off (measured: states 5.1e-16, monodromies 3.6e-14 of their largest entry: the set
    phases' complex modes against the free table's real ones)."""
    single = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=2e-6,
                          contact_damping=damping)
    two = single.replace(contacts=(Contact(clearance=2e-6, damping=damping),
                                   Contact(MID, clearance=1e-3)))
    one_map, two_map = PeriodMap(single, N_MODES), ContactsPeriodMap(two, N_MODES)
    z = settled(one_map, 40)
    one, several = one_map(z, directions="all"), two_map(z, directions="all")
    assert several.trajectory.mask.tolist() == one.trajectory.phase.tolist()  # 0 free, 1
    assert np.count_nonzero(several.trajectory.mask) >= 2  # it closes, twice
    assert np.abs(several.state - one.state).max() < 2e-15 * np.abs(one.state).max()
    assert np.abs(several.jacobian - one.jacobian).max() < 1e-13 * np.abs(one.jacobian).max()
    assert (several.contacts, several.episodes) == (one.contacts, one.episodes)
    assert several.peak_force == pytest.approx(one.peak_force, rel=1e-13)
    assert several.impulse == pytest.approx(one.impulse, rel=1e-13)


def test_a_section_state_in_contact_starts_in_its_active_set():
    """A state pushed into the tip stop (gap < 0, force > 0): the single contact's start
    (`phase_state`) is in contact, so is the active set found, and the maps agree to round-off
    (measured 1.4e-16 and 2.3e-15); pushed into both stops, both are closed at the start."""
    single = STOP.replace(force_amplitude=1e-3, omega=400.0, clearance=2e-6)
    two = single.replace(contacts=(Contact(clearance=2e-6), Contact(MID, clearance=1e-3)))
    one_map, two_map = PeriodMap(single, N_MODES), ContactsPeriodMap(two, N_MODES)
    weights = one_map.packed.tables[FREE, ROW_EVENT]
    z = np.concatenate([-3e-6 * weights / (weights @ weights), np.zeros(N_MODES)])
    assert phase_state(one_map.packed, z)[2] == 1 and two_map.active_mask(z) == 1
    one, several = one_map(z, directions="all"), two_map(z, directions="all")
    assert np.abs(several.state - one.state).max() < 1e-14 * np.abs(one.state).max()
    assert np.abs(several.jacobian - one.jacobian).max() < 1e-13 * np.abs(one.jacobian).max()
    together = ContactsPeriodMap(TOGETHER, N_MODES)
    b = together.contacts.gap_weights  # the gaps' weights: both modal gaps -5 um
    q = b.T @ np.linalg.solve(b @ b.T, np.array([-6e-6, -7e-6]))
    pushed = np.concatenate([q, np.zeros(N_MODES)])
    assert together.active_mask(pushed) == 3
    assert together(pushed).trajectory.mask[0] == 3


@pytest.mark.parametrize("name", list(RUNS))
def test_orbits_of_several_contacts_are_where_a_long_simulate_settles(orbits, name):
    """``simulate`` over 300 periods from rest (its own run, not restarted at the sections):
    its last period's contact gaps and forces (257 samples) are the orbit's, from its
    section state, to 1e-10 of their largest value (measured 3e-13..1e-12 for the gaps,
    3e-12..7e-12 for the forces; the transient has decayed as |mu|^300 < 1e-15), and so are
    its tips (measured 3e-13..1.1e-12); the orbit's largest tip deflection bounds them, above
    the largest sample by 1.6e-8..1.4e-4 (the samples' spacing)."""
    orbit, period_map = orbits[name]
    params = RUNS[name]
    assert orbit.residual <= 1e-11 and orbit.stable and orbit.contacts >= 2
    period = 2 * np.pi / params.omega
    times = np.linspace(299 * period, 300 * period, 257)
    ds = simulate(params, 300 * period, N_MODES, times=times)
    result = period_map(orbit.state, measures=False)
    local = times - 299 * period
    q, v, mask = sample(period_map.contacts, result.trajectory, local)
    own = contact_quantities(period_map.contacts, local, q, v, mask)
    for key, simulated in (("gap", ds.contact_gaps.values),
                           ("contact_force", ds.contact_forces.values)):
        assert np.abs(simulated - own[key]).max() < 1e-10 * np.abs(own[key]).max(), key
    tips = period_map.tip_motions(result, local)[:, TIP_Y1]
    simulated = ds.tip_deflection_1.values
    assert np.abs(simulated - tips).max() < 1e-10 * np.abs(tips).max()
    # the orbit's refined maximum bounds the samples, 257 a period (within 1e-3 of it)
    largest = np.abs(simulated).max()
    assert largest <= orbit.max_tip1 * (1 + 1e-12) and orbit.max_tip1 < largest * (1 + 1e-3)


@pytest.mark.parametrize("name", list(RUNS))
def test_the_orbits_tip_velocities_are_its_tips_rates(orbits, name):
    """``tip_motions``' velocity of beam 1's tip (its modes' and the closed forces' rates
    through the flexibility the modes miss) against central differences of its deflection at
    255 times of the period, each farther than two steps from a switch: the difference is the
    differences' truncation, O(h^2), falling 100-fold from steps 1e-5 T to 1e-6 T (measured
    4.1e-8 -> 4.4e-10, 6.0e-7 -> 6.0e-9, 3.4e-7 -> 3.4e-9 of the largest velocity)."""
    orbit, period_map = orbits[name]
    result = period_map(orbit.state, measures=False)
    switches = result.trajectory.time
    times = np.linspace(0.0, period_map.horizon, 257)[1:-1]
    errors = []
    for step in (1e-5 * period_map.horizon, 1e-6 * period_map.horizon):
        t = times[[np.min(np.abs(switches - at)) > 2 * step for at in times]]
        velocity = period_map.tip_motions(result, t)[:, TIP_V1]
        rates = (period_map.tip_motions(result, t + step)[:, TIP_Y1]
                 - period_map.tip_motions(result, t - step)[:, TIP_Y1]) / (2 * step)
        errors.append(np.abs(rates - velocity).max() / np.abs(velocity).max())
    assert errors[1] < 1e-8 and 50 < errors[0] / errors[1] < 200


def test_a_symmetric_two_sided_stop_has_a_symmetric_orbit(orbits):
    """Equal clearances on both sides and F0 sin(Omega t): the equations are invariant under
    z -> -z, t -> t + T/2, and the stable orbit with them: z(T/2) = -z(0) (measured 3e-15 in
    the energy norm), each stop's contacts the other's half a period later."""
    orbit, period_map = orbits["two-sided"]
    result = period_map(orbit.state, measures=False)
    half = np.pi / TWO_SIDED.omega
    q, v, _ = sample(period_map.contacts, result.trajectory, np.array([half]))
    scale = energy_scale(period_map)
    mirrored = scale * (np.concatenate([q[0], v[0]]) + orbit.state)
    assert np.linalg.norm(mirrored) < 1e-13 * np.linalg.norm(scale * orbit.state)
    run = result.trajectory
    onsets = [(int(f), t) for f, t, mask in zip(run.switched, run.time, run.mask, strict=True)
              if f >= 0 and (mask >> f) & 1]
    below = [t for f, t in onsets if f == 0]
    above = [t for f, t in onsets if f == 1]
    assert len(below) == len(above) >= 2
    assert np.allclose(np.sort(np.mod(np.array(below) + half, 2 * half)), np.sort(above),
                       rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", list(RUNS))
def test_multipliers_are_the_finite_difference_monodromys_eigenvalues(orbits, name):
    """The orbit's multipliers against the eigenvalues of the central differences' monodromy
    at the orbit (step 1e-5, which differ from the Jacobian by < 1e-8 of its norm): the four
    leading within 1e-7 (measured 3.4e-10 at most); Newton-Picard's the same orbit and leading
    multipliers (measured 5e-13, 1e-11)."""
    orbit, period_map = orbits[name]
    reference = central_jacobian(lambda x: period_map(x, measures=False).state, orbit.state,
                                 energy_scale(period_map), 1e-5)
    eigenvalues = np.linalg.eigvals(reference)
    eigenvalues = eigenvalues[np.lexsort((-eigenvalues.imag, -np.abs(eigenvalues)))]
    assert np.abs(orbit.multipliers[:4] - eigenvalues[:4]).max() < 1e-7
    picard = periodic_orbit(RUNS[name], N_MODES, guess=orbit.state, method="newton-picard")
    scale = energy_scale(period_map)
    assert (np.linalg.norm(scale * (picard.state - orbit.state))
            < 1e-10 * np.linalg.norm(scale * orbit.state))
    assert np.abs(picard.multipliers[:2] - orbit.multipliers[:2]).max() < 1e-9


def test_what_orbits_of_several_contacts_refuse(orbits):
    """A continuation of a flat contact key and the single contact's PeriodMap refuse
    several contacts in one line; the contacts' measures are there."""
    with pytest.raises(ParameterError, match="parameter = 'clearance' is not allowed: with 2 "
                                             "contacts each gives its own"):
        Continuation(TWO_SIDED, "clearance", 1e-6, 4e-6)
    with pytest.raises(ParameterError, match="not allowed in PeriodMap"):
        PeriodMap(TWO_SIDED, N_MODES)
    result = ContactsPeriodMap(TWO_SIDED, N_MODES)(settled(ContactsPeriodMap(TWO_SIDED,
                                                                              N_MODES), 40))
    assert result.peak_force > 0 and result.impulse > 0 and result.peak_forces.size >= 2
    assert result.max_tip1 > 0


def test_an_orbit_whose_section_lies_in_a_dashpots_early_release():
    """A two-sided stop (1 um each side, dashpots) at 426.5 rad/s: the stop above releases
    early at 0.9984 T and its gap opens at 1.0017 T, so the orbit's section state lies in that
    early release (the stop's gap -15 nm while open). The map starts there as the run goes on
    after the release (`resume_contacts` with it released early): `simulate` from rest over
    300 periods, its own run through the early release, ends on the orbit's state to 1e-11
    in the energy norm (measured 2.6e-13; the transient decays as |mu|^300), and the
    monodromy carried from that start is central differences' to their truncation (1.6e-9
    at step 1e-5, falling as h^2)."""
    params = FORCED.replace(omega=426.5, contacts=two_sided_stop(MID, 1e-6, 1e-6, damping=0.5))
    orbit = periodic_orbit(params, N_MODES, method="newton")
    period_map = ContactsPeriodMap(params, N_MODES)
    z = orbit.state
    m = z.size // 2
    gaps = period_map._events(0, z[:m], z[m:])
    assert orbit.residual < 1e-12 and period_map.active_mask(z) == 0
    assert gaps[0] > 0 > gaps[1] and period_map.early_released(0, z[:m], z[m:]) == 2
    run = period_map(z, measures=False).trajectory
    assert run.switched[1] == 3 and run.time[1] < 0.01 * period_map.horizon  # it opens
    period = period_map.forcing_period
    ds = simulate(params, 300 * period, N_MODES, times=np.array([300 * period]))
    end = np.concatenate([ds.final_displacement.values, ds.final_velocity.values])
    scale = energy_scale(period_map)
    assert np.linalg.norm(scale * (end - z)) < 1e-11 * np.linalg.norm(scale * z)
    carried = in_energy(period_map, period_map(z, directions="all", measures=False).jacobian)
    errors = []
    for step in (1e-4, 1e-5):
        reference = in_energy(period_map, central_jacobian(
            lambda x: period_map(x, measures=False).state, z, scale, step))
        errors.append(np.linalg.norm(carried - reference, 2) / np.linalg.norm(reference, 2))
    assert errors[1] < 1e-8 and 50 < errors[0] / errors[1] < 200


def test_a_section_state_that_pulls_if_closed_starts_released_early():
    """Overlapping but opening fast enough that the dashpot's pull exceeds the spring's push:
    the contact starts released early, as the single contact's `phase_state` starts free
    there, and its gap's opening (function n + f) is the run's first switch. The mid-span
    stop alone (gap -1.1 um); then both stops overlapping by 1 um, the tip's opening at
    0.05 m/s: no set fits, and the one chosen has the mid-span stop closed (its force > 0)
    with the tip's released early (closed, it would pull), not the empty set."""
    period_map = ContactsPeriodMap(DASHPOTS, N_MODES)
    weights = period_map.packed.tables[FREE, ROW_EVENT]  # the mid-span stop's gap
    unit = weights / (weights @ weights)
    z = np.concatenate([-1.1e-6 * unit, 5e-2 * unit])
    assert period_map.active_mask(z) == 0 and period_map.early_released(0, z[:N_MODES],
                                                                 z[N_MODES:]) == 1
    single = PeriodMap(STOP.replace(force_amplitude=1e-3, omega=400.0, contact_position1=MID,
                                    clearance=1e-6, contact_damping=0.5), N_MODES)
    assert phase_state(single.packed, z)[2] == FREE
    assert period_map(z).trajectory.switched[1] == 2  # contact 0's gap opens: function 2 + 0
    b = period_map.contacts.gap_weights  # the modal gaps: clearances 1, 2 um, both -3 um
    z = np.concatenate([b.T @ np.linalg.solve(b @ b.T, rows) for rows in ([-3e-6, -3e-6],
                                                                          [0.0, 5e-2])])
    assert period_map.active_mask(z) == 1 and period_map.early_released(1, z[:N_MODES],
                                                                 z[N_MODES:]) == 2
    assert period_map(z).trajectory.switched[1] == 3  # contact 1's gap opens


# a two-sided stop 3 um below and 6 um above mid-span: along F0 the orbit first touches the
# stop below, then the one above (a two-sided stop's second grazing)
BACKLASH = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 6e-6))


def _grazings(dataset):
    labels = dataset.bifurcation.values
    return [i for i in np.flatnonzero(labels) if BIFURCATIONS[labels[i]] == "grazing"]


def _located_against_the_orbits_gap(dataset, index, contact):
    """The located F0 against the root of the orbit's smallest gap, extrapolated linearly
    from periodic orbits 1e-5 and 2e-5 (relative) below it; that gap is ``contact``'s. The
    continuation locates to 1e-11 of its range; the extrapolation's truncation is the gap's
    curvature in F0 times (1e-5)^2, so 1e-8 bounds the difference."""
    located = dataset.force_amplitude.values[index]
    values = []
    for below in (2e-5, 1e-5):
        params = BACKLASH.replace(force_amplitude=located * (1 - below))
        orbit = periodic_orbit(params, N_MODES, guess=dataset.section_state.values[index])
        period_map = ContactsPeriodMap(params, N_MODES)
        result = period_map.approach(period_map(orbit.state, measures=False))
        gaps, _ = period_map._gaps(result.trajectory, np.array([result.min_gap_time]))
        assert gaps[0, contact] == pytest.approx(result.min_gap, rel=1e-12)
        values.append((params.force_amplitude, result.min_gap))
    (f1, g1), (f2, g2) = values
    return abs(f2 - g2 * (f2 - f1) / (g2 - g1) - located) / located


def test_continuation_of_a_two_sided_stop_locates_its_first_grazing():
    """From the non-impacting orbit at F0 = 0.3 mN: the grazing with the stop below (0 to
    1 contact per orbit) located where the orbit's smallest gap, the lower stop's,
    extrapolates to 0 (measured 2.2e-15 relative: without contact the orbit, and its gap, is
    linear in F0); the tips' amplitudes are measured at every point."""
    dataset = continue_orbits(Continuation(BACKLASH, "force_amplitude", 3e-4, 3.8e-4,
                                           n_modes=N_MODES))
    (index,) = _grazings(dataset)
    assert list(dataset.contacts_per_orbit.values[index - 1:index + 2]) == [0, 0, 1]
    error = _located_against_the_orbits_gap(dataset, index, 0)
    print(f"first grazing located to {error:.1e}")
    assert error < 1e-8
    assert np.all(dataset.tip_amplitude_1.values > 0)  # the measures of several contacts


def test_continuation_in_one_contacts_clearance_is_the_single_contacts_branch():
    """``contacts.0.clearance`` continued (a stop below mid-span, one far above that never
    closes): every branch point is a fixed point of the single stop's own period map
    (`PeriodMap`, the one-contact kernels) at that clearance, to 1e-12 of the state
    (measured 1.1e-15), across the grazing where the orbit's 2 contacts become 1."""
    params = FORCED.replace(contacts=two_sided_stop(MID, None, 1e-4), force_amplitude=3.8e-4)
    name = "contacts.0.clearance"
    dataset = continue_orbits(Continuation(params, name, 2.5e-6, 2.9e-6, n_modes=N_MODES))
    assert dataset[name].dims == ("branch_point",) and dataset[name].attrs["units"] == "m"
    assert dataset[name].attrs["long_name"].endswith(" of contacts[0]")
    assert dataset.attrs["continued_parameter"] == name
    assert {1, 2} <= set(dataset.contacts_per_orbit.values.tolist())
    single = FORCED.replace(contact_position1=MID, force_amplitude=3.8e-4)
    for clearance, state in zip(dataset[name].values, dataset.section_state.values,
                                strict=True):
        mapped = PeriodMap(single.replace(clearance=float(clearance)), N_MODES)(state).state
        assert np.linalg.norm(mapped - state) <= 1e-12 * np.linalg.norm(state), clearance


@pytest.mark.parametrize(("parameter", "params", "message"), [
    ("contacts.0.position1", TWO_SIDED, "a contact's continuable fields are clearance, "
     "stiffness, damping"),
    ("contacts.2.stiffness", TWO_SIDED, "there are 2 contacts (indices 0 to 1)"),
    ("contacts.0.clearance", FORCED, "continues a field of one of several contacts, and params "
     "has one or none: one contact is the flat keys (continue clearance)"),
    ("clearance", TWO_SIDED, "with 2 contacts each gives its own: continue one contact's as "
     "'contacts.INDEX.FIELD' (FIELD one of clearance, stiffness, damping)")])
def test_what_a_continuation_of_several_contacts_refuses(parameter, params, message):
    with pytest.raises(ParameterError, match=re.escape(f"parameter = {parameter!r} is not "
                                                       f"allowed: {message}")):
        Continuation(params, parameter, 1e-6, 4e-6)


@pytest.mark.slow  # 25 s: 55 points along a branch that touches three times
def test_continuation_of_a_two_sided_stop_locates_the_second_stops_grazing():
    """Up to F0 = 0.475 mN: grazings at 0.372 mN (the stop below), 0.412 mN (a second
    contact with it) and 0.474 mN, where the stop above is touched first (its contacts
    appear in the orbit's active sets); that one located where the orbit's smallest gap, the
    upper stop's, extrapolates to 0 (measured 1.2e-10 relative), a fold just past it."""
    dataset = continue_orbits(Continuation(BACKLASH, "force_amplitude", 3e-4, 4.75e-4,
                                           n_modes=N_MODES, max_points=55))
    indices = _grazings(dataset)
    assert len(indices) == 3
    counts = dataset.contacts_per_orbit.values
    assert [list(counts[i - 1:i + 2]) for i in indices] == [[0, 0, 1], [1, 1, 2], [2, 2, 3]]
    sets = []
    for i in (indices[2] - 1, indices[2] + 1):
        params = BACKLASH.replace(force_amplitude=dataset.force_amplitude.values[i])
        run = ContactsPeriodMap(params, N_MODES)(dataset.section_state.values[i]).trajectory
        sets.append(set(run.mask.tolist()))
    assert sets == [{0, 1}, {0, 1, 2}]  # the stop above (bit 2) closes past the grazing
    error = _located_against_the_orbits_gap(dataset, indices[2], 1)
    print(f"second stop's grazing located to {error:.1e}")
    assert error < 1e-8


@pytest.mark.parametrize("name", list(RUNS))
def test_an_orbits_dataset_is_one_period_of_simulate_from_its_state(orbits, name):
    """``to_dataset()``: `simulate` of several contacts over one period from the orbit's
    section state (every variable bit for bit: its tips, energies, each contact's gap and
    force, contacts and episodes) with the multipliers; the run closes on the orbit, its end
    state within the orbit's residual of its start (energy norm: the same map, another run
    of it, measured equal to 1e-15)."""
    orbit, period_map = orbits[name]
    dataset = orbit.to_dataset(samples_per_period=64)
    times = np.linspace(0.0, orbit.duration, 65)
    alone = simulate(RUNS[name], orbit.duration, N_MODES, times=times,
                     initial_state=orbit.state)
    for variable in alone.variables:
        np.testing.assert_array_equal(dataset[variable].values, alone[variable].values)
    assert dataset.contact_forces.dims == ("time", "contact") and dataset.sizes["impact"] >= 2
    np.testing.assert_array_equal(dataset.floquet_multiplier_real, orbit.multipliers.real)
    assert dataset.attrs["orbit_stable"] == 1 and dataset.attrs["orbit_contacts"] >= 2
    scale = energy_scale(period_map)
    end = np.concatenate([dataset.final_displacement, dataset.final_velocity])
    assert (np.linalg.norm(scale * (end - orbit.state))
            <= (orbit.residual + 1e-13) * np.linalg.norm(scale * orbit.state))


def test_an_orbits_dataset_beside_a_contact_that_never_closes_is_the_single_contacts():
    """A tip stop beside a mid-span one 1 mm away: the single contact's orbit Dataset in the
    variables both have (tips, energies, contacts, episodes, multipliers), to 1e-12 of each
    one's largest (measured 2.7e-14 for tip_velocity_1, 7e-15 or less otherwise; the
    multipliers' exponents 7e-11, the logarithm of multipliers that agree to 3e-15)."""
    single = FORCED.replace(clearance=2e-6)
    two = single.replace(contacts=(Contact(clearance=2e-6), Contact(MID, clearance=1e-3)))
    with pytest.warns(RuntimeWarning, match="does not resolve"):
        one = periodic_orbit(single, N_MODES).to_dataset(samples_per_period=64)
    several = periodic_orbit(two, N_MODES).to_dataset(samples_per_period=64)
    assert several.sizes["impact"] == one.sizes["impact"] >= 2
    for name in ("tip_deflection_1", "tip_velocity_1", "energy", "kinetic_energy",
                 "impact_onset_time", "impact_duration", "impact_impulse", "impact_peak_force",
                 "episode_onset_time", "episode_peak_force", "floquet_multiplier_real",
                 "floquet_multiplier_imag", "final_displacement", "final_velocity"):
        reference = one[name].values
        assert np.abs(several[name].values - reference).max() <= 1e-12 * np.abs(
            reference).max(), name
    np.testing.assert_allclose(several.contact_forces.sel(contact=1), 0.0, rtol=0, atol=0)


# issue 31's merge (`tests/test_continuation_events.py`): two beams, 3 modes, the tips' contact
# at 11 um; near 257.46 rad/s the orbit's 3 contacts become 2
BEAMS = Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5,
               clearance=1.1e-5)
FAR = BEAMS.replace(contacts=(Contact(clearance=1.1e-5),
                              Contact(0.5 * BEAMS.l1, 0.5 * BEAMS.l2, clearance=1e-3)))
# a second contact at 0.8 of both beams, 8.75 um: it closes too (a merge near 257.176 rad/s)
BOTH = BEAMS.replace(contacts=(Contact(clearance=1.1e-5),
                               Contact(0.8 * BEAMS.l1, 0.8 * BEAMS.l2, clearance=8.75e-6)))


def _located(params, low, high, **extra):
    dataset = continue_orbits(Continuation(params, "omega", low, high, n_modes=3,
                                           max_branches=1, **extra))
    labels = [BIFURCATIONS[code] for code in dataset.bifurcation.values]
    return dataset, [(label, float(dataset.omega[i])) for i, label in enumerate(labels)
                     if label in ("contact_merge", "contact_split")]


def test_interval_value_beside_a_contact_that_never_closes_is_the_single_contacts():
    """The interval value of the tips' contact beside one 1 mm away that never closes: the
    single contact's (`PeriodMap`, its kernel) at every point of the branch from 257.44 to
    257.5 rad/s, on both sides of the merge (a free interval's height > 0, a contact's rise
    < 0), to 1e-14 of the clearance, a few times a gap's round-off (measured 6.5e-16: the
    set's force over its effective stiffness against the free coordinates' gap), and the
    merge located at the same frequency (measured 2.2e-16 relative; each to 1e-11 of the
    range at the root of its interval value)."""
    one, one_events = _located(BEAMS, 257.44, 257.5, start=257.44)
    two, two_events = _located(FAR, 257.44, 257.5, start=257.44)
    assert [label for label, _ in one_events] == ["contact_merge"]
    assert [label for label, _ in two_events] == ["contact_merge"]
    assert two_events[0][1] == pytest.approx(one_events[0][1], rel=1e-14)
    signs = set()
    for omega, state in zip(one.omega.values, one.section_state.values, strict=True):
        single = PeriodMap(BEAMS.replace(omega=float(omega)), 3)
        several = ContactsPeriodMap(FAR.replace(omega=float(omega)), 3)
        expected = single.approach(single(state, measures=False)).interval_gap
        value = several.approach(several(state, measures=False)).interval_gap
        assert abs(value - expected) <= 1e-14 * BEAMS.clearance, omega
        signs.add(np.sign(expected))
    assert {-1.0, 1.0} <= signs


def test_a_merge_with_two_contacts_closing_is_where_bisection_finds_it(monkeypatch):
    """Both contacts close in the orbit (each alone, both each period) and 4 contacts per
    orbit become 3 near 257.176 rad/s: the merge located at the root of the interval value
    (0 there to 1e-9 of the clearance; measured 8.6e-16) is where bisection on the contacts
    per orbit (the interval value NaN, as before it was built) finds it, within the
    bisection's tolerance, 1e-11 of the range (measured: the same frequency)."""
    dataset, events = _located(BOTH, 257.1, 257.25)
    assert [label for label, _ in events] == ["contact_merge"]
    index = int(np.flatnonzero(dataset.omega.values == events[0][1])[0])
    period_map = ContactsPeriodMap(BOTH.replace(omega=events[0][1]), 3)
    result = period_map.approach(period_map(dataset.section_state.values[index],
                                            measures=False))
    assert {1, 2} <= set(result.trajectory.mask.tolist())
    assert abs(result.interval_gap) <= 1e-9 * BOTH.clearance
    monkeypatch.setattr(ContactsPeriodMap, "_interval_gap", lambda self, run: np.nan)
    _, bisected = _located(BOTH, 257.1, 257.25)
    assert [label for label, _ in bisected] == ["contact_merge"]
    assert abs(bisected[0][1] - events[0][1]) <= 1e-11 * (257.25 - 257.1)
