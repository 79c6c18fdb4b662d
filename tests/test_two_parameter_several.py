"""Bifurcation curves in two parameters with several contacts (issue 33, "several contacts").

The independent checks: beside a stop that never closes, the single contact's curves (its own
map's kernels); with two contacts active, a curve's end against the fold or grazing that a
one-parameter branch locates at the end's second parameter.
"""

import dataclasses
import math

import numpy as np
import pytest
import xarray as xr

from impactbeams import Contact, ParameterError, simulate
from impactbeams.continuation import (
    BifurcationCurve,
    Continuation,
    ContinuationInterrupted,
    continue_orbits,
)
from impactbeams.continuation.checkpoint import saved_points
from impactbeams.continuation.twoparameter import continue_curve
from impactbeams.orbits import ContactsPeriodMap, PeriodMap
from impactbeams.params import with_parameter
from impactbeams.variables import BIFURCATIONS, CURVE_EVENTS, validate
from orbit_reference import map_energy_scale
from several_stops import FAR, N_MODES, STOP, TWO, TWO_TOML
from test_continuation_resume import _stop_after
from test_resume import assert_same_map
from test_two_parameter import SMALL

# a curve's end on its box's edge solves the augmented system to Newton's 1e-10 of the scaled
# unknowns, and a one-parameter branch locates its event to 1e-11 of its range: 1e-9 relative,
# as tests/test_two_parameter.py's AGREE
AGREE = 1e-9


def _single_start(low, high):
    """The single stop's branch in Omega over [low, high], with its continuation."""
    continuation = Continuation(STOP, "omega", low, high, n_modes=N_MODES, max_branches=1)
    return continuation, continue_orbits(continuation)


@pytest.fixture(scope="module")
def single_grazing():
    """The single stop's grazing at 201.78 rad/s followed up in F0 to 1.5e-4 N."""
    started = _single_start(195.0, 205.0)
    curve = BifurcationCurve.from_branch(*started, "grazing", "force_amplitude", 5e-5, 1.5e-4,
                                         box=(150.0, 330.0), max_points=15)
    return curve, continue_curve(curve)


def test_grazing_curve_beside_a_stop_that_never_closes_is_the_single_stops(single_grazing):
    """From the same start, the grazing curve of the tip stop with a far stop above is the
    single stop's, point by point: the maps agree to round-off (states 5e-16, monodromies
    4e-14: tests/test_orbits_several.py), so the corrector takes the same steps and lands
    where it stops, within its last correction (1e-10 of the scaled unknowns, F0 per its range
    1e-4 N: 1e-10 of F0; measured 7e-12 relative)."""
    curve, single = single_grazing
    several = continue_curve(dataclasses.replace(curve, params=FAR))
    validate(several)
    assert several.attrs["curve_contact"] == 0 and "curve_contact" not in single.attrs
    assert several.attrs["curve_ending"] == single.attrs["curve_ending"] == "bound"
    assert several.branch_point.size == single.branch_point.size >= 10
    for name in ("omega", "force_amplitude"):
        np.testing.assert_allclose(several[name].values, single[name].values, rtol=1e-10,
                                   atol=0.0)
    states = single.section_state.values
    assert np.abs(several.section_state.values - states).max() < 1e-10 * np.abs(states).max()
    # (not the contacts per orbit: each point's orbit touches at zero depth, 0 or 1 by
    # round-off)


def test_fold_curve_beside_a_stop_that_never_closes_is_the_single_stops():
    """The upper fold (317.95 rad/s at 0.1 mN) followed up in F0: the far stop's curve lies
    on the single stop's. Its points slide along the curve by up to 6e-10 of F0 (the
    pseudo-arclength planes are set by tangents from differences over 1e-8 of the state, which
    the maps' round-off moves by 1e-6 of their size: measured, the points' Omega and F0
    differ in the curve's own proportion), so each one is checked to be a fold of the single
    stop's own map (`PeriodMap`, the one-contact kernels): a fixed point and a multiplier at
    +1 to 1e-10 (each point solves the far stop's system to Newton's tolerance, its residual
    ~1e-20 at quadratic convergence, and the maps agree to 4e-14: measured 1.7e-15 of the
    state and 4.9e-15); the ends, at the same F0 on the box's edge, agree in Omega to 1e-12
    (measured 3.3e-16)."""
    started = _single_start(290.0, 322.0)
    curve = BifurcationCurve.from_branch(*started, "fold", "force_amplitude", 5e-5, 1.5e-4,
                                         box=(150.0, 330.0), max_points=15)
    single = continue_curve(curve)
    several = continue_curve(dataclasses.replace(curve, params=FAR))
    assert several.attrs["curve_ending"] == single.attrs["curve_ending"] == "bound"
    for end in (0, -1):
        assert float(several.force_amplitude[end]) == float(single.force_amplitude[end])
        assert float(several.omega[end]) == pytest.approx(float(single.omega[end]), rel=1e-12)
    for mu in _single_maps_multipliers(several, STOP):
        assert np.abs(mu - 1.0).min() < 1e-10


def _single_maps_multipliers(curve, params):
    """The multipliers at each point of ``curve`` (in Omega and F0) of ``params``' own map
    (`PeriodMap`), whose fixed point each point's orbit is checked to be (to 1e-10)."""
    for point in range(curve.branch_point.size):
        at = curve.isel(branch_point=point)
        z = at.section_state.values
        result = PeriodMap(params.replace(omega=float(at.omega),
                                          force_amplitude=float(at.force_amplitude)),
                           N_MODES)(z, directions="all", measures=False)
        assert np.linalg.norm(result.state - z) <= 1e-10 * np.linalg.norm(z)
        yield np.linalg.eigvals(result.jacobian)


# tests/test_two_parameter.py's small model (two beams, a stiff spring between the tips) with
# a second contact between the tips from above 1 mm away, which its orbits never close
SMALL_FAR = SMALL.replace(contacts=(Contact(clearance=1.1e-5),
                                    Contact(side="above", clearance=1e-3)))


@pytest.mark.parametrize(("kind", "direction"), [("period_doubling", "up"),
                                                 ("neimark_sacker", "down")])
def test_multiplier_curves_beside_a_contact_that_never_closes_are_the_single_ones(kind,
                                                                                  direction):
    """The small model's period doubling (244.73 rad/s) and Neimark-Sacker point
    (243.83 rad/s) followed up in F0 by 10 %: with the far contact, the same points to 1e-10
    relative (measured 7.4e-13), each one a period doubling (a multiplier at -1) or a
    Neimark-Sacker point (a pair on the unit circle) of the single contact's own map, to
    1e-10 (measured 9.2e-14 and 4.3e-14; fixed points to 2.2e-15 of the state)."""
    continuation = Continuation(SMALL, "omega", 236.0, 246.0, start=244.0,
                                direction=direction, n_modes=N_MODES, max_branches=1,
                                max_points=60, transient_periods=600)
    curve = BifurcationCurve.from_branch(continuation, continue_orbits(continuation), kind,
                                         "force_amplitude", 3e-5, 3.3e-5, max_points=12)
    single = continue_curve(curve)
    several = continue_curve(dataclasses.replace(curve, params=SMALL_FAR))
    assert several.branch_point.size == single.branch_point.size == 12
    for name in ("omega", "force_amplitude"):
        np.testing.assert_allclose(several[name].values, single[name].values, rtol=1e-10,
                                   atol=0.0)
    for mu in _single_maps_multipliers(several, SMALL):
        critical = (np.abs(mu + 1.0) if kind == "period_doubling"
                    else np.abs(np.abs(mu[mu.imag > 0]) - 1.0))
        assert critical.min() < 1e-10


def test_fold_curve_of_a_stop_with_a_dashpot():
    """A dashpot of 0.02 N s/m on the soft stop moves its upper fold to 308.98 rad/s (from
    317.95); followed up in F0 to 0.15 mN, every point is a fold of the stop's own map at its
    Omega and F0 (a fixed point to 1e-10 and a multiplier at +1 to 1e-10: measured 2.2e-15),
    and the end is the fold the branch in Omega at 0.15 mN locates (1e-9; measured equal)."""
    params = STOP.replace(contact_damping=0.02)
    continuation = Continuation(params, "omega", 290.0, 330.0, n_modes=N_MODES, max_branches=1)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "fold", "force_amplitude", 5e-5, 1.5e-4,
        box=(150.0, 330.0), max_points=15))
    assert curve.attrs["curve_ending"] == "bound"
    assert float(curve.omega[0]) == pytest.approx(308.98, abs=0.01)
    for mu in _single_maps_multipliers(curve, params):
        assert np.abs(mu - 1.0).min() < 1e-10
    end = curve.isel(branch_point=-1)
    (located,) = _events(params.replace(force_amplitude=1.5e-4), float(end.omega),
                         end.section_state.values, "fold")
    assert float(end.omega) == pytest.approx(float(located), rel=AGREE, abs=0.0)


# the small model with a second contact between the tips, from above 12 um away: its orbits
# from 240 rad/s up close both (2 contacts per orbit, one each)
SMALL_TWO = SMALL.replace(contacts=(Contact(clearance=1.1e-5),
                                    Contact(side="above", clearance=1.2e-5)))


# (the undamped case in the slow run: the dashpot's is the same test of both contacts closed)
@pytest.mark.parametrize("dashpot", [pytest.param(0.0, marks=pytest.mark.slow), 0.02])
def test_period_doubling_curve_with_two_contacts_closed(dashpot):
    """The period doubling of the orbits closing both contacts (245.157 rad/s; 245.192 with a
    dashpot of 0.02 N s/m on each) followed up in F0 by 10 % (Omega falls 0.19 rad/s):
    every point is a period doubling of its own map (`ContactsPeriodMap` at its Omega and
    F0, the multipliers its monodromy's eigenvalues, not the curve's bordered test): a fixed
    point to 1e-10 of the state (measured 7.7e-15) with a multiplier at -1 to 1e-10
    (measured 8.5e-14), whose run closes both contacts; at its end the branch in Omega at
    that F0 locates a period doubling at the end's frequency, to 1e-9 (measured 4.3e-15)."""
    params = SMALL_TWO.replace(contact_damping=dashpot)
    continuation = Continuation(params, "omega", 245.0, 245.4, n_modes=N_MODES,
                                max_branches=1, max_points=20, transient_periods=300)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "period_doubling", "force_amplitude",
        3e-5, 3.3e-5, box=(244.0, 246.0), step=0.1, max_step=0.25, max_points=12))
    assert curve.attrs["curve_ending"] == "bound" and float(curve.force_amplitude[-1]) == 3.3e-5
    assert float(curve.omega[0]) == pytest.approx(245.157 if dashpot == 0 else 245.192,
                                                  abs=1e-3)
    for mu in _both_closing_multipliers(curve, params):
        assert np.abs(mu + 1.0).min() < 1e-10
    end = curve.isel(branch_point=-1)
    (located,) = _events(params.replace(force_amplitude=3.3e-5), float(end.omega),
                         end.section_state.values, "period_doubling", width=0.1)
    assert float(end.omega) == pytest.approx(float(located), rel=AGREE, abs=0.0)


# the small model's contact split in two springs of half its stiffness, at the tips and 2 mm
# inward (10.7 um): orbits closing both, with Neimark-Sacker points
SMALL_SPLIT = SMALL.replace(contacts=(Contact(clearance=1.1e-5, stiffness=5e3),
                                      Contact(0.098, 0.118, clearance=1.07e-5, stiffness=5e3)))


def _neimark_sacker_curve(high, max_points):
    """SMALL_SPLIT's first Neimark-Sacker point coming down from 248 rad/s, followed in F0
    from 30 uN up to ``high`` (N)."""
    continuation = Continuation(SMALL_SPLIT, "omega", 242.0, 250.0, start=248.0,
                                direction="down", n_modes=N_MODES, max_branches=1,
                                max_points=12, transient_periods=600)
    return continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "neimark_sacker", "force_amplitude",
        3e-5, high, max_points=max_points))


@pytest.mark.slow  # (8 s; the period doubling's curve above is the fast check of two contacts)
def test_neimark_sacker_curve_with_two_contacts_closed():
    """The first Neimark-Sacker point coming down from 248 rad/s (247.24 rad/s, both contacts
    closing) followed up in F0: every point is a Neimark-Sacker point of its own map
    (`ContactsPeriodMap`'s monodromy: a complex pair on the unit circle to 1e-10, measured
    3.6e-12; a fixed point to 1e-10, measured 3.7e-15) whose run closes both contacts."""
    curve = _neimark_sacker_curve(3.2e-5, max_points=12)
    assert curve.branch_point.size == 12
    assert float(curve.omega[0]) == pytest.approx(247.237, abs=1e-3)
    for mu in _both_closing_multipliers(curve, SMALL_SPLIT):
        assert np.abs(np.abs(mu[mu.imag > 0]) - 1.0).min() < 1e-10


@pytest.mark.slow  # (18 s; the period doubling's curve above is the fast check of an end)
def test_neimark_sacker_curve_with_two_contacts_ends_on_the_branchs_point():
    """The same Neimark-Sacker curve followed up to the box edge F0 = 31 uN (23 points,
    "bound"; Omega falls from 247.237 to 247.094 rad/s): at the end's F0 the one-parameter
    branch in Omega through the end's frequency, a continuation of its own (started 0.1 rad/s
    below from the end's orbit, which is only its guess), locates one Neimark-Sacker point,
    at the end's frequency to 1e-9 (the curve's Newton and the branch's location tolerances,
    as AGREE; measured 8.1e-16 relative)."""
    curve = _neimark_sacker_curve(3.1e-5, max_points=40)
    assert curve.attrs["curve_ending"] == "bound" and float(curve.force_amplitude[-1]) == 3.1e-5
    end = curve.isel(branch_point=-1)
    assert float(end.omega) < float(curve.omega[0]) - 0.1
    (located,) = _events(SMALL_SPLIT.replace(force_amplitude=3.1e-5), float(end.omega),
                         end.section_state.values, "neimark_sacker", width=0.1)
    assert float(end.omega) == pytest.approx(float(located), rel=AGREE, abs=0.0)


def _both_closing_multipliers(curve, params):
    """The multipliers at each point of ``curve`` (in Omega and F0) of ``params``' own map
    (`ContactsPeriodMap`), whose fixed point each point's orbit is checked to be (to 1e-10)
    and whose run is checked to close both contacts."""
    for point in range(curve.branch_point.size):
        at = curve.isel(branch_point=point)
        z = at.section_state.values
        result = ContactsPeriodMap(params.replace(
            omega=float(at.omega), force_amplitude=float(at.force_amplitude)), N_MODES)(
            z, directions="all", measures=False)
        assert np.linalg.norm(result.state - z) <= 1e-10 * np.linalg.norm(z)
        assert np.bitwise_or.reduce(np.asarray(result.trajectory.mask, dtype=int)) == 0b11
        yield np.linalg.eigvals(result.jacobian)


def _events(params, omega, state, label, width=0.3):
    """The ``label`` events the branch in Omega over ``omega`` +- ``width`` locates, started
    at ``omega - width`` from ``state`` (the guess only: the events are the branch's own)."""
    branch = continue_orbits(Continuation(params, "omega", omega - width, omega + width,
                                          state=state, n_modes=N_MODES, max_branches=1,
                                          transient_periods=0))
    return branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index(label)]


@pytest.fixture(scope="module")
def clearance_spec():
    """The mid-span stop's grazing (209.83 rad/s, both stops closed past it) followed up in
    its own clearance to 4.1 um (the command's file below)."""
    continuation = Continuation(TWO, "omega", 205.0, 215.0, n_modes=N_MODES, max_branches=1)
    branch = continue_orbits(continuation)
    return BifurcationCurve.from_branch(continuation, branch, "grazing",
                                        "contacts.1.clearance", 3e-6, 4.1e-6, max_points=10)


@pytest.fixture(scope="module")
def clearance_file(clearance_spec, tmp_path_factory):
    """The curve's file written by an uninterrupted call."""
    out = tmp_path_factory.mktemp("uninterrupted") / "curve.nc"
    continue_curve(clearance_spec, None, out)
    return out


@pytest.fixture(scope="module")
def clearance_curve(clearance_file):
    with xr.open_dataset(clearance_file) as dataset:
        return dataset.load()


def test_an_interrupted_curve_of_several_contacts_resumes_to_the_same_file(
        clearance_spec, clearance_file, tmp_path):
    """Interrupted at its second point (Ctrl-C) and called again, the curve ends with the
    uninterrupted call's file, bit for bit: the contact it follows is its start's again."""
    out = tmp_path / "out.nc"
    with pytest.raises(ContinuationInterrupted) as interrupted:
        continue_curve(clearance_spec, _stop_after(2), out)
    assert interrupted.value.dataset.attrs["curve_contact"] == 1
    assert saved_points(out) >= 1  # resumed from them
    continue_curve(clearance_spec, None, out)
    assert_same_map(out, clearance_file)


def test_grazing_curve_of_the_second_contact_in_its_clearance(clearance_curve):
    """Both stops closed: the mid-span stop's grazing (209.83 rad/s: 1 to 2 contacts per
    orbit) followed in its own clearance, ``contacts.1.clearance``, to 4.1 um. The curve
    follows that stop (``curve_contact`` 1), and at its end the branch in Omega at that
    clearance locates a grazing at the end's frequency (measured 2.5e-14 relative). The gap
    is the stop's physical one, the tip stop's force deflecting it through the flexibility
    the modes miss: read from the free coordinates alone, the end was 1.7e-4 off."""
    name = "contacts.1.clearance"
    curve = clearance_curve
    validate(curve)
    assert curve.attrs["curve_contact"] == 1 and curve.attrs["curve_ending"] == "bound"
    assert curve.attrs["curve_parameters"] == f"omega {name}"
    assert curve[name].attrs["long_name"].endswith(" of contacts[1]")
    end = curve.isel(branch_point=-1)
    assert float(end[name]) == 4.1e-6 and 1 <= int(end.contacts_per_orbit) <= 2
    params = with_parameter(TWO, name, 4.1e-6)
    (located,) = _events(params, float(end.omega), end.section_state.values, "grazing")
    assert float(end.omega) == pytest.approx(located, rel=AGREE, abs=0.0)


# TWO with a dashpot on each stop (0.02 N s/m): the tip stop's is closed on every orbit
DASHPOTS = TWO.replace(contacts=tuple(dataclasses.replace(c, damping=0.02) for c in TWO.contacts))


# (the curve's steps scale with its box: the wide box's 10 points reach 2.7 times the damping)
@pytest.mark.parametrize(("box", "max_points", "reach"), [
    ((209.0, 211.0), 4, 0.022),
    pytest.param((205.0, 215.0), 10, 0.05, marks=pytest.mark.slow)])  # 12 s
def test_grazing_curve_in_the_closed_contacts_dashpot(box, max_points, reach):
    """The mid-span stop's grazing (209.796 rad/s) with the tip stop closed on the orbit,
    followed in the tip stop's own damping, ``contacts.0.damping``, from 0.02 N s/m up. At
    every point, the map built at its Omega and damping (`ContactsPeriodMap`) has the point's
    orbit as a fixed point to 1e-8 of the state in the energy norm (the curve's Newton stops
    at 1e-10 of its scaled unknowns, the state per ``state_scale``, 10 clearances = 40 um of
    tip motion, several times the orbit's; measured 5.5e-15, and 1.3e-9 at one point of the
    wide box) whose run closes the tip stop, and its grazing contact's least physical gap,
    the stop's gap with the tip stop's force (spring and dashpot) deflecting it, is 0 to
    1e-10 of the stop's 4 um clearance (Newton's tolerance on the curve's scaled unknowns;
    measured 1.3e-20 m). Independently,
    `simulate` of one period from the point's state, sampled 4096 times: the stop never
    pushes, its sampled gap never falls below 0 (round-off: 1e-18 m) and comes within
    1e-6 of the gap's range of it (a quadratic touch sampled dt apart misses by at most
    (pi / 4096)^2 / 2 = 2.9e-7 of that; measured 2e-12 m)."""
    name = "contacts.0.damping"
    continuation = Continuation(DASHPOTS, "omega", 209.7, 209.9, n_modes=N_MODES, step=0.05,
                                max_branches=1)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "grazing", name, 0.02, 0.2, box=box,
        max_points=max_points))
    assert curve.attrs["curve_contact"] == 1 and curve.branch_point.size == max_points
    assert float(curve[name][-1]) > reach
    for point in range(curve.branch_point.size):
        at = curve.isel(branch_point=point)
        params = with_parameter(DASHPOTS.replace(omega=float(at.omega)), name, float(at[name]))
        period_map, z = ContactsPeriodMap(params, N_MODES), at.section_state.values
        result, scale = period_map(z, measures=False), map_energy_scale(period_map)
        assert (np.linalg.norm(scale * (result.state - z))
                <= 1e-8 * np.linalg.norm(scale * z))
        assert np.bitwise_or.reduce(np.asarray(result.trajectory.mask, dtype=int)) & 1
        assert abs(period_map.least_gap(result, 1)) < 1e-10 * 4e-6
        period = 2 * math.pi / params.omega
        run = simulate(params, period, N_MODES, times=np.linspace(0.0, period, 4097),
                       initial_state=z)
        gap = run.contact_gaps.sel(contact=1).values
        assert np.all(run.contact_forces.sel(contact=1).values == 0.0)
        assert -1e-18 < gap.min() < 1e-6 * np.ptp(gap)


def test_grazing_curve_from_a_branch_in_one_contacts_clearance():
    """The contact's field as the first parameter: the branch in ``contacts.1.clearance`` at
    212 rad/s locates the mid-span stop's grazing (4.098 um); followed up in Omega to
    212.5 rad/s, the curve's end is the grazing that the branch in that clearance at 212.5
    rad/s locates (started 0.02 um below the end's, from its orbit; measured 2.1e-15
    relative)."""
    name = "contacts.1.clearance"
    continuation = Continuation(TWO.replace(omega=212.0), name, 3e-6, 5e-6, direction="down",
                                n_modes=N_MODES, max_branches=1)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, continue_orbits(continuation), "grazing", "omega", 211.0, 212.5,
        max_points=10))
    assert curve.attrs["curve_parameters"] == f"{name} omega"
    assert curve.attrs["curve_contact"] == 1 and curve.attrs["curve_ending"] == "bound"
    end = curve.isel(branch_point=-1)
    assert float(end.omega) == 212.5
    clearance = float(end[name])
    branch = continue_orbits(Continuation(
        TWO.replace(omega=212.5), name, clearance - 2e-8, clearance + 2e-8,
        state=end.section_state.values, n_modes=N_MODES, max_branches=1, transient_periods=0))
    (located,) = branch[name].values[branch.bifurcation.values == BIFURCATIONS.index(
        "grazing")]
    assert clearance == pytest.approx(float(located), rel=AGREE, abs=0.0)


def test_fold_curve_with_two_contacts_closed():
    """The upper fold of the orbits with both stops closed (323.55 rad/s, 2 contacts per
    orbit) followed up in F0 to 0.102 mN: at its end the branch in Omega at that force
    locates a fold at the end's frequency (measured 8.9e-16 relative)."""
    continuation = Continuation(TWO, "omega", 280.0, 330.0, n_modes=N_MODES, max_branches=1,
                                max_points=80)  # up to just past the fold
    branch = continue_orbits(continuation)
    curve = continue_curve(BifurcationCurve.from_branch(
        continuation, branch, "fold", "force_amplitude", 1e-4, 1.02e-4, step=0.1, max_step=0.2,
        max_points=20))
    assert curve.attrs["curve_ending"] == "bound" and "curve_contact" not in curve.attrs
    assert np.all(curve.contacts_per_orbit.values == 2)
    end = curve.isel(branch_point=-1)
    assert float(end.force_amplitude) == 1.02e-4
    located = _events(TWO.replace(force_amplitude=1.02e-4), float(end.omega),
                      end.section_state.values, "fold")
    assert float(end.omega) == pytest.approx(float(located[0]), rel=AGREE, abs=0.0)
    assert list(np.flatnonzero(curve.curve_event.values)) == [curve.branch_point.size - 1]
    assert CURVE_EVENTS[int(end.curve_event)] == "end"


@pytest.mark.parametrize(("changes", "message"), [
    ({"second": "clearance"}, "second = 'clearance' is not allowed: with 2 contacts each "
     "gives its own: continue one contact's as 'contacts.INDEX.FIELD'"),
    ({"second": "contacts.2.clearance"}, "second = 'contacts.2.clearance' is not allowed: "
     "there are 2 contacts (indices 0 to 1)"),
    ({"parameter": "contacts.0.position1"}, "parameter = 'contacts.0.position1' is not "
     "allowed: a contact's continuable fields are clearance, stiffness, damping"),
    ({"second": "contacts.0.clearance", "params": STOP}, "second = 'contacts.0.clearance' is "
     "not allowed: continues a field of one of several contacts, and params has one or none"),
    ({"second": "contacts.1.clearance", "low": 1e-6, "high": 3e-6},
     "contacts.1.clearance = 4e-06 is not allowed: (the start's, from params) must lie in "
     "[1e-06, 3e-06]"),
])
def test_bad_input_with_several_contacts_in_one_line(changes, message):
    values = {"params": TWO, "kind": "grazing", "parameter": "omega", "value": 300.0,
              "state": np.zeros(6), "second": "force_amplitude", "low": 5e-5, "high": 3e-4,
              "parameter_low": 200.0, "parameter_high": 400.0, "n_modes": N_MODES, **changes}
    with pytest.raises(ParameterError) as error:
        BifurcationCurve(**values)
    assert message in str(error.value) and "\n" not in str(error.value)


CURVE_FILE = "n_modes = 3\n" + TWO_TOML + """[continuation]
parameter = "omega"
min = 205.0
max = 215.0
max_branches = 1
[curve]
kind = "grazing"
second = "contacts.1.clearance"
min = 3e-6
max = 4.1e-6
max_points = 10
"""


def test_the_command_follows_a_curve_of_several_contacts(clearance_curve, tmp_path):
    """`impactbeams continue` with ``[[params.contacts]]`` and a ``[curve]``: the file is the
    Python call's curve, bit for bit."""
    from impactbeams.cli import main

    path, out = tmp_path / "two.toml", tmp_path / "two.nc"
    path.write_text(CURVE_FILE)
    assert main(["continue", str(path), "-o", str(out), "--quiet"]) == 0
    expected = clearance_curve
    with xr.open_dataset(out) as written:
        validate(written)
        assert written.attrs["curve_contact"] == 1
        for name in ("omega", "contacts.1.clearance", "section_state"):
            np.testing.assert_array_equal(written[name].values, expected[name].values)


def test_a_flat_contact_key_in_the_curve_table_is_one_line(tmp_path, capsys):
    from impactbeams.cli import main

    path, out = tmp_path / "two.toml", tmp_path / "two.nc"
    path.write_text(CURVE_FILE.replace('second = "contacts.1.clearance"',
                                       'second = "clearance"'))
    assert main(["continue", str(path), "-o", str(out)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("impactbeams: error: second = 'clearance' is not allowed: with 2 "
                           "contacts each gives its own")
    assert not out.exists()
