"""Continuation against stepped-sine sweeps (issue 22): the stable parts of the branch equal the
shaker's up and down sweeps, and the sweeps jump at the branch's folds.

The case is the shipped sweeps/continuation-stop-fold.toml (a cantilever against a soft stop,
5 modes, zeta = 0.02, F0 = 0.1 mN) over Omega = 275..325 rad/s: the impacting resonance rises to
the upper fold (317.95 rad/s), returns unstable to the lower fold (282.60 rad/s, where it meets
the non-impacting response at a grazing) and the non-impacting response continues stable above.
The stepped sweep runs up and down over 275, 277.5, ..., 325 rad/s, a grid whose cells past
each fold are 2 rad/s or more beyond it. Nearer, two things hold a sweep back that are not a
disagreement with the branch (measured with 2 rad/s grids): 0.05 rad/s past the upper fold the
up sweep still drifts along the vanished branch after 300 periods (the fold's bottleneck); at
283 rad/s, 0.4 rad/s above the lower fold, the non-impacting orbit passes 8e-8 m (0.75 % of the
clearance) from the stop and the transient of the 2 rad/s step from 285 reaches it: the down
sweep jumps one cell early onto the impacting branch, which coexists there.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from impactbeams.continuation import continue_orbits, load_continuation
from impactbeams.orbits import PeriodicOrbit, periodic_orbit
from impactbeams.sweep import run_sweep, sweep_from_mapping
from impactbeams.variables import BIFURCATIONS

EXAMPLE = Path(__file__).parents[1] / "sweeps" / "continuation-stop-fold.toml"
LOW, HIGH = 275.0, 325.0
DWELL = 300  # forcing periods at each stepped cell before it is sampled
STEPPED = {"n_modes": 5, "transient_periods": DWELL, "sampled_periods": 2, "stepping": "both",
           "observables": ["poincare_deflection1", "poincare_velocity1"],
           "axes": {"omega": {"min": LOW, "max": HIGH, "num": 21}}}
# The transient of a cell (after a jump: an offset as large as the response) decays by the
# cell's leading Floquet multiplier per period, |mu|^DWELL: the free modes' damping
# exp(-zeta omega_1 T) = 0.89..0.91 per period away from the folds (zeta omega_1 = 4.9 /s),
# 1e-15..1e-12 after 300 periods; near the folds more (0.96 at 317.5 rad/s, 0.45 rad/s below
# the upper fold: 5e-6, where the step's transient is small, not a jump).
# Bound: the scale times that decay times a margin of 10 for the transient's non-normal growth,
# and no less than 1e-10 of the scale (the orbits' Newton tolerance, 1e-11, and round-off).
MARGIN, FLOOR = 10.0, 1e-10
# folds and grazings located to locate_tolerance = 1e-11 of the range (5e-10 to 2e-9 rad/s
# here) on orbits corrected to 1e-10 of state_scale; measured spread over the starts: 1.4e-9
LOCATED = 1e-8  # rad/s
# the grazing gap at a grazing label: its rate along the branch, 3.2e-7 m per rad/s near
# 282.74 rad/s, times LOCATED is 3e-15 m, 3e-10 of the clearance (measured: at most 5e-16 m)
GRAZING_GAP = 1e-9  # of the clearance


@pytest.fixture(scope="module")
def branch() -> xr.Dataset:
    """The example's branch over [LOW, HIGH], started at LOW from rest (the impacting orbit)."""
    continuation = load_continuation(EXAMPLE)
    return continue_orbits(dataclasses.replace(continuation, low=LOW, high=HIGH))


@pytest.fixture(scope="module")
def stepped() -> xr.Dataset:
    """The up and down stepped-sine sweeps with the example's fixed parameters."""
    params = load_continuation(EXAMPLE).params.as_dict()
    fixed = {key: params[key] for key in ("counterpart", "contact_stiffness", "damping_ratio",
                                          "force_amplitude")}
    return run_sweep(sweep_from_mapping({**STEPPED, "params": fixed}))


@pytest.fixture(scope="module")
def other_starts() -> dict[str, xr.Dataset]:
    """The example's branch through the band from other starts and directions."""
    continuation = load_continuation(EXAMPLE)
    return {
        # up from 260 over 260..450: its steps once overshot the lower fold and stopped
        # short of the grazing behind it, labelling a point still in contact (gap -1.02e-8 m)
        "up from 260": continue_orbits(dataclasses.replace(continuation, low=260.0)),
        # down from the non-impacting orbit: the grazing first, then the fold behind it
        "down from 340": continue_orbits(dataclasses.replace(
            continuation, low=LOW, high=340.0, direction="down")),
    }


def located(branch: xr.Dataset, label: str) -> np.ndarray:
    """The parameter values labelled ``label``, in increasing order."""
    return np.sort(branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index(label)])


def test_the_same_folds_and_grazing_whichever_start(branch, other_starts):
    """The two folds and the grazing just above the lower fold (282.7394 rad/s, where the
    returning branch leaves the stop) are the same from every start; every grazing label
    has a gap of zero (to GRAZING_GAP) and neighbours with different contacts per orbit."""
    clearance = load_continuation(EXAMPLE).params.clearance
    for name, other in {"up from 275": branch, **other_starts}.items():
        for label in ("fold", "grazing"):
            np.testing.assert_allclose(located(other, label), located(branch, label),
                                       rtol=0.0, atol=LOCATED, err_msg=f"{name}: {label}")
        contacts = other.contacts_per_orbit.values
        for i in np.flatnonzero(other.bifurcation.values == BIFURCATIONS.index("grazing")):
            assert abs(float(other.grazing_gap[i])) < GRAZING_GAP * clearance, name
            assert contacts[i - 1] != contacts[i + 1], name
    assert located(branch, "grazing").size == 1


def folds(branch: xr.Dataset) -> tuple[float, float]:
    """(lower, upper) fold frequencies from the branch's labels."""
    located = branch.omega.values[branch.bifurcation.values == BIFURCATIONS.index("fold")]
    assert located.size == 2
    return float(located.min()), float(located.max())


def parts(branch: xr.Dataset) -> list[tuple[bool, np.ndarray]]:
    """The branch cut into its stable and unstable parts: (stable, indices of its points)."""
    stable = branch.stable.values.astype(bool)
    cuts = np.flatnonzero(np.diff(stable.astype(int))) + 1
    return [(bool(stable[run[0]]), run) for run in np.split(np.arange(stable.size), cuts)]


def orbit_at(branch: xr.Dataset, run: np.ndarray, omega: float) -> PeriodicOrbit | None:
    """The orbit at ``omega`` corrected from the nearest point of a part, None if the part does
    not reach ``omega``."""
    omegas = branch.omega.values[run]
    if not omegas.min() <= omega <= omegas.max():
        return None
    nearest = run[np.argmin(abs(omegas - omega))]
    params = dataclasses.replace(load_continuation(EXAMPLE).params, omega=omega)
    return periodic_orbit(params, 5, guess=branch.section_state.values[nearest], measures=False)


def section(orbit: PeriodicOrbit) -> np.ndarray:
    """The orbit's (y1, v1 / Omega) at the tip on the section (m), as the sweep samples it."""
    start = orbit.to_dataset(1).isel(time=0)
    return np.array([start.tip_deflection_1, start.tip_velocity_1 / orbit.params.omega])


@pytest.fixture(scope="module")
def matched(branch, stepped):
    """Per direction, per cell: (index of the part of the branch the samples equal, their
    distance to it, its bound, the distance to the unstable orbit at that Omega or inf)."""
    samples = np.stack([stepped.poincare_deflection1,
                        stepped.poincare_velocity1 / stepped.omega], axis=-1)
    scale = np.abs(samples).max()
    found = {}
    for cell, omega in enumerate(stepped.omega.values):
        orbits = {number: orbit_at(branch, run, float(omega))
                  for number, (_, run) in enumerate(parts(branch))}
        orbits = {number: orbit for number, orbit in orbits.items() if orbit is not None}
        for direction in ("up", "down"):
            sample = samples[list(stepped.sweep_direction.values).index(direction), cell]
            distance = {number: np.abs(sample - section(orbit)).max() / scale
                        for number, orbit in orbits.items()}
            stable = {number: orbit for number, orbit in orbits.items() if orbit.stable}
            nearest = min(stable, key=distance.get)
            decay = np.abs(stable[nearest].multipliers).max() ** DWELL
            unstable = [distance[n] for n, orbit in orbits.items() if not orbit.stable]
            found[direction, cell] = (nearest, distance[nearest], max(MARGIN * decay, FLOOR),
                                      min(unstable, default=np.inf))
    return found


def test_every_stepped_cell_equals_a_stable_orbit_of_the_branch(stepped, matched):
    """(a) each sample equals the stable orbit of the branch at its Omega (corrected from the
    part's nearest point), within the dwell's leftover transient."""
    for (direction, cell), (_, distance, bound, _) in matched.items():
        assert distance < bound, (direction, float(stepped.omega[cell]), distance, bound)


def test_the_sweeps_jump_between_the_cells_bracketing_the_folds(branch, stepped, matched):
    """(b) swept up, the response stays on the impacting part up to the last cell below the
    upper fold and is on the non-impacting part from the first cell above it; swept down, it
    stays on the non-impacting part down to the first cell above the lower fold."""
    lower, upper = folds(branch)
    omega = stepped.omega.values
    impacting = next(n for n, (stable, run) in enumerate(parts(branch))
                     if stable and branch.omega.values[run].min() <= LOW)
    for direction, fold in (("up", upper), ("down", lower)):
        on_impacting = np.array([matched[direction, cell][0] == impacting
                                 for cell in range(omega.size)])
        np.testing.assert_array_equal(on_impacting, omega < fold, err_msg=direction)
    assert 1 < omega[omega < lower].size and omega[omega > upper].size > 1  # jumps inside


def test_no_stepped_cell_lies_on_an_unstable_part(matched):
    """(c) where the unstable orbit exists, every sample is far from it (the nearest passes
    at 1e-2 of the scale, the samples equal their stable orbit to 1e-10 or better)."""
    apart = [unstable for (_, _, _, unstable) in matched.values() if np.isfinite(unstable)]
    assert len(apart) > 10 and min(apart) > 1e-3
