"""Continuation of the beams' periodic orbits: the command, the file, and the located events
checked against independent computations (tests/continuation_reference.py).

The case is the shipped sweeps/continuation-stop-fold.toml: a cantilever against a soft stop
(k = 100 N/m, 5 modes, zeta = 0.02, F0 = 0.1 mN), whose resonance grazes the stop, bends to a
fold and returns, unstable, to a second fold.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import continuation_reference as reference
from impactbeams.cli import main
from impactbeams.continuation import continue_orbits, load_continuation
from impactbeams.variables import BIFURCATIONS

EXAMPLE = Path(__file__).parents[1] / "sweeps" / "continuation-stop-fold.toml"
GRAZING, FOLD = BIFURCATIONS.index("grazing"), BIFURCATIONS.index("fold")
# located to locate_tolerance = 1e-11 of the range (3e-9 rad/s on 150-450 rad/s); the
# references converge to ~1e-12: the brief's 1e-8 rad/s holds with room
LOCATED = 1e-8


def reduced(tmp_path, low, high, **extra):
    """The example file over [low, high] (other keys added or replaced by ``extra``)."""
    text = EXAMPLE.read_text().replace("min = 150.0", f"min = {low}").replace(
        "max = 450.0", f"max = {high}")
    for key, value in extra.items():
        text += f"{key} = {value}\n"
    path = tmp_path / "branch.toml"
    path.write_text(text)
    return path


def test_grazing_located_and_crossed(tmp_path, capsys):
    """Up to the first grazing (the linear resonance touching the stop) and past it."""
    path = reduced(tmp_path, 195.0, 210.0)
    assert main(["continue", str(path), "-o", str(tmp_path / "b.nc")]) == 0
    assert "1 grazing" in capsys.readouterr().err
    with xr.open_dataset(tmp_path / "b.nc") as branch:
        (index,) = np.flatnonzero(branch.bifurcation.values == GRAZING)
        omega = float(branch.omega[index])
        params = load_continuation(path).params
        assert omega == pytest.approx(reference.stop_grazing(params, 5, 195.0, 210.0),
                                      abs=LOCATED)
        assert branch.contacts_per_orbit[index] == 0 and branch.contacts_per_orbit[index + 1] == 1
        assert (branch.contacts_per_orbit[:index] == 0).all()
        assert branch.attrs["branch_endings"] == "bound" and float(branch.omega[-1]) == 210.0
        assert (branch.stable == 1).all()  # the multipliers stay inside the unit circle here


@pytest.mark.parametrize(("text", "message"), [
    ("[continuation]\nparameter = 'uplift1'\nmin = 0.0\nmax = 1.0\n",
     "parameter = 'uplift1' is not allowed: must be one of"),
    ("[continuation]\nparameter = 'omega'\nmin = 10.0\nmax = 5.0\n",
     "high = 5.0 is not allowed: the range [10.0, 5.0] is empty"),
    ("[continuation]\nparameter = 'omega'\nmin = 1.0\nmax = 5.0\nspeed = 1\n",
     "'speed' in [continuation] of"),
    ("[continuation]\nparameter = 'omega'\nmin = 1.0\nmax = 5.0\n[params]\ncontact_law = 'tied'\n",
     "periodic orbits need the spring contact law"),
    ("period = 0\n[continuation]\nparameter = 'omega'\nmin = 1.0\nmax = 5.0\n",
     "period = 0 is not allowed"),
    ("[continuation]\nparameter = 'omega'\nmin = 1.0\nmax = 5.0\nmethod = 'picard'\n",
     "method = 'picard' is not allowed: must be one of 'auto', 'newton', 'newton-picard'"),
    ("[continuation]\nparameter = 'omega'\nmin = 1.0\nmax = 5.0\nsubspace = 2\n",
     "subspace = 2 is not allowed"),
    ("[continuation]\nparameter = 'omega'\nmin = 1.0\n", "needs parameter, min and max"),
])
def test_bad_files_exit_2_in_one_line(tmp_path, capsys, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["continue", str(path), "-o", str(tmp_path / "out.nc")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("impactbeams: error: ") and message in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "out.nc").exists()


@pytest.mark.slow
def test_example_folds_and_grazings_against_references(tmp_path):
    """The shipped example: two folds (hysteresis), each a multiplier at +1, the upper one
    checked against the vertex of the branch parametrised by a state component (Newton with
    finite differences); the grazings against the steady amplitude's root."""
    output = tmp_path / "fold.nc"
    assert main(["continue", str(EXAMPLE), "-o", str(output), "--quiet"]) == 0
    continuation = load_continuation(EXAMPLE)
    with xr.open_dataset(output) as branch:
        folds = np.flatnonzero(branch.bifurcation.values == FOLD)
        grazings = np.flatnonzero(branch.bifurcation.values == GRAZING)
        assert len(folds) == 2 and len(grazings) == 2
        upper, lower = (float(branch.omega[i]) for i in folds)
        assert 300 < upper < 330 and 270 < lower < 290  # the hysteresis band
        for i in folds:  # a real multiplier at +1
            mu = branch.multiplier_modulus[i].values * np.exp(
                1j * branch.multiplier_argument[i].values)
            assert np.min(np.abs(mu - 1.0)) < 1e-4
        # stable below the upper fold's band, unstable between the folds (the returning part)
        assert branch.stable[folds[0] - 1] == 1 and branch.stable[folds[0] + 1] == 0
        assert branch.stable[folds[1] + 2] == 1
        z = branch.section_state.values
        k = int(np.argmax(np.abs(z[folds[0] + 1] - z[folds[0] - 1])))
        vertex = reference.fold_vertex(continuation.params, "omega", 5, z[folds[0]], upper, k,
                                       3e-4 * abs(z[folds[0], k]))
        assert upper == pytest.approx(vertex, abs=LOCATED)
        first = float(branch.omega[grazings[0]])
        assert first == pytest.approx(
            reference.stop_grazing(continuation.params, 5, 195.0, 210.0), abs=LOCATED)
        # started at 260 rad/s (once labelled a grazing on an orbit still in contact, just
        # past the lower fold): the same folds and second grazing
        later = continue_orbits(dataclasses.replace(continuation, low=260.0))
        for label, expected in ((FOLD, branch.omega[folds]), (GRAZING, branch.omega[grazings[1:]])):
            np.testing.assert_allclose(
                np.sort(later.omega.values[later.bifurcation.values == label]),
                np.sort(expected.values), rtol=0.0, atol=LOCATED)
        for dataset in (branch, later):
            contacts = dataset.contacts_per_orbit.values
            for i in np.flatnonzero(dataset.bifurcation.values == GRAZING):
                assert contacts[i - 1] != contacts[i + 1]


@pytest.mark.slow
def test_period_doubling_where_the_diagram_from_rest_changes_period():
    """Beam 1 against a stiffer stop (k = 1e4 N/m, 12 modes, F0 = 0.4 mN): going down in
    Omega the impacting period-1 orbit doubles its period; a diagram from rest (400 transient
    periods, period tolerance 1e-4) is period 1 at 302.5 rad/s and period 2 at 300.5 rad/s. The
    switched branch is period 2, stable there, and its two section samples are the diagram's
    two (the transient has decayed to ~1e-12 of the orbit's size: its multipliers are below 0.9
    per two periods). The orbit's Dataset (`to_dataset`) holds both periods: it passes through
    both samples, at t = 0 and T, and closes at 2 T."""
    from impactbeams import Params
    from impactbeams.continuation import Continuation, continue_orbits
    from impactbeams.orbits import periodic_orbit
    from impactbeams.sweep import run_sweep
    from impactbeams.sweep.definition import sweep_from_mapping

    fixed = {"counterpart": "stop", "contact_stiffness": 1e4, "damping_ratio": 0.02,
             "force_amplitude": 4e-4}
    branches = continue_orbits(Continuation(Params(**fixed), "omega", 300.5, 312.0,
                                            direction="down", step=1.0, max_step=3.0,
                                            n_modes=12))
    doubling = np.flatnonzero(branches.bifurcation.values == BIFURCATIONS.index(
        "period_doubling"))
    assert len(doubling) >= 1
    first = doubling[0]
    assert branches.branch[first] == 0 and 300.5 < float(branches.omega[first]) < 302.5
    assert float(branches.multiplier_modulus[first, 0]) == pytest.approx(1.0, abs=1e-6)
    assert float(branches.multiplier_argument[first, 0]) == pytest.approx(np.pi, abs=1e-6)
    assert branches.attrs["branch_origins"] == f"- 0:{first}"
    ends = [np.flatnonzero(branches.branch.values == b)[-1] for b in (0, 1)]
    assert [int(branches.orbit_period[end]) for end in ends] == [1, 2]
    assert [float(branches.omega[end]) for end in ends] == [300.5, 300.5]
    assert [int(branches.stable[end]) for end in ends] == [0, 1]
    diagram = run_sweep(sweep_from_mapping({
        "n_modes": 12, "observables": ["poincare_deflection1", "response_period"],
        "transient_periods": 400, "sampled_periods": 32, "params": fixed,
        "axes": {"omega": {"min": 300.5, "max": 302.5, "num": 2}}}))
    assert diagram.response_period.values.tolist() == [2, 1]
    samples = diagram.poincare_deflection1.sel(omega=300.5).values
    scale = np.max(np.abs(samples))
    orbit = branches.section_deflection_1[ends[1]].values
    assert np.isnan(branches.section_deflection_1[ends[0], 1])  # period 1: one sample
    assert abs(orbit[1] - orbit[0]) > 1e-3 * scale  # two distinct samples (3.5e-2 measured)
    for sample in orbit:
        assert np.min(np.abs(samples - sample)) < 1e-8 * scale
    period_2 = periodic_orbit(Params(**fixed, omega=300.5), 12, period=2,
                              guess=branches.section_state[ends[1]].values)
    tips = period_2.to_dataset(samples_per_period=16).tip_deflection_1.values
    assert tips.size == 33
    np.testing.assert_allclose(tips[[0, 16, 32]], [*orbit, orbit[0]], rtol=0, atol=1e-10 * scale)


def test_interrupt_writes_the_points_computed(tmp_path, capsys, monkeypatch):
    """Ctrl-C (here in the progress report of the 5th point): exit 130, the points computed
    are in OUT.nc.partial/OUT.nc (the start and 5 points, its branch ending 'interrupted'),
    OUT.nc is not written: the same command resumes (tests/test_continuation_resume.py)."""
    import impactbeams.cli as cli

    class Interrupting(cli._BranchProgress):
        def __call__(self, branch, point):
            if len(branch.points) == 6:
                raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_BranchProgress", Interrupting)
    output = tmp_path / "cut.nc"
    assert main(["continue", str(reduced(tmp_path, 195.0, 210.0)), "-o", str(output)]) == 130
    assert "branch points computed are in" in capsys.readouterr().err
    assert not output.exists()
    with xr.open_dataset(tmp_path / "cut.nc.partial" / "cut.nc") as branch:
        assert branch.branch_point.size == 6
        assert branch.attrs["branch_endings"] == "interrupted"


@pytest.mark.parametrize("path", sorted(EXAMPLE.parent.glob("continuation-*.toml")),
                         ids=lambda p: p.name)
def test_shipped_continuation_files_are_valid(path):
    continuation = load_continuation(path)
    assert continuation.high > continuation.low and continuation.params.damping_ratio > 0


def test_newton_picard_branch_is_the_newton_branch():
    """The example's branch over its upper fold (2 N = 10) by Newton-Picard on 6 carried
    directions against full Newton: the same fold, the same end orbit and multipliers.

    The fold: both are located to locate_tolerance (4e-10 rad/s on this range), and
    Newton-Picard's vanishes where its dr/dz, exact on V and the residual's direction, is
    singular, i.e. where a Ritz value of an almost invariant V is 1; the amplitude there moves
    like the square root of the parameter's error (1e-6 relative). The end at the bound: both
    converged to tolerance 1e-10 in x~ (1e-10 relative); the leading Ritz values converge
    with the subspace iteration carried along the branch (measured: 5e-8 apart).
    """
    import dataclasses
    import warnings

    from impactbeams.continuation import continue_orbits

    base = dataclasses.replace(load_continuation(EXAMPLE), low=290.0, high=330.0,
                               max_branches=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the complement's check passes at every point
        newton, picard = (continue_orbits(dataclasses.replace(base, method=method, subspace=6))
                          for method in ("newton", "newton-picard"))
    (i,), (j,) = (np.flatnonzero(branch.bifurcation.values == FOLD)
                  for branch in (newton, picard))
    assert float(picard.omega[j]) == pytest.approx(float(newton.omega[i]), abs=LOCATED)
    assert float(picard.tip_amplitude_1[j]) == pytest.approx(float(newton.tip_amplitude_1[i]),
                                                             rel=1e-6)
    assert float(picard.omega[-1]) == float(newton.omega[-1]) == 290.0
    scale = np.abs(newton.section_state[-1]).max().item()
    assert np.abs(picard.section_state[-1] - newton.section_state[-1]).max() < 1e-10 * scale
    np.testing.assert_allclose(picard.multiplier_modulus[-1, :3],
                               newton.multiplier_modulus[-1, :3], rtol=1e-6)
    assert float(picard.multiplier_modulus[j, 0]) == pytest.approx(1.0, abs=1e-6)
    assert picard.attrs["branch_endings"] == newton.attrs["branch_endings"] == "bound"
    assert (newton.attrs["corrector"], picard.attrs["corrector"]) == ("newton", "newton-picard")
    assert picard.sizes["multiplier"] == 4  # the leading m - GUARD Ritz values


def test_newton_picard_warns_when_the_complement_may_hold_a_crossing():
    """The smallest Ritz value bounds the complement's multipliers: at or outside the unit
    circle it may hide a crossing, and the problem says so (once)."""
    import warnings

    from impactbeams.continuation.beams import BeamOrbits

    problem = BeamOrbits(load_continuation(EXAMPLE).params, "omega", 5,
                         method="newton-picard", subspace=3)
    with pytest.warns(RuntimeWarning, match="modulus 1.02 >= 1"):
        problem._check_complement(np.array([1.5, 1.2, 1.02 + 0j]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        problem._check_complement(np.array([1.5, 1.2, 1.02 + 0j]))  # once per problem
        BeamOrbits(problem.params, "omega", 5, method="newton-picard",
                   subspace=3)._check_complement(np.array([1.5, 0.99 + 0j]))


def test_equal_beams_on_one_shaker_impact_only_in_their_unforced_difference():
    """The one configuration with a symmetry (docs/continuation.md, Symmetry): equal beams on
    one shaker, no tip force. The in-phase motion y1 + y2 is the linear response whatever the
    contacts (7 here, from an asymmetric start): equal to the run without contact to 1e-12 of
    its amplitude (measured 3e-14: both phases' modal bases, round-off); the contact lives in
    the difference, which nothing drives and the damping empties."""
    from impactbeams import Params, simulate

    equal = {"l2": 0.1, "force_amplitude": 0.0, "base_amplitude": 2e-6, "damping_ratio": 0.02,
             "contact_stiffness": 100.0, "omega": 240.0, "uplift1": 3e-5}
    duration = 40 * 2 * np.pi / 240.0
    times = np.linspace(0.0, duration, 2001)
    runs = [simulate(Params(**equal, clearance=clearance), duration, n_modes=5, times=times)
            for clearance in (1.1e-5, 1e-2)]
    in_phase = [run.tip_deflection_1 + run.tip_deflection_2 + run.attrs["clearance"]
                for run in runs]
    assert runs[0].impact.size > 0 and runs[1].impact.size == 0
    scale = float(abs(in_phase[1]).max())
    assert float(abs(in_phase[0] - in_phase[1]).max()) < 1e-12 * scale
    difference = (runs[0].tip_deflection_1 - runs[0].tip_deflection_2).values
    assert abs(difference[-500:]).max() < 0.5 * abs(difference[:500]).max()


def test_progress_gives_no_time_left_for_a_branch_switched_at_a_doubling(capsys):
    """A period-2 branch ends where it rejoins its origin, which the range does not tell: its
    progress lines say where it was switched, not a share of the range and a time left (on
    the stiff stop going down: 1673 s announced, the whole run 74 s); the started branch keeps
    both."""
    import types

    from impactbeams import cli
    from impactbeams.continuation.arclength import Scaling

    progress = cli._BranchProgress(65.6, 262.5)
    scaling = Scaling(np.ones(1), 1.0)

    def point(p):
        evaluation = types.SimpleNamespace(multipliers=np.array([0.5]), contacts=2)
        return types.SimpleNamespace(parameter=lambda s: p, evaluation=evaluation, label="")

    started = types.SimpleNamespace(points=[None] * 20, scaling=scaling, origin=None, period=1)
    switched = types.SimpleNamespace(points=[None] * 20, scaling=scaling, origin=(0, 7),
                                     period=2)
    for branch, first in ((started, 100.0), (switched, 160.16)):
        branch.points = [None] * 19
        progress(branch, point(first))
        branch.points = [None] * 20
        progress(branch, point(first + 0.2))
    lines = capsys.readouterr().err.splitlines()
    assert "% of the way to 262.5" in lines[0]
    assert "switched at 160.16: where it ends is not known in advance" in lines[1]
    assert "s left" not in lines[1] and "% of the way" not in lines[1]
