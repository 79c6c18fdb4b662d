"""One writer per output: an exclusive lock on ``OUT.nc``, the file ``OUT.nc.lock`` next to it.

A run takes the lock before it creates or writes anything for its output and holds it until
the file is complete (or the run stops): a second run on the same output is refused at once
([`OutputInUse`][], naming the first one's process, host and start). The lock is
``fcntl.flock`` on the lock file, which records the holder; the operating system releases it
when its process ends, however it ends, so a lock file left by a killed run is stale and the
next run takes it over (with a warning). A normal release deletes the file.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import fcntl
import json
import os
import socket
import threading
import time
import warnings
from collections.abc import Iterator
from pathlib import Path

from impactbeams.io import writing
from impactbeams.params import ParameterError

# lock files held by this process, and the thread holding each: a call inside a run holding
# the lock (``impactbeams run`` takes it before it announces, then calls write_sweep) reuses it
_HELD: dict[str, int] = {}
# how long a refused run waits for the holder's record (written just after its lock is taken)
_RECORD_WAIT = 0.5


class OutputInUse(ParameterError):
    """Another run (process, host, start named in the message) is writing the same output."""


def lock_path(output: Path) -> Path:
    """The lock file of ``output``."""
    return output.with_name(output.name + ".lock")


@contextlib.contextmanager
def output_lock(output: str | Path) -> Iterator[None]:
    """Hold the exclusive lock on ``output`` for the body ([`OutputInUse`][] if taken).

    Missing folders above ``output`` are created for the lock file, and removed again if they
    are still empty when the lock is released. Writing the lock file may raise
    [`WriteError`][impactbeams.io.WriteError].
    """
    path = lock_path(Path(output))
    key = os.path.realpath(path)
    if _HELD.get(key) == threading.get_ident():
        yield
        return
    created = _missing_folders(path.parent)
    try:
        descriptor = _acquire(path)
    except BaseException:
        _remove_empty(created)
        raise
    _HELD[key] = threading.get_ident()
    try:
        yield
    finally:
        del _HELD[key]
        with contextlib.suppress(OSError):  # unlink while locked: nobody locks a dead file
            path.unlink()
        os.close(descriptor)
        _remove_empty(created)


def _acquire(path: Path) -> int:
    """The descriptor of ``path`` locked by this process, with this process's record in it."""
    while True:
        with writing(path):
            descriptor = _open(path)
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            holder = _wait_for_record(descriptor)
            os.close(descriptor)
            if error.errno not in (errno.EAGAIN, errno.EACCES):
                raise
            raise OutputInUse(f"output {path.with_suffix('')} is being written by another "
                              f"run ({_describe(holder)}; lock file {path}): wait for it to "
                              "finish, or choose another output") from None
        if _is_current(descriptor, path):
            break
        os.close(descriptor)  # its holder deleted it as it finished: lock the new one
    try:
        previous = _record(descriptor)
        with writing(path):
            os.ftruncate(descriptor, 0)
            os.pwrite(descriptor, json.dumps(_this_process()).encode(), 0)
    except BaseException:
        with contextlib.suppress(OSError):  # still locked: nobody else has opened this file
            path.unlink()
        os.close(descriptor)
        raise
    if previous:
        warnings.warn(f"took over the lock file {path} left by {_describe(previous)}, which "
                      "ended without releasing it", RuntimeWarning, stacklevel=4)
    return descriptor


def _open(path: Path, attempts: int = 10) -> int:
    """``path`` opened for reading and writing, created with its folders if missing.

    Retried if the folder disappears in between (a refused run removing the folder it made).
    """
    for _ in range(attempts):
        path.parent.mkdir(parents=True, exist_ok=True)
        with contextlib.suppress(FileNotFoundError):
            return os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    return os.open(path, os.O_RDWR | os.O_CREAT, 0o644)


def _is_current(descriptor: int, path: Path) -> bool:
    """Whether ``path`` still names the file open as ``descriptor``."""
    try:
        return os.path.samestat(os.fstat(descriptor), os.stat(path))
    except FileNotFoundError:
        return False


def _this_process() -> dict[str, object]:
    since = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    return {"pid": os.getpid(), "host": socket.gethostname(), "since": since}


def _record(descriptor: int) -> dict | None:
    """The holder recorded in the open lock file, None if it is empty or unreadable."""
    try:
        record = json.loads(os.pread(descriptor, 4096, 0) or b"null")
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def _wait_for_record(descriptor: int) -> dict | None:
    """The holder's record, waiting a moment if it has the lock but has not yet written it."""
    deadline = time.monotonic() + _RECORD_WAIT
    while (record := _record(descriptor)) is None and time.monotonic() < deadline:
        time.sleep(0.01)
    return record


def _describe(record: dict | None) -> str:
    """E.g. ``"process 1234 on host node1, since 2026-11-24 18:45:16 UTC"``."""
    if record is None:
        return "a process that has not recorded itself"
    return (f"process {record.get('pid', '?')} on host {record.get('host', '?')}, since "
            f"{record.get('since', '?')}")


def _missing_folders(folder: Path) -> list[Path]:
    """The folders from ``folder`` up that do not exist, deepest first."""
    missing = []
    while not folder.exists() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    return missing


def _remove_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first) while they are empty: a refused run leaves none."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return
