"""One writer per output, and write errors that lose nothing (issue 20).

The lock: a second run on an output being written is refused at once (one line, exit 2,
naming the first run's process), a lock left by a killed run is taken over with a warning, and
the lock is released on every exit. Write errors: an ``OSError(ENOSPC)`` (or netCDF's HDF
error) injected at each write site of a run gives one line naming the file, exit 1, the
finished chunks kept, and the same command then resumes to the bits of an uninterrupted run.
A real full disk and a read-only one (a tmpfs, where mounting is allowed) do the same.
"""

import errno
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time

import netCDF4
import numpy as np
import pytest
import xarray as xr

from impactbeams.cli import main
from impactbeams.io import WriteError
from impactbeams.lock import OutputInUse, lock_path, output_lock
from impactbeams.params import ParameterError
from impactbeams.sweep import load_sweep, write_sweep

# a first-impact map of 6 x 5 cells in 6 chunks of one omega line each: fast, and enough chunks
# for a fault before, between and after them
SWEEP = ("t_max = 0.3\nn_modes = 4\n[params]\nclearance = 1.1e-5\n"
         "[axes.omega]\nmin = 20.0\nmax = 400.0\nnum = 6\n"
         "[axes.force_amplitude]\nmin = 1e-5\nmax = 1e-3\nnum = 5\nscale = \"log\"\n")
RUN = ["run", "map.toml", "-o", "out.nc", "--quiet", "--chunk-cells", "5"]
CHUNKS = 6
ENOSPC = os.strerror(errno.ENOSPC)


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "map.toml").write_text(SWEEP)
    return tmp_path


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted run's file."""
    path = tmp_path_factory.mktemp("reference") / "whole.nc"
    write_sweep(load_sweep_text(path.parent), path, chunk_cells=5)
    return path


def load_sweep_text(folder):
    (folder / "map.toml").write_text(SWEEP)
    return load_sweep(folder / "map.toml")


def assert_same_contents(path, reference):
    """Every data variable and coordinate equal bit for bit, with its dtype."""
    with xr.open_dataset(path) as a, xr.open_dataset(reference) as b:
        assert set(a.variables) == set(b.variables)
        for name in b.variables:
            assert a[name].dtype == b[name].dtype, name
            assert a[name].values.tobytes() == b[name].values.tobytes(), name


def one_error_line(capsys):
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert "Traceback" not in err
    assert lines and lines[-1].startswith("impactbeams: error: "), err
    return lines[-1].removeprefix("impactbeams: error: ")


# --- one writer per output ----------------------------------------------------------------------

HOLDER = """
import sys, time
from impactbeams.lock import output_lock
with output_lock(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(120)
"""


@pytest.fixture
def holder(scratch):
    """Another process holding the lock of out.nc (killed at the end)."""
    process = subprocess.Popen([sys.executable, "-c", HOLDER, str(scratch / "out.nc")],
                               stdout=subprocess.PIPE, text=True)
    assert process.stdout.readline() == "locked\n"
    yield process
    process.kill()
    process.wait()
    process.stdout.close()


def test_a_second_run_is_refused_at_once_naming_the_first(scratch, holder, capsys):
    before = sorted(os.listdir(scratch))
    start = time.perf_counter()
    assert main(RUN) == 2
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err  # one line, no plan printed before it
    assert err.startswith("impactbeams: error: output out.nc is being written by another run "
                          f"(process {holder.pid} on host {socket.gethostname()}, since ")
    assert "lock file out.nc.lock" in err
    assert sorted(os.listdir(scratch)) == before  # nothing created, the lock left alone
    assert elapsed < 5  # at once: nothing computed (imports only, 0.5 s measured)


def test_the_library_and_simulate_are_refused_too(scratch, holder, capsys):
    with pytest.raises(OutputInUse, match=f"process {holder.pid} on host"):
        write_sweep(load_sweep("map.toml"), "out.nc")
    assert issubclass(OutputInUse, ParameterError)
    assert main(["simulate", "--t-max", "0.01", "-o", "out.nc"]) == 2
    assert f"process {holder.pid} on host" in one_error_line(capsys)
    assert not (scratch / "out.nc").exists()


def test_a_stale_lock_of_a_killed_run_is_taken_over_with_a_warning(scratch, holder):
    holder.send_signal(signal.SIGKILL)
    holder.wait()
    assert lock_path(scratch / "out.nc").exists()  # left behind, its flock gone with the process
    with pytest.warns(RuntimeWarning, match=f"took over the lock file .*out.nc.lock left by "
                      f"process {holder.pid} on host .* which ended without releasing it"):
        with output_lock(scratch / "out.nc"):
            pass
    assert not lock_path(scratch / "out.nc").exists()


@pytest.mark.parametrize("stop", [KeyboardInterrupt, ParameterError, SystemExit])
def test_the_lock_is_released_on_every_exit(tmp_path, stop):
    output = tmp_path / "new" / "sub" / "x.nc"
    with pytest.raises(stop), output_lock(output):
        assert lock_path(output).exists()
        raise stop()
    assert not (tmp_path / "new").exists()  # the folders made for the lock file are gone
    with output_lock(output):  # free again
        (output.parent / "kept").touch()
    assert sorted(os.listdir(output.parent)) == ["kept"]


def test_a_thread_of_the_same_process_is_refused(tmp_path):
    """The lock is per run, not per process: another thread's write_sweep is refused."""
    refused = []

    def second():
        try:
            write_sweep(load_sweep_text(tmp_path), tmp_path / "out.nc")
        except OutputInUse as error:
            refused.append(str(error))

    with output_lock(tmp_path / "out.nc"):
        thread = threading.Thread(target=second)
        thread.start()
        thread.join()
    assert len(refused) == 1 and f"process {os.getpid()} on host" in refused[0]


SLOW_RUN = """
import sys, time
import impactbeams.sweep.run as run
from impactbeams.cli import main

compute = run.compute_chunk
def slow(*args, **kwargs):  # 0.2 s per chunk: the run lasts 6 s, whatever the machine's load
    time.sleep(0.2)
    return compute(*args, **kwargs)
run.compute_chunk = slow
sys.exit(main(sys.argv[1:]))
"""


def test_two_runs_half_a_second_apart_give_one_correct_result(scratch, reference):
    """The issue's case: ``run -o two.nc`` twice, 0.5 s apart; the first one slowed down."""
    (scratch / "map.toml").write_text(SWEEP.replace("num = 6", "num = 30"))
    arguments = ["run", "map.toml", "-o", "two.nc", "--quiet", "--chunk-cells", "5"]
    first = subprocess.Popen([sys.executable, "-c", SLOW_RUN, *arguments],
                             stderr=subprocess.PIPE, text=True)
    while not (scratch / "two.nc.lock").exists() and first.poll() is None:
        time.sleep(0.01)
    time.sleep(0.5)
    second = subprocess.run([sys.executable, "-m", "impactbeams.cli", *arguments],
                            stderr=subprocess.PIPE, text=True, timeout=300)
    _, first_err = first.communicate(timeout=300)
    assert first.returncode == 0, first_err
    assert second.returncode == 2, second.stderr
    assert second.stderr.count("\n") == 1
    assert f"being written by another run (process {first.pid} on host" in second.stderr
    write_sweep(load_sweep("map.toml"), scratch / "whole.nc", chunk_cells=5)
    assert_same_contents(scratch / "two.nc", scratch / "whole.nc")
    assert sorted(os.listdir(scratch)) == ["map.toml", "two.nc", "whole.nc"]


# --- write errors at every write site ------------------------------------------------------------


def full_disk(*_, **__):
    raise OSError(errno.ENOSPC, ENOSPC)


class _Variable:
    """A netCDF variable whose block writes fail from the ``fail_at``-th one on."""

    def __init__(self, variable, writes):
        self._variable, self._writes = variable, writes

    def __setitem__(self, box, values):
        self._writes.append(box)
        if len(self._writes) >= self._writes.fail_at:
            raise RuntimeError("NetCDF: HDF error")  # what HDF5 gives for a full disk
        self._variable[box] = values


class _Writes(list):
    fail_at = 0


class _FaultyDataset:
    """A netCDF file being built whose ``site`` fails as HDF5 fails on a full disk."""

    def __init__(self, nc, site, writes):
        self._nc, self._site, self._writes = nc, site, writes

    def __getattr__(self, name):
        if self._site == "define" and name == "createVariable":
            raise RuntimeError("NetCDF: HDF error")
        return getattr(self._nc, name)

    def __getitem__(self, name):
        return _Variable(self._nc[name], self._writes) if self._site == "block" else self._nc[name]

    def close(self):
        self._nc.close()
        if self._site == "close":
            raise RuntimeError("NetCDF: HDF error")


def inject(site, monkeypatch, output):
    """Make the write at ``site`` fail as a full disk does; returns the file it names."""
    partial = output.with_name(output.name + ".partial")
    if site == "lock":
        monkeypatch.setattr(os, "pwrite", full_disk)
        return lock_path(output)
    if site == "record":
        write_text = type(output).write_text

        def failing(path, *args, **kwargs):
            if path.name.startswith(".run.json"):
                full_disk()
            return write_text(path, *args, **kwargs)

        monkeypatch.setattr(type(output), "write_text", failing)
        return partial / "run.json"
    if site == "chunk":  # the third chunk's save
        savez, saves = np.savez, []

        def failing_savez(*args, **kwargs):
            saves.append(1)
            if len(saves) == 3:
                full_disk()
            return savez(*args, **kwargs)

        monkeypatch.setattr(np, "savez", failing_savez)
        return partial / "chunk_000002.npz"
    if site == "rename":
        replace = os.replace

        def failing_replace(source, target):
            if os.path.abspath(target) == str(output):
                full_disk()
            replace(source, target)

        monkeypatch.setattr(os, "replace", failing_replace)
        return output
    dataset, writes = netCDF4.Dataset, _Writes()
    writes.fail_at = 5  # the third chunk's first variable (two per chunk)

    def faulty(path, mode="r", **kwargs):
        if mode != "w":
            return dataset(path, mode, **kwargs)
        if site == "create":
            raise OSError(errno.ENOSPC, ENOSPC, str(path))
        return _FaultyDataset(dataset(path, mode, **kwargs), site, writes)

    monkeypatch.setattr(netCDF4, "Dataset", faulty)
    return partial / output.name


# site: the finished chunks kept when it fails (6 chunks; every one but the last is saved)
SITES = {"lock": 0, "record": 0, "create": 0, "define": 0, "chunk": 2, "block": 3,
         "close": CHUNKS - 1, "rename": CHUNKS - 1}


@pytest.mark.parametrize(("site", "kept"), SITES.items(), ids=SITES.keys())
def test_a_write_error_is_one_line_keeps_the_chunks_and_the_run_resumes(
        scratch, reference, monkeypatch, capsys, site, kept):
    output = scratch / "out.nc"
    with monkeypatch.context() as patch:
        failed = inject(site, patch, output)
        assert main(RUN) == 1
    message = one_error_line(capsys)
    cause = ENOSPC if site in ("lock", "record", "chunk", "create", "rename") else "HDF error"
    assert message.startswith(f"could not write {failed.relative_to(scratch)}: "), message
    assert cause in message
    partial = scratch / "out.nc.partial"
    assert len(list(partial.glob("chunk_*.npz"))) == kept
    assert message.endswith(f"; {kept} finished chunks are kept in out.nc.partial/ and the "
                            "same command resumes from them" if kept else
                            "; no finished chunk is kept: the same command starts again")
    assert not output.exists() and not lock_path(output).exists()
    assert not list(scratch.rglob(".*.tmp")) and not (partial / "out.nc").exists()

    computed = []
    assert write_sweep(load_sweep("map.toml"), output, chunk_cells=5, on_chunk=computed.append)
    assert sorted(computed) == list(range(kept, CHUNKS))  # nothing saved is computed again
    assert_same_contents(output, reference)
    assert sorted(os.listdir(scratch)) == ["map.toml", "out.nc"]


def test_a_write_error_in_the_library_is_a_write_error(scratch, monkeypatch):
    inject("chunk", monkeypatch, scratch / "out.nc")
    with pytest.raises(WriteError) as caught:
        write_sweep(load_sweep("map.toml"), scratch / "out.nc", chunk_cells=5)
    assert isinstance(caught.value, OSError) and caught.value.errno == errno.ENOSPC
    assert caught.value.filename == str(scratch / "out.nc.partial" / "chunk_000002.npz")


def test_a_partial_folder_that_cannot_be_deleted_is_a_warning(scratch, monkeypatch):
    """A leftover partial folder that cannot be deleted at the end is a warning, not an error:
    the result is complete."""
    monkeypatch.setattr(shutil, "rmtree", full_disk)
    with pytest.warns(RuntimeWarning, match="the result is complete, but .*out.nc.partial "
                      "could not be deleted"):
        write_sweep(load_sweep("map.toml"), scratch / "out.nc", chunk_cells=5)
    assert (scratch / "out.nc").exists()


# --- a real full or read-only disk --------------------------------------------------------------


def mount_tmpfs(folder, size):
    """Mount a tmpfs of ``size`` at ``folder``, or skip: mounting needs root (CAP_SYS_ADMIN)."""
    folder.mkdir()
    if shutil.which("mount") is None:
        pytest.skip("no mount command here")
    result = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                            capture_output=True, text=True)
    if result.returncode:
        pytest.skip(f"cannot mount a tmpfs here ({result.stderr.strip() or 'not root'}); "
                    "chmod cannot make a read-only folder for root either")


@pytest.fixture
def tmpfs(tmp_path):
    folder = tmp_path / "disk"
    mount_tmpfs(folder, "100k")
    yield folder
    subprocess.run(["umount", "-l", str(folder)], check=False)


def remount(folder, options):
    subprocess.run(["mount", "-o", f"remount,{options}", str(folder)], check=True)


def test_a_real_full_disk_keeps_the_chunks_and_resumes(tmpfs):
    """100 kB hold the run record and about five 16 kB chunks of a 40 x 50 map in 40 chunks."""
    text = SWEEP.replace("num = 6", "num = 40").replace("num = 5", "num = 50")
    sweep_file = tmpfs.parent / "big.toml"
    sweep_file.write_text(text)
    output = tmpfs / "out.nc"
    with pytest.raises(WriteError) as caught:
        write_sweep(load_sweep(sweep_file), output, chunk_cells=50)
    kept = len(list(tmpfs.glob("out.nc.partial/chunk_*.npz")))
    assert kept > 0 and f"; {kept} finished chunks are kept in " in str(caught.value)
    assert ENOSPC in str(caught.value) or "the disk is full" in str(caught.value)
    assert not lock_path(output).exists() and not output.exists()
    # HDF5 keeps a file it could not flush open until the process ends; emptied, it holds no
    # space: the disk holds the saved chunks and the run record only
    usage = shutil.disk_usage(tmpfs)
    assert usage.total - usage.free == sum(p.stat().st_blocks * 512 for p in tmpfs.rglob("*"))
    remount(tmpfs, "size=4m")
    computed = []
    write_sweep(load_sweep(sweep_file), output, chunk_cells=50, on_chunk=computed.append)
    assert len(computed) == 40 - kept
    whole = tmpfs.parent / "whole.nc"
    write_sweep(load_sweep(sweep_file), whole, chunk_cells=50)
    assert_same_contents(output, whole)


def test_a_read_only_disk_is_one_line(tmpfs, scratch, capsys):
    """A read-only folder from the start (the CLI refuses it before any work; the library when
    it writes the lock file). Made read-only during a run, it cannot be: Linux refuses to
    remount a file system read-only while a file is open for writing on it (the netCDF file
    being built), and chmod does not stop root."""
    remount(tmpfs, "ro")
    output = tmpfs / "out.nc"
    with pytest.raises(WriteError, match=f"could not write {output}.lock: "
                       f"{os.strerror(errno.EROFS)}; no finished chunk is kept"):
        write_sweep(load_sweep("map.toml"), output)
    assert main(["run", "map.toml", "-o", str(output)]) == 2
    assert "does not accept new files (Read-only file system)" in one_error_line(capsys)


def test_a_partial_folder_removed_during_the_run_is_one_line(scratch, reference, monkeypatch,
                                                            capsys):
    """The partial folder deleted while the third chunk is saved: that save fails (its folder
    is not made again: the chunks before it are gone), the run stops, and starts again."""
    savez, saves = np.savez, []

    def removing_savez(*args, **kwargs):
        saves.append(1)
        if len(saves) == 3:
            shutil.rmtree(scratch / "out.nc.partial")
        return savez(*args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(np, "savez", removing_savez)
        assert main(RUN) == 1
    assert one_error_line(capsys) == (
        f"could not write out.nc.partial/chunk_000002.npz: {os.strerror(errno.ENOENT)}; no "
        "finished chunk is kept: the same command starts again")
    assert sorted(os.listdir(scratch)) == ["map.toml"]
    assert main(RUN) == 0
    assert_same_contents(scratch / "out.nc", reference)
