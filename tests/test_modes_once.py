"""A geometry's modes are built once per run, and one function says how many a run needs.

Issue 33: a run built a beam's modes again each time it asked how many modes its contact needs
(`required_modes` counts them on built modes) and again for its model: `impactbeams continue`
five times per beam, a long-time sweep twice, `simulate` twice where the count and the run
take the same number. The closed-form builder's builds are counted here (its calls of the
cantilever's roots): each (beam, n) is built once per run.
"""

import collections
import contextlib
import sys

import pytest

import impactbeams as ib
import impactbeams.modes as modes
from impactbeams.cli import main
from impactbeams.contact.spring import (
    TIED_MODES,
    needed_modes,
    recommended_modes,
    required_modes,
)
from impactbeams.continuation import Continuation
from impactbeams.continuation.run import mode_count
from impactbeams.orbits import PeriodMap
from impactbeams.params import MAX_MODES

SPRING = ib.Params(contact_stiffness=1e4, damping_ratio=0.02, force_amplitude=3e-5,
                   clearance=1.1e-5)


@pytest.fixture
def builds(monkeypatch):
    """Each closed-form build of a beam's modes, by (beam length, n): the builder's calls of
    the roots (one per build), whatever caches it; none kept from earlier tests."""
    counted = collections.Counter()
    roots = modes.cantilever_roots

    def counting(n):
        caller = sys._getframe(1)
        if caller.f_code is getattr(modes.free_modes, "__wrapped__", modes.free_modes).__code__:
            counted[(caller.f_locals["length"], n)] += 1
        return roots(n)

    getattr(modes.free_modes, "cache_clear", lambda: None)()
    monkeypatch.setattr(modes, "cantilever_roots", counting)
    return counted


def test_simulate_builds_each_beams_modes_once(builds):
    """k = 1e4 N/m: the count of the modes it needs is decided on 5 modes per beam, the run's
    own n_modes: built once for both."""
    with pytest.warns(RuntimeWarning, match="does not resolve"):
        ib.simulate(SPRING, 0.005, n_modes=5)
    assert builds == {(SPRING.l1, 5): 1, (SPRING.l2, 5): 1}


def test_the_continue_command_builds_each_beams_modes_once(builds, tmp_path):
    (tmp_path / "c.toml").write_text(
        "[params]\ncontact_stiffness = 1e4\ndamping_ratio = 0.02\nforce_amplitude = 3e-5\n"
        "clearance = 1.1e-5\n[continuation]\nparameter = 'omega'\nmin = 248.8\nmax = 249.5\n"
        "start = 248.9\nmax_points = 3\nmax_branches = 1\n")
    assert main(["continue", str(tmp_path / "c.toml"), "-o", str(tmp_path / "c.nc"),
                 "--quiet", "--allow-incomplete"]) == 0
    assert builds and set(builds.values()) == {1}, builds


def test_a_long_time_sweep_builds_each_beams_modes_once(builds):
    from impactbeams.sweep.definition import sweep_from_mapping
    from impactbeams.sweep.run import run_sweep

    sweep = sweep_from_mapping({
        "n_modes": 4, "observables": ["response_period"], "transient_periods": 5,
        "sampled_periods": 4, "params": {"contact_stiffness": 1e4, "force_amplitude": 1e-2},
        "axes": {"omega": {"min": 100.0, "max": 200.0, "num": 2}}})
    with pytest.warns(RuntimeWarning, match="does not resolve"):
        run_sweep(sweep, parallel=False)
    assert builds and set(builds.values()) == {1}, builds


def test_built_modes_are_read_only():
    free = modes.free_modes(0.35, 0.157, 0.2, 3)
    for array in (free.frequencies, free.shapes.k, free.shapes.amplitude):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 0.0


def _unresolved_warned(params):
    """A contact past MAX_MODES' resolution is run at MAX_MODES, with a warning."""
    if needed_modes(params) <= MAX_MODES:
        return contextlib.nullcontext()
    return pytest.warns(RuntimeWarning, match="does not resolve")


@pytest.mark.parametrize("params", [ib.Params(), SPRING, ib.Params(contact_law="tied"),
                                    ib.Params(contact_stiffness=1e12)],
                         ids=["hertz", "soft", "tied", "past-max"])
def test_one_answer_to_how_many_modes(params):
    """simulate, a period map, basins and continuation take `recommended_modes` when no
    n_modes is given: the modes that resolve the contact (5 under the tied law), capped."""
    needed = required_modes(params) if params.law.compliant else TIED_MODES
    assert needed_modes(params) == needed
    assert recommended_modes(params) == min(needed, MAX_MODES)
    with _unresolved_warned(params):
        run = ib.simulate(params, 1e-4, dt_output=1e-4)
    assert run.attrs["n_modes"] == recommended_modes(params)
    if params.law.tangent_flow and needed <= MAX_MODES:
        assert PeriodMap(params.replace(omega=250.0)).n_modes == recommended_modes(params)
        assert mode_count(Continuation(params, "omega", 200.0, 300.0)) == recommended_modes(
            params)


def test_basins_take_the_recommended_modes():
    from impactbeams.orbits.basin_map import _Setup

    for params in (SPRING.replace(omega=250.0), ib.Params(contact_law="tied", omega=250.0)):
        setup = _Setup.checked(params, None, None, [], 16, 1, None, False)
        assert setup.n_modes == recommended_modes(params)
