"""Checkpoints of a continuation, so that a killed or interrupted one resumes bit for bit.

At the top of every step `impactbeams.continuation.branch.continue_branches` hands its
`Course` (the points so far, the step, the steps' points, the branches switched to, each
follower's carried Newton-Picard basis) to a [`CourseLog`][], which appends it to a log under
``OUT.nc.partial/``, next to the output (as a sweep saves its chunks there,
`impactbeams.sweep.store`). The same command reads the log's last whole record and goes on from
that step as the first run would have: the same points, bit for bit, whether the first run was
stopped by Ctrl-C, SIGTERM or SIGKILL.

The log is one pickle stream per run (``course_0000.log``, ``course_0001.log`` after a resume,
...) whose records share their objects: a record writes only the points that are new since
the last one (a few kB per point, the monodromy's size), and refers to the others, so that the
objects shared between branches, steps and points (the same ``x`` array, on which
`branch._append` decides) are shared again when read. Each record is framed by its length and
CRC-32: a record cut by a kill, or damaged, ends the log where it starts. A resumed run starts
a new stream with its first record and then deletes the older ones. ``run.json`` records the
continuation's fingerprint and the code's digest: a partial run of another continuation, or of
other code, is refused (one line), never resumed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import json
import pickle
import shutil
import struct
import warnings
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np

from impactbeams import __version__
from impactbeams.continuation.arclength import Follower, Settings
from impactbeams.continuation.branch import Branch, ContinuationInterrupted, Course, Position
from impactbeams.io import WriteError, write_netcdf, write_text, writing
from impactbeams.lock import output_lock
from impactbeams.params import ParameterError
from impactbeams.sweep.plan import NUMERIC_CODE, code_digest
from impactbeams.sweep.store import partial_folder

if TYPE_CHECKING:
    import xarray as xr

    from impactbeams.continuation.problem import Problem
    from impactbeams.continuation.run import Continuation
    from impactbeams.continuation.twoparameter import BifurcationCurve

RECORD = "run.json"  # what the log belongs to
SEGMENT = "course_{:04d}.log"
_FRAME = struct.Struct("<QI")  # a record's length and CRC-32
# the code a continuation's points depend on, beyond a sweep's
CONTINUATION_CODE = (*NUMERIC_CODE, "continuation/*.py", "orbits/*.py", "trajectory/*.py")


def fingerprint(continuation: Continuation | BifurcationCurve) -> str:
    """Hash of everything ``continuation`` (or a two-parameter curve) sets and the version."""
    fields = {field.name: getattr(continuation, field.name)
              for field in dataclasses.fields(continuation)}
    fields["params"] = continuation.params.as_dict()
    if fields["state"] is not None:
        fields["state"] = np.asarray(fields["state"], dtype=float).tolist()
    text = json.dumps({"continuation": fields, "version": __version__}, sort_keys=True,
                      default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class CourseLog:
    """The checkpoints of one continuation into ``output``, appended under ``OUT.nc.partial/``.

    Call it with a `Course` to save it; `restore` gives the last one saved by an earlier run
    (after checking that it was of the same continuation and code). A curve in two
    parameters (`impactbeams.continuation.twoparameter`) is saved as a `Course` of one
    branch: its points, and the step it is at.
    """

    def __init__(self, output: Path, continuation: Continuation | BifurcationCurve) -> None:
        self.directory = partial_folder(output)
        self.identity = {"continuation": fingerprint(continuation),
                         "code": code_digest(patterns=CONTINUATION_CODE)}
        self.segment = 0
        self._stream: BinaryIO | None = None
        self._pickler: pickle.Pickler | None = None
        self._buffer = io.BytesIO()
        self._saved: tuple[int, ...] = ()

    def restore(self, problem: Problem, settings: Settings) -> Course | None:
        """The last `Course` saved for this continuation, or None if there is none.

        ``problem``: the first branch's; a branch switched to is followed on it iterated.
        A ParameterError if the folder holds another continuation's or other code's log.
        """
        if not self.check():
            return None
        segments = sorted(self.directory.glob(SEGMENT.replace("{:04d}", "*")))
        last = None
        for path in segments:
            last = _last_record(path) or last
        self.segment = int(segments[-1].stem.split("_")[-1]) + 1 if segments else 0
        return None if last is None else _course(last, problem, settings)

    def check(self) -> bool:
        """Whether there is a partial run to resume; a ParameterError if it is not this one's.

        (Of another continuation, of other code, or without a readable record.)
        """
        record = self.directory / RECORD
        if not record.exists():
            if any(self.directory.glob(SEGMENT.replace("{:04d}", "*"))):
                raise ParameterError(f"{self.directory} holds no partial continuation this "
                                     f"impactbeams can resume (no {RECORD}): delete it or "
                                     "choose another output")
            return False
        try:
            saved = json.loads(record.read_text())
        except (OSError, ValueError):
            saved = None
        if not isinstance(saved, dict):
            raise ParameterError(f"{self.directory} holds no partial continuation this "
                                 f"impactbeams can resume (no readable {RECORD}): delete it or "
                                 "choose another output")
        if saved.get("continuation") != self.identity["continuation"]:
            raise ParameterError(f"{self.directory} holds a partial run of a different "
                                 "continuation: delete it or choose another output")
        if saved.get("code") != self.identity["code"]:
            raise ParameterError(
                f"{self.directory} holds a partial continuation computed by other impactbeams "
                f"code (code digest {saved.get('code')}, this code {self.identity['code']}): "
                "delete it to recompute with this code, or choose another output")
        return True

    def __call__(self, course: Course) -> None:
        """Append ``course`` (unless it is the last one saved: a step retried shorter)."""
        counts = (len(course.branches), course.index, len(course.position.steps),
                  *(len(branch.points) for branch in course.branches))
        if counts == self._saved:
            return
        if self._pickler is None:
            self._open()
        self._buffer.seek(0)
        self._buffer.truncate()
        self._pickler.dump(_plain(course))
        payload = self._buffer.getvalue()
        assert self._stream is not None
        with writing(Path(self._stream.name)):
            self._stream.write(_FRAME.pack(len(payload), zlib.crc32(payload)) + payload)
            self._stream.flush()
        if self.segment and not self._saved:  # the new stream holds a whole record: the
            self._remove_older()  # older ones can go
        self._saved = counts

    def _open(self) -> None:
        with writing(self.directory):
            self.directory.mkdir(parents=True, exist_ok=True)
        if not (self.directory / RECORD).exists():
            write_text(self.directory / RECORD, json.dumps(self.identity))
        path = self.directory / SEGMENT.format(self.segment)
        with writing(path):
            self._stream = open(path, "wb")  # noqa: SIM115  (closed by close())
        self._pickler = pickle.Pickler(self._buffer, protocol=pickle.HIGHEST_PROTOCOL)

    def _remove_older(self) -> None:
        for number in range(self.segment):
            with contextlib.suppress(OSError):
                (self.directory / SEGMENT.format(number)).unlink(missing_ok=True)

    def close(self) -> None:
        """Close the log's file (it stays on disk: `remove` deletes it)."""
        if self._stream is not None:
            self._stream.close()

    def remove(self) -> None:
        """Delete the partial folder once the output is written (a failure is a warning)."""
        self.close()
        try:
            shutil.rmtree(self.directory)
        except FileNotFoundError:
            pass
        except OSError as error:
            warnings.warn(f"the result is complete, but {self.directory} could not be deleted "
                          f"({error.strerror or error}): delete it by hand", RuntimeWarning,
                          stacklevel=2)


def saved_points(output: Path) -> int:
    """How many branch points the partial folder of ``output`` holds (0: none to resume)."""
    folder = partial_folder(output)
    last = None
    for path in sorted(folder.glob(SEGMENT.replace("{:04d}", "*"))):
        last = _last_record(path) or last
    return 0 if last is None else sum(len(points) for points, *_ in last["branches"])


def _plain(course: Course) -> dict[str, Any]:
    """What is saved of ``course``: plain containers (new each time) of the shared objects."""
    position = course.position
    return {"branches": [(tuple(branch.points), branch.period, branch.scaling, branch.ending,
                          branch.origin) for branch in course.branches],
            "index": course.index, "carried": _carried(course.follower.problem),
            "position": (position.current, position.ds, tuple(position.steps), position.near),
            "queue": [(index, _carried(follower.problem)) for follower, index in course.queue]}


def _course(saved: dict[str, Any], problem: Problem, settings: Settings) -> Course:
    """The `Course` of a saved record; its followers on ``problem`` (iterated as they were)."""
    branches = [Branch(list(points), period, scaling, ending, origin)
                for points, period, scaling, ending, origin in saved["branches"]]

    def follower(index: int, carried: np.ndarray | None) -> Follower:
        followed = problem
        while followed.period < branches[index].period:  # a branch switched to: doubled
            followed = followed.iterated(2)
        if carried is not None:
            followed.basis = carried  # type: ignore[attr-defined]
        return Follower(followed, branches[index].scaling, settings)

    current, ds, steps, near = saved["position"]
    return Course(branches, follower(saved["index"], saved["carried"]), saved["index"],
                  Position(current, ds, list(steps), near),
                  [(follower(index, carried), index) for index, carried in saved["queue"]])


def _carried(problem: Problem) -> np.ndarray | None:
    """The state a problem carries from evaluation to evaluation (Newton-Picard's basis)."""
    return getattr(problem, "basis", None)


def _records(path: Path) -> Iterator[dict[str, Any]]:
    """The whole records of one log file, in order (up to the first cut or damaged one)."""
    try:
        data = path.read_bytes()
    except OSError:
        return
    stream = io.BytesIO()
    unpickler = pickle.Unpickler(stream)  # one memo for the whole stream, as it was written
    offset = 0
    while offset + _FRAME.size <= len(data):
        size, crc = _FRAME.unpack_from(data, offset)
        payload = data[offset + _FRAME.size:offset + _FRAME.size + size]
        if len(payload) < size or zlib.crc32(payload) != crc:
            return
        stream.seek(0)
        stream.truncate()
        stream.write(payload)
        stream.seek(0)
        try:
            yield unpickler.load()
        except Exception:  # noqa: BLE001  (a record this code cannot read ends the log)
            return
        offset += _FRAME.size + size


def _last_record(path: Path) -> dict[str, Any] | None:
    last = None
    for last in _records(path):  # noqa: B007
        pass
    return last


def checkpointed(output: Path, subject: Continuation | BifurcationCurve,
                 compute: Callable[[CourseLog], xr.Dataset]) -> xr.Dataset:
    """``compute(log)``'s Dataset, written to ``output``, checkpointed into ``log``.

    ``subject``: the continuation or curve the log is of. One writer per output (the lock of
    `impactbeams.lock`); the log is removed once the output is written. On Ctrl-C
    (`ContinuationInterrupted`, its ``dataset`` what was computed) that dataset is written to
    ``OUTPUT.partial/OUTPUT``, to look at, and the log kept to resume from.
    """
    with reporting_kept_points(output), output_lock(output):
        log = CourseLog(output, subject)
        try:
            dataset = compute(log)
        except ContinuationInterrupted as interrupted:
            log.close()  # what was computed, to look at: the log resumes from its last step
            write_netcdf(interrupted.dataset, log.directory / output.name)
            raise
        write_netcdf(dataset, output)
        log.remove()
    return dataset


@contextlib.contextmanager
def reporting_kept_points(output: Path) -> Iterator[None]:
    """Add to a [`WriteError`][impactbeams.io.WriteError] of the body what the run keeps."""
    try:
        yield
    except WriteError as error:
        kept = saved_points(output)
        error.advice = (f"{kept} branch points are kept in {partial_folder(output)}/ and the "
                        "same command resumes from them" if kept else
                        "no branch point is kept: the same command starts again")
        raise


# bytes a branch point takes in the log beyond its monodromy (state, tangent, residual,
# multipliers, measures, each record's list of the points): 2.5 kB of 3.3 kB on the shipped
# example (5 modes; docs/benchmarks/continuation_checkpoint.json)
POINT_OVERHEAD = 2048


def expected_log_size(continuation: Continuation) -> int:
    """Disk space (bytes) the checkpoints and the output of ``continuation`` need at least.

    Each point keeps its monodromy (8 (2 N)^2 bytes) and its vectors; the first branch has
    at least `fewest_points`; the output holds far less than the log.
    """
    from impactbeams.continuation.run import fewest_points, state_size

    n = state_size(continuation)
    return 2 * fewest_points(continuation) * (8 * n * n + 64 * n + POINT_OVERHEAD)
