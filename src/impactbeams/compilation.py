"""Numba's compile of the kernels: whether a run will compile, and a report while it does.

Kernels compile on their first call and are cached on disk (``cache=True``): a fresh install
pays for it once per kind of run (docs/limits.md, "Time": cold compile times measured by
``benchmarks/calibrate_costs.py``). `kernels_cached` tells, before a run, whether its
entry kernels are in Numba's disk cache; `reporting_compiles` prints a line when a compile
starts and when it ends, from Numba's own compile events (no thread: the lines come from the
thread that compiles).
"""

from __future__ import annotations

import atexit
import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

REPORTED_COMPILE = 1.0  # s: an outermost compile at least this long ends with a line
# s: a compile (or a wait for the helper's) this long without a line gets one, and again after
# as long: no silent minutes under load
COMPILE_HEARTBEAT = 20.0

# The kernels called from Python by each kind of run (their callees compile with them, linked
# into their code, and load with them from the cache): (module in impactbeams.kernels, kernel
# names). Of several names, the run calls one: a first-impact map calls its serial twin when
# it is one block (`sweep.plan.first_impact_kernel`), and `kernels_cached` is told which.
ENTRY_KERNELS = {
    "first_impact": (("first_impact", ("first_impact_map_parallel",
                                       "first_impact_map_serial")),),
    "dynamics": (("observables", ("observables_map_parallel",)),),
    "lyapunov": (("lyapunov", ("lyapunov_map_parallel",)),),
    "long_time": (("stroboscope", ("stroboscope_map_serial", "stepped_map_serial")),),
    "simulate": (("dynamics", ("run_events",)), ("dynamics", ("sample_states",)),
                 ("dynamics", ("observed_states",)), ("stroboscope", ("tip_motions",)),
                 ("records", ("segments",))),
    # periodic orbits and their continuation: a run's kernels and the tangent dynamics'
    "orbits": (("dynamics", ("run_events",)), ("dynamics", ("sample_states",)),
               ("tangent", ("carry_tangents",)), ("contact", ("tangent_switch",)),
               ("stroboscope", ("tip_motions",))),
}


# A cold run's compile in two processes (`compile_in_two_processes`): what a helper process
# compiles while this one compiles the rest, and what this one compiles first (before the run,
# so that it is busy while the helper compiles what the run needs next). Each job: (module in
# impactbeams.kernels, kernel, argument types as `signature_text` writes them), as a cold run
# calls them (tests/test_compile.py checks them against a run). Shares of simulate's cold
# run in one process (16.6 s, load 2, 2026-11-25): run_events 54 % (the helper's) against
# run_inputs 16 % and the sampling kernels with peak_force 20 %.
_SETTINGS_ARRAYS = "float64[:, :, ::1], complex128[:, ::1]"
_SEGMENTS = ("Segments(float64[::1], int64[::1], bool[::1], float64[:, ::1], float64[:, ::1], "
             "float64[:, ::1], float64[:, ::1])")
_SWITCHING = ("Tuple((float64[:, ::1], float64[:, ::1], UniTuple(complex128[:, ::1], 3), "
              "complex128[:, ::1],))")
HELPER_JOBS = {
    "simulate": (("dynamics", "run_events",
                  f"{_SETTINGS_ARRAYS}, float64[:, ::1], {_SWITCHING}, settings, float64[::1], "
                  f"float64[::1], {_SEGMENTS}, float64, int64"),),
}
# What a helper compiles only to link, as a calling kernel would (`kernels.linking`), and hands over
# in a file that this process links instead of compiling it: a first map calls one kernel
# linking all the others; the helper takes its largest callee, `events.walk` (2.6 of its 7.2 s
# of CPU, 2026-11-28), which the map types after the columns' preparation and flank search
# (2.8 s), so this process rarely waits for it.
_BOUNDS = "Tuple((complex128, float64, float64, float64, bool,))"
LINK_JOBS = {
    "first_impact": (("events", "walk",
                      "float64[::1], float64[::1], float64, float64, float64, "
                      "Oscillators(float64[::1], float64[::1], complex128[::1], float64), "
                      "EventFunction(float64[::1], float64, complex128, float64), float64, "
                      f"float64, {_BOUNDS}, float64, float64[::1], float64[::1], "
                      "Rotor(complex128[::1], complex128[::1], bool[::1], int64[::1], "
                      "complex128[:, ::1], complex128[:, ::1], float64[:, ::1], "
                      "complex128[::1])"),),
}
AHEAD_JOBS = {
    "simulate": (
        ("forcing", "run_inputs",
         f"float64[::1], float64[:, :, ::1], float64[::1], {_SWITCHING}, float64, float64"),
        ("records", "segments", "int64, int64"),
        ("dynamics", "sample_states",
         f"{_SETTINGS_ARRAYS}, {_SWITCHING}, settings, {_SEGMENTS}, float64[::1], "
         "float64[:, ::1], float64[:, ::1], int64[::1]"),
        ("stroboscope", "tip_loads_at", "settings, int64[::1], float64[::1], float64[:, ::1]"),
        ("stroboscope", "tip_motions",
         f"{_SETTINGS_ARRAYS}, float64[:, ::1], settings, int64[::1], float64[::1], "
         "float64[:, ::1], float64[:, ::1], float64[:, ::1]"),
        ("contact_spring", "contact_states",
         f"{_SETTINGS_ARRAYS}, float64[:, ::1], settings, int64[::1], float64[::1], "
         "float64[:, ::1], float64[:, ::1], float64[:, ::1]"),
        ("dynamics", "observed_states",
         f"int64[::1], float64[::1], float64[:, ::1], float64[:, ::1], {_SWITCHING}, settings, "
         "float64[:, ::1], float64[:, ::1]"),
        ("peaks", "peak_force",
         "float64[:, ::1], complex128[::1], float64[::1], settings, float64[::1], float64[::1], "
         "float64, float64"),
    ),
}
HELPER = "IMPACTBEAMS_COMPILE_HELPER"  # "0" in the environment: compile in this process alone
_helpers: dict[str, subprocess.Popen] = {}  # kind -> its helper process (one per run kind)


def kernels_cached(kind: str, entry: str | None = None) -> bool:
    """Whether the entry kernels of a run of ``kind`` (``ENTRY_KERNELS``) are in the disk cache.

    ``entry``: the one name, of several, that the run calls (any of them otherwise). Each twin
    counts alone, since each compiles its callees anew (`kernels.linking`).

    Reads each kernel's cache index, as Numba does before it compiles (the file
    ``<module>.<name>-<line>.py<version>.nbi`` in the cache folder, which Numba's locator
    finds): it holds machine code for this CPU if it names this machine's code generator and
    its source stamp matches the kernel's file. Cheap (a small pickle per kernel).
    """
    for module, names in ENTRY_KERNELS[kind]:
        names = (entry,) if entry in names else names
        if not any(_has_machine_code(_kernel(module, name)) for name in names):
            return False
    return True


def _has_machine_code(dispatcher: Any) -> bool:
    cache = getattr(dispatcher, "_cache", None)
    index = getattr(cache, "_cache_file", None)
    if index is None:  # caching disabled: every process compiles
        return False
    try:
        magic = dispatcher.targetctx.codegen().magic_tuple()
        overloads = index._load_index()
    except Exception:  # an unreadable index (or a Numba without these): taken as a compile
        return False
    return any(key[1] == magic for key in overloads)


def compile_in_two_processes(kind: str, entry: str | None = None,
                             stream: TextIO | None = None) -> None:
    """Before a run of ``kind`` that will compile: split the compile with a helper process.

    The helper (``python -m impactbeams.compilation``) compiles ``HELPER_JOBS[kind]`` into
    Numba's disk cache and ``LINK_JOBS[kind]`` into files it hands over; meanwhile this process
    compiles ``AHEAD_JOBS[kind]``, then runs, and a kernel the helper owns is loaded from the
    cache, or linked from its file, once the helper has it (`kernels.linking` waits for it).
    A helper that fails or dies leaves its kernels to this process (with a line on ``stream``
    saying so). Nothing happens when the run's kernels are cached, with one core, in a helper
    itself, with ``IMPACTBEAMS_COMPILE_HELPER=0``, or on the plain path (`kernels.jit`: its
    kernels compile in full, as Numba does).
    """
    from impactbeams.kernels.jit import plain_numba

    jobs = (tuple(("cache", *job) for job in HELPER_JOBS.get(kind, ()))
            + tuple(("link", *job) for job in LINK_JOBS.get(kind, ())))
    if (not jobs or kind in _helpers or os.environ.get(HELPER) == "0"
            or (os.cpu_count() or 1) < 2 or plain_numba() or kernels_cached(kind, entry)):
        return
    helper = _start_helper(jobs, stream or sys.stderr)
    if helper is None:
        return
    _helpers[kind] = helper
    for module, name, text in AHEAD_JOBS.get(kind, ()):
        with contextlib.suppress(Exception):  # a stale job: the run compiles what it calls
            _kernel(module, name).compile(parse_signature(text))


def _kernel(module: str, name: str) -> Any:
    import importlib

    return getattr(importlib.import_module(f"impactbeams.kernels.{module}"), name)


def _helper_command() -> list[str]:
    return [sys.executable, "-m", "impactbeams.compilation"]


def _start_helper(jobs: tuple, stream: TextIO) -> subprocess.Popen | None:
    """Start the helper on ``jobs``; register each job's wait with `kernels.linking`.

    A job: (how, module, kernel, signature), how ``cache`` (compiled in full into the disk
    cache) or ``link`` (compiled to link, handed over in a file).
    """
    from impactbeams.kernels import linking

    handovers = tempfile.mkdtemp(prefix="impactbeams-compile-")  # the link jobs' files
    arguments = [handovers, *(field for job in jobs for field in job)]
    # the helper imports this package from where this process did (a path added at run time)
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    path = os.pathsep.join(filter(None, (package, os.environ.get("PYTHONPATH"))))
    try:
        helper = subprocess.Popen([*_helper_command(), *arguments], stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
                                  text=True, env={**os.environ, HELPER: "0", "PYTHONPATH": path})
    except OSError:
        shutil.rmtree(handovers, ignore_errors=True)
        return None
    outcomes = [threading.Event() for _ in jobs]
    done: set[int] = set()

    def read() -> None:  # the helper's "done i" lines, then its exit (reaped: no zombie)
        assert helper.stdout is not None
        for line in helper.stdout:
            words = line.split()
            if len(words) == 2 and words[0] == "done" and words[1].isdigit():
                done.add(int(words[1]))
                outcomes[int(words[1])].set()
        helper.stdout.close()
        helper.wait()
        for outcome in outcomes:
            outcome.set()

    threading.Thread(target=read, daemon=True, name="compile helper").start()
    atexit.register(_stop, helper, handovers)
    for index, (how, module, name, text) in enumerate(jobs):
        def wait(index: int = index, name: str = name, how: str = how) -> str | None:
            outcomes[index].wait()
            if index not in done:
                stream.write(f"impactbeams: the compile helper process did not compile "
                             f"{name} (exit {helper.poll()}): compiling it here\n")
                stream.flush()
                return None
            return _handover_file(handovers, index) if how == "link" else None
        try:
            key = (_kernel(module, name), parse_signature(text))
        except Exception:  # a stale job (renamed kernel): the helper fails on it too
            continue
        linking.COMPILED_ELSEWHERE[key] = wait
    return helper


def _handover_file(folder: str, index: int) -> str:
    """Where the helper writes link job ``index``'s compile (`linking._Kernel.link_into`)."""
    return os.path.join(folder, f"{index}.link")


def _stop(helper: subprocess.Popen, handovers: str) -> None:
    """End a helper still running when this process exits (an interrupted run).

    Removes the folder of its handed-over compiles too.
    """
    if helper.poll() is None:
        helper.terminate()
        helper.wait()
    shutil.rmtree(handovers, ignore_errors=True)


def _compile_jobs(fields: list[str]) -> None:
    """The helper: compile each (how, module, kernel, signature) job; ``done i`` after each.

    ``fields``: the folder for the link jobs' files, then the jobs' fields.
    """
    handovers, fields = fields[0], fields[1:]
    for index in range(len(fields) // 4):
        how, module, name, text = fields[4 * index: 4 * index + 4]
        try:
            kernel, args = _kernel(module, name), parse_signature(text)
            if how == "link":
                kernel.link_into(args, Path(_handover_file(handovers, index)))
            else:
                kernel.compile(args)
        except Exception:  # left to the calling process
            continue
        print(f"done {index}", flush=True)


@contextlib.contextmanager
def reporting_compiles(expected: Any = None, cached: bool = False,
                       stream: TextIO | None = None) -> Iterator[None]:
    """Print ``compiling kernels ...`` when a compile starts, and its time when it ends.

    ``expected``: the cold compile expected here (`impactbeams.costs.CompileEstimate`, or None
    where none is calibrated), announced with the first compile; ``cached``: whether the run's
    entry kernels are in the disk cache (`kernels_cached`), when a compile is only of kernels
    missing from it and nothing is announced as once per install. Each outermost compile (a
    kernel called from Python, with every kernel it calls) of at least ``REPORTED_COMPILE``
    seconds ends with a line ``compiled N kernels in S s (... announced A-B s)``: the kernels and
    the time since the first compile started, beside the announced range. On a terminal one
    line shows the group being compiled (the kernels' module: ``events``, ``dynamics``...), the
    kernels done and the time since the first compile started. Nothing is printed when every
    kernel loads from the cache (Numba signals a compile only on a cache miss).
    """
    from numba.core import event

    from impactbeams.kernels.jit import COMPILE_WAIT

    listener = _compile_report(expected, cached, stream or sys.stderr)
    for kind in ("numba:compile", COMPILE_WAIT):  # a wait for the helper's share is one too
        event.register(kind, listener)
    try:
        yield
    finally:
        for kind in ("numba:compile", COMPILE_WAIT):
            event.unregister(kind, listener)


def _announcement(expected: Any, cached: bool) -> str:
    """The line that starts a compile: what compiles, and how long it is expected to take."""
    if cached:
        return "compiling kernels missing from the disk cache (the run's others load from it)"
    what = ("compiling the kernels of this kind of run (once per install: later runs load "
            "them from the disk cache)")
    return what if expected is None else f"{what}, expected {expected.describe()}"


def _compile_report(expected: Any, cached: bool, stream: TextIO) -> Any:
    """A Numba ``numba:compile`` listener printing the compile's progress on ``stream``."""
    from numba.core import event

    announced = ("" if expected is None or cached else
                 f"; announced {expected.low:.0f}-{expected.high:.0f} s")
    expecting = announced.replace("; announced", ", expected")

    class CompileReport(event.Listener):
        def __init__(self) -> None:
            self.interactive = stream.isatty()
            self.local = threading.local()  # each thread's compile depth (Dask, long runs)
            self.lock = threading.Lock()
            self.announced = False
            self.first = self.start = 0.0  # the first compile's start, the outermost one's
            self.kernels = 0
            self.active = 0  # outermost compiles going on, in any thread
            self.written = 0.0  # when the last line was written
            self.beating: threading.Thread | None = None

        def _beat(self, compile_event: Any) -> None:
            """Start the heartbeat: a line after every ``COMPILE_HEARTBEAT`` s without one."""
            if self.beating is not None and self.beating.is_alive():
                return
            self.written = time.perf_counter()

            def beat() -> None:
                while True:
                    time.sleep(min(1.0, COMPILE_HEARTBEAT))
                    with self.lock:
                        if not self.active:
                            return
                        now = time.perf_counter()
                        if now - self.written >= COMPILE_HEARTBEAT:
                            self._write(f"still compiling: {_group(compile_event)}, "
                                        f"{self.kernels} kernels compiled, "
                                        f"{now - self.first:.0f} s{expecting}",
                                        final=not self.interactive)

            self.beating = threading.Thread(target=beat, daemon=True, name="compile report")
            self.beating.start()

        def on_start(self, compile_event: Any) -> None:
            depth = getattr(self.local, "depth", 0)
            self.local.depth = depth + 1
            with self.lock:
                if depth == 0:
                    self.start = time.perf_counter()
                    self.active += 1
                    self._beat(compile_event)
                if not self.announced:
                    self.announced, self.first = True, self.start
                    self._write(_announcement(expected, cached), final=not self.interactive)
                elif self.interactive:
                    self._progress(compile_event)

        def on_end(self, compile_event: Any) -> None:
            self.local.depth -= 1
            with self.lock:
                self.kernels += 1
                if self.local.depth == 0:
                    self.active -= 1
                now = time.perf_counter()
                if self.local.depth == 0 and now - self.start >= REPORTED_COMPILE:
                    self._write(f"compiled {self.kernels} kernels in {now - self.first:.1f} s "
                                f"(cached for later runs{announced})", final=True)
                elif self.interactive:
                    self._progress(compile_event)

        def _progress(self, compile_event: Any) -> None:
            self._write(f"compiling kernels{expecting}: {_group(compile_event)}, "
                        f"{self.kernels} compiled, {time.perf_counter() - self.first:.0f} s",
                        final=False)

        def _write(self, line: str, final: bool) -> None:
            self.written = time.perf_counter()
            if self.interactive:  # rewrite the line in place; end it when final
                stream.write(f"\rimpactbeams: {line}\033[K" + ("\n" if final else ""))
            else:
                stream.write(f"impactbeams: {line}\n")
            stream.flush()

    return CompileReport()


def _group(compile_event: Any) -> str:
    """The group of the kernel a compile event is about: its module (``events``, ``numba``)."""
    module = compile_event.data["dispatcher"].py_func.__module__
    return module.removeprefix("impactbeams.kernels.").split(".")[0]


# --- kernel signatures as text ---------------------------------------------------------------

def signature_text(args: tuple) -> str:
    """A kernel's argument types as text that `parse_signature` reads back (the compile plan).

    Arrays as Numba writes them (``float64[:, ::1]`` is C-contiguous), tuples, the records of
    `impactbeams.kernels.records` by name, the run settings' record as ``settings``.
    """
    return ", ".join(map(_type_text, args))


def parse_signature(text: str) -> tuple:
    """The argument types `signature_text` wrote."""
    return tuple(eval(f"({text},)", {"__builtins__": {}}, _type_names()))  # noqa: S307


def _type_text(numba_type: Any) -> str:
    from numba.core import types

    if isinstance(numba_type, types.Array):
        axes = [":"] * numba_type.ndim
        if numba_type.layout == "C":
            axes[-1] = "::1"
        elif numba_type.layout == "F":
            axes[0] = "::1"
        return f"{_type_text(numba_type.dtype)}[{', '.join(axes)}]"
    if isinstance(numba_type, types.BaseNamedTuple):
        return f"{numba_type.instance_class.__name__}({signature_text(tuple(numba_type))})"
    if isinstance(numba_type, types.UniTuple):
        return f"UniTuple({_type_text(numba_type.dtype)}, {numba_type.count})"
    if isinstance(numba_type, types.Tuple):
        return f"Tuple(({signature_text(tuple(numba_type))},))"
    if numba_type == _type_names()["settings"]:
        return "settings"
    return str(numba_type)


def _type_names() -> dict[str, Any]:
    import numba
    from numba.core import types

    from impactbeams.kernels import layout, records

    def named(cls: type) -> Any:
        return lambda *fields: types.NamedTuple(fields, cls)

    return {**vars(types), "bool": types.boolean,
            "settings": numba.from_dtype(layout.SETTINGS_DTYPE),
            **{name: named(getattr(records, name)) for name in (
                "Segments", "RunInputs", "Oscillators", "EventFunction", "Rotor", "Tangent")}}


if __name__ == "__main__":
    _compile_jobs(sys.argv[1:])
