"""Sweeps on a Dask LocalCluster (loopback): same bits as a local run, lost workers, resume."""

import contextlib
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest
import xarray as xr

from fe_reference import beam_matrices, tip_dof
from impactbeams import MatrixStructure, Params
from impactbeams.cli import main
from impactbeams.sweep import run_sweep, sweep_from_mapping
from impactbeams.sweep.dask_runner import dask_client, dask_runner, default_threads_per_task

GRID = {  # 40 x 30 cells, a fraction of a second of serial work
    "t_max": 0.3,
    "n_modes": 4,
    "params": {"clearance": 1.1e-5},
    "axes": {
        "omega": {"min": 20.0, "max": 400.0, "num": 40},
        "force_amplitude": {"min": 1e-5, "max": 1e-3, "num": 30, "scale": "log"},
    },
}
SLOW_GRID = {  # 250000 cells, about 2 s of serial work: 16 chunks of 32 lines, ~0.1 s each
    "t_max": 1.0,
    "n_modes": 20,
    "params": {"clearance": 1.1e-5},
    "axes": {
        "omega": {"min": 10.0, "max": 400.0, "num": 500},
        "force_amplitude": {"min": 1e-5, "max": 1e-3, "num": 500},
    },
}


def _children():
    """Child processes, without multiprocessing's resource tracker (it lives as long as we do)."""
    import psutil

    children = set()
    for child in psutil.Process().children(recursive=True):
        with contextlib.suppress(psutil.Error):
            if "resource_tracker" not in " ".join(child.cmdline()):
                children.add(child.pid)
    return children


# Generous: on a loaded 2-core CI machine workers start, compile and stop several times more
# slowly; every wait polls for its event and ends as soon as it occurs.
DEADLINE = 600.0


def wait_for(condition, what, deadline=DEADLINE, interval=0.02):
    """Poll ``condition()`` until it returns a true value (returned); fail clearly on timeout."""
    end = time.monotonic() + deadline
    while not (value := condition()):
        if time.monotonic() > end:
            pytest.fail(f"{what}: not within {deadline} s")
        time.sleep(interval)
    return value


@contextlib.contextmanager
def no_process_left():
    """Check on exit that every child process started inside has ended."""
    before = _children()
    yield
    wait_for(lambda: not _children() - before, "worker processes left behind", deadline=300)


@contextlib.contextmanager
def local_cluster(workers=2):
    """A client of a fresh LocalCluster of loopback workers, all gone on exit."""
    with no_process_left(), dask_client(local_workers=workers) as client:
        yield client


@pytest.fixture(scope="module")
def client():
    with local_cluster() as client:
        yield client


def assert_same_map(a, b):
    assert np.array_equal(a.first_impact_time, b.first_impact_time, equal_nan=True)
    assert np.array_equal(a.impacted, b.impacted)


@pytest.mark.parametrize("threads_per_task", [None, 2], ids=["serial-kernel", "parallel-kernel"])
def test_distributed_map_is_bitwise_equal_to_local(client, threads_per_task, tmp_path):
    sweep = sweep_from_mapping(GRID, source="grid")
    local = run_sweep(sweep, progress=False)
    seen = []
    out = tmp_path / "map.nc"
    runner = dask_runner(client, threads_per_task=threads_per_task)
    remote = run_sweep(sweep, output=out, progress=False, chunk_cells=120, runner=runner,
                       on_chunk=seen.append)
    assert sorted(seen) == list(range(10))  # every chunk (4 lines of 30 cells) exactly once
    assert_same_map(remote, local)
    assert out.exists() and not (tmp_path / "map.nc.partial").exists()
    assert default_threads_per_task(client) == max(1, os.cpu_count() // 2)


def test_a_map_over_a_contacts_field_on_the_cluster_is_the_local_map(client, tmp_path):
    """Several contacts, an axis on one contact's clearance (each contact's map over its own
    axes, shared along the other's): in chunks of 12 cells on the cluster, the local bits."""
    sweep = sweep_from_mapping({
        "t_max": 0.05, "n_modes": 4,
        "params": {"counterpart": "stop", "contacts": [{"position1": 0.05}, {"clearance": 6e-6}]},
        "axes": {"omega": {"min": 100.0, "max": 400.0, "num": 5},
                 "contacts.0.clearance": {"min": 0.3e-6, "max": 3e-6, "num": 6}}},
        source="contacts")
    local = run_sweep(sweep, progress=False)
    remote = run_sweep(sweep, output=tmp_path / "contacts.nc", progress=False, chunk_cells=12,
                       runner=dask_runner(client))
    assert_same_map(remote, local)
    assert np.array_equal(remote.first_contact, local.first_contact)
    assert 0 < int(local.first_contact.sum()) < local.first_contact.size


@pytest.mark.slow  # 36 s: the workers compile the full dynamics' cell kernels
def test_maps_of_the_structures_people_test_on_the_cluster_are_the_local_maps(client,
                                                                              tmp_path):
    """A tip mass's mass as an axis, and the tests' FE model as a user structure (matrices,
    pickled to the workers with the sweep): each map in chunks of 4 cells on the cluster has
    the local bits, impact counts too (the full dynamics' cell kernels)."""
    beam = Params()
    K, M = beam_matrices(beam.EI1, beam.rhoA1, beam.l1, 10)  # 20 DOFs
    structures = {
        "attachments1": {"params": {"attachments1": [{"position": beam.l1}]},
                         "axis": ("attachments1.0.mass", 0.0, 2e-3)},
        "structure1": {"params": {"structure1": MatrixStructure(M, K, contact_dof=tip_dof(10),
                                                                length=beam.l1)},
                       "axis": ("clearance", 1e-5, 2e-5)}}
    for name, case in structures.items():
        axis, low, high = case["axis"]
        sweep = sweep_from_mapping({
            "t_max": 0.05, "n_modes": 12, "observables": ["first_impact_time", "impact_count"],
            "params": {"counterpart": "stop", "contact_stiffness": 1e4, **case["params"]},
            "axes": {"omega": {"min": 40.0, "max": 60.0, "num": 3},
                     axis: {"min": low, "max": high, "num": 4}}}, source=name)
        local = run_sweep(sweep, progress=False, parallel=False)
        remote = run_sweep(sweep, output=tmp_path / f"{name}.nc", progress=False,
                           chunk_cells=4, runner=dask_runner(client))
        assert_same_map(remote, local)
        assert np.array_equal(remote.impact_count, local.impact_count)
        assert int(local.impact_count.sum()) > 0, name  # the maps see contacts


def test_interrupted_client_resumes_from_saved_chunks(client, tmp_path):
    sweep = sweep_from_mapping(GRID, source="grid")
    out = tmp_path / "map.nc"
    done = []

    def stop_after_three(chunk):
        done.append(chunk)
        if len(done) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep, output=out, progress=False, chunk_cells=120,
                  runner=dask_runner(client), on_chunk=stop_after_three)
    partial = tmp_path / "map.nc.partial"
    assert sorted(int(p.stem[6:]) for p in partial.glob("chunk_*.npz")) == sorted(done)
    computed = []
    resumed = run_sweep(sweep, output=out, progress=False, chunk_cells=120,
                        runner=dask_runner(client), on_chunk=computed.append)
    assert sorted(computed) == sorted(set(range(10)) - set(done))
    assert_same_map(resumed, run_sweep(sweep, progress=False))
    assert not partial.exists()


def test_the_client_holds_the_output_lock_while_the_cluster_computes(client, tmp_path):
    """The writes happen in the client: a run on the same output from another thread (as
    from another process) is refused while the cluster's chunks come in."""
    from impactbeams.lock import OutputInUse, lock_path

    sweep = sweep_from_mapping(GRID, source="grid")
    out, refusals = tmp_path / "map.nc", []

    def second_run(chunk):
        def attempt():
            try:
                run_sweep(sweep, output=out, progress=False)
            except OutputInUse as error:
                refusals.append(str(error))

        thread = threading.Thread(target=attempt)
        thread.start()
        thread.join()

    run_sweep(sweep, output=out, progress=False, chunk_cells=120, runner=dask_runner(client),
              on_chunk=second_run).close()
    assert len(refusals) == 10 and all(f"process {os.getpid()} on host" in r for r in refusals)
    assert not lock_path(out).exists()


def test_workers_of_another_version_are_refused(client, monkeypatch):
    import impactbeams.sweep.dask_runner as dask_runner_module

    monkeypatch.setattr(dask_runner_module, "__version__", "0.0.0")  # client side only
    sweep = sweep_from_mapping(GRID, source="grid")
    with pytest.raises(RuntimeError, match="install the same version on every worker"):
        run_sweep(sweep, progress=False, runner=dask_runner(client))


def test_workers_with_other_code_are_refused(client, monkeypatch):
    """Same version, edited kernels (another code digest) on this side only: refused."""
    import impactbeams.sweep.dask_runner as dask_runner_module

    monkeypatch.setattr(dask_runner_module, "code_digest", lambda: "0" * 16)  # client side
    sweep = sweep_from_mapping(GRID, source="grid")
    with pytest.raises(RuntimeError, match=r"\(code 0{16}\): install the same version"):
        run_sweep(sweep, progress=False, runner=dask_runner(client))


def test_killed_worker_loses_and_doubles_no_chunk(tmp_path):
    """SIGKILL one of two workers while it computes a chunk: the scheduler reruns that chunk
    elsewhere, every chunk arrives once, and the map equals the local one."""
    sweep = sweep_from_mapping(SLOW_GRID, source="slow grid")
    seen, killed = [], {}
    with local_cluster() as client:

        def executing():
            keys = client.run(lambda dask_worker: [t.key for t in dask_worker.state.executing])
            return next(((w, k) for w, k in keys.items() if k), None)

        def kill_a_computing_worker(chunk):
            seen.append(chunk)
            if len(seen) != 3:
                return
            # all 16 chunks were submitted at once (window 16), so 13 are queued or running:
            # poll until a worker is inside one (it may be between two tasks right now)
            victim, keys = wait_for(executing, "a worker executing a chunk")
            killed["worker"], killed["keys"] = victim, keys
            os.kill(client.run(os.getpid, workers=[victim])[victim], signal.SIGKILL)

        remote = run_sweep(sweep, output=tmp_path / "s.nc", progress=False, chunk_cells=16000,
                           runner=dask_runner(client, window=16),
                           on_chunk=kill_a_computing_worker)
        # it died (the nanny may start a new one, at another address)
        wait_for(lambda: killed["worker"] not in client.nthreads(),
                 "the scheduler dropping the killed worker")
    lost = {int(key.split("-")[2]) for key in killed["keys"]}  # chunk numbers from task keys
    assert lost and lost <= set(seen[3:])  # the interrupted chunk arrived later, recomputed
    assert sorted(seen) == list(range(16))  # every chunk once: none lost, none doubled
    assert_same_map(remote, run_sweep(sweep, progress=False))


def test_cli_runs_on_a_local_cluster_and_at_a_scheduler_address(client, tmp_path, capsys):
    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text(
        "t_max = 0.2\n[axes.omega]\nmin = 20.0\nmax = 300.0\nnum = 8\n"
        '[axes.clearance]\nmin = 1e-6\nmax = 3e-5\nnum = 6\nscale = "log"\n'
    )
    run = ["run", str(sweep_file), "--chunk-cells", "10"]
    assert main([*run, "-o", str(tmp_path / "local.nc")]) == 0
    address = client.scheduler.address  # an existing cluster, as with `dask scheduler`
    for name, option in [("new", ["--local-cluster", "2"]), ("at", ["--scheduler", address])]:
        out = tmp_path / f"{name}.nc"
        with no_process_left():
            assert main([*run, "-o", str(out), *option]) == 0
        assert "100.0%" in capsys.readouterr().err
        with xr.open_dataset(out) as remote, xr.open_dataset(tmp_path / "local.nc") as local:
            assert_same_map(remote, local)


def test_cli_cluster_options_are_exclusive(tmp_path, capsys):
    assert main(["run", "s.toml", "--scheduler", "tcp://127.0.0.1:8786", "--local-cluster",
                 "2"]) == 2
    assert "not allowed with argument" in capsys.readouterr().err


def test_unreachable_scheduler_is_reported(tmp_path, capsys):
    import dask

    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text("[axes.omega]\nmin = 20.0\nmax = 300.0\nnum = 8\n")
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        code = main(["run", str(sweep_file), "--scheduler", "tcp://127.0.0.1:9"])
    assert code == 2
    assert "scheduler = 'tcp://127.0.0.1:9': cannot connect" in capsys.readouterr().err


def test_missing_dask_gives_an_install_hint(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    with pytest.raises(ImportError, match=r"pip install 'impactbeams\[distributed\]'"):
        with dask_client(local_workers=1):
            pass
    sweep_file = tmp_path / "s.toml"
    sweep_file.write_text("[axes.omega]\nmin = 20.0\nmax = 300.0\nnum = 8\n")
    assert main(["run", str(sweep_file), "-o", str(tmp_path / "s.nc"), "--local-cluster", "1"]) == 2
    assert "impactbeams[distributed]" in capsys.readouterr().err
