"""Full-dynamics observables of a sweep against simulate()'s per-impact table."""

import numpy as np
import pytest

from impactbeams.params import Params
from impactbeams.sweep import (
    DYNAMICS_OBSERVABLES,
    FIRST_IMPACT,
    build_plan,
    run_sweep,
    sweep_from_mapping,
)
from impactbeams.sweep.plan import chunk_cells
from impactbeams.trajectory import simulate
from test_columns import round_off_band

T_MAX = 0.2
# both contact laws: the tied one at the paper's 5 modes, the spring one resolved (k = 1e4 N/m
# needs 12 modes per beam, see docs/model.md)
LAWS = {"tied": ({"contact_law": "tied"}, 5),
        "spring": ({"contact_law": "spring", "contact_stiffness": 1e4}, 12)}


@pytest.fixture(scope="module", params=list(LAWS))
def law(request):
    return request.param


def definition(law):
    params, n_modes = LAWS[law]
    return {"t_max": T_MAX, "n_modes": n_modes, "params": {"clearance": 1.1e-5, **params},
            "axes": {"omega": {"min": 40.0, "max": 260.0, "num": 3},
                     "force_amplitude": {"min": 2e-4, "max": 1e-3, "num": 2}}}


@pytest.fixture(scope="module")
def dynamics_map(law):
    sweep = sweep_from_mapping({**definition(law), "observables": [FIRST_IMPACT,
                                                                   *DYNAMICS_OBSERVABLES]})
    return run_sweep(sweep, progress=False)


def test_observables_equal_simulate_impact_table(dynamics_map, law):
    """Same kernel events, different reductions (the sweep's in Numba, simulate's in NumPy):
    counts, contact time and peak forces agree to round-off."""
    ds = dynamics_map
    assert np.all(ds.dynamics_status == 0)
    for i in range(ds.omega.size):
        for j in range(ds.force_amplitude.size):
            fixed, n_modes = LAWS[law]
            params = Params(clearance=1.1e-5, omega=float(ds.omega[i]),
                            force_amplitude=float(ds.force_amplitude[j]), **fixed)
            run = simulate(params, T_MAX, n_modes=n_modes)
            cell = ds.isel(omega=i, force_amplitude=j)
            assert int(cell.impact_count) == run.impact.size
            if run.impact.size == 0:
                assert np.isnan(cell.first_impact_time) and cell.max_contact_force == 0
                continue
            assert float(cell.first_impact_time) == float(run.impact_onset_time[0])
            assert float(cell.max_contact_force) == pytest.approx(
                float(run.impact_peak_force.max()), rel=1e-14)
            # a contact still open at t_max has no duration in the table: it lasts to t_max
            durations = run.impact_duration.fillna(T_MAX - run.impact_onset_time)
            assert float(cell.contact_fraction) == pytest.approx(
                float(durations.sum()) / T_MAX, rel=1e-12)
            closed = np.isfinite(run.separation_velocity) & (run.impact_velocity < 0)
            weighted = (-run.separation_velocity[closed].sum() / run.impact_velocity[closed].sum())
            assert float(cell.mean_restitution) == pytest.approx(float(weighted), rel=1e-12)


def test_first_impact_agrees_with_the_free_phase_kernel(dynamics_map, law):
    """The free-phase-only map and the full dynamics locate the same first root, each to
    within the gap's round-off: the map stops on its round-off rule, the dynamics (no rule)
    at a few ulps of time, and they evaluate the gap in different forms (the dynamics with
    beam 2's modes and the steady states split off). Their difference stays within the band
    of ``test_columns.round_off_band``."""
    sweep = sweep_from_mapping(definition(law))
    alone = run_sweep(sweep, progress=False)
    a, b = dynamics_map.first_impact_time.values.ravel(), alone.first_impact_time.values.ravel()
    assert np.array_equal(np.isnan(a), np.isnan(b))
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, sweep.size)
    for i in np.flatnonzero(~np.isnan(b)):
        assert abs(a[i] - b[i]) <= round_off_band(cells[i], plan, b[i]), i


def test_dynamics_map_parallel_equals_serial(dynamics_map, law):
    sweep = sweep_from_mapping({**definition(law), "observables": list(DYNAMICS_OBSERVABLES)})
    serial = run_sweep(sweep, progress=False, parallel=False, chunk_cells=2)
    for name in DYNAMICS_OBSERVABLES:
        assert np.array_equal(serial[name], dynamics_map[name], equal_nan=True)


def test_contact_law_and_stiffness_axes():
    """Both laws and two stiffnesses in one map; each cell equals its own simulate() run."""
    sweep = sweep_from_mapping({
        "t_max": 0.05, "n_modes": 12, "observables": ["impact_count", "max_contact_force"],
        "params": {"clearance": 1.1e-5, "omega": 50.0},
        "axes": {"contact_law": {"values": ["tied", "spring"]},
                 "contact_stiffness": {"min": 3e3, "max": 1e4, "num": 2}}})
    ds = run_sweep(sweep)
    assert list(ds.contact_law.values) == ["tied", "spring"]
    for law in ("tied", "spring"):
        for k in ds.contact_stiffness.values:
            cell = ds.sel(contact_law=law, contact_stiffness=k)
            run = simulate(Params(clearance=1.1e-5, contact_law=law, contact_stiffness=float(k)),
                           0.05, n_modes=12)
            assert int(cell.impact_count) == run.impact.size
            assert float(cell.max_contact_force) == pytest.approx(
                float(run.impact_peak_force.max()), rel=1e-14)
    # the tied law ignores the stiffness: its two columns are the same
    tied = ds.sel(contact_law="tied")
    assert np.array_equal(tied.impact_count[0], tied.impact_count[1])


@pytest.mark.parametrize("how", ["run_sweep", "write_sweep", "cli"])
def test_each_geometry_is_built_once_per_run(how, tmp_path, monkeypatch):
    """The check of damped spring contacts builds what the plan needs; the plan takes it.

    Before issue 33 a damped geometry was built twice by `run_sweep` and `write_sweep` (the
    check, the plan) and three times by ``impactbeams run`` (its own check too). The map is
    the same either way: the arrays taken are those built.
    """
    from impactbeams import packing
    from impactbeams.cli import main
    from impactbeams.sweep import plan, run_sweep, write_sweep

    definition = {"t_max": 0.01, "n_modes": 5, "observables": ["impact_count"],
                  "params": {"damping_ratio": 0.01, "contact_damping": 0.05,
                             "contact_stiffness": 100.0},
                  "axes": {"l1": {"min": 0.1, "max": 0.11, "num": 2},
                           "omega": {"min": 50.0, "max": 60.0, "num": 2}}}
    built = []
    build = packing.dynamics_arrays
    monkeypatch.setattr(packing, "dynamics_arrays",
                        lambda params, n_modes: built.append(params.l1) or build(params, n_modes))
    path = tmp_path / "sweep.toml"  # the same sweep as a file
    path.write_text('t_max = 0.01\nn_modes = 5\nobservables = ["impact_count"]\n'
                    "[params]\ndamping_ratio = 0.01\ncontact_damping = 0.05\n"
                    "contact_stiffness = 100.0\n"
                    "[axes.l1]\nmin = 0.1\nmax = 0.11\nnum = 2\n"
                    "[axes.omega]\nmin = 50.0\nmax = 60.0\nnum = 2\n")
    if how == "run_sweep":
        run_sweep(sweep_from_mapping(definition))
    elif how == "write_sweep":
        write_sweep(sweep_from_mapping(definition), tmp_path / "out.nc")
    else:
        assert main(["run", str(path), "-o", str(tmp_path / "out.nc")]) == 0
    assert sorted(built) == [0.1, 0.11]
    assert plan._BUILT == []  # nothing kept past the run

