"""Numerical stress cases: every case checks an invariant or an independent value.

Resonance, up to 100+ modes per beam, equal and nearly equal beams, grazing contact, clearance
from 1e-12 m to 1e-3 m, F0 = 0 with uplift, horizons up to 300 s, extreme l2/l1 and EI2/EI1,
and random parameters from hypothesis. All are marked ``stress``; the long ones also ``slow``
(``pytest -m "stress and not slow"`` is the fast subset, well under a minute).
The independent values come from ``references.py`` (textbook closed form in long double, dense
sampling, bisection) or from closed forms written out here.
"""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.first_impact import first_impact_cells
from impactbeams.kernels.layout import CELL_COLUMNS
from impactbeams.kernels.propagation import advance
from impactbeams.model import build_free_phase
from impactbeams.modes import contact_frequencies, contact_modes
from impactbeams.packing import free_tables, geometry_row
from impactbeams.params import Params
from impactbeams.trajectory import observables, pack_run, run, sample
from impactbeams.trajectory.fields import energy_integrals
from references import (
    free_tip_gap,
    gauss_rule,
    left_bracket,
    reference_first_impact,
)

pytestmark = pytest.mark.stress

EPS = np.finfo(float).eps
LD = np.longdouble
CLAMPED_PINNED_1 = 3.9266023120  # first root of tan b = tanh b (Blevins, 10 decimals)


# --- helpers ----------------------------------------------------------------------------------


def first_impacts(params, n_modes, rows, t_max):
    """First-impact kernel on cells (clearance, F0, Omega, uplift1, uplift2) of params."""
    free = build_free_phase(params, n_modes)
    # undamped, geometry 0, no base drive
    cells = np.array([[*row[:5], 0.0, 0.0, 0.0] for row in rows], dtype=float)
    assert cells.shape[1] == len(CELL_COLUMNS)
    out = np.empty(len(cells))
    first_impact_cells(cells, free_tables(free)[None], geometry_row(params, free)[None], t_max,
                       out)
    return out


def reference_time(params, n_modes, row, t_max, samples_per_period=16):
    """(long-double gap, dense-sampling + bisection first root) of one cell."""
    free = build_free_phase(params, n_modes)
    args = (free, params.tip_compliance[0], *row[:5])
    gap, scan = free_tip_gap(*args), free_tip_gap(*args, dtype=np.float64)
    # modes that start at rest and are not driven stay at 0: only the others set the sampling
    moving = (free.drive * row[1] != 0) | (free.unit1 * row[3] != 0) | (free.unit2 * row[4] != 0)
    fastest = max(free.frequencies[moving].max(initial=0.0), row[2])
    return gap, reference_first_impact(gap, t_max, fastest, samples_per_period, scan=scan)


def assert_matches_reference(params, n_modes, row, t_kernel, t_max, rel=1e-12):
    """Kernel time equals the reference, or is a root the sampling missed (verified in ld)."""
    gap, ref = reference_time(params, n_modes, row, t_max)
    if np.isnan(ref) and np.isfinite(t_kernel):
        # a closure too brief for the sampling: the long-double gap must close there too
        assert gap(t_kernel) <= 16 * EPS * row[0], (row, t_kernel)
        return
    assert np.isnan(ref) == np.isnan(t_kernel), (row, ref, t_kernel)
    if np.isfinite(ref):
        assert abs(t_kernel - ref) <= rel * ref, (row, ref, t_kernel)


def phase_energy_drift(params, t_max, n_modes, count=20_001):
    """Largest change of (energy - unresolved KE - work of F + damping loss) within a phase.

    Of the tied law: the spring law's energy checks are in test_spring.py.

    Relative to the largest energy seen; also returns the trajectory and the energies just
    before and after every event (for checks at the switches).
    """
    packed = pack_run(params.replace(contact_law="tied"), n_modes, t_max, t_max)
    traj = run(packed, 2_000_000)
    assert traj.status == "complete"
    times = np.unique(np.concatenate([np.linspace(0.0, t_max, count), traj.time]))
    phase, q, v = sample(packed, traj, times)
    obs = observables(packed, phase, times, q, v)
    work, loss = energy_integrals(packed, traj, times)
    balance = obs["energy"] - obs["unresolved_kinetic_energy"] - work + loss
    segment = np.searchsorted(traj.time, times, side="right") - 1
    start = balance[np.searchsorted(times, traj.time)][segment]
    scale = np.max(np.abs(obs["energy"]))
    return np.max(np.abs(balance - start)) / scale, packed, traj


# --- resonance --------------------------------------------------------------------------------


@pytest.mark.parametrize("horizon", [1.0, 30.0, 300.0])
@pytest.mark.parametrize("detune", [0.0, 1e-12, 1e-8, -1e-12])
def test_propagation_at_and_near_resonance_against_long_double(horizon, detune):
    """Driven from rest at Omega = omega (1 + detune): the response grows like t for 300 s.

    Reference: the sum-to-product form, exact at resonance, in long double. The only error of
    the double kernel is the rounding of the phase omega h (~eps omega h, measured 1.6e-12 at
    omega h = 7.4e4): the bound 2 eps omega h leaves a margin of 20.
    """
    w, f = 246.12, 3.0
    big = w * (1 + detune)
    q, v = np.empty(1), np.empty(1)
    advance(np.zeros(1), np.zeros(1), 0.0, horizon, np.array([w]), np.zeros(1),
            np.array([complex(f)]), big, q, v)
    wl, bl, t = LD(w), LD(big), LD(horizon)
    half = (bl - wl) * t / 2
    sinc = LD(1) if half == 0 else np.sin(half) / half
    expected = f * (np.sin(wl * t) / wl - t * np.cos((wl + bl) * t / 2) * sinc) / (wl + bl)
    assert abs(q[0] - float(expected)) <= 2 * EPS * w * horizon * abs(float(expected))


@pytest.fixture(scope="module")
def beam1_modes():
    return build_free_phase(Params(), 10).beam1.frequencies


@pytest.mark.parametrize("mode", [0, 2])
@pytest.mark.parametrize("detune", [0.0, 1e-12, -1e-12])
def test_first_impact_at_resonance_of_modes_1_and_3(beam1_modes, mode, detune):
    """10 modes per beam, forcing at (and 1e-12 off) the 1st and 3rd resonance of beam 1.

    Against the long-double reference to 1e-12 (measured ~1e-14), and continuous in Omega.
    """
    omega = float(beam1_modes[mode]) * (1 + detune)
    row = [1.1e-5, 2e-5 if mode == 0 else 1e-3, omega, 0.0, 0.0]
    t_max = 0.2
    t = first_impacts(Params(), 10, [row], t_max)[0]
    assert np.isfinite(t)
    assert_matches_reference(Params(), 10, row, t, t_max)
    exact = first_impacts(Params(), 10, [[*row[:2], float(beam1_modes[mode]), 0.0, 0.0]], t_max)
    # dt*/dOmega ~ t* / Omega at most: a 1e-12 detuning moves t* by ~1e-12 relative
    assert abs(t - exact[0]) <= 1e-10 * t


# --- many modes -------------------------------------------------------------------------------


def test_first_impact_converges_up_to_200_modes_per_beam():
    """t* with 25, 50, 100, 200 modes per beam (400 coordinates): the kernel stays stable
    and t* converges. Forced from rest, the high modes are barely excited: 100 and 200 modes
    agree to 1e-15 s (measured 2e-16; t* ~ 0.01 s). Released from the uplift shape, the
    modal series of the tip converges slowly (measured distances to 400 modes: 4e-9, 1.5e-11,
    9e-12, 1.4e-12 s for 25..200 modes): bounds 2e-11 s and monotone shrinking."""
    rows = [[1.1e-5, 1e-3, 50.0, 0, 0], [1.1e-5, 2e-4, 150.0, 0, 0], [2e-6, 1e-4, 300.0, 0, 0],
            [1.1e-5, 0.0, 0.0, 3e-5, 0]]
    times = {n: first_impacts(Params(), n, rows, 1.0) for n in (25, 50, 100, 200)}
    assert np.all(np.isfinite(times[200]))
    assert np.abs(times[200][:3] - times[100][:3]).max() < 1e-15
    uplift = {n: t[3] for n, t in times.items()}
    assert abs(uplift[200] - uplift[100]) < 2e-11
    assert abs(uplift[200] - uplift[100]) < abs(uplift[50] - uplift[25])


def test_200_contact_modes_interlace_and_stay_orthonormal():
    """Contact frequencies of a 100-mode model (200 contact modes) lie strictly between
    consecutive merged free frequencies (interlacing, an exact property of adding one
    constraint), and the top modes stay orthonormal under an independent quadrature
    (shapes with 100+ half-waves: 1e-9 leaves 1e3 margin over the measured ~1e-12)."""
    p = Params()
    free = build_free_phase(p, 201)  # 201 per beam: surely holds the 201 lowest merged
    merged = np.sort(free.frequencies)
    contact = contact_frequencies(p, 200)
    assert np.all(merged[:200] < contact) and np.all(contact < merged[1:201])
    modes = contact_modes(p, 200)
    x1, w1 = gauss_rule(p.l1, panels=1600)
    x2, w2 = gauss_rule(p.l2, panels=1600)
    top = slice(180, 200)
    z1, z2 = modes.beam1(x1)[top], modes.beam2(x2)[top]
    gram = p.rhoA1 * (z1 * w1) @ z1.T + p.rhoA2 * (z2 * w2) @ z2.T
    assert np.abs(gram - np.eye(20)).max() < 1e-9


# --- equal and nearly equal beams -------------------------------------------------------------


@pytest.mark.parametrize("eta", [0.0, 1e-9])
def test_equal_beams_unforced_dynamics_conserve_energy_within_phases(eta):
    """l2 = l1 (1 + eta), F0 = 0, beam 1 lifted: double contact frequencies. Within every
    phase the energy is constant to round-off (exact propagation, 1e-12 relative), and the
    first impact, a free-phase quantity, is continuous in eta."""
    base = Params(force_amplitude=0.0, uplift1=3e-5, l2=0.1 * (1 + eta))
    drift, packed, traj = phase_energy_drift(base, 0.5, 5)
    assert drift < 1e-12
    assert np.count_nonzero(traj.phase == dyn.CONTACT) > 5
    equal = first_impacts(Params(l2=0.1), 5, [[1.1e-5, 0.0, 0.0, 3e-5, 0.0]], 1.0)[0]
    assert traj.time[1] == pytest.approx(equal, rel=1e-12)  # onset needs only beam 1


# --- grazing ----------------------------------------------------------------------------------


def _deepest_dip(free, compliance, force, omega, t_max):
    """Clearance at which the gap just touches 0, and when (long double, golden refinement)."""
    from scipy.optimize import minimize_scalar

    response = free_tip_gap(free, compliance, 0.0, force, omega)
    scan = free_tip_gap(free, compliance, 0.0, force, omega, dtype=np.float64)
    t = np.linspace(0.0, t_max, int(t_max * free.frequencies.max() * 4) + 2)
    j = int(np.argmin(scan(t)))
    found = minimize_scalar(lambda s: float(response(s)), bounds=(t[j - 1], t[j + 1]),
                            method="bounded", options={"xatol": 1e-15})
    return -float(response(found.x)), found.x


@pytest.mark.parametrize("depth", [1e-4, 1e-8, 1e-11, 1e-13])
@pytest.mark.parametrize(("omega", "force"), [(37.0, 2.8e-4), (173.0, 1.1e-4), (333.0, 8e-5)])
def test_grazing_closure_found_and_near_miss_rejected(omega, force, depth):
    """Clearance at the deepest dip x (1 -+ depth): the gap closes for ~sqrt(depth) of a period
    or stays open by depth x clearance. Closed: a root where the long-double gap is <= 0
    within round-off; open: NaN. Down to depth 1e-13 (1e-14 fails by design: a gap within
    round-off of 0 counts as touching; docs/limits.md)."""
    p, t_max = Params(), 0.3
    free = build_free_phase(p, 5)
    c1 = p.tip_compliance[0]
    graze, t_graze = _deepest_dip(free, c1, force, omega, t_max)
    closed = [graze * (1 - depth), force, omega, 0, 0]
    opened = [graze * (1 + depth), force, omega, 0, 0]
    t_closed, t_open = first_impacts(p, 5, [closed, opened], t_max)
    assert np.isnan(t_open)
    assert np.isfinite(t_closed)
    gap = free_tip_gap(free, c1, *closed)
    assert gap(t_closed) <= 16 * EPS * graze
    assert gap(left_bracket(gap, t_closed, 1e-12)) > 0
    # the closure lies inside the dip: within the time the dip is below 0, ~sqrt(depth)/omega
    slowest = min(omega, free.frequencies[0])
    assert abs(t_closed - t_graze) <= 10 * math.sqrt(depth) / slowest + 1e-12


# --- clearance range --------------------------------------------------------------------------


def test_clearance_from_1e_12_to_1e_3_is_monotone_and_matches_reference():
    """In the free phase the tip motion does not depend on the clearance, so t*(clearance) is
    non-decreasing; small clearances impact, 1e-3 m (27x the static deflection) never does;
    every value matches the long-double reference to 1e-12 (smallest ones: to 1e-10, the
    first root is then in the initial cubic rise where the gap's slope is tiny)."""
    clearances = np.geomspace(1e-12, 1e-3, 19)
    rows = [[c, 1e-3, 50.0, 0, 0] for c in clearances]
    times = first_impacts(Params(), 5, rows, 1.0)
    finite = times[np.isfinite(times)]
    assert np.all(np.diff(finite) >= 0)
    assert np.isfinite(times[0]) and np.isnan(times[-1])
    for row, t in zip(rows, times, strict=True):
        assert_matches_reference(Params(), 5, row, t, 1.0, rel=1e-10 if row[0] < 1e-9 else 1e-12)


@pytest.mark.parametrize("clearance", [1e-12, 1e-3])
def test_clearance_extremes_in_full_dynamics_keep_the_energy_balance(clearance):
    """Forced run with the smallest and a large clearance (large F0 so that it impacts):
    (energy - unresolved KE - work of F) is constant within every phase to 1e-10 of the
    energy scale (exact propagation; the work integral is 12-point Gauss per half period)."""
    params = Params(clearance=clearance, force_amplitude=1e-3 if clearance < 1e-6 else 0.1)
    drift, _, traj = phase_energy_drift(params, 0.05, 5)
    assert np.count_nonzero(traj.phase == dyn.CONTACT) >= 1
    assert drift < 1e-10


# --- F0 = 0 with uplift -----------------------------------------------------------------------


@pytest.mark.parametrize("uplift1", [2e-5, 1e-4, 1e-3])
def test_unforced_uplift_single_mode_has_closed_form(uplift1):
    """One mode per beam, F0 = 0, beam 1 lifted: the gap is clearance + a cos(omega_1 t) with
    a = delta_1 Y_1(l1) <u_1, Y_1>, so t* = arccos(-clearance / a) / omega_1 (an independent
    closed form; 1e-13 relative allows the arccos conditioning near a = clearance)."""
    p = Params(uplift1=uplift1, force_amplitude=0.0)
    free = build_free_phase(p, 1)
    a = uplift1 * free.tip1[0] * free.unit1[0]
    expected = math.acos(-p.clearance / a) / free.frequencies[0]
    t = first_impacts(p, 1, [[p.clearance, 0.0, 0.0, uplift1, 0.0]], 1.0)[0]
    assert t == pytest.approx(expected, rel=1e-13)


def test_unforced_beam2_uplift_below_clearance_never_impacts_with_one_mode():
    """Beam 2 lifted by less than the clearance, one mode each, F0 = 0: y2 <= delta_2 Y(l2)
    <u_2, Y> < clearance forever: the gap cannot close (NaN over 30 s)."""
    p = Params(force_amplitude=0.0, uplift2=0.9 * Params().clearance)
    free = build_free_phase(p, 1)
    assert p.uplift2 * free.tip2[1] * free.unit2[1] < p.clearance
    assert np.isnan(first_impacts(p, 1, [[p.clearance, 0.0, 0.0, 0.0, p.uplift2]], 30.0)[0])


# --- extreme ratios ---------------------------------------------------------------------------


@pytest.mark.parametrize("ratio", [1e2, 1e4, 1e6])
def test_stiff_beam2_limit_is_clamped_pinned_beam1(ratio):
    """EI2 / EI1 -> inf: beam 2 becomes a rigid stop at beam 1's tip, so the first contact
    frequency tends to beam 1's clamped-pinned frequency a1 (3.9266023120 / l1)^2. The
    deviation falls like EI1 / EI2 (measured 11.8, 8.4, 8.4 EI1/EI2 at 1e2, 1e4, 1e6):
    bound 15 EI1/EI2."""
    p = Params()
    stiff = p.replace(EI2=p.EI1 * ratio)
    limit = stiff.wave_constant[0] * (CLAMPED_PINNED_1 / p.l1) ** 2
    assert abs(contact_frequencies(stiff, 1)[0] / limit - 1) < 15 / ratio
    # the clamped-pinned root itself, independently: tan b = tanh b
    assert brentq(lambda b: math.tan(b) - math.tanh(b), 3.5, 4.5) == pytest.approx(
        CLAMPED_PINNED_1, abs=1e-10)


EXTREME = [Params(l2=0.1 * 0.05), Params(l2=0.1 * 20), Params(EI2=Params().EI1 * 1e-4),
           Params(EI2=Params().EI1 * 1e4)]
EXTREME_IDS = ["l2/l1=0.05", "l2/l1=20", "EI2/EI1=1e-4", "EI2/EI1=1e4"]


@pytest.mark.parametrize("params", EXTREME, ids=EXTREME_IDS)
def test_extreme_ratios_first_impact_and_contact_modes(params):
    """First impact against the long-double reference (1e-12), contact modes orthonormal
    under an independent quadrature (1e-10; measured ~1e-13) with tied tips."""
    rows = [[1.1e-5, 5e-4, 50.0, 0, 0], [1.1e-5, 0.0, 0.0, 4e-5, 0], [2e-6, 1e-4, 300.0, 0, 0]]
    for row, t in zip(rows, first_impacts(params, 5, rows, 0.5), strict=True):
        assert_matches_reference(params, 5, row, t, 0.5)
    modes = contact_modes(params, 10)
    x1, w1 = gauss_rule(params.l1)
    x2, w2 = gauss_rule(params.l2)
    z1, z2 = modes.beam1(x1), modes.beam2(x2)
    gram = params.rhoA1 * (z1 * w1) @ z1.T + params.rhoA2 * (z2 * w2) @ z2.T
    assert np.abs(gram - np.eye(10)).max() < 1e-10
    tips = np.abs(modes.beam1.tip() - modes.beam2.tip())
    assert tips.max() <= 1e-10 * np.abs(modes.beam1.tip()).max()


@pytest.mark.parametrize("params", EXTREME, ids=EXTREME_IDS)
def test_extreme_ratios_unforced_dynamics_conserve_energy_within_phases(params):
    """F0 = 0, beam 1 lifted, 0.2 s: energy constant within each phase (1e-12, round-off)."""
    drift, _, traj = phase_energy_drift(params.replace(force_amplitude=0.0, uplift1=3e-5),
                                        0.2, 5)
    assert traj.time.size >= 2
    assert drift < 1e-12


# --- random parameters (property-based) -------------------------------------------------------


@st.composite
def random_cells(draw):
    """A geometry and a cell with every parameter over a few decades (SI units)."""
    params = Params(l1=draw(st.floats(0.05, 0.2)), l2=draw(st.floats(0.05, 0.2)),
                    EI2=Params().EI1 * 10 ** draw(st.floats(-1, 1)),
                    rhoA2=Params().rhoA1 * 10 ** draw(st.floats(-0.5, 0.5)))
    clearance = 10 ** draw(st.floats(-7, -4.3))
    row = [clearance, 10 ** draw(st.floats(-5.5, -3)), draw(st.floats(1.0, 600.0)),
           draw(st.sampled_from([0.0, 1e-5, 3e-5])), draw(st.sampled_from([0.0, 0.5 * clearance]))]
    return params, row


def _random_property(params, row):
    t_max = 0.3
    t, t_wider = first_impacts(params, 3, [row, [row[0] * 1.5, *row[1:]]], t_max)
    assert_matches_reference(params, 3, row, t, t_max, rel=1e-11)
    if np.isfinite(t_wider):  # opening the clearance can only delay the first impact
        assert t_wider >= t


# derandomize: the same examples every run, so the suite cannot flake; 1e-11 relative allows
# near-tangent roots (time error eps / sqrt(dip depth)) down to depths of ~1e-9
@settings(max_examples=25, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(random_cells())
def test_random_parameters_against_reference(case):
    _random_property(*case)


@pytest.mark.slow
@settings(max_examples=300, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(random_cells())
def test_random_parameters_against_reference_many(case):
    _random_property(*case)


# --- long horizons (slow) ---------------------------------------------------------------------


@pytest.mark.slow
def test_unforced_300_s_energy_within_phases_and_only_lost_at_onsets():
    """F0 = 0, no damping, 300 s: energy constant within every phase (1e-11 relative: the
    phase rounding grows like eps omega t, ~1e-12 at 300 s) and it never rises at an onset."""
    drift, packed, traj = phase_energy_drift(Params(force_amplitude=0.0, uplift1=2e-5), 300.0,
                                             5, count=300_001)
    assert drift < 1e-11
    before = observables(packed, traj.phase, traj.segment_end, traj.end_q, traj.end_v)
    after = observables(packed, traj.phase, traj.time, traj.q, traj.v)
    onset = np.flatnonzero(traj.phase == dyn.CONTACT)
    kinetic_loss = before["kinetic_energy"][onset - 1] - after["kinetic_energy"][onset]
    assert np.all(kinetic_loss >= -1e-15 * after["energy"][0])


@pytest.mark.slow
def test_forced_300_s_energy_balance_within_phases():
    """Paper's forced case for 300 s: energy - unresolved KE - work of F constant within each
    phase to 1e-9 of the energy scale (measured drift reported in docs/limits.md)."""
    drift, _, traj = phase_energy_drift(Params(), 300.0, 5, count=300_001)
    assert np.count_nonzero(traj.phase == dyn.CONTACT) > 10_000
    assert drift < 1e-9


@pytest.mark.slow
def test_first_impact_after_a_long_quiet_time():
    """A cell that impacts only after ~100 s of beating (Omega close to omega_1, small F0):
    against a chunked long-double-verified scan over 300 s."""
    p = Params()
    free = build_free_phase(p, 5)
    row = [1.1e-5, 2.2e-7, float(free.frequencies[0]) * (1 - 2e-4), 0, 0]
    t = first_impacts(p, 5, [row], 300.0)[0]
    assert np.isfinite(t) and t > 10.0
    gap = free_tip_gap(free, p.tip_compliance[0], *row)
    scan = free_tip_gap(free, p.tip_compliance[0], *row, dtype=np.float64)
    step = 2 * np.pi / free.frequencies.max() / 16
    for start in np.arange(0.0, t, 1.0):
        times = np.arange(start, min(start + 1.0, t * (1 - 1e-12)), step)
        assert np.all(scan(times) > 0)
    assert gap(t) <= 16 * EPS * row[0]
    assert gap(left_bracket(gap, t, 1e-12)) > 0
