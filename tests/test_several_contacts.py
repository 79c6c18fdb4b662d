"""Several contacts closed at once (issue 33, item 3): the run of the active sets' phases.

`impactbeams.kernels.several_contacts` through `contact_sequence` and `simulate`, against the
finite-element reference with several contacts (tests/fe_spring.py, `fe_several_contacts`:
FE modes per active set, the first root among all gaps and forces), against energy
conservation, and the static correction's convergence in the modes with two contacts closed.
"""

import numpy as np
import pytest

from impactbeams import (
    Contact,
    Params,
    contact_sequence,
    first_contact,
    simulate,
    two_sided_stop,
)
from impactbeams.contact.active_sets import active_set, several_contacts
from impactbeams.params import ParameterError

STOP = Params(counterpart="stop", contact_stiffness=1e4)
MID = 0.5 * STOP.l1  # m
FORCED = STOP.replace(force_amplitude=1e-3, omega=400.0)
# a stop at mid-span and one at the tip, both below: closed together in 4 of 15 phases
TOGETHER = FORCED.replace(contacts=(Contact(MID, clearance=1e-6), Contact(clearance=2e-6)))
KEYS = (("onset", "impact_onset_time"), ("duration", "impact_duration"),
        ("impulse", "impact_impulse"), ("peak", "impact_peak_force"))


def _against_fe(params: Params, t_max: float, n_events: int) -> dict[str, tuple]:
    """Each released episode's deviation from the 40-element FE model and that model's own
    error |f_40 - f_20| (onsets and durations relative to the shortest duration, impulses and
    peaks to their own size), at 20 modes; the contacts' order must agree."""
    from fe_spring import fe_several_contacts

    got = contact_sequence(params, t_max, n_modes=20)
    coarse, fine = (fe_several_contacts(params.each_contact(), t_max, (n, n),
                                        n_events=n_events) for n in (20, 40))
    k = next((i for i, e in enumerate(fine) if np.isnan(e["release"])), len(fine))
    fine, coarse = fine[:k], coarse[:k]
    assert list(got.impact_contact.values[:k]) == [e["contact"] for e in fine] == [
        e["contact"] for e in coarse]
    shortest = min(e["release"] - e["onset"] for e in fine)
    out = {}
    for key, name in KEYS:
        def of(episodes, key=key):
            return np.array([e["release"] - e["onset"] if key == "duration" else e[key]
                             for e in episodes])
        norm = shortest if key in ("onset", "duration") else np.abs(of(fine))
        out[key] = (np.abs(got[name].values[:k] - of(fine)) / norm,
                    np.abs(of(fine) - of(coarse)) / norm)
    return out


def test_a_mid_span_and_a_tip_stop_closed_together_against_the_fe_model():
    """Five contacts (tip, mid, tip, tip, mid), the mid-span stop closing while the tip's is
    closed: onsets, durations, impulses and peaks within the FE model's own error (the largest
    of the episodes' |f_40 - f_20|; one episode's may vanish by chance). Measured: at most
    8.3e-5 (onsets; FE 2.2e-3), 1.2e-4 (durations; 1.4e-3), 1.0e-4 (impulses; 1.4e-3),
    2.5e-4 (peaks; 6.4e-4)."""
    for key, (deviation, fe_error) in _against_fe(TOGETHER, 0.03, 6).items():
        assert deviation.size == 5
        assert deviation.max() <= fe_error.max() + 1e-6, (key, deviation, fe_error)
        assert deviation.max() < 3e-4, key
    ds = simulate(TOGETHER, 0.03, n_modes=20, dt_output=1e-5)
    both = np.all(ds.contact_forces.values > 0.0, axis=1)
    assert np.count_nonzero(both) > 100  # closed together for over 1 ms


@pytest.mark.slow  # 34 s (the FE model's eight contacts at 40 elements)
def test_a_two_sided_stop_over_several_rebounds_against_the_fe_model():
    """A stop below and one above mid-span, 3 um each (forced): eight contacts, both sides,
    each quantity within the FE's own error plus 1e-6 episode by episode. Measured: at most
    3.1e-5 (onsets; FE 4.1e-4), 2.9e-5 (durations), 1.8e-6 (impulses), 3.5e-5 (peaks)."""
    params = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6))
    for key, (deviation, fe_error) in _against_fe(params, 0.03, 8).items():
        assert deviation.size >= 7
        assert np.all(deviation <= fe_error + 1e-6), (key, deviation, fe_error)
        assert deviation.max() < 5e-5, key


@pytest.mark.parametrize(("contacts", "uplift"), [
    ((Contact(MID, clearance=1e-6), Contact(clearance=2e-6)), 20e-6),
    (two_sided_stop(MID, 1e-6, 1e-6), 3.15e-6),
])
def test_energy_is_conserved_to_round_off_over_many_contacts(contacts, uplift):
    """zeta = 0, c = 0, F0 = 0, released from an uplift: E = kinetic + strain + the closed
    contacts' g_S^T K_eff g_S / 2 (the springs and the flexibility the modes miss in series)
    stays within 1e-13 of itself over 0.3 s and dozens of contacts (measured 4.7e-14 with 76
    contacts, 858 samples with both stops closed; 2.2e-14 over 33 on both sides)."""
    params = STOP.replace(force_amplitude=0.0, uplift1=uplift, contacts=contacts)
    ds = simulate(params, 0.3, n_modes=12, dt_output=1e-5)
    energy = ds.energy.values
    assert ds.attrs["status"] == "complete" and ds.sizes["impact"] > 30
    assert set(ds.impact_contact.values) == {0, 1}
    assert np.max(np.abs(energy - energy[0])) < 1e-13 * energy[0]


def test_static_correction_converges_like_n_to_the_minus_5_with_two_contacts_closed():
    """The three lowest frequencies of the phase with both stops closed, against 160 modes:
    with the matrix static correction each doubling of the modes divides the error by more than
    2^5 (measured 9.2e-6, 9.8e-8, 7.4e-10 at 10, 20, 40 modes: 94x and 132x); without it
    (K_eff = K) by about 2^3 (2.4e-3, 3.5e-4, 4.3e-5: 6.8x and 8.2x)."""
    params = STOP.replace(contacts=TOGETHER.contacts)
    reference = several_contacts(params, 160).sets[(0, 1)].frequencies[:3]
    corrected, uncorrected = [], []
    for n in (10, 20, 40):
        contacts = several_contacts(params, n)
        plain = active_set((contacts.frees, contacts.stiffness, contacts.damping,
                            np.zeros_like(contacts.residual)), (0, 1), 0.0)
        for errors, phase in ((corrected, contacts.sets[(0, 1)]), (uncorrected, plain)):
            errors.append(np.max(np.abs(phase.frequencies[:3] / reference - 1.0)))
    assert corrected[0] / corrected[1] > 2**5 and corrected[1] / corrected[2] > 2**5
    assert all(5.0 < a / b < 12.0 for a, b in zip(uncorrected, uncorrected[1:], strict=False))
    assert corrected[2] < 1e-9


def test_contact_sequence_event_limit_and_what_is_refused():
    """max_contacts cuts the episodes (with dashpots too, whose early releases add phases);
    simulate's other options are refused in one line before any compute."""
    limited = contact_sequence(TOGETHER, 0.03, n_modes=12, max_contacts=3)
    assert limited.sizes["impact"] == 3 and limited.attrs["status"] == "event_limit"
    assert list(limited.impact_contact.values) == [1, 0, 1]
    damped = FORCED.replace(contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                                      Contact(clearance=2e-6, damping=0.5)))
    whole = contact_sequence(damped, 0.03, n_modes=12)
    assert whole.attrs["status"] == "complete" and whole.sizes["impact"] > 4
    cut = contact_sequence(damped, 0.03, n_modes=12, max_contacts=4)
    assert cut.attrs["status"] == "event_limit"
    for name in cut.data_vars:
        np.testing.assert_array_equal(cut[name].values, whole[name].values[:4])


@pytest.mark.parametrize("params", [STOP, TOGETHER])
@pytest.mark.parametrize("call", [first_contact, contact_sequence])
def test_a_horizon_beyond_the_runs_range_is_refused_before_any_compute(params, call):
    """first_contact and contact_sequence check each contact's run as simulate does
    (`preflight.check_run`): t_max = 1e9 s would turn the highest mode through ~1e16 rad (the
    kernel would search for hours); refused in one line within 5 s (cold compiles included)."""
    import time

    start = time.perf_counter()
    with pytest.raises(ParameterError, match=r"^t_max = 1000000000\.0 .*t_max <= "):
        call(params, 1e9)
    assert time.perf_counter() - start < 5.0


# --- contacts closed together against DOP853 at equal modes ------------------------------------


def _dop853_together(contacts, t_max: float, count: int, damping=None,
                     ) -> list[tuple[int, float, int]]:
    """The first ``count`` switches of stops on beam 1 by DOP853 on the modal equations.

    ``contacts``: `point_reference.PointContact`s on one beam (their own modes, Green's function
    and residuals, no impactbeams); ``damping``: their dashpots c_j (N s/m, default none).
    With closed set S, R_S = -K_S g_S - C_S g_S' (modal gaps and rates), K_S = (K^-1 +
    R_N)^-1, C_S = K_S K^-1 C K^-1 K_S, R_N[j, l] = s_j s_l R_N,1(x_j, x_l); the equations gain
    sum_S w_j R_j; an open contact i closes where g_i + R_N[i, S] R_S falls through 0, a closed
    one opens where its R does. A contact released with that gap < 0 (a dashpot) closes again
    where its force in S + i rises through 0, unless the gap first rises through 0.
    Returns (contact, time, kind) per switch: kind 1 onset, 0 release, 2 gap opened.
    """
    from scipy.integrate import solve_ivp

    beam, n = contacts[0].beam1, len(contacts)
    residual = np.array([[a.side * b.side * beam.residual(a.x1, b.x1) for b in contacts]
                         for a in contacts])
    stiffness = np.array([c.stiffness for c in contacts])
    dashpots = np.zeros(n) if damping is None else np.asarray(damping, dtype=float)
    weights = np.array([c.weights for c in contacts])
    w2, load, m = contacts[0].frequencies**2, contacts[0].load, weights.shape[1]

    def forces(t, y, closed):
        gaps = np.array([contacts[j].gap(t, y) for j in closed])
        rates = np.array([contacts[j].gap_rate(t, y) for j in closed])
        k_eff = np.linalg.inv(np.diag(1.0 / stiffness[closed]) + residual[np.ix_(closed, closed)])
        c_eff = k_eff @ np.diag(dashpots[closed] / stiffness[closed]**2) @ k_eff
        return -k_eff @ gaps - c_eff @ rates

    def gap(s, y, j, now):
        return contacts[j].gap(s, y) + (residual[j, now] @ forces(s, y, now) if now else 0.0)

    t, state, closed, early, done = 0.0, contacts[0].initial_state(), [], set(), []
    while len(done) < count and t < t_max:
        now = list(closed)

        def rhs(s, y, now=now):
            push = weights[now].T @ forces(s, y, now) if now else 0.0
            force = contacts[0].force_amplitude * np.sin(contacts[0].omega * s)
            return np.concatenate([y[m:], -w2 * y[:m] - load * force + push])

        events, kinds = [], []
        for j in range(n):
            if j in now:
                def event(s, y, j=j, now=now):
                    return forces(s, y, now)[now.index(j)]
                event.direction, kind = -1.0, 0
            elif j in early:
                def event(s, y, j=j, now=now):
                    together = sorted((*now, j))
                    return forces(s, y, together)[together.index(j)]
                opening = lambda s, y, j=j, now=now: gap(s, y, j, now)  # noqa: E731
                opening.terminal, opening.direction = True, 1.0
                events.append(opening)
                kinds.append((j, 2))
                event.direction, kind = 1.0, 1
            else:
                def event(s, y, j=j, now=now):
                    return gap(s, y, j, now)
                event.direction, kind = -1.0, 1
            event.terminal = True
            events.append(event)
            kinds.append((j, kind))
        solution = solve_ivp(rhs, (t, t_max), state, method="DOP853", rtol=1e-13, atol=1e-24,
                             events=events, first_step=1e-9)
        hits = [(float(times[0]), e) for e, times in enumerate(solution.t_events) if times.size]
        if not hits:
            break
        t, e = min(hits)
        state = solution.y_events[e][0]
        j, kind = kinds[e]
        done.append((j, t, kind))
        early.discard(j)
        if kind == 2:
            continue
        closed = sorted(set(closed) ^ {j})
        if kind == 0 and dashpots.any() and gap(t, state, j, closed) < 0.0:
            early.add(j)
    return done


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_a_mid_span_and_a_tip_stop_closed_together_against_dop853():
    """The stops of `TOGETHER` at 4 modes: the first twelve switches (which contact, onset or
    release, when), among them the mid-span stop closing and opening while the tip's is closed,
    against DOP853 on the same modal equations with the matrix static correction
    (point_reference's own modes and residuals; rtol 1e-13): measured 3.4e-16 s, asserted
    1e-12 s (DOP853's own error at rtol 1e-11 with a margin, as the two-sided stop's test in
    tests/test_contacts.py)."""
    from impactbeams.active_phases import pack_contacts, run_contacts
    from point_reference import Beam, PointContact

    n = 4
    beam = Beam(STOP.EI1, STOP.rhoA1, STOP.l1, n)
    contacts = [PointContact(beam, None, x, 0.0, 1.0, 1e4, clearance, 1e-3, 400.0)
                for x, clearance in ((MID, 1e-6), (STOP.l1, 2e-6))]
    expected = _dop853_together(contacts, 0.03, 12)
    run = run_contacts(pack_contacts(TOGETHER, n, 0.03, 0.03), 100)
    got = _switches(run)
    assert [(j, kind) for j, _, kind in got[:12]] == [(j, kind) for j, _, kind in expected]
    assert any(mask == 3 for mask in run.mask[:13])  # both closed in some phase
    np.testing.assert_allclose([t for _, t, _ in got[:12]], [t for _, t, _ in expected],
                               rtol=0, atol=1e-12)


def test_the_active_sets_record_holds_each_sets_phase_c_contiguous():
    """`pack_contacts`' active sets record: its fields in `records.ACTIVE_SETS`' order (each
    set's 2 n event functions, its change of coordinates, the set of each mask: {}, {0}, {1},
    {0, 1} for `TOGETHER`) and every array C-contiguous, so that the kernels compile one
    signature for it whoever packed it."""
    from impactbeams.active_phases import pack_contacts
    from impactbeams.kernels.layout import PHASE_SCALARS, SPRING_DRIVE_ROWS, TABLE_ROWS
    from impactbeams.kernels.records import ACTIVE_SETS

    n_modes = 4
    packed = pack_contacts(TOGETHER, n_modes, 0.03, 0.03)
    sets, functions = len(packed.members), 2 * len(packed.runs)
    shapes = {"tables": (sets, functions, len(TABLE_ROWS), n_modes),
              "forces": (sets, functions, n_modes),
              "scalars": (sets, functions, len(PHASE_SCALARS)),
              "modes": (sets, functions, 2, n_modes),
              "drives": (sets, functions, len(SPRING_DRIVE_ROWS), n_modes),
              "lefts": (sets, 2 * n_modes, n_modes), "rights": (sets, n_modes, 2 * n_modes),
              "set_of_mask": (4,)}
    assert [field.shape for field in packed.active_sets] == [shapes[name]
                                                             for name in ACTIVE_SETS]
    assert all(field.flags.c_contiguous for field in packed.active_sets)
    assert [packed.set_of_mask[sum(1 << f for f in members)]
            for members in packed.members] == list(range(sets))
    assert sorted(packed.members) == [(), (0,), (0, 1), (1,)]


def _switches(run) -> list[tuple[int, float, int]]:
    """A kernel run's switches as `_dop853_together` gives them (contact, time, kind)."""
    n = run.impulses.shape[1]
    return [(int(j) - n, float(t), 2) if j >= n else (int(j), float(t), int((mask >> j) & 1))
            for j, t, mask in zip(run.switched[1:], run.time[1:], run.mask[1:], strict=True)]


def test_simulate_of_several_contacts_gaps_forces_and_episodes():
    """Each closed contact's physical gap is -R_j / k_j (its own stiffness: 1e4 and 3e4 N/m) to
    round-off (measured 4e-22 m of gaps ~1e-6), each open one's > 0; the episodes are
    contact_sequence's bit for bit (one kernel); the tips include the closed forces' shifts."""
    params = FORCED.replace(contacts=(Contact(MID, clearance=1e-6),
                                      Contact(clearance=2e-6, stiffness=3e4)))
    ds = simulate(params, 0.03, n_modes=12, dt_output=1e-5)
    gaps, forces = ds.contact_gaps.values, ds.contact_forces.values
    closed = forces > 0.0
    assert np.all(closed.sum(axis=0) > 100)
    assert np.max(np.abs(gaps + forces / np.array([1e4, 3e4]))[closed]) < 1e-20
    assert np.all(gaps[~closed] > -1e-20)
    # the tip stop's gap is the tip's: clearance + y1(l1)
    np.testing.assert_allclose(gaps[:, 1], 2e-6 + ds.tip_deflection_1.values, rtol=0,
                               atol=1e-18)
    sequence = contact_sequence(params, 0.03, n_modes=12)
    for name in sequence.data_vars:
        np.testing.assert_array_equal(ds[name].values, sequence[name].values)


# --- dashpots: early release and re-onset per contact ------------------------------------------

# forced stops at mid-span and the tip with dashpots (c = 0.5 N s/m each): every release is
# early (R = -k g - c g' reaches 0 with the gap still closed), contact 1 closes again once
# before its gap opens (a re-onset), both are closed together in three phases
DAMPED = FORCED.replace(contacts=(Contact(MID, clearance=1e-6, damping=0.5),
                                  Contact(clearance=2e-6, damping=0.5)))


def _reonsets(switches: list[tuple[int, float, int]]) -> int:
    """How many onsets follow their contact's own release with no opening of its gap between."""
    last, count = {}, 0
    for j, _, kind in switches:
        count += kind == 1 and last.get(j) == 0
        last[j] = kind
    return count


def test_one_dashpot_beside_a_contact_that_never_closes_is_the_single_contacts_run():
    """contacts = [tip stop with c = 0.5 N s/m, a mid-span stop 1 mm away] against simulate of
    that tip stop alone (`kernels.dynamics.run_events`, the single contact's early releases):
    the same contacts, onsets and durations to 1e-12 s (measured 8.9e-17 s), impulses, peaks
    and the gap's rates to 1e-10 relative (measured 1.2e-12 at most, an impact velocity)."""
    from impactbeams.active_phases import pack_contacts, run_contacts

    single = FORCED.replace(contact_damping=0.5, clearance=2e-6)
    alone = simulate(single, 0.03, n_modes=12, dt_output=1e-3)
    params = FORCED.replace(contacts=(Contact(clearance=2e-6, damping=0.5),
                                      Contact(MID, clearance=1e-3)))
    got = contact_sequence(params, 0.03, n_modes=12)
    assert got.sizes["impact"] == alone.sizes["impact"] >= 4
    assert set(got.impact_contact.values) == {0}
    for name in ("impact_onset_time", "impact_duration"):
        np.testing.assert_allclose(got[name].values, alone[name].values, rtol=0, atol=1e-12)
    for name in ("impact_impulse", "impact_peak_force", "impact_velocity",
                 "separation_velocity"):
        np.testing.assert_allclose(got[name].values, alone[name].values, rtol=1e-10)
    run = run_contacts(pack_contacts(params, 12, 0.03, 0.03), 100)
    assert any(kind == 2 for _, _, kind in _switches(run))  # early releases, gaps opened


def test_dashpots_closed_together_against_dop853():
    """`DAMPED` at 8 modes: all 17 switches by 0.03 s (onsets, releases, gaps opening after
    early releases), among them a re-onset while the other contact is closed, against DOP853
    on the same modal equations with R_S = -K_S g_S - C_S g_S' and the same rules
    (`_dop853_together`; rtol 1e-13): measured 2.5e-15 s, asserted 1e-12 s as without
    dashpots."""
    from impactbeams.active_phases import pack_contacts, run_contacts
    from point_reference import Beam, PointContact

    n = 8
    beam = Beam(STOP.EI1, STOP.rhoA1, STOP.l1, n)
    contacts = [PointContact(beam, None, x, 0.0, 1.0, 1e4, clearance, 1e-3, 400.0)
                for x, clearance in ((MID, 1e-6), (STOP.l1, 2e-6))]
    expected = _dop853_together(contacts, 0.03, 40, damping=[0.5, 0.5])
    run = run_contacts(pack_contacts(DAMPED, n, 0.03, 0.03), 100)
    got = _switches(run)
    assert run.status == "complete" and len(got) == len(expected) == 17
    assert [(j, kind) for j, _, kind in got] == [(j, kind) for j, _, kind in expected]
    assert _reonsets(got) == 1 and np.count_nonzero(run.mask == 3) == 3
    np.testing.assert_allclose([t for _, t, _ in got], [t for _, t, _ in expected], rtol=0,
                               atol=1e-12)


def test_dashpots_dissipate_what_the_energy_loses():
    """zeta = 0, F0 = 0, released from an uplift, stiffer stops with dashpots (k = 1e5 N/m,
    c = 0.5 N s/m, 12 modes, 35 switches, a re-onset, five phases with both closed): the
    energy E = kinetic + strain + g_S^T K_S g_S / 2 of the closed set S, plus the dashpots'
    dissipation int g_S'^T C_S g_S' dt (20-point Gauss on pieces of 1 / omega_max), plus what
    the springs give up at each switch (E jumps there by the change of S's term at one state,
    as the single contact's dashpot absorbs the relaxing spring after an early release), stays
    E(0) to 1e-10 (measured 9.2e-14). The dissipation is 23 % of E(0), the switches' share
    0.3 % (so both are checked)."""
    from impactbeams.active_phases import (
        _modal_gap_rates,
        contact_quantities,
        pack_contacts,
        run_contacts,
        sample,
    )
    from impactbeams.kernels.layout import TABLE_ROWS

    params = STOP.replace(force_amplitude=0.0, uplift1=2e-5, contacts=(
        Contact(MID, clearance=1e-6, damping=0.5, stiffness=1e5),
        Contact(clearance=2e-6, damping=0.5, stiffness=1e5)))
    packed = pack_contacts(params, 12, 0.03, 0.03)
    run = run_contacts(packed, 200)
    assert run.status == "complete" and _reonsets(_switches(run)) == 1
    omega = packed.runs[0].tables[0, TABLE_ROWS.index("frequency")]

    def energy(k, mask):
        t, q, v = run.time[k:k + 1], run.q[k:k + 1], run.v[k:k + 1]
        beams = 0.5 * np.sum(v**2) + 0.5 * np.sum(omega**2 * q**2)
        return beams + contact_quantities(packed, t, q, v, np.array([mask]))["contact_energy"][0]

    nodes, weights = np.polynomial.legendre.leggauss(20)
    ends = np.append(run.time[1:], run.t_end)
    e0, dissipated, given_up, balance = energy(0, 0), 0.0, 0.0, []
    for k in range(1, run.time.size):
        active = packed.members[packed.set_of_mask[run.mask[k - 1]]]
        if active:
            pieces = int(np.ceil((ends[k - 1] - run.time[k - 1]) * omega.max()))
            edges = np.linspace(run.time[k - 1], ends[k - 1], pieces + 1)
            middle, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
            times = (middle[:, None] + half[:, None] * nodes).ravel()
            rates = _modal_gap_rates(packed, times, sample(packed, run, times)[1])[:, active]
            power = np.einsum("ki,ij,kj->k", rates, packed.contacts.sets[active].effective_damping,
                              rates).reshape(pieces, -1)
            dissipated += np.sum(half[:, None] * weights * power)
        before = energy(k, run.mask[k - 1])
        balance.append(before + dissipated + given_up)
        given_up += before - energy(k, run.mask[k])
    assert np.max(np.abs(np.array(balance) - e0)) < 1e-10 * e0
    assert dissipated > 0.1 * e0 and given_up > 1e-3 * e0


def test_simulate_of_dashpots_forces_reach_the_kernels_peaks():
    """simulate's contact forces with dashpots, R_S = -K_S g_S - C_S g_S' from the sampled
    states, against each episode's certified peak from the kernel's event functions: the
    samples (every 1 us) stay below it and come within 1e-5 of it (measured 5.8e-6; without
    the dashpots' term the forces move by up to 32 % of the largest), and >= 0 while closed."""
    ds = simulate(DAMPED, 0.03, n_modes=12, dt_output=1e-6)
    forces, t = ds.contact_forces.values, ds.time.values
    assert ds.sizes["impact"] == 6
    for i in range(ds.sizes["impact"]):
        j, onset = int(ds.impact_contact[i]), float(ds.impact_onset_time[i])
        closed = forces[(t >= onset) & (t < onset + float(ds.impact_duration[i])), j]
        peak = float(ds.impact_peak_force[i])
        assert peak * (1.0 - 1e-5) < closed.max() <= peak * (1.0 + 1e-12)
        assert closed.min() >= 0.0
