"""Sweep files, validation, resumable chunked runs, netCDF output and the CLI."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from impactbeams.cli import main
from impactbeams.model import build_free_phase
from impactbeams.params import ParameterError, Params
from impactbeams.sweep import load_sweep, run_sweep, sweep_from_mapping
from impactbeams.sweep.plan import contact_resolution
from references import free_tip_gap, reference_first_impact

SWEEPS = Path(__file__).parents[1] / "sweeps"

SMALL = {
    "t_max": 0.3,
    "n_modes": 4,
    "params": {"clearance": 1.1e-5},
    "axes": {
        "omega": {"min": 20.0, "max": 400.0, "num": 13},
        "force_amplitude": {"min": 1e-5, "max": 1e-3, "num": 7, "scale": "log"},
    },
}


def small(**changes):
    return sweep_from_mapping({**SMALL, **changes}, source="test sweep")


# continuation files (impactbeams continue) are tested in tests/test_continuation_beams.py
@pytest.mark.parametrize("path", sorted(p for p in SWEEPS.glob("*.toml")
                                        if not p.name.startswith("continuation-")),
                         ids=lambda p: p.name)
def test_shipped_sweeps_are_valid(path):
    sweep = load_sweep(path)
    if sweep.long_time is None:  # maps of the first impact or of the dynamics over t_max
        assert sweep.size >= 1e4 and len(sweep.axes) >= 2
    else:  # long runs: a bifurcation diagram or a period map, at the resolved n_modes
        assert sweep.size >= 400 and sweep.n_modes >= contact_resolution(sweep)


@pytest.mark.parametrize(
    ("changes", "fragment"),
    [
        ({"tmax": 1.0}, "unknown top-level key 'tmax' in test sweep (did you mean 't_max'?)"),
        ({"t_max": -1.0}, "t_max in test sweep = -1.0 is not allowed: must be > 0 (s)"),
        ({"n_modes": 0}, "n_modes in test sweep = 0 is not allowed"),
        ({"observables": ["impact_time"]}, "unknown observable 'impact_time' in the observables "
                                           "of test sweep (did you mean 'first_impact_time'?)"),
        ({"params": {"clearence": 1e-5}}, "unknown parameter 'clearence' in [params]"),
        ({"params": {"clearance": -1e-5}}, "clearance = -1e-05 is not allowed: must be > 0"),
        ({"axes": {}}, "a sweep needs at least one [axes.NAME] table"),
        ({"axes": {"omegaa": {"min": 1, "max": 2, "num": 3}}},
         "unknown parameter 'omegaa' in [axes] of test sweep (did you mean 'omega'?)"),
        ({"axes": {"omega": {"min": 5, "max": 2, "num": 3}}}, "empty or reversed"),
        ({"axes": {"omega": {"min": 2, "max": 2, "num": 3}}}, "empty or reversed"),
        (
            {"axes": {"omega": {"min": 1, "max": 2, "num": 0}}},
            "num in [axes.omega] of test sweep = 0 is not allowed",
        ),
        ({"axes": {"omega": {"min": 1, "max": 2, "num": 3, "scale": "log2"}}}, "'log2'"),
        ({"axes": {"omega": {"min": 0, "max": 2, "num": 3, "scale": "log"}}}, "needs min > 0"),
        ({"axes": {"omega": {"min": 1, "max": 2, "num": 3, "step": 1}}}, "'step' in [axes"),
        ({"axes": {"omega": {"min": 1, "num": 3}}}, "max in [axes.omega] of test sweep"),
        (
            {"axes": {"clearance": {"min": -1e-5, "max": 1e-5, "num": 3}}},
            "axis 'clearance' of test sweep reaches a non-physical point: clearance = -1e-05",
        ),
        ({"axes": {"damping_ratio": {"min": 0.5, "max": 1.0, "num": 3}}}, "damping_ratio = 1.0"),
        ({"axes": {"uplift2": {"min": 0.0, "max": 2e-5, "num": 5}}}, "initial gap clearance"),
    ],
)
def test_bad_sweeps_are_rejected_naming_key_and_value(changes, fragment):
    with pytest.raises(ParameterError) as error:
        small(**changes)
    assert fragment in str(error.value)


def test_map_cells_equal_independent_per_point_computation():
    sweep = small()
    ds = run_sweep(sweep, progress=False)
    assert ds.first_impact_time.dims == ("omega", "force_amplitude")
    free = build_free_phase(Params(), 4)
    c1 = Params().tip_compliance[0]
    rng = np.random.default_rng(0)
    for i, j in rng.integers(0, [13, 7], size=(12, 2)):
        omega = float(ds.omega[i])
        force = float(ds.force_amplitude[j])
        args = (free, c1, 1.1e-5, force, omega)
        ref = reference_first_impact(
            free_tip_gap(*args), 0.3, free.frequencies.max(),
            scan=free_tip_gap(*args, dtype=np.float64)
        )
        got = float(ds.first_impact_time[i, j])
        assert np.isnan(ref) == np.isnan(got)
        assert np.isnan(ref) or abs(got - ref) <= 1e-12 * ref
        assert int(ds.impacted[i, j]) == int(np.isfinite(ref))


def test_geometry_axis_equals_separate_fixed_geometry_runs():
    sweep = small(
        axes={"omega": SMALL["axes"]["omega"], "l2": {"min": 0.08, "max": 0.14, "num": 3}},
        params={"clearance": 1.1e-5, "uplift2": 4e-6, "force_amplitude": 3e-4},
    )
    ds = run_sweep(sweep, progress=False)
    for k, l2 in enumerate(ds.l2.values):
        one = small(
            axes={"omega": SMALL["axes"]["omega"]},
            params={"clearance": 1.1e-5, "uplift2": 4e-6, "force_amplitude": 3e-4, "l2": float(l2)},
        )
        alone = run_sweep(one, progress=False)
        assert np.array_equal(ds.first_impact_time[:, k], alone.first_impact_time, equal_nan=True)
    assert "l2" not in ds.attrs and ds.attrs["l1"] == 0.1


def test_parallel_serial_and_chunking_give_bitwise_identical_maps():
    sweep = small()
    a = run_sweep(sweep, progress=False, parallel=True)
    b = run_sweep(sweep, progress=False, parallel=False, chunk_cells=10)
    assert np.array_equal(a.first_impact_time, b.first_impact_time, equal_nan=True)


def _refusing_runner(sweep, chunks):
    """A chunk runner for runs that must compute nothing: fails if asked for any chunk."""
    assert not chunks, f"chunks {[c[0] for c in chunks]} were recomputed"
    yield from ()


def test_interrupted_run_resumes_to_the_same_result(tmp_path):
    sweep = small()
    out = tmp_path / "map.nc"

    def stop_after_three(chunk):
        if chunk == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep, output=out, progress=False, chunk_cells=10, on_chunk=stop_after_three)
    partial = tmp_path / "map.nc.partial"
    assert not out.exists()
    assert len(list(partial.glob("chunk_*.npz"))) == 3
    assert not list(partial.glob("*.nc"))  # the unfinished file is deleted on the interrupt
    computed = []
    resumed = run_sweep(sweep, output=out, progress=False, chunk_cells=10, on_chunk=computed.append)
    # 13 x 7 cells in chunks of at most 10 whole lines of 7: only the unsaved ones are computed
    assert computed == list(range(3, 13))
    fresh = run_sweep(sweep, progress=False)
    assert np.array_equal(resumed.first_impact_time, fresh.first_impact_time, equal_nan=True)
    assert out.exists() and not partial.exists()
    # a finished output of the same sweep is returned as it is: nothing computed (the runner
    # refuses any chunk, on_chunk is never called) and the file is not rewritten (same inode,
    # modification time to the nanosecond and bytes)
    before, content = out.stat(), out.read_bytes()
    again = run_sweep(sweep, output=out, progress=False, on_chunk=computed.append,
                      runner=_refusing_runner)
    after = out.stat()
    assert computed == list(range(3, 13))
    assert (after.st_ino, after.st_mtime_ns, after.st_size) == (
        before.st_ino, before.st_mtime_ns, before.st_size)
    assert out.read_bytes() == content
    assert again.attrs == resumed.attrs
    assert np.array_equal(again.first_impact_time, fresh.first_impact_time, equal_nan=True)
    # another sweep is refused, and leaves the file alone too
    with pytest.raises(ParameterError, match="exists and holds a different result"):
        run_sweep(small(t_max=0.2), output=out, progress=False, runner=_refusing_runner)
    assert out.stat().st_mtime_ns == before.st_mtime_ns and out.read_bytes() == content


# Generous: a loaded 2-core CI machine runs these subprocesses several times slower, and the
# first one may compile the kernels; every wait polls for an event and ends as soon as it occurs.
PROCESS_DEADLINE = 600.0


def _wait_for(condition, what, process=None, log=None, deadline=PROCESS_DEADLINE):
    """Poll ``condition()`` until true; fail clearly on timeout or if ``process`` exits first."""
    end = time.monotonic() + deadline
    while not condition():
        if process is not None and process.poll() is not None:
            output = log.read_text() if log is not None and log.exists() else ""
            pytest.fail(f"the process exited with code {process.returncode} before {what}; "
                        f"its stderr:\n{output}")
        if time.monotonic() > end:
            if process is not None:
                process.kill()
                process.wait()
            pytest.fail(f"no {what} within {deadline} s")
        time.sleep(0.02)


def test_killed_process_loses_no_finished_chunk(tmp_path):
    """SIGKILL mid-run: saved chunks stay readable, no result file appears, and the same
    command resumes from them (a marked value in a saved chunk reaches the result: it was
    loaded, not recomputed); all other cells equal an uninterrupted run."""
    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text(  # 3600 cells in 180 chunks: killed after 3, the run is 2 % done
        "t_max = 3.0\nn_modes = 5\n[axes.omega]\nmin = 300.0\nmax = 500.0\nnum = 60\n"
        "[axes.force_amplitude]\nmin = 1e-5\nmax = 2e-4\nnum = 60\n"
    )
    out = tmp_path / "s.nc"
    command = [sys.executable, "-m", "impactbeams.cli", "run", str(sweep_file), "-o", str(out),
               "--chunk-cells", "20", "--threads", "1", "--quiet"]
    partial = tmp_path / "s.nc.partial"
    log = tmp_path / "stderr.txt"
    with open(log, "w") as stderr:
        process = subprocess.Popen(command, stderr=stderr)
        try:
            _wait_for(lambda: len(list(partial.glob("chunk_*.npz"))) >= 3,
                      "3 saved chunks", process, log)
            os.kill(process.pid, signal.SIGKILL)
        finally:
            process.kill()  # no-op when it is dead already; never leave it running
            process.wait()
    assert process.returncode == -signal.SIGKILL, (
        f"the run ended by itself (code {process.returncode}) before it was killed")
    assert not out.exists()
    saved = sorted(partial.glob("chunk_*.npz"))
    assert 3 <= len(saved) < 180
    for chunk in saved:
        assert np.load(chunk)["first_impact_time"].shape == (20,)
    # mark one saved chunk: a value no computation gives (t_max is 3 s)
    number = int(saved[0].stem[6:])
    with np.load(saved[0]) as data:
        values = {name: data[name].copy() for name in data.files}
    values["first_impact_time"][0] = 99.0
    marked = saved[0].with_name("marked.tmp")
    with open(marked, "wb") as stream:
        np.savez(stream, **values)
    os.replace(marked, saved[0])
    resumed_run = subprocess.run(command, capture_output=True, text=True,
                                 timeout=PROCESS_DEADLINE)
    assert resumed_run.returncode == 0, resumed_run.stderr
    assert not partial.exists()
    fresh = run_sweep(load_sweep(sweep_file), progress=False).first_impact_time.values.ravel()
    with xr.open_dataset(out) as resumed:
        got = resumed.first_impact_time.values.ravel()
    assert got[20 * number] == 99.0  # the saved chunk was used as it was
    expected = fresh.copy()
    expected[20 * number] = 99.0
    assert np.array_equal(got, expected, equal_nan=True)


def test_netcdf_file_is_self_describing(tmp_path):
    out = tmp_path / "map.nc"
    ds = run_sweep(small(), output=out, progress=False)
    with netCDF4.Dataset(out) as nc:
        assert nc.Conventions == "CF-1.8"
        assert "impactbeams" in nc.history and nc.t_max == 0.3 and nc.n_modes == 4
        assert nc["omega"].units == "rad/s" and nc["force_amplitude"].units == "N"
        assert nc["first_impact_time"].units == "s"
        assert nc.clearance == 1.1e-5 and nc.EI1 == Params().EI1
    with xr.open_dataset(out) as back:
        assert np.array_equal(back.first_impact_time, ds.first_impact_time, equal_nan=True)
        assert back.force_amplitude.attrs["scale"] == "log"
    with netCDF4.Dataset(out) as nc:  # small maps are compressed too (issue 13)
        for name in ("first_impact_time", "impacted"):
            filters = nc[name].filters()
            assert filters["zlib"] and filters["shuffle"] and filters["complevel"] == 4


def test_cli_run_and_plot(tmp_path, capsys):
    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text(
        "t_max = 0.2\n[axes.omega]\nmin = 20.0\nmax = 300.0\nnum = 8\n"
        '[axes.clearance]\nmin = 1e-6\nmax = 3e-5\nnum = 6\nscale = "log"\n'
    )
    out, png = tmp_path / "s.nc", tmp_path / "s.png"
    assert main(["run", str(sweep_file), "-o", str(out)]) == 0
    assert "100.0%" in capsys.readouterr().err
    assert main(["plot", str(out), "-o", str(png)]) == 0
    assert png.stat().st_size > 10_000
    sweep_file.write_text("[axes.omega]\nmin = 20.0\nmax = 10.0\nnum = 8\n")
    assert main(["run", str(sweep_file), "-o", str(out)]) == 2
    assert "empty or reversed" in capsys.readouterr().err
    assert main(["plot", str(tmp_path / "none.nc"), "-o", str(png)]) == 2


def test_plot_rejects_a_cube(tmp_path):
    from impactbeams.plotting import plot_dataset

    clearance = {"min": 1e-5, "max": 2e-5, "num": 2}
    cube = small(params={}, axes={**SMALL["axes"], "clearance": clearance})
    ds = run_sweep(cube, progress=False)
    with pytest.raises(ParameterError, match="needs a 2-D sweep"):
        plot_dataset(ds, tmp_path / "c.png")


def test_every_chunk_of_a_map_calls_the_same_twin(monkeypatch):
    """A map larger than one block calls the parallel twin for its short last chunk too.

    Each twin compiles its callees anew (`kernels.jit` links them, uncached), so a last chunk on
    the serial twin would cost a second cold compile. Equal results either way.
    """
    from impactbeams.kernels import first_impact
    from impactbeams.sweep.plan import first_impact_kernel

    sweep = small(axes={"omega": {"min": 20.0, "max": 400.0, "num": 37},
                        "force_amplitude": {"min": 1e-5, "max": 1e-3, "num": 8,
                                            "scale": "log"}})
    assert sweep.size > first_impact._BLOCK and small().size <= first_impact._BLOCK
    assert first_impact_kernel(sweep) == "first_impact_map_parallel"
    assert first_impact_kernel(small()) == first_impact_kernel(sweep, parallel=False) \
        == "first_impact_map_serial"
    expected = run_sweep(sweep, progress=False).first_impact_time.values

    def refused(*args):
        raise AssertionError("the serial twin was called")

    monkeypatch.setattr(first_impact, "first_impact_map_serial", refused)
    chunked = run_sweep(sweep, progress=False, chunk_cells=first_impact._BLOCK + 8)
    np.testing.assert_array_equal(chunked.first_impact_time.values, expected)


@pytest.mark.parametrize(("params", "axis", "first", "worst"), [
    # a longer beam 1 is softer: more of its modes lie below the contact's stiffness
    ({"contact_stiffness": 1e5}, {"l1": {"min": 0.1, "max": 0.3, "num": 3}}, 20, 44),
    # the second of two contacts stiffens from 1e3 to 1e6 N/m
    ({"contacts": [{"clearance": 1e-5}, {"position1": 0.05, "clearance": 1e-5}]},
     {"contacts.1.stiffness": {"min": 1e3, "max": 1e6, "num": 3}}, 32, 36),
], ids=["length", "several"])
def test_the_contact_resolution_warning_reads_the_grids_worst_point(params, axis, first,
                                                                   worst):
    """Along an axis that changes the geometry the warning reads the point that needs the
    most modes, not the first: there `needed_modes` of every contact, each grid point's
    (computed here point by point), gives ``first`` and at the grid's end ``worst``; a run
    with ``first`` modes warns that it needs ``worst``, and its Dataset says so."""
    from impactbeams.contact.spring import needed_modes

    sweep = sweep_from_mapping({"t_max": 1e-3, "n_modes": first,
                                "observables": ["impact_count"], "params": params,
                                "axes": axis}, source="test sweep")
    (name, spec), = axis.items()
    per_point = [max(needed_modes(run) for run in sweep.params_at({name: value}).each_contact())
                 for value in np.linspace(spec["min"], spec["max"], spec["num"])]
    assert per_point[0] == first and max(per_point) == per_point[-1] == worst
    assert contact_resolution(sweep) == worst
    with pytest.warns(RuntimeWarning, match=f"n_modes = {first} does not resolve the spring "
                                            f"contact of test sweep: use n_modes >= {worst}"):
        dataset = run_sweep(sweep, parallel=False)
    assert dataset.attrs["contact_resolved"] == 0
    assert dataset.attrs["contact_resolution_modes"] == worst
