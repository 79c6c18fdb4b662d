"""The compliant (spring) contact law against independent references.

Frequencies against the continuous two-beam problem (coupled_beams.py), contacts against a
DOP853 integration of the same modal equations (spring_modal_reference.py) and against an FE
model with the same law (data/spring_fig3_fe.json from fe_spring.py), energy invariants, and
convergence in n_modes.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from coupled_beams import coupled_frequencies
from impactbeams import Params, simulate
from impactbeams.compliant import (
    recommended_modes,
    required_modes,
    resolution_modes,
    spring_contact,
)
from impactbeams.model import build_free_phase
from impactbeams.modes import contact_frequencies
from impactbeams.params import MAX_CONTACT_STIFFNESS, MAX_MODES, ParameterError
from spring_modal_reference import spring_modal_contacts

FIG3 = Params(contact_stiffness=1e4)  # the paper's Fig. 3 forcing, k = 1e4 N/m
FE = json.loads((Path(__file__).parent / "data" / "spring_fig3_fe.json").read_text())
TIP_STIFFNESS = 3 * Params().EI1 / Params().l1**3  # beam 1, ~27 N/m


def contacts(ds, count=5):
    """Onset, duration, impulse and peak force of the first ``count`` contacts."""
    return {"onset": ds.impact_onset_time.values[:count],
            "duration": ds.impact_duration.values[:count],
            "impulse": ds.impact_impulse.values[:count],
            "peak": ds.impact_peak_force.values[:count]}


@pytest.fixture(scope="module")
def fig3_runs():
    return {n: simulate(FIG3, 0.0135, n_modes=n) for n in (40, 80)}


# --- the contact phase's frequencies ------------------------------------------------------------


@pytest.mark.parametrize("ratio", [1e-2, 1.0, 1e2, 1e4, 1e6])
def test_contact_frequencies_converge_to_the_continuous_coupled_beams(ratio):
    """Undamped contact oscillators = exact frequencies of two beams joined by a tip spring.

    With the static correction the lowest five converge fast in n_modes: 40 per beam agree
    with the continuous problem to 1e-7 relative for every k (measured worst 2e-8 at
    k = 1e6 x tip stiffness, where the contact frequency lies among modes ~10-15).
    """
    params = Params(contact_stiffness=ratio * TIP_STIFFNESS)
    free = build_free_phase(params, 40)
    spring = spring_contact(free, params.tip_compliance, 0.0, params.contact_stiffness)
    exact = coupled_frequencies(params, params.contact_stiffness, 5)
    np.testing.assert_allclose(spring.frequencies[:5], exact, rtol=1e-7)


def test_stiff_spring_approaches_the_tied_frequencies():
    """k -> infinity: the spring law's contact frequencies tend to eq. (9)'s (tied)."""
    tied = contact_frequencies(Params(), 5)
    errors = []
    for k in (1e6, 1e8, 1e10):
        params = Params(contact_stiffness=k)
        spring = spring_contact(build_free_phase(params, 60), params.tip_compliance, 0.0, k)
        errors.append(np.max(np.abs(spring.frequencies[:5] / tied - 1)))
    # the gap to the tied limit falls like 1/k (until the 60-mode truncation, ~1e-9)
    assert errors[0] > 30 * errors[1] > 30 * 30 * errors[2] / 30
    assert errors[-1] < 1e-6


def test_resolution_rule():
    """n* counts modes whose modal tip stiffness omega^2 / Y(l)^2 is below k (per beam)."""
    free = build_free_phase(Params(), 40)
    # modal tip stiffness of mode n of beam 1: omega_n^2 rhoA l / 4 (Y(l)^2 = 4 / (rhoA l))
    p = Params()
    stiffness1 = free.beam1.frequencies**2 * p.rhoA1 * p.l1 / 4
    k = 0.5 * (stiffness1[4] + stiffness1[5])  # between beam 1's 5th and 6th modes
    assert resolution_modes(free, k) >= 5
    assert recommended_modes(Params(contact_stiffness=k)) == 4 * resolution_modes(free, k)


def _required_modes_built(params):
    """`required_modes` as it was before issue 33: both beams' MAX_MODES modes built."""
    free = build_free_phase(params, MAX_MODES)
    return int(max(5, 4 * resolution_modes(free, params.contact_stiffness)))


def _modal_tip_stiffnesses(params):
    """Each free mode's omega^2 / Y(l)^2 (N/m), as `resolution_modes` computes it."""
    free = build_free_phase(params, MAX_MODES)
    return free.frequencies**2 / (free.tip1 - free.tip2) ** 2


def test_required_modes_counts_as_many_as_building_them_all():
    """The count without MAX_MODES modes per beam is the built count, at every kind of k.

    Random geometries and stiffnesses from a soft contact to one past the 200th mode, both
    counterparts, and the edges where a bit decides: k equal to a mode's modal tip stiffness
    as `resolution_modes` computes it (that mode is not below k), and the floats either side.
    """
    rng = np.random.default_rng(33)
    cases = []
    for _ in range(40):
        beam2 = {"l2": rng.uniform(0.05, 0.3), "EI2": rng.uniform(0.05, 2.0)}
        params = Params(l1=rng.uniform(0.05, 0.3), EI1=rng.uniform(0.05, 2.0),
                        rhoA1=rng.uniform(0.05, 1.0), contact_stiffness=10 ** rng.uniform(2, 12),
                        **(beam2 if rng.uniform() < 0.5 else {"counterpart": "stop"}))
        cases.append(params)
        stiffnesses = _modal_tip_stiffnesses(params)
        stiffnesses = stiffnesses[stiffnesses < MAX_CONTACT_STIFFNESS]
        for edge in stiffnesses[rng.integers(0, stiffnesses.size, 3)]:
            cases += [params.replace(contact_stiffness=float(k))
                      for k in (edge, np.nextafter(edge, 0.0), np.nextafter(edge, np.inf))]
    cases.append(Params(l1=0.3, l2=0.3, EI1=0.05, EI2=0.05, contact_stiffness=1e12))  # all soft
    counts = [(required_modes(p), _required_modes_built(p)) for p in cases]
    assert all(new == old for new, old in counts), counts
    assert {old for _, old in counts} >= {5, 4 * MAX_MODES}  # the floor and the cap reached
    assert len({old for _, old in counts}) > 30


@pytest.mark.parametrize("params", [Params(), Params(counterpart="stop", contact_stiffness=1e9),
                                    Params(contact_stiffness=1e3)], ids=["default", "stop", "soft"])
def test_required_modes_builds_only_the_modes_that_decide(monkeypatch, params):
    """At most 3 modes past n* per beam are built, not MAX_MODES (issue 33)."""
    import impactbeams.modes

    built = []
    impactbeams.modes.free_modes.cache_clear()  # modes built by earlier tests are kept
    roots = impactbeams.modes.cantilever_roots
    monkeypatch.setattr(impactbeams.modes, "cantilever_roots",
                        lambda n: built.append(n) or roots(n))
    count = max(5, required_modes(params)) // 4
    assert built and max(built) <= count + 3, (built, count)


# --- contacts against a different integrator of the same equations ------------------------------


@pytest.mark.parametrize(("zeta", "damping"), [(0.0, 0.0), (0.02, 0.0), (0.0, 0.3), (0.01, 0.1)])
def test_contacts_equal_dop853_on_the_same_modal_equations(zeta, damping):
    """First 5 contacts of the exact kernel against solve_ivp(DOP853, rtol 1e-12) with events.

    Same equations (10 modes per beam, static correction, modal damping and dashpot), so the
    difference is DOP853's: ~1e-9 relative on times and ~1e-8 on impulses and peaks.
    """
    params = FIG3.replace(damping_ratio=zeta, contact_damping=damping)
    with pytest.warns(RuntimeWarning, match="does not resolve"):
        ds = simulate(params, 0.0135, n_modes=10)
    spring = spring_contact(build_free_phase(params, 10), params.tip_compliance, zeta,
                            params.contact_stiffness, damping)
    # the reference applies its dashpot as given: hand it the corrected one
    ref = spring_modal_contacts(params, 10, params.contact_stiffness,
                                c=spring.effective_damping, n_contacts=5, t_max=0.0135)
    got = contacts(ds)
    np.testing.assert_allclose(got["onset"], ref["onset"][:5], rtol=0, atol=2e-12)
    np.testing.assert_allclose(got["duration"], ref["duration"][:5], rtol=1e-8)
    np.testing.assert_allclose(got["impulse"], ref["impulse"][:5], rtol=1e-8)
    np.testing.assert_allclose(got["peak"], ref["peak"][:5], rtol=1e-8)


# --- convergence and the FE model -------------------------------------------------------------


def test_fig3_contacts_converge_from_40_to_80_modes(fig3_runs):
    """The issue's bound: the first 5 contacts change by < 1e-4 relative from 40 to 80 modes
    (measured: ~6e-6; durations relative to themselves, onsets to the durations)."""
    a, b = contacts(fig3_runs[40]), contacts(fig3_runs[80])
    assert np.max(np.abs(a["onset"] - b["onset"]) / b["duration"]) < 1e-4
    for name in ("duration", "impulse", "peak"):
        assert np.max(np.abs(a[name] / b[name] - 1)) < 1e-4, name


def test_fig3_contacts_agree_with_the_finite_element_model(fig3_runs):
    """80 modes per beam against the FE model with the same law (160 elements per beam).

    Bound: the FE's own estimated error (stored with the data, up to 4.4e-6 relative) plus the
    modal truncation at 80 modes (MODEL: ~1e-6): 1e-5 relative, onsets relative to durations.
    """
    got, ref = contacts(fig3_runs[80]), FE["fig3"]["reference"]
    np.testing.assert_allclose(got["onset"], ref["onset"], rtol=0,
                               atol=1e-5 * min(ref["duration"]))
    for name in ("duration", "impulse", "peak"):
        np.testing.assert_allclose(got[name], ref[name], rtol=1e-5, err_msg=name)


def test_free_vibration_interaction_impulse_hardly_depends_on_k():
    """F0 = 0, uplift 30 um: the first interaction (7 micro-contacts from 8.06 to 10.81 ms at
    k = 1e5 N/m) has the FE's total impulse (160 elements, its mesh error ~1e-5; 40 modes per
    beam: truncation ~5e-6), and nearly the same total for a 10 times stiffer spring, whose
    micro-contacts are more."""
    base = Params(force_amplitude=0.0, uplift1=3e-5)
    fe_total = sum(FE["free_vibration_k1e5"]["fe_160"]["impulse"])
    impulses, counts = [], []
    for k in (1e5, 1e6):
        params = base.replace(contact_stiffness=k)
        ds = simulate(params, 0.013, n_modes=40)
        impulses.append(float(ds.impact_impulse.sum()))
        counts.append(ds.impact.size)
    assert counts[0] == len(FE["free_vibration_k1e5"]["fe_160"]["impulse"])
    assert impulses[0] == pytest.approx(fe_total, rel=2e-5)
    assert impulses[1] == pytest.approx(impulses[0], rel=0.02)
    assert counts[1] > counts[0]


# --- invariants ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def unforced():
    """F0 = 0, c = 0, zeta = 0, uplift: 1 s of free vibration with many contacts."""
    params = Params(force_amplitude=0.0, uplift1=3e-5, contact_stiffness=1e5)
    return simulate(params, 1.0, n_modes=recommended_modes(params), dt_output=2e-5)


def test_unforced_energy_is_constant_over_1_s_of_contacts(unforced):
    """E = kinetic + bending + k_e g^2 / 2 is an exact invariant of the undamped law."""
    assert unforced.impact.size > 100
    energy = unforced.energy.values
    # exact propagation and identity switches: round-off only (measured ~1e-14)
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-12


def test_force_is_compressive_and_gap_signs_match_the_phases(unforced):
    """R >= 0; the gap is <= 0 in contact and >= 0 out of it, to round-off of the clearance."""
    ds = unforced
    contact = ds.in_contact.values == 1
    scale = 1e-14 * float(ds.attrs["clearance"])
    assert np.all(ds.contact_force.values >= 0.0)
    assert np.all(ds.gap.values[contact] <= scale)
    assert np.all(ds.gap.values[~contact] >= -scale)


def test_restitution_is_never_negative_with_the_spring_law(unforced):
    """The spring law releases with dg/dt >= 0 (no projection at release), so e >= 0; only the
    tied law's release projection gives e < 0, as the Dataset's description says."""
    e = unforced.restitution_coefficient
    released = np.isfinite(e.values)
    assert released.sum() > 100 and np.all(e.values[released] >= 0.0)
    assert "Negative under the tied law" in e.attrs["description"]


@pytest.mark.parametrize("forced", [False, True], ids=["unforced", "forced"])
def test_dashpot_and_modal_damping_dissipate_what_the_energy_loses(forced):
    """c > 0, zeta > 0: energy + dissipation - work of F is constant, and the dissipation
    never decreases (the dashpot's c_e g'^2 and the modal damping are sums of squares)."""
    params = Params(force_amplitude=1e-3 if forced else 0.0, uplift1=0.0 if forced else 3e-5,
                    contact_stiffness=1e5, contact_damping=2.0, damping_ratio=0.01)
    ds = simulate(params, 0.15, n_modes=recommended_modes(params), dt_output=1e-5,
                  energy_balance=True)
    assert ds.impact.size > 10
    balance = (ds.energy - ds.unresolved_kinetic_energy - ds.work_of_force
               + ds.damping_dissipation).values
    scale = float(ds.energy.max())
    # work and dissipation by 12-point Gauss per half period of the fastest mode (~1e-18);
    # what is left is the damped contact modes' eigenvalues, exact to eps omega_max / omega
    # (~1e-13 for the lowest): a drift of ~3e-10 per second (measured 1e-11 to 5e-11 here)
    assert np.max(np.abs(balance - balance[0])) < 1e-10 * scale
    assert np.all(np.diff(ds.damping_dissipation.values) >= -1e-16 * scale)
    assert float(ds.damping_dissipation[-1]) > 0.01 * scale
    if not forced:  # the energy never rises (to round-off)
        assert np.all(np.diff(ds.energy.values) <= 1e-13 * scale)


def test_tied_and_spring_are_labelled_in_the_dataset():
    ds = simulate(FIG3, 0.005, n_modes=12)
    assert ds.attrs["contact_law"] == "spring"
    assert ds.attrs["contact_resolved"] == 1
    assert 0 < ds.attrs["contact_stiffness_effective"] < FIG3.contact_stiffness


# --- bad input ----------------------------------------------------------------------------------


@pytest.mark.parametrize(("changes", "message"), [
    ({"contact_stiffness": 0.0}, "contact_stiffness"),
    ({"contact_stiffness": -1.0}, "contact_stiffness"),
    ({"contact_stiffness": float("nan")}, "contact_stiffness"),
    ({"contact_stiffness": 1e13}, "contact_stiffness"),
    ({"contact_damping": -1e-3}, "contact_damping"),
    ({"contact_damping": float("inf")}, "contact_damping"),
    ({"contact_law": "rigid"}, "contact_law"),
])
def test_bad_contact_parameters_are_refused(changes, message):
    with pytest.raises(ParameterError, match=message):
        Params(**changes)


@pytest.mark.parametrize("axis", [{"values": ["rigid"]}, {"values": ["tied", "tied"]},
                                  {"min": 0, "max": 1, "num": 2}, {"values": []}])
def test_bad_contact_law_axes_are_refused(axis):
    from impactbeams.sweep import sweep_from_mapping

    with pytest.raises(ParameterError, match="contact_law"):
        sweep_from_mapping({"axes": {"contact_law": axis}, "observables": ["impact_count"]})


def test_cli_modes_prints_the_spring_contact_frequencies(capsys):
    """`impactbeams modes` follows the contact law: the default (spring, Hertz k) gives the
    contact oscillators at the resolving n_modes, close to the continuous two-beam values."""
    from impactbeams.cli import main

    assert main(["modes", "--n", "3", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["contact_law"] == "spring"
    exact = coupled_frequencies(Params(), Params().contact_stiffness, 3)
    # 32 modes per beam with the static correction: ~1e-7 (the frequencies test's bound)
    np.testing.assert_allclose(result["contact"], exact, rtol=1e-6)


@pytest.mark.parametrize("stiffness", [5e-324, 1e-300, 1e-200])
def test_a_vanishing_contact_stiffness_leaves_the_free_frequencies(stiffness):
    """k down to the smallest subnormal: every weight deflates, the contact phase is the free one.

    (Found by the input fuzz: LAPACK's secular iteration failed on the underflowing update.)
    The frequency shift of such a spring is below round-off, so the contact frequencies equal the
    free ones bitwise, and the modes are the unit vectors.
    """
    aluminium = Params.from_mapping({"E1": 7e10, "rho1": 2700.0, "thickness1": 5e-4})
    free = build_free_phase(aluminium, 10)
    contact = spring_contact(free, (1e-3, 1e-3), 0.0, stiffness)
    np.testing.assert_array_equal(contact.frequencies, np.sort(free.frequencies))
