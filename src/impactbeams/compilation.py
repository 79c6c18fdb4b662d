"""Numba's compile of the kernels: whether a run will compile, and a report while it does.

Kernels compile on their first call and are cached on disk (``cache=True``): a fresh install
pays for it once per kind of run (docs/limits.md, "Time": cold compile times measured by
``benchmarks/calibrate_costs.py``). `kernels_cached` tells, before a run, whether its
entry kernels are in Numba's disk cache; `reporting_compiles` prints a line when a compile
starts and when it ends, from Numba's own compile events (no thread: the lines come from the
thread that compiles).
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any, TextIO

REPORTED_COMPILE = 1.0  # s: an outermost compile at least this long ends with a line

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
}


def kernels_cached(kind: str, entry: str | None = None) -> bool:
    """Whether the entry kernels of a run of ``kind`` (``ENTRY_KERNELS``) are in the disk cache.

    ``entry``: the one name, of several, that the run calls (any of them otherwise). Each twin
    counts alone, since each compiles its callees anew (`kernels.jit`).

    Reads each kernel's cache index, as Numba does before it compiles (the file
    ``<module>.<name>-<line>.py<version>.nbi`` in the cache folder, which Numba's locator
    finds): it holds machine code for this CPU if it names this machine's code generator and
    its source stamp matches the kernel's file. Cheap (a small pickle per kernel).
    """
    import importlib

    for module, names in ENTRY_KERNELS[kind]:
        kernels = importlib.import_module(f"impactbeams.kernels.{module}")
        names = (entry,) if entry in names else names
        if not any(_has_machine_code(getattr(kernels, name)) for name in names):
            return False
    return True


def _has_machine_code(dispatcher: Any) -> bool:
    cache = getattr(dispatcher, "_cache", None)
    index = getattr(cache, "_cache_file", None)
    if index is None:  # caching disabled: every process compiles
        return False
    magic = dispatcher.targetctx.codegen().magic_tuple()
    try:
        overloads = index._load_index()
    except Exception:  # an unreadable index: Numba recompiles, and so does the run
        return False
    return any(key[1] == magic for key in overloads)


@contextlib.contextmanager
def reporting_compiles(expected: float, stream: TextIO | None = None) -> Iterator[None]:
    """Print ``compiling kernels ...`` when a compile starts, and its time when it ends.

    ``expected``: the measured cold compile time (s) announced. Each outermost compile (a
    kernel called from Python, with every kernel it calls) of at least ``REPORTED_COMPILE``
    seconds ends with a line ``compiled N kernels in S s``; on a terminal one line shows the
    group being compiled (the kernels' module: ``events``, ``dynamics``...), the kernels done
    and the time since the first compile started. Nothing is printed when every kernel loads
    from the cache (Numba signals a compile only on a cache miss).
    """
    from numba.core import event

    listener = _compile_report(expected, stream or sys.stderr)
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)


def _compile_report(expected: float, stream: TextIO) -> Any:
    """A Numba ``numba:compile`` listener printing the compile's progress on ``stream``."""
    from numba.core import event

    class CompileReport(event.Listener):
        def __init__(self) -> None:
            self.interactive = stream.isatty()
            self.local = threading.local()  # each thread's compile depth (Dask, long runs)
            self.lock = threading.Lock()
            self.announced = False
            self.first = self.start = 0.0
            self.kernels = 0

        def on_start(self, compile_event: Any) -> None:
            depth = getattr(self.local, "depth", 0)
            self.local.depth = depth + 1
            with self.lock:
                if depth == 0:
                    self.start, self.kernels = time.perf_counter(), 0
                if not self.announced:
                    self.announced, self.first = True, self.start
                    self._write(f"compiling kernels (once per install), about {expected:.0f} s",
                                final=not self.interactive)
                elif self.interactive:
                    self._progress(compile_event)

        def on_end(self, compile_event: Any) -> None:
            self.local.depth -= 1
            with self.lock:
                self.kernels += 1
                elapsed = time.perf_counter() - self.start
                if self.local.depth == 0 and elapsed >= REPORTED_COMPILE:
                    self._write(f"compiled {self.kernels} kernels in {elapsed:.1f} s (cached "
                                "for later runs)", final=True)
                elif self.interactive:
                    self._progress(compile_event)

        def _progress(self, compile_event: Any) -> None:
            self._write(f"compiling kernels (once per install), about {expected:.0f} s: "
                        f"{_group(compile_event)}, {self.kernels} compiled, "
                        f"{time.perf_counter() - self.first:.0f} s", final=False)

        def _write(self, line: str, final: bool) -> None:
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
