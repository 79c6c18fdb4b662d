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
    """max_contacts cuts the episodes; dashpots and simulate's other options are refused in
    one line before any compute."""
    limited = contact_sequence(TOGETHER, 0.03, n_modes=12, max_contacts=3)
    assert limited.sizes["impact"] == 3 and limited.attrs["status"] == "event_limit"
    assert list(limited.impact_contact.values) == [1, 0, 1]
    damped = FORCED.replace(contacts=(Contact(MID, clearance=1e-6), Contact(damping=0.1)))
    with pytest.raises(ParameterError, match=r"^contacts\[1\]\.damping = 0\.1 is not allowed "
                                             "with several contacts"):
        contact_sequence(damped, 0.03)
    with pytest.raises(ParameterError, match="^fields = True is not allowed with 2 contacts"):
        simulate(TOGETHER, 0.03, fields=True)


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


def _dop853_together(contacts, t_max: float, count: int) -> list[tuple[int, float, float]]:
    """The first ``count`` switches of stops on beam 1 by DOP853 on the modal equations.

    ``contacts``: `point_reference.PointContact`s on one beam (their own modes, Green's function
    and residuals, no impactbeams). With closed set S, R_S = -(K^-1 + R_N)^-1 g_S (modal gaps),
    R_N[j, l] = s_j s_l R_N,1(x_j, x_l); the equations gain sum_S w_j R_j; an open contact i
    closes where g_i + R_N[i, S] R_S falls through 0, a closed one opens where its R does.
    Returns (contact, time, onset 1 / release 0) per switch.
    """
    from scipy.integrate import solve_ivp

    beam, n = contacts[0].beam1, len(contacts)
    residual = np.array([[a.side * b.side * beam.residual(a.x1, b.x1) for b in contacts]
                         for a in contacts])
    stiffness = np.array([c.stiffness for c in contacts])
    weights = np.array([c.weights for c in contacts])
    w2, load, m = contacts[0].frequencies**2, contacts[0].load, weights.shape[1]

    def forces(t, y, closed):
        gaps = np.array([contacts[j].gap(t, y) for j in closed])
        k_eff = np.linalg.inv(np.diag(1.0 / stiffness[closed]) + residual[np.ix_(closed, closed)])
        return -k_eff @ gaps

    t, state, closed, done = 0.0, contacts[0].initial_state(), [], []
    while len(done) < count and t < t_max:
        now = list(closed)

        def rhs(s, y, now=now):
            push = weights[now].T @ forces(s, y, now) if now else 0.0
            force = contacts[0].force_amplitude * np.sin(contacts[0].omega * s)
            return np.concatenate([y[m:], -w2 * y[:m] - load * force + push])

        events = []
        for j in range(n):
            if j in now:
                def event(s, y, j=j, now=now):
                    return forces(s, y, now)[now.index(j)]
            else:
                def event(s, y, j=j, now=now):
                    shift = residual[j, now] @ forces(s, y, now) if now else 0.0
                    return contacts[j].gap(s, y) + shift
            event.terminal, event.direction = True, -1.0
            events.append(event)
        solution = solve_ivp(rhs, (t, t_max), state, method="DOP853", rtol=1e-13, atol=1e-24,
                             events=events, first_step=1e-9)
        hits = [(float(times[0]), j) for j, times in enumerate(solution.t_events) if times.size]
        if not hits:
            break
        t, j = min(hits)
        state = solution.y_events[j][0]
        done.append((j, t, 0 if j in closed else 1))
        closed = sorted(set(closed) ^ {j})
    return done


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_a_mid_span_and_a_tip_stop_closed_together_against_dop853():
    """The stops of `TOGETHER` at 4 modes: the first twelve switches (which contact, onset or
    release, when), among them the mid-span stop closing and opening while the tip's is closed,
    against DOP853 on the same modal equations with the matrix static correction
    (point_reference's own modes and residuals; rtol 1e-13): measured 3.4e-16 s, asserted
    1e-12 s (DOP853's own error at rtol 1e-11 with a margin, as the two-sided stop's test in
    tests/test_contacts.py)."""
    from impactbeams.trajectory.active_phases import pack_contacts, run_contacts
    from point_reference import Beam, PointContact

    n = 4
    beam = Beam(STOP.EI1, STOP.rhoA1, STOP.l1, n)
    contacts = [PointContact(beam, None, x, 0.0, 1.0, 1e4, clearance, 1e-3, 400.0)
                for x, clearance in ((MID, 1e-6), (STOP.l1, 2e-6))]
    expected = _dop853_together(contacts, 0.03, 12)
    run = run_contacts(pack_contacts(TOGETHER, n, 0.03, 0.03), 100)
    got = [(int(j), float(t), int((mask >> j) & 1))
           for j, t, mask in zip(run.switched[1:], run.time[1:], run.mask[1:], strict=True)]
    assert [(j, kind) for j, _, kind in got[:12]] == [(j, kind) for j, _, kind in expected]
    assert any(mask == 3 for mask in run.mask[:13])  # both closed in some phase
    np.testing.assert_allclose([t for _, t, _ in got[:12]], [t for _, t, _ in expected],
                               rtol=0, atol=1e-12)


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
