"""The claims of docs/tutorial-hysteresis.md, checked apart from the page's own code.

The model is the shipped sweeps/continuation-stop-fold.toml (beam 1 against a soft stop, 5 modes,
zeta = 0.02, F0 = 0.1 mN). Three independent computations meet: the continuation's folds and
grazings (Newton on the exact period map), stepped-sine sweeps (time stepping from cell to
cell) and the closed-form grazing curve of the linear response; the fold and grazing curves
in (Omega, F0) by continuation against one-parameter branches' folds and the closed form; and
the basin map's attractors (run on from its initial states) against the sweeps' end states.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactbeams as ib
from impactbeams.continuation import continue_orbits, load_continuation
from impactbeams.longtime import hysteresis
from impactbeams.sweep import run_sweep, sweep_from_mapping
from impactbeams.variables import BIFURCATIONS

EXAMPLE = Path(__file__).parents[1] / "sweeps" / "continuation-stop-fold.toml"
N_MODES = 5
FIXED = ("counterpart", "contact_stiffness", "damping_ratio")
# the page's sweeps: 0.1 rad/s over the band, 1000 periods of dwell (300 leave the up sweep on
# the vanished branch 0.05 rad/s past the upper fold: the fold's bottleneck); 2.5 rad/s over
# the whole range at 20 force levels, 300 periods
FINE = {"min": 275.0, "max": 325.0, "num": 501}
FINE_DWELL = 1000
PLANE = {"force_amplitude": {"min": 1e-5, "max": 2e-4, "num": 20},
         "omega": {"min": 150.0, "max": 450.0, "num": 121}}
# The continuation locates its grazings to 1e-11 of the range on orbits corrected to 1e-10 of
# the state; the closed form sums the same modal terms (tests/test_grazing_curve.py)
LOCATED = 1e-9
# a sweep's end state after 1000 periods of dwell has lost its transient (|mu|^1000 < 1e-30
# at 300 rad/s, |mu| < 0.92); a basin attractor is run on to 1e-10 of its state
SAME_STATE = 1e-9


@pytest.fixture(scope="module")
def example():
    return load_continuation(EXAMPLE)


@pytest.fixture(scope="module")
def branch(example) -> xr.Dataset:
    return continue_orbits(example)


def located(branch: xr.Dataset, label: str) -> np.ndarray:
    return np.sort(branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index(label)])


def stepped(example, axes: dict, dwell: int, drive: bool = True) -> xr.Dataset:
    params = example.params.as_dict()
    keys = FIXED + (("force_amplitude",) if drive else ())
    return run_sweep(sweep_from_mapping({
        "n_modes": N_MODES, "transient_periods": dwell, "sampled_periods": 2,
        "stepping": "both", "axes": axes, "params": {key: params[key] for key in keys},
        "observables": ["poincare_deflection1", "poincare_velocity1", "steady_impact_rate"]}))


@pytest.fixture(scope="module")
def fine(example) -> xr.Dataset:
    return stepped(example, {"omega": FINE}, FINE_DWELL)


def test_the_fine_sweeps_jump_within_one_step_of_the_folds(branch, fine):
    """Up: on the impacting branch at the last cell below the upper fold, off it at a cell
    within one step past it; down: on the small orbit above the lower fold, jumped at a cell
    within one step of it."""
    lower, upper = located(branch, "fold")
    step = float(fine.omega[1] - fine.omega[0])
    band = fine.omega.values[hysteresis(fine).values]
    assert band.size > 300  # one band, between the folds
    assert np.all(np.diff(band) == pytest.approx(step))
    up_stays, up_drops = band[-1], band[-1] + step
    down_stays, down_jumps = band[0], band[0] - step
    assert up_stays < upper and abs(up_drops - upper) < step
    assert down_stays > lower and abs(down_jumps - lower) < step


def test_the_dwell_decides_the_last_cell_below_the_upper_fold(example, branch):
    """With 300 periods instead of 1000 the up sweep is still on the impacting response at
    the first cell past the upper fold (the page's point about the dwell)."""
    upper = located(branch, "fold")[1]
    short = stepped(example, {"omega": FINE}, 300)
    last = short.omega.values[hysteresis(short).values][-1]
    assert 0.0 < last - upper < float(short.omega[1] - short.omega[0])


@pytest.fixture(scope="module")
def plane(example) -> xr.Dataset:
    return stepped(example, PLANE, 300, drive=False)


def test_impacts_start_within_a_step_of_the_closed_form_curve(example, branch, plane):
    """Over (Omega, F0): no impact at a level the linear response never lifts to the stop;
    every cell inside the grazing curve impacts both ways; swept up, impacts start at the first
    cell past the curve's lower branch; swept down, within one step of its upper branch, and
    where a cell above it impacts the up sweep impacts there too (the coexisting response);
    where only the up sweep impacts is right of the curve, where only the down sweep is left.
    At the example's level only the up sweep impacts exactly at the cells between its
    branch's folds."""
    impacts = plane.steady_impact_rate > 0
    omega = plane.omega.values
    step = omega[1] - omega[0]
    levels_with_roots = 0
    for force in plane.force_amplitude.values:
        roots = ib.grazing_frequencies(example.params.replace(force_amplitude=force), N_MODES,
                                       omega[0], omega[-1]).omega.values
        up, down = (impacts.sel(sweep_direction=direction, force_amplitude=force).values
                    for direction in ("up", "down"))
        if roots.size == 0:
            assert not up.any() and not down.any(), force
            continue
        levels_with_roots += 1
        low = roots[0] if roots.size == 2 else omega[0]
        within = (omega > low) & (omega < roots[-1])
        assert up[within].all() and down[within].all(), force
        if roots.size == 2:
            assert 0.0 < omega[up].min() - roots[0] < step, force
        onset = omega[down].max()
        assert abs(onset - roots[-1]) < step, force
        if onset > roots[-1]:
            assert up[omega == onset].all(), force
        assert np.all(omega[up & ~down] > roots[-1]), force
        assert np.all(omega[down & ~up] < low), force
    assert levels_with_roots == 19
    only_up = (impacts.sel(sweep_direction="up") & ~impacts.sel(sweep_direction="down")).sel(
        force_amplitude=example.params.force_amplitude, method="nearest").values
    lower, upper = located(branch, "fold")
    np.testing.assert_array_equal(omega[only_up], omega[(omega > lower) & (omega < upper)])


def test_the_continuations_grazings_lie_on_the_closed_form_curve(example, branch):
    grazings = located(branch, "grazing")
    assert grazings.size == 2
    curve = ib.grazing_curve(example.params, N_MODES, "force_amplitude", grazings)
    np.testing.assert_allclose(curve.force_amplitude.values, example.params.force_amplitude,
                               rtol=LOCATED, atol=0.0)


def test_the_basins_attractors_are_the_sweeps_ends(example, fine):
    """At 300 rad/s the basin map finds two attractors, the up sweep's end state (impacting)
    and the down sweep's (not), each to SAME_STATE."""
    inside = float(fine.omega.sel(omega=300.0, method="nearest"))
    starts = (np.linspace(-4e-5, 4e-5, 15), np.linspace(-1.2e-2, 1.2e-2, 15))
    basins = ib.basins(example.params.replace(omega=inside), starts, n_modes=N_MODES)
    assert basins.sizes["attractor"] == 2
    attractors = np.concatenate([basins.attractor_displacement, basins.attractor_velocity], 1)
    for direction, contacts in (("up", 1), ("down", 0)):
        end = fine.sel(sweep_direction=direction, omega=inside)
        state = np.concatenate([end.final_displacement.values, end.final_velocity.values])
        (k,) = np.flatnonzero(basins.attractor_contacts.values == contacts)
        scale = np.abs(attractors[k]).max()
        assert np.abs(state - attractors[k]).max() < SAME_STATE * scale, direction
    assert np.all(basins.basin.values >= 0)  # every start settled


@pytest.mark.parametrize("force", [4e-5, 7e-5, 1e-4, 1.3e-4])
def test_the_up_sweeps_last_impact_within_a_step_below_the_upper_fold(example, plane, force):
    """The right edge of the region where only the up sweep impacts: at four levels, the
    upper fold of that level's one-parameter branch lies within one step above the up sweep's
    last impacting cell."""
    level = continue_orbits(dataclasses.replace(
        example, params=example.params.replace(force_amplitude=force), max_branches=1))
    upper = located(level, "fold").max()
    up = (plane.steady_impact_rate > 0).sel(sweep_direction="up").sel(
        force_amplitude=force, method="nearest")
    assert float(up.force_amplitude) == pytest.approx(force, rel=1e-12)
    omega = plane.omega.values
    assert 0.0 < upper - omega[up.values].max() < omega[1] - omega[0]


def _curve(example, branch, kind, low, high, direction):
    from impactbeams.continuation import BifurcationCurve, continue_curve

    return continue_curve(BifurcationCurve.from_branch(
        example, branch, kind, "force_amplitude", low, high, direction=direction,
        max_points=400))


@pytest.mark.parametrize("direction", ["up", "down"])
def test_the_continued_grazing_curves_are_the_closed_form(example, branch, direction):
    """The page's grazing curves in F0, from the branch's first grazing up to the map's top
    level and down (round the resonance), against the closed form at every point."""
    curve = _curve(example, branch, "grazing", 1e-6, PLANE["force_amplitude"]["max"],
                   direction)
    closed = ib.grazing_curve(example.params, N_MODES, "force_amplitude", curve.omega.values)
    np.testing.assert_allclose(curve.force_amplitude.values, closed.force_amplitude.values,
                               rtol=LOCATED, atol=0.0)


@pytest.mark.parametrize(("force", "fold"), [(4e-5, "upper"), (7e-5, "upper"),
                                             (1.3e-4, "upper"), (1e-4, "lower")])
def test_the_fold_curve_ended_on_a_level_is_that_levels_fold(example, branch, force, fold):
    """The upper fold's curve, ended on a drive level (the box's edge), is at the fold that
    level's own one-parameter branch locates; followed down past the cusp and back up to the
    example's level, at the branch's lower fold."""
    start = example.params.force_amplitude
    low, high, direction = ((1e-6, start, "down") if fold == "lower" else
                            (force, start, "down") if force < start else (start, force, "up"))
    curve = _curve(example, branch, "fold", low, high, direction)
    end = curve.isel(branch_point=-1)
    assert curve.attrs["curve_ending"] == "bound" and float(end.force_amplitude) == force
    level = continue_orbits(dataclasses.replace(
        example, params=example.params.replace(force_amplitude=force), max_branches=1))
    lower, upper = located(level, "fold")
    expected = upper if fold == "upper" else lower
    assert float(end.omega) == pytest.approx(expected, rel=LOCATED, abs=0.0)
    if fold == "lower":  # reached past the cusp, where the band closes
        from impactbeams.variables import CURVE_EVENTS

        codes = curve.curve_event.values
        assert [CURVE_EVENTS[code] for code in codes[codes > 0]] == ["cusp", "end"]
