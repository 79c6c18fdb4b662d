"""Stepped long-time sweeps of several contacts (issue 33, item 5).

Each cell of a row starts from the state its predecessor ended in, as `simulate` starts from
that ``initial_state``. The runs: `tests/test_orbits_several.py`'s stops (8 modes,
k = 1e4 N/m, zeta = 0.05, F0 = 1 mN at the tip), 20 transient and 4 sampled periods a cell.
"""

import math
import warnings

import numpy as np
import pytest

from impactbeams import ParameterError, simulate
from impactbeams.sweep import run_sweep, sweep_from_mapping
from test_orbits_several import MID, N_MODES

BASE = {"counterpart": "stop", "contact_stiffness": 1e4, "damping_ratio": 0.05,
        "force_amplitude": 1e-3}
STEPPED = {"t_max": 0.1, "n_modes": N_MODES, "transient_periods": 20, "sampled_periods": 4,
           "stepping": "both",
           "observables": ["poincare_deflection1", "poincare_velocity1", "steady_impact_rate",
                           "response_period"],
           "axes": {"omega": {"min": 380.0, "max": 420.0, "num": 3}}}
TOGETHER = [{"position1": MID, "clearance": 1e-6}, {"clearance": 2e-6}]
SERIES = ("poincare_deflection1", "poincare_velocity1", "steady_impact_rate",
          "final_displacement", "final_velocity")


def run(definition):
    with warnings.catch_warnings():  # 8 modes do not resolve k (their own advice)
        warnings.filterwarnings("ignore", "n_modes = 8 does not resolve", RuntimeWarning)
        return run_sweep(sweep_from_mapping(definition))


@pytest.mark.parametrize(("axis", "values"), [
    ("omega", {"min": 380.0, "max": 420.0, "num": 3}),
    ("contacts.1.clearance", {"min": 1e-6, "max": 3e-6, "num": 3})])
def test_each_stepped_cell_is_simulate_from_its_predecessors_end_state(axis, values):
    """Up and down, along Omega or one contact's clearance: every cell after a row's first is
    `simulate` of its parameters from the stored end state of the cell before it, bit for
    bit (the same packing, start and run); the first from rest."""
    contacts = [dict(each) for each in TOGETHER]
    if axis != "omega":
        del contacts[1]["clearance"]
    fixed = {**BASE, "contacts": contacts} | ({} if axis == "omega" else {"omega": 400.0})
    definition = {**STEPPED, "stepped_axis": axis, "axes": {axis: values}, "params": fixed}
    sweep = sweep_from_mapping(definition)
    maps = run(definition)
    assert np.all(maps.dynamics_status == 0) and np.all(maps.steady_impact_rate > 0)
    horizon = sweep.long_time.horizon
    for direction in ("up", "down"):
        row = maps.sel(sweep_direction=direction)
        order = range(3) if direction == "up" else range(2, -1, -1)
        before = None
        for k in order:
            cell = row.isel({axis: k})
            params = sweep.params_at({axis: float(cell[axis])})
            state = (None if before is None else
                     np.concatenate([before.final_displacement, before.final_velocity]))
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", "n_modes = 8", RuntimeWarning)
                alone = simulate(params, horizon(params.omega, 20), N_MODES, initial_state=state,
                                 transient_periods=20, long_time=sweep.long_time)
            for name in SERIES:
                np.testing.assert_array_equal(alone[name].values, cell[name].values)
            before = cell


def test_beside_a_contact_that_never_closes_it_is_the_single_contacts_stepped_sweep():
    """A tip stop with a dashpot beside a mid-span one 1 mm away: the single contact's stepped
    sweep (its own kernel, which carries its phase), up and down, to round-off (measured 2e-14
    of each variable's largest)."""
    several = run({**STEPPED, "params": {**BASE, "contacts": [
        {"clearance": 2e-6, "damping": 0.5}, {"position1": MID, "clearance": 1e-3}]}})
    single = run({**STEPPED, "params": {**BASE, "clearance": 2e-6, "contact_damping": 0.5}})
    assert np.all(single.steady_impact_rate > 0)
    for name in SERIES:
        reference = single[name].values
        assert np.abs(several[name].values - reference).max() < 1e-12 * np.abs(reference).max()


def test_a_stepped_axis_that_changes_the_modes_is_refused_in_one_line():
    """A contact's position changes the active sets' phases: not a stepped axis."""
    with pytest.raises(ParameterError, match=r"^stepped_axis = 'contacts.0.position1' is not "
                                             "allowed: must be one of omega"):
        sweep_from_mapping({**STEPPED, "stepped_axis": "contacts.0.position1",
                            "params": {**BASE, "contacts": [{}, {"position1": MID}]},
                            "axes": {"contacts.0.position1": {"min": 0.1, "max": 0.2,
                                                              "num": 2}}})


def test_the_up_and_down_rows_differ_only_where_they_start():
    """Each row's first cell starts from rest: the up row's first (the lowest Omega) is the
    unstepped sweep's cell, bit for bit, as is the down row's first (the highest); the
    others are not."""
    definition = {**STEPPED, "params": {**BASE, "contacts": TOGETHER}}
    stepped = run(definition)
    unstepped = run({key: value for key, value in definition.items() if key != "stepping"})
    for name in SERIES[:3]:
        np.testing.assert_array_equal(stepped[name].sel(sweep_direction="up").isel(omega=0),
                                      unstepped[name].isel(omega=0))
        np.testing.assert_array_equal(stepped[name].sel(sweep_direction="down").isel(omega=-1),
                                      unstepped[name].isel(omega=-1))
    # the middle cell is carried: its transient (|mu|^20 of the start's offset) differs
    middle = stepped.poincare_deflection1.sel(sweep_direction="up").isel(omega=1)
    assert not np.array_equal(middle, unstepped.poincare_deflection1.isel(omega=1))
    assert math.isclose(float(stepped.omega[-1]), 420.0)


def test_a_carried_state_no_set_fits_starts_the_cell_from_rest_with_a_warning():
    """A predecessor's end inside a dashpot's early release (contact 0 overlapping 0.1 um while
    its gap opens at 1 m/s: its force would pull; contact 1 open) fits no set of closed
    contacts, which simulate refuses: the cell starts from rest, saying so; a predecessor that
    stopped early (NaN) hands on nothing, silently; a state a set fits is simulate's start."""
    from impactbeams.active_phases import contacts_start, pack_contacts
    from impactbeams.sweep.plan import _carried_start
    from test_orbits_several import DASHPOTS

    packed = pack_contacts(DASHPOTS, N_MODES, 0.1, 0.1)
    b = packed.gap_weights
    gaps, rates = np.array([-1e-7, 1e-5]), np.array([1.0, 0.0])
    rest_gaps, rest_rates = _modal_gaps_at_rest(packed)
    state = np.concatenate([b.T @ np.linalg.solve(b @ b.T, gaps - rest_gaps),
                            b.T @ np.linalg.solve(b @ b.T, rates - rest_rates)])
    with pytest.raises(ParameterError, match="no set of closed contacts fits it"):
        contacts_start(packed, state)
    with pytest.warns(RuntimeWarning, match="a stepped cell starts from rest: initial_state is "
                                            "not allowed: no set of closed contacts fits it"):
        assert _carried_start(state)(packed) is None
    assert _carried_start(np.full(state.size, np.nan))(packed) is None
    open_state = np.zeros(state.size)
    q, v, mask = _carried_start(open_state)(packed)
    assert mask == 0 and np.array_equal(np.concatenate([q, v]), open_state)



def _modal_gaps_at_rest(packed):
    """Each contact's modal gap (m) and rate (m/s) at z = 0, t = 0: the clearances and drive."""
    from impactbeams.packing import section_gap

    zero = np.zeros(2 * packed.runs[0].q0.size)
    return np.array([section_gap(run, zero) for run in packed.runs]).T


def test_rows_on_threads_equal_rows_in_turn():
    """A stepped sweep's rows run on threads, each row's cells in turn: the same map as one
    thread, bit for bit."""
    definition = {**STEPPED, "params": {**BASE, "contacts": TOGETHER}}
    sweep = sweep_from_mapping(definition)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "n_modes = 8 does not resolve", RuntimeWarning)
        threaded, serial = run_sweep(sweep, parallel=True), run_sweep(sweep, parallel=False)
    for name in SERIES:
        np.testing.assert_array_equal(threaded[name].values, serial[name].values)
