"""What a run that stops short of its range suggests: only what applies to how it ended.

On main every short branch was told to try micro_contacts = "summarise", which changes only
how changes of the contacts within an impact episode are followed: at a fold on a grazing (the
stiff stop-and-shaker case's period-2 branch, docs/continuation.md Limits) it stops or turns
back the same. Branches are built with the endings and the last events of such runs, and the
warning's suggestions read against them.
"""

import numpy as np
import pytest
import xarray as xr

import impactbeams as ib
from impactbeams.cli import _short_branches
from impactbeams.continuation import Continuation
from impactbeams.variables import BIFURCATIONS

SHAKER = ib.Params.from_mapping({
    "l1": 0.2, "width1": 0.02, "thickness1": 0.001, "counterpart": "stop", "clearance": 5e-4,
    "shaker": "beam1", "base_amplitude": 1e-4, "force_amplitude": 0.0, "damping_ratio": 0.01})


def ended(ending, last_events, period=1):
    """A branch of 30 points along Omega that ended (``ending``) after ``last_events``."""
    n = 30
    codes = np.zeros(n, np.int8)
    codes[n - 1 - len(last_events):n - 1] = [BIFURCATIONS.index(kind) for kind in last_events]
    return xr.Dataset(
        {"branch": ("branch_point", np.zeros(n, np.int32)),
         "orbit_period": ("branch_point", np.full(n, period, np.int32)),
         "bifurcation": ("branch_point", codes),
         "contacts_per_orbit": ("branch_point", np.full(n, 4, np.int32)),
         "multiplier_modulus": (("branch_point", "multiplier"), np.full((n, 2), 1.016))},
        coords={"omega": ("branch_point", np.linspace(115.0, 115.87, n))},
        attrs={"branch_endings": ending})


def advice(ending, last_events, period=1, **given):
    """The warning's line for a branch of ``period`` of a period-1 run (``given``)."""
    continuation = Continuation(SHAKER, "omega", 65.6, 262.5, n_modes=4, max_points=1000,
                                **given)
    (line,) = _short_branches(ended(ending, last_events, period), continuation)
    assert line.startswith(f"branch 0 ended ({ending}) at omega = 115.87, short of "
                           "[65.6, 262.5], with 4 contacts per orbit and largest |mu| 1.016")
    return line


def test_a_stall_at_a_fold_on_a_grazing_is_not_told_to_summarise():
    line = advice("min_step", ["fold", "grazing"], period=2)
    assert "summarise" not in line
    assert "a smaller min_step" in line
    assert "a second run of period 2 from past it (period = 2, start =)" in line
    assert "max_points" not in line and "max_step" not in line


def test_a_stall_among_located_micro_contacts_is_told_to_summarise():
    for ending in ("min_step", "stalled"):
        line = advice(ending, ["contact_merge", "grazing", "contact_split"])
        assert 'micro_contacts = "summarise"' in line
        assert ("a smaller min_step" in line) == (ending == "min_step")
        assert 'from the other end (direction = "down")' in line


def test_summarised_micro_contacts_are_not_suggested_again():
    line = advice("min_step", ["chatter", "contact_merge"], micro_contacts="summarise")
    assert "summarise" not in line


@pytest.mark.parametrize("events", [[], ["contact_merge"]])
def test_a_branch_out_of_points_is_told_to_take_more(events):
    line = advice("max_points", events, direction="down")
    assert "a larger max_points (now 1000)" in line
    assert "summarise" not in line and "min_step" not in line
    assert 'from the other end (direction = "up")' in line


def test_a_branch_that_jumped_back_is_told_a_smaller_max_step():
    line = advice("retraced", ["contact_merge", "fold"])
    assert "a smaller max_step" in line
    assert "summarise" not in line and "min_step" not in line


def test_branches_that_ended_on_their_own_get_no_warning():
    continuation = Continuation(SHAKER, "omega", 65.6, 262.5, n_modes=4)
    for ending in ("bound", "closed_loop", "joined_origin"):
        assert _short_branches(ended(ending, ["contact_merge"]), continuation) == []
