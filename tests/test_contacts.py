"""Several contacts and two-sided stops (issue 33, item 3): the API and the first contact.

The API (`impactbeams.Contact`, ``Params(contacts=...)``, ``[[params.contacts]]``): one contact
given through it is today's run bit for bit; what it cannot do yet is refused in one line.
The first contact among several (`impactbeams.first_contact`) and the contacts of a two-sided
stop (`impactbeams.contact_sequence`) against the finite-element reference extended to several
contacts at any node (tests/fe_spring.py, `fe_several_contacts`: one FE eigen-decomposition per
active set, the first root among all gaps and forces).
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
from impactbeams.params import ParameterError

STOP = Params(counterpart="stop")
MID = 0.5 * STOP.l1  # m
# a forced stop of k = 1e4 N/m (the FE tests' resolution: 20 modes, 20 and 40 elements)
FORCED = STOP.replace(force_amplitude=1e-3, omega=400.0, contact_stiffness=1e4)


# --- the API ----------------------------------------------------------------------------------


def test_one_contact_through_the_api_is_the_flat_keys_bit_for_bit():
    """Contact(0.05, side="above", clearance=3e-6, stiffness=1e4) is contact_position1,
    contact_side, clearance and contact_stiffness: the same Params and the same run's bits."""
    flat = FORCED.replace(contact_position1=MID, contact_side="above", clearance=3e-6)
    given = Params(counterpart="stop", force_amplitude=1e-3, omega=400.0,
                   contacts=(Contact(MID, side="above", clearance=3e-6, stiffness=1e4),))
    assert given == flat and given.contacts == ()
    a, b = (simulate(p, 0.03, n_modes=8, dt_output=1e-3) for p in (flat, given))
    for name in ("impact_onset_time", "impact_duration", "impact_impulse", "gap"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    assert a.sizes["impact"] > 0


def test_contacts_from_a_toml_file(tmp_path):
    """An array of tables [[params.contacts]]: each a Contact, the run's keys their defaults."""
    path = tmp_path / "p.toml"
    path.write_text('[params]\ncounterpart = "stop"\nclearance = 4e-6\n'
                    '[[params.contacts]]\nposition1 = 0.05\n'
                    '[[params.contacts]]\nposition1 = 0.05\nside = "above"\nclearance = 2e-6\n')
    params = Params.from_toml(path)
    assert params.contacts == two_sided_stop(MID, clearance_above=2e-6)
    below, above = params.each_contact()
    assert (below.contact_position1, below.contact_side, below.clearance) == (MID, "below", 4e-6)
    assert (above.contact_position1, above.contact_side, above.clearance) == (MID, "above", 2e-6)
    assert params.replace(omega=60.0).each_contact()[1].omega == 60.0


@pytest.mark.parametrize(("values", "message"), [
    ({"contact_position1": MID, "contacts": (Contact(), Contact(side="above"))},
     "contact_position1 = 0.05 in Params() is not allowed with contacts"),
    ({"contact_side": "above", "contacts": (Contact(),)},
     "contact_side = 'above' in Params() is not allowed with contacts"),
    ({"contacts": (Contact(0.2), Contact())},
     "contacts[0]: contact_position1 = 0.2 is not allowed"),
    ({"contacts": (Contact(position2=0.05), Contact())},
     "contacts[0]: contact_position2 = 0.05 is not allowed: counterpart = 'stop' has no beam 2"),
    ({"contacts": (Contact(), Contact())}, "contacts[1] = Contact("),
    ({"contacts": (1, 2)}, "contacts[0] = 1 is not allowed: a contact is an impactbeams.Contact"),
    ({"contacts": ({"position": 0.05},)}, "contacts[0] = {'position': 0.05} is not allowed"),
    ({"contacts": Contact()}, "contacts = Contact("),
    ({"contact_law": "tied", "contacts": two_sided_stop()},
     "contacts: 2 contacts are not allowed with contact_law = 'tied'"),
])
def test_contacts_refused_in_one_line(values, message):
    with pytest.raises(ParameterError) as error:
        Params(counterpart="stop", **values)
    assert message in str(error.value) and "\n" not in str(error.value)


_UNUSED = ("is not allowed: each of the 2 contacts gives its own {field}, so it would be used "
           "by none (it is the default of a contact that leaves its {field} out): leave {key} "
           "out, or {field} out of a contact")


@pytest.mark.parametrize(("key", "field", "value", "contacts"), [
    ("clearance", "clearance", 2e-6, two_sided_stop(MID, 3e-6, 4e-6)),
    ("contact_stiffness", "stiffness", 1e5, two_sided_stop(MID, stiffness=1e4)),
    ("contact_damping", "damping", 0.1, (Contact(MID, damping=0.0), Contact(damping=0.2))),
])
def test_a_flat_law_key_every_contact_gives_its_own_of_is_refused(tmp_path, capsys, key, field,
                                                                  value, contacts):
    """Given beside contacts that all give their own, clearance, contact_stiffness or
    contact_damping would be used by none: refused in one line from Params(), a TOML file,
    replace(), a sweep file and the command line (before, it went unused without a word)."""
    from impactbeams.cli import main
    from impactbeams.sweep import sweep_from_mapping

    rule = _UNUSED.format(field=field, key=key)
    tables = [{name: getattr(c, name) for name in ("position1", "side", field)
               if getattr(c, name) is not None} for c in contacts]
    calls = {f"{key} = {value!r} in Params() ": lambda: Params(
                 counterpart="stop", contacts=contacts, **{key: value}),
             f"{key} = {value!r} in Params.replace() ": lambda: STOP.replace(
                 contacts=contacts).replace(**{key: value}),
             f"{key} = {value!r} in [params] of sweep ": lambda: sweep_from_mapping({
                 "params": {"counterpart": "stop", key: value, "contacts": tables},
                 "axes": {"omega": {"min": 10.0, "max": 20.0, "num": 2}}})}
    for start, call in calls.items():
        with pytest.raises(ParameterError) as error:
            call()
        assert str(error.value) == start + rule
    path = tmp_path / "p.toml"
    lines = "".join("[[params.contacts]]\n" + "".join(f"{name} = {item!r}\n".replace("'", '"')
                                                       for name, item in table.items())
                    for table in tables)
    path.write_text(f'[params]\ncounterpart = "stop"\n{lines}')
    assert Params.from_toml(path).contacts == contacts
    flag = "--" + key.replace("_", "-")
    assert main(["modes", "--params", str(path), flag, str(value)]) == 2
    assert capsys.readouterr().err == (
        f"impactbeams: error: {key} = {value!r} in the command line (beside the contacts of "
        f"{path}) {rule}\n")
    path.write_text(f'[params]\ncounterpart = "stop"\n{key} = {value!r}\n{lines}')
    with pytest.raises(ParameterError, match=rf"^{key} = {value!r} in \[params\] of {path} "):
        Params.from_toml(path)


def test_a_flat_law_key_is_the_default_of_the_contacts_that_leave_theirs_out():
    """Where one contact leaves its clearance (stiffness, damping) out, the flat key is its
    value there, as documented, and taken; one contact giving its own refuses it too."""
    params = Params(counterpart="stop", clearance=2e-6, contact_stiffness=1e5,
                    contacts=two_sided_stop(MID, clearance_above=3e-6))
    below, above = params.each_contact()
    assert (below.clearance, above.clearance) == (2e-6, 3e-6)
    assert below.contact_stiffness == above.contact_stiffness == 1e5
    assert params.replace(clearance=1e-6).each_contact()[0].clearance == 1e-6
    with pytest.raises(ParameterError, match=r"^clearance = 2e-06 in Params\(\) is not allowed: "
                                             "the contact gives its own clearance"):
        Params(counterpart="stop", clearance=2e-6, contacts=(Contact(MID, clearance=3e-6),))
    # a copy given new contacts that give their own leaves the old flat value out
    again = params.replace(contacts=two_sided_stop(MID, 1e-6, 1e-6))
    assert [p.clearance for p in again.each_contact()] == [1e-6, 1e-6]


@pytest.mark.parametrize(("field", "value"), [("side", "left"), ("clearance", 0.0),
                                              ("stiffness", -1.0), ("damping", np.nan),
                                              ("position1", "tip")])
def test_a_contact_checks_its_fields_on_creation(field, value):
    with pytest.raises(ParameterError, match=rf"^Contact\.{field} = .* is not allowed"):
        Contact(**{field: value})


def test_what_several_contacts_cannot_do_yet_is_refused_before_any_compute(tmp_path):
    """Sweeps, periodic orbits (and so continuation) and the free phase say so."""
    from impactbeams import PeriodMap
    from impactbeams.contact import build_free_phase
    from impactbeams.sweep import sweep_from_mapping

    params = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6))
    calls = [lambda: PeriodMap(params, 8), lambda: build_free_phase(params, 8)]
    for call in calls:
        with pytest.raises(ParameterError, match="contacts: 2 contacts are not allowed in"):
            call()
    with pytest.raises(ParameterError, match=r"contacts is not sweepable"):
        sweep_from_mapping({"axes": {"contacts": {"min": 1.0, "max": 2.0, "num": 2}},
                            "t_max": 0.01})
    several = {"counterpart": "stop", "contacts": [{"side": "below"}, {"side": "above"}]}
    omega = {"omega": {"min": 10.0, "max": 20.0, "num": 2}}
    with pytest.raises(ParameterError, match=r"clearance is not sweepable with contacts"):
        sweep_from_mapping({"params": several, "t_max": 0.01, "axes": {
            **omega, "clearance": {"min": 1e-6, "max": 2e-6, "num": 2}}})


# --- the first contact among several, against the FE reference --------------------------------


def _fe_first(params: Params, t_max: float, n_elements: int) -> dict:
    from fe_spring import fe_several_contacts

    return fe_several_contacts(params.each_contact(), t_max, (n_elements, n_elements),
                               n_events=1)[0]


def test_the_several_contact_fe_reference_with_one_contact_is_the_one_contact_fe():
    """`fe_several_contacts` of one contact reproduces `fe_spring_contacts` (the same FE model,
    its own event loop): the first contacts to 1e-12 relative (measured to a few ulps)."""
    from fe_spring import fe_several_contacts, fe_spring_contacts

    params = FORCED.replace(clearance=3e-6, contact_position1=MID, contact_side="above")
    one = fe_spring_contacts(params, 1e4, t_max=0.03, n_elements=(20, 20), n_contacts=2)
    several = fe_several_contacts((params,), 0.03, (20, 20), n_events=2)
    for i in range(2):
        assert several[i]["onset"] == pytest.approx(one["onset"][i], rel=1e-12)
        assert several[i]["release"] == pytest.approx(one["release"][i], rel=1e-12)
        assert several[i]["impulse"] == pytest.approx(one["impulse"][i], rel=1e-12)
        assert several[i]["peak"] == pytest.approx(one["peak"][i], rel=1e-12)


@pytest.mark.parametrize(("below", "above", "hit"), [(3e-6, 3e-6, 0), (20e-6, 1e-6, 1)])
def test_first_contact_of_a_two_sided_stop_against_the_fe_model(below, above, hit):
    """A stop below and a stop above mid-span (k = 1e4 N/m, forced): which side closes first and
    its whole first contact (onset, duration, impulse, peak force) at 20 modes, against the FE
    model with both gaps at the mid-span node (20 and 40 elements), within the FE's own error
    |f_40 - f_20| plus 1e-6 for the modal truncation (as tests/test_contact_point.py's single
    stop at mid-span), onsets relative to the duration. Measured: at most 6.3e-6 (the release;
    the FE's estimate 6e-5), onsets 2e-9 and 8.8e-8."""
    params = FORCED.replace(contacts=two_sided_stop(MID, below, above))
    got = first_contact(params, 0.03, n_modes=20)
    coarse, fine = (_fe_first(params, 0.03, n) for n in (20, 40))
    assert got.contact == coarse["contact"] == fine["contact"] == hit
    assert got.episode_certain
    duration = fine["release"] - fine["onset"]
    for value, key, norm in ((got.onset, "onset", duration), (got.release, "release", duration),
                             (got.impulse, "impulse", fine["impulse"]),
                             (got.peak_force, "peak", fine["peak"])):
        deviation = abs(value - fine[key]) / norm
        fe_error = abs(fine[key] - coarse[key]) / norm
        assert deviation <= fe_error + 1e-6, (key, deviation, fe_error)
        assert deviation < 5e-5, key


def test_first_contact_of_stops_at_mid_span_and_at_the_tip_against_the_fe_model():
    """A stop at mid-span and one at the tip, both below (k = 1e4 N/m): which closes first and
    when, against the FE model with both gaps (as above; measured 2.4e-7 and 9e-8 of the FE's
    first contact duration, its own error 8.7e-7 and 6.4e-7). Its contact phase is not reported
    (NaN): whether the other gap closes during it is the several-contact dynamics."""
    for mid_clearance, tip_clearance, hit in ((0.5e-6, 6e-6, 0), (2e-6, 3e-6, 1)):
        params = FORCED.replace(contacts=(Contact(MID, clearance=mid_clearance),
                                          Contact(clearance=tip_clearance)))
        got = first_contact(params, 0.03, n_modes=20)
        coarse, fine = (_fe_first(params, 0.03, n) for n in (20, 40))
        assert got.contact == coarse["contact"] == fine["contact"] == hit
        assert not got.episode_certain and np.isnan(got.impulse)
        duration = fine["release"] - fine["onset"]  # onsets relative to it, as above
        deviation = abs(got.onset - fine["onset"]) / duration
        assert deviation <= abs(fine["onset"] - coarse["onset"]) / duration + 1e-6, deviation
        assert deviation < 5e-6


@pytest.mark.parametrize(("dashpot", "zeta"), [(0.5, 0.0), (5.0, 0.02)])
def test_first_contact_of_a_damped_two_sided_stop_is_certain(dashpot, zeta):
    """A two-sided stop with dashpots (N s/m) and modal damping: while one stop is closed the
    other's gap exceeds the sum of the clearances, so the first contact's episode is certain and
    reported. Against the several contacts' own dynamics (`contact_sequence`: both stops, the
    active sets' kernel): the same first contact to 1e-12 (measured 2.2e-14: the two kernels sum
    their closed forms in another order), and the next contact starts after its release."""
    params = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6, damping=dashpot),
                            damping_ratio=zeta)
    got = first_contact(params, 0.03, n_modes=8)
    sequence = contact_sequence(params, 0.03, n_modes=8)
    assert got.episode_certain and got.contact == int(sequence.impact_contact[0]) == 0
    for value, name in ((got.onset, "onset_time"), (got.duration, "duration"),
                        (got.impulse, "impulse"), (got.peak_force, "peak_force")):
        assert value == pytest.approx(float(sequence[f"impact_{name}"][0]), rel=1e-12), name
    assert got.release < float(sequence.impact_onset_time[1])


def test_first_contact_of_one_contact_is_simulates_first_contact_bit_for_bit():
    params = FORCED.replace(clearance=3e-6, contact_position1=MID)
    got = first_contact(params, 0.03, n_modes=12)
    ds = simulate(params, 0.03, n_modes=12, dt_output=0.01)
    assert (got.contact, got.onset, got.duration) == (
        0, float(ds.impact_onset_time[0]), float(ds.impact_duration[0]))
    assert got.episode_certain


def test_the_contacts_of_one_contact_are_simulates_bit_for_bit():
    """contact_sequence restarts the event kernel at each release from the recorded free state,
    where simulate's own windows resume: the same onsets, durations and peaks, bit for bit (the
XX
    their closed forms evaluated one contact at a time, simulate's vectorised over all, sum in
    another order)."""
    params = FORCED.replace(clearance=3e-6, contact_position1=MID)
    got = contact_sequence(params, 0.03, n_modes=12)
    ds = simulate(params, 0.03, n_modes=12, dt_output=0.01)
    assert got.sizes["impact"] == ds.sizes["impact"] == 5 and got.attrs["status"] == "complete"
    for name in ("impact_onset_time", "impact_duration", "impact_peak_force"):
        np.testing.assert_array_equal(got[name].values, ds[name].values)
    for name in ("impact_impulse", "impact_velocity", "separation_velocity"):
        np.testing.assert_allclose(got[name].values, ds[name].values, rtol=1e-14, atol=0)
    assert np.all(got.impact_contact.values == 0)
    limited = contact_sequence(params, 0.03, n_modes=12, max_contacts=2)
    assert limited.sizes["impact"] == 2 and limited.attrs["status"] == "event_limit"


def test_the_contacts_of_a_two_sided_stop_against_the_fe_model():
    """A stop below and one above mid-span, 3 um each (k = 1e4 N/m, forced): the first three
    contacts (twice below, then above) at 20 modes against the FE model with both gaps at the
    mid-span node, as the first contact above (the FE's own error |f_40 - f_20| plus 1e-6,
    onsets and durations relative to the shortest duration). Measured: at most 2e-5 (the third
    peak; the FE's estimate 3e-4), onsets 2.4e-6, durations 6.3e-6."""
    from fe_spring import fe_several_contacts

    params = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6))
    got = contact_sequence(params, 0.03, n_modes=20)
    coarse, fine = (fe_several_contacts(params.each_contact(), 0.03, (n, n), n_events=3)
                    for n in (20, 40))
    assert list(got.impact_contact.values[:3]) == [e["contact"] for e in fine] == [0, 0, 1]
    assert [e["contact"] for e in coarse] == [0, 0, 1]
    shortest = min(e["release"] - e["onset"] for e in fine)
    for key, name in (("onset", "impact_onset_time"), ("duration", "impact_duration"),
                      ("impulse", "impact_impulse"), ("peak", "impact_peak_force")):
        def of(episodes, key=key):
            return np.array([e["release"] - e["onset"] if key == "duration" else e[key]
                             for e in episodes])
        norm = shortest if key in ("onset", "duration") else np.abs(of(fine))
        deviation = np.abs(got[name].values[:3] - of(fine)) / norm
        fe_error = np.abs(of(fine) - of(coarse)) / norm
        assert np.all(deviation <= fe_error + 1e-6), (key, deviation, fe_error)
        assert deviation.max() < 5e-5, key


def test_the_sequence_of_one_contact_with_a_dashpot_is_simulates():
    """After a dashpot's early release the free flight is two segments (until the gap opens,
    then on): contact_sequence follows them to every contact of simulate's run (5 by 0.03 s;
    it stopped after the first), onsets, durations, peaks and rates bit for bit, impulses to
    1e-13 (measured 1 ulp: the run is cut into episodes)."""
    single = FORCED.replace(contact_damping=0.5, clearance=2e-6)
    alone = simulate(single, 0.03, n_modes=12, dt_output=1e-3)
    sequence = contact_sequence(single, 0.03, n_modes=12)
    assert sequence.sizes["impact"] == alone.sizes["impact"] == 5
    for name in ("impact_onset_time", "impact_duration", "impact_peak_force", "impact_velocity",
                 "separation_velocity"):
        np.testing.assert_array_equal(sequence[name].values, alone[name].values)
    np.testing.assert_allclose(sequence.impact_impulse.values, alone.impact_impulse.values,
                               rtol=1e-13)


def test_the_contacts_of_a_two_sided_stop_with_dashpots_never_overlap():
    """With dashpots (tests/test_several_contacts.py checks them against DOP853) a two-sided
    stop's sides close one at a time: each contact is released before the next one's onset
    (9 contacts on both sides by 0.03 s, some rebounding on one side)."""
    damped = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 3e-6, damping=0.1))
    sequence = contact_sequence(damped, 0.03, n_modes=12)
    onsets, durations = sequence.impact_onset_time.values, sequence.impact_duration.values
    assert sequence.attrs["status"] == "complete" and onsets.size >= 4
    assert set(sequence.impact_contact.values) == {0, 1}
    assert np.all(onsets[:-1] + durations[:-1] < onsets[1:])


# --- first-impact maps of several contacts ----------------------------------------------------

_OMEGA = {"omega": {"min": 100.0, "max": 400.0, "num": 4},
          "force_amplitude": {"min": 1e-3, "max": 3e-3, "num": 2}}


def _map(params: dict, n_modes: int = 8, axes: dict = _OMEGA, first: bool = False):
    from impactbeams.sweep import run_sweep, sweep_from_mapping

    ds = run_sweep(sweep_from_mapping({"params": {"counterpart": "stop", **params},
                                       "axes": axes, "t_max": 0.05, "n_modes": n_modes}),
                   parallel=False)
    return (ds.first_impact_time.values, ds.first_contact.values) if first else (
        ds.first_impact_time.values)


def test_a_first_impact_map_of_several_contacts_is_the_earliest_of_each_contacts_map():
    """Cell by cell the earliest of each contact's own map (NaN where none closes), bit for
    bit, and ``first_contact`` says which (-1 where none); one contact through
    [[params.contacts]] is the flat keys' map bit for bit."""
    mid = {"position1": MID, "clearance": 0.5e-6}
    tip = {"clearance": 6e-6}
    several, first = _map({"contacts": [mid, tip]}, first=True)
    alone = [_map({"contact_position1": MID, "clearance": 0.5e-6}), _map({"clearance": 6e-6})]
    np.testing.assert_array_equal(several, np.fmin(*alone))
    np.testing.assert_array_equal(first, np.where(alone[0] <= alone[1], 0, 1))
    assert 0 < first.sum() < first.size  # both close first somewhere
    _, none = _map({"contacts": [{"clearance": 1e-2}, {"side": "above", "clearance": 1e-2}]},
                   first=True)
    assert np.all(none == -1)
    np.testing.assert_array_equal(_map({"contacts": [{**mid, "side": "above"}]}),
                                  _map({"contact_position1": MID, "clearance": 0.5e-6,
                                        "contact_side": "above"}))


def test_a_first_impact_map_of_stops_at_mid_span_and_tip_against_the_fe_model():
    """Two cells of a map of a stop at mid-span and one at the tip (20 modes, the free phase
    alone) against the FE model's first contact among both gaps (20 and 40 elements), as
    `first_contact` above: within the FE's own error plus 1e-6 of its contact's duration."""
    from fe_spring import fe_several_contacts

    axes = {"omega": {"min": 200.0, "max": 400.0, "num": 2}}
    times = _map({"force_amplitude": 1e-3, "contacts": [{"position1": MID, "clearance": 0.5e-6},
                                                        {"clearance": 6e-6}]}, 20, axes)
    for omega, time in zip((200.0, 400.0), times, strict=True):
        params = FORCED.replace(omega=omega, contacts=(Contact(MID, clearance=0.5e-6),
                                                       Contact(clearance=6e-6)))
        # the first episode's release comes after the tip's (closed meanwhile): 3 events
        coarse, fine = (fe_several_contacts(params.each_contact(), 0.05, (n, n), n_events=3)[0]
                        for n in (20, 40))
        duration = fine["release"] - fine["onset"]
        deviation = abs(time - fine["onset"]) / duration
        assert deviation <= abs(fine["onset"] - coarse["onset"]) / duration + 1e-6, deviation


# --- a two-sided stop against DOP853 at equal modes -------------------------------------------


def _dop853_two_sided(sides, t_max: float, count: int) -> list[tuple[int, float, float, float]]:
    """The first ``count`` contacts of a two-sided stop by DOP853 on the modal equations.

    ``sides``: the two contacts as `point_reference.PointContact` (one beam, one point, s = +1
    and -1). Free phase: integrated to the first gap of either falling through 0; contact: that
    contact's equations to its gap rising through 0 (R = -k_e g). Returns (contact, onset,
    release, peak force) per contact.
    """
    from scipy.integrate import solve_ivp

    t, state, done = 0.0, sides[0].initial_state(), []
    while len(done) < count and t < t_max:
        events = []
        for side in sides:
            def closing(s, y, side=side):
                return side.gap(s, y)
            closing.terminal, closing.direction = True, -1.0
            events.append(closing)
        free = solve_ivp(sides[0]._rhs(False), (t, t_max), state, method="DOP853", rtol=1e-13,
                         atol=1e-24, events=events, dense_output=True, first_step=1e-9)
        hits = [(float(times[0]), j) for j, times in enumerate(free.t_events) if times.size]
        if not hits:
            break
        onset, j = min(hits)
        contact = sides[j]

        def opening(s, y, contact=contact):
            return contact.gap(s, y)
        opening.terminal, opening.direction = True, 1.0
        closed = solve_ivp(contact._rhs(True), (onset, t_max), free.sol(onset), method="DOP853",
                           rtol=1e-13, atol=1e-24, events=opening, dense_output=True,
                           first_step=1e-9)
        if not closed.t_events[0].size:
            break
        release = float(closed.t_events[0][0])
        done.append((j, onset, release, contact._peak(closed.sol, onset, release)))
        t, state = release, closed.sol(release)
    return done


@pytest.mark.filterwarnings("ignore:n_modes = 4 does not resolve:RuntimeWarning")
def test_the_contacts_of_two_sided_stop_against_dop853():
    """A stop 3 um below and one 2 um above mid-span (k = 1e4 N/m), 4 modes, forced: the first
    six contacts (which side, onset, release, peak force) against DOP853 on the same modal
    equations, each side's force at that point (point_reference.PointContact, rtol 1e-13), as
    tests/test_contact_point.py's one-sided stop: measured 2.3e-16 s and 7e-14 (below, below,
    above, above, above, below), asserted 1e-12 s and 1e-9 (DOP853's own error at rtol 1e-11
    with a margin of 100)."""
    from point_reference import Beam, PointContact

    n = 4
    params = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 2e-6))
    beam1 = Beam(params.EI1, params.rhoA1, params.l1, n)
    sides = [PointContact(beam1, None, MID, 0.0, s, 1e4, clearance, 1e-3, 400.0)
             for s, clearance in ((1.0, 3e-6), (-1.0, 2e-6))]
    expected = _dop853_two_sided(sides, 0.03, 6)
    assert [j for j, *_ in expected] == [0, 0, 1, 1, 1, 0]
    _assert_like(contact_sequence(params, 0.03, n_modes=n), expected)


def _assert_like(got, expected) -> None:
    """The contacts of `contact_sequence` ``got`` are those of `_dop853_two_sided`: which
    side, onsets and releases to 1e-12 s, peak forces to 1e-9."""
    count = len(expected)
    assert list(got.impact_contact.values[:count]) == [j for j, *_ in expected]
    onset = got.impact_onset_time.values[:count]
    np.testing.assert_allclose(onset, [e[1] for e in expected], rtol=0, atol=1e-12)
    np.testing.assert_allclose(onset + got.impact_duration.values[:count],
                               [e[2] for e in expected], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.impact_peak_force.values[:count], [e[3] for e in expected],
                               rtol=1e-9)


@pytest.mark.filterwarnings("ignore:n_modes = 3 does not resolve:RuntimeWarning")
def test_two_beams_with_backlash_at_offset_points_against_dop853():
    """Beam 1 at x1 = 0.07 m between two faces of beam 2 at x2 = 0.05 m, 6 um below and 1 um
    above (k = 1e4 N/m), 3 modes per beam, forced: the first six contacts (three below, then
    three above) against DOP853 on both beams' modal equations, as above: measured 2.8e-16 s
    and 1.7e-13, asserted 1e-12 s and 1e-9."""
    from point_reference import Beam, PointContact

    n = 3
    params = Params(force_amplitude=1e-3, omega=300.0, contact_stiffness=1e4,
                    contacts=(Contact(0.07, 0.05, "below", 6e-6),
                              Contact(0.07, 0.05, "above", 1e-6)))
    beams = [Beam(getattr(params, f"EI{i}"), getattr(params, f"rhoA{i}"),
                  getattr(params, f"l{i}"), n) for i in (1, 2)]
    faces = [PointContact(*beams, 0.07, 0.05, s, 1e4, clearance, 1e-3, 300.0)
             for s, clearance in ((1.0, 6e-6), (-1.0, 1e-6))]
    expected = _dop853_two_sided(faces, 0.04, 6)
    assert [j for j, *_ in expected] == [0, 0, 0, 1, 1, 1]
    _assert_like(contact_sequence(params, 0.04, n_modes=n), expected)


# --- sweep axes on a contact's field ----------------------------------------------------------

_ALONG_CONTACTS = {"omega": {"min": 100.0, "max": 400.0, "num": 3},
                   "contacts.1.clearance": {"min": 4e-6, "max": 8e-6, "num": 2},
                   "contacts.0.clearance": {"min": 0.3e-6, "max": 3e-6, "num": 4}}
_FORCED_STOP = {"counterpart": "stop", "force_amplitude": 1e-3, "contact_stiffness": 1e4}


def _contact_sweep(axes: dict = _ALONG_CONTACTS, **params):
    from impactbeams.sweep import sweep_from_mapping

    return sweep_from_mapping({"params": {**_FORCED_STOP, "contacts": [
        {"position1": MID}, {}], **params}, "axes": axes, "t_max": 0.05, "n_modes": 8})


def test_a_map_over_contacts_clearances_is_each_cells_first_contact(tmp_path):
    """A map over omega and each contact's clearance (contact 0's last: by columns in its own
    map) is, cell by cell, `first_contact` of that cell's contacts: which contact the same,
    the onset to 1e-15 s (the map's column kernel and the event kernel locate the same root by
    different paths: a few ulps of a 5 ms onset, 8.7e-19 s each). Written to a file in chunks of
    3 or 4 cells (columns cut, contact 1's run shared along contact 0's axis) bit for bit."""
    from impactbeams.sweep import run_sweep

    sweep = _contact_sweep()
    ds = run_sweep(sweep, parallel=False)
    assert ds.first_impact_time.dims == ("omega", "contacts.1.clearance", "contacts.0.clearance")
    assert ds["contacts.0.clearance"].attrs["units"] == "m"
    assert ds["contacts.0.clearance"].attrs["long_name"].endswith(" of contacts[0]")
    # the contacts as given: a swept field's values are its coordinate's, not the first one
    assert ds.attrs["contacts"].startswith("Contact(position1=0.05, position2=None, "
                                           "side='below', clearance=None")
    assert "clearance" not in ds.attrs  # every contact's own: the flat one is used by none
    assert ds.attrs["contact_stiffness"] == 1e4  # the contacts' stiffness
    first = ds.first_contact.values
    assert 0 < first.sum() < first.size  # both contacts close first somewhere
    for (i, j, k), time in np.ndenumerate(ds.first_impact_time.values):
        params = Params(**_FORCED_STOP, omega=float(ds.omega[i]), contacts=(
            Contact(MID, clearance=float(ds["contacts.0.clearance"][k])),
            Contact(clearance=float(ds["contacts.1.clearance"][j]))))
        expected = first_contact(params, 0.05, n_modes=8)
        assert expected.contact == first[i, j, k]
        assert abs(expected.onset - time) <= 1e-15, (i, j, k)
    for cells in (3, 4):
        path = tmp_path / f"{cells}.nc"
        written = run_sweep(sweep, path, parallel=False, chunk_cells=cells)
        for name in ("first_impact_time", "first_contact"):
            np.testing.assert_array_equal(written[name].values, ds[name].values)


def test_a_map_over_a_contacts_point_is_each_cells_first_contact():
    """A stop 1 um below a point swept along beam 1 (a geometry axis: its gap weights) and one
    6 um below the tip: cell by cell `first_contact` of that cell's contacts, which contact the
    same (each closes first somewhere), onsets to 1e-15 s (measured 2.9e-17 s)."""
    from impactbeams.sweep import run_sweep

    axes = {"omega": {"min": 100.0, "max": 400.0, "num": 3},
            "contacts.0.position1": {"min": 0.02, "max": 0.1, "num": 5}}
    ds = run_sweep(_contact_sweep(axes, contacts=[{"clearance": 1e-6}, {"clearance": 6e-6}]),
                   parallel=False)
    first = ds.first_contact.values
    assert 0 < first.sum() < first.size
    for (i, k), time in np.ndenumerate(ds.first_impact_time.values):
        params = Params(**_FORCED_STOP, omega=float(ds.omega[i]), contacts=(
            Contact(float(ds["contacts.0.position1"][k]), clearance=1e-6),
            Contact(clearance=6e-6)))
        expected = first_contact(params, 0.05, n_modes=8)
        assert expected.contact == first[i, k]
        assert abs(expected.onset - time) <= 1e-15, (i, k)


def test_axes_on_contacts_fields_only_and_a_contact_not_left_out_is_its_own_map():
    """A grid over one contact's field alone is, bit for bit, the earliest of that contact's own
    map over its clearance and the other's one-cell map; the unquoted TOML form
    [axes.contacts.0.clearance] (nested tables) is the same sweep."""
    import tomllib

    from impactbeams.sweep import run_sweep, sweep_from_mapping

    axes = {"contacts.0.clearance": {"min": 0.3e-6, "max": 3e-6, "num": 3}}
    ds = run_sweep(_contact_sweep(axes, clearance=6e-6), parallel=False)
    alone = _map({"force_amplitude": 1e-3, "contact_stiffness": 1e4, "contact_position1": MID},
                 axes={"clearance": axes["contacts.0.clearance"]})
    tip = _map({"force_amplitude": 1e-3, "contact_stiffness": 1e4},
               axes={"clearance": {"min": 6e-6, "max": 6e-6, "num": 1}})
    np.testing.assert_array_equal(ds.first_impact_time.values, np.fmin(alone, tip))
    text = ('t_max = 0.05\nn_modes = 8\n[params]\ncounterpart = "stop"\nforce_amplitude = 1e-3\n'
            'contact_stiffness = 1e4\nclearance = 6e-6\n[[params.contacts]]\nposition1 = 0.05\n'
            '[[params.contacts]]\n[axes.contacts.0.clearance]\nmin = 0.3e-6\nmax = 3e-6\n'
            'num = 3\n')
    nested = run_sweep(sweep_from_mapping(tomllib.loads(text)), parallel=False)
    np.testing.assert_array_equal(nested.first_impact_time.values, ds.first_impact_time.values)


_AXIS = {"min": 1e-6, "max": 2e-6, "num": 2}


@pytest.mark.parametrize(("axes", "params", "message"), [
    ({"contacts.2.clearance": _AXIS}, {},
     '[axes."contacts.2.clearance"] of sweep = \'contacts.2.clearance\' is not allowed: there '
     "are 2 contacts in [params] (indices 0 to 1)"),
    ({"contacts.0.side": {"min": 0.02, "max": 0.05, "num": 2}}, {},
     "a contact's side is not sweepable (give it in the contact: one sweep per side); "
     "sweepable: position1, position2, clearance, stiffness, damping"),
    ({"contacts.1.position1": {"min": 0.02, "max": 0.2, "num": 2}}, {},
     "at the grid point omega = 10.0, contacts.1.position1 = 0.2 of sweep: contacts[1]: "
     "contact_position1 = 0.2 is not allowed: must be > 0 and <= l1 = 0.1"),
    ({"contacts.1.position1": {"min": 0.02, "max": 0.1, "num": 2},
      "l1": {"min": 0.08, "max": 0.1, "num": 2}}, {},
     "at the grid point omega = 10.0, contacts.1.position1 = 0.1, l1 = 0.08 of sweep: "
     "contacts[1]: contact_position1 = 0.1 is not allowed: must be > 0 and <= l1 = 0.08"),
    ({"contacts.1.position1": {"min": -0.02, "max": 0.1, "num": 2}}, {},
     "axis 'contacts.1.position1' of sweep reaches a non-physical point: contact_position1 = "
     "-0.02 is not allowed: must be > 0"),
    ({"contacts.0.clearence": _AXIS}, {},
     "unknown contact field 'clearence' in [axes.\"contacts.0.clearence\"] of sweep (did you "
     "mean 'clearance'?)"),
    ({"contacts.01.clearance": _AXIS}, {},
     "an axis on a contact's field is named contacts.INDEX.FIELD, e.g. 'contacts.0.clearance'"),
    ({"contacts.0.stiffness": {"min": 0.0, "max": 1e4, "num": 2}}, {},
     "axis 'contacts.0.stiffness' of sweep reaches a non-physical point: contact_stiffness = 0.0"),
    ({"contacts.1.clearance": _AXIS}, {"contacts": [{"position1": MID}, {"clearance": 3e-6}]},
     "is given both in [params] (contacts[1].clearance = 3e-06) and as an axis"),
    ({"contacts.0.clearance": _AXIS}, {"contacts": [{"position1": MID}]},
     "[params] has fewer than two ([[params.contacts]]): one contact is the flat keys, sweep "
     "[axes.clearance]"),
    ({"contacts.0.clearance": _AXIS}, {"clearance": 5e-6, "contacts": [
        {"position1": MID}, {"clearance": 3e-6}]},
     "clearance = 5e-06 in [params] of sweep is not allowed: each of the 2 contacts gives its "
     "own clearance"),
    ({"clearance": _AXIS}, {},
     "clearance is not sweepable with contacts: each contact has its own; sweep one contact's "
     'as [axes."contacts.INDEX.FIELD"]'),
])
def test_bad_axes_on_contacts_fields_are_refused_in_one_line(axes, params, message):
    with pytest.raises(ParameterError) as error:
        _contact_sweep({"omega": {"min": 10.0, "max": 20.0, "num": 2}, **axes}, **params)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_a_bad_contact_axis_exits_2_from_the_command_line(tmp_path, capsys):
    from impactbeams.cli import main

    path = tmp_path / "bad.toml"
    path.write_text('t_max = 0.05\n[params]\ncounterpart = "stop"\n[[params.contacts]]\n'
                    '[[params.contacts]]\nside = "above"\n[axes."contacts.2.clearance"]\n'
                    'min = 1e-6\nmax = 2e-6\nnum = 2\n')
    assert main(["run", str(path), "-o", str(tmp_path / "out.nc"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("impactbeams: error: [axes.\"contacts.2.clearance\"] of ")
    assert err.count("\n") == 1 and not (tmp_path / "out.nc").exists()


# --- the command line: impactbeams contacts ---------------------------------------------------

_TWO_SIDED = ('[params]\ncounterpart = "stop"\nforce_amplitude = 1e-3\nomega = 400.0\n'
              'contact_stiffness = 1e4\n[[params.contacts]]\nposition1 = 0.05\nclearance = 3e-6\n'
              '[[params.contacts]]\nposition1 = 0.05\nside = "above"\nclearance = 2e-6\n')
_TWO_SIDED_PARAMS = FORCED.replace(contacts=two_sided_stop(MID, 3e-6, 2e-6))


def _contacts_command(tmp_path, capsys, text, *options):
    from impactbeams.cli import main

    path = tmp_path / "p.toml"
    path.write_text(text)
    code = main(["contacts", "--params", str(path), "--t-max", "0.03", *options])
    out, err = capsys.readouterr()
    return code, out, err


def test_the_contacts_command_prints_the_librarys_first_contact_and_sequence(tmp_path, capsys):
    """--json is first_contact's and contact_sequence's values bit for bit (JSON floats
    round-trip); the table prints the same contacts; -o writes the sequence with CF attributes."""
    import json

    import xarray as xr

    code, out, _ = _contacts_command(tmp_path, capsys, _TWO_SIDED, "--n-modes", "8", "--json")
    assert code == 0
    data = json.loads(out)
    first = first_contact(_TWO_SIDED_PARAMS, 0.03, n_modes=8)
    assert data["first_contact"] == {key: (None if value != value else value)
                                     for key, value in vars(first).items()}
    sequence = contact_sequence(_TWO_SIDED_PARAMS, 0.03, n_modes=8)
    assert data["sequence"]["status"] == "complete" and data["sequence_refused"] is None
    for name in sequence.data_vars:
        np.testing.assert_array_equal(np.array(data["sequence"][name], dtype=float),
                                      sequence[name].values)
    assert set(sequence.impact_contact.values) == {0, 1}  # both sides close
    output = tmp_path / "s.nc"
    code, out, err = _contacts_command(tmp_path, capsys, _TWO_SIDED, "--n-modes", "8", "-o",
                                       str(output))
    assert code == 0
    assert err == f"wrote {output}: {sequence.impact.size} contacts, status complete\n"
    lines = out.splitlines()
    assert lines[:3] == ["2 contacts, 8 modes of beam 1, t_max = 0.03 s",
                         "  contacts[0] (below, x1 = 0.05 m)",
                         "  contacts[1] (above, x1 = 0.05 m)"]
    assert lines[3] == (f"first contact: contacts[{first.contact}] (below, x1 = 0.05 m) at t = "
                        f"{first.onset!r} s, gap rate {first.impact_velocity:.6g} m/s")
    rows = [line.split() for line in lines[6:]]
    assert [int(row[1]) for row in rows] == sequence.impact_contact.values.tolist()
    assert [float(row[2]) for row in rows] == [float(f"{t:.10f}") for t in
                                               sequence.impact_onset_time.values]
    with xr.open_dataset(output) as written:
        np.testing.assert_array_equal(written.impact_onset_time.values,
                                      sequence.impact_onset_time.values)
        assert written.impact_onset_time.attrs["units"] == "s"
        assert written.attrs["status"] == "complete" and "position1=0.05" in written.contacts
        assert "clearance" not in written.attrs and written.contact_stiffness == 1e4


def test_the_contacts_command_of_contacts_that_close_together_and_bad_input(tmp_path, capsys):
    """Contacts that can be closed together: the first contact and their sequence (exit 0),
    with a dashpot among them too. Bad input: one line, exit 2, nothing written."""
    text = ('[params]\ncounterpart = "stop"\nforce_amplitude = 1e-3\nomega = 400.0\n'
            'contact_stiffness = 1e4\n[[params.contacts]]\nposition1 = 0.05\nclearance = 0.5e-6\n'
            '[[params.contacts]]\nclearance = 6e-6\n')
    code, out, _ = _contacts_command(tmp_path, capsys, text, "--n-modes", "8")
    together = FORCED.replace(contacts=(Contact(MID, clearance=0.5e-6), Contact(clearance=6e-6)))
    first = first_contact(together, 0.03, n_modes=8)
    sequence = contact_sequence(together, 0.03, n_modes=8)
    assert code == 0 and f"at t = {first.onset!r} s" in out
    assert f"contact sequence: {sequence.impact.size} contacts, status complete" in out
    damped = text.replace("clearance = 0.5e-6\n", "clearance = 0.5e-6\ndamping = 0.1\n")
    code, out, _ = _contacts_command(tmp_path, capsys, damped, "--n-modes", "8")
    sequence = contact_sequence(together.replace(contacts=(
        Contact(MID, clearance=0.5e-6, damping=0.1), Contact(clearance=6e-6))), 0.03, n_modes=8)
    assert code == 0
    assert f"contact sequence: {sequence.impact.size} contacts, status complete" in out
    output = tmp_path / "x.nc"
    for options, message in [
            (("--clearance", "1e-6"), "clearance = 1e-06 in the command line (beside the "
                                      "contacts of"),
            (("--t-max", "-1"), "t_max = -1.0 is not allowed: must be > 0 (s)"),
            (("--n-modes", "0"), "argument --n-modes: 0 is not allowed"),
            (("-o", str(tmp_path / "x.png")), "-o/--output")]:
        code, out, err = _contacts_command(tmp_path, capsys, text, *options)
        assert code == 2 and not output.exists(), options
        last = err.splitlines()[-1]
        assert last.startswith("impactbeams: error: ") and message in last, (options, err)
    code, _, err = _contacts_command(tmp_path, capsys, _TWO_SIDED, "--n-modes", "8",
                                     "--max-contacts", "2")
    assert code == 3 and "stopped after --max-contacts 2 contacts" in err
