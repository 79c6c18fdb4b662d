"""Loading the kernels from Numba's disk cache with only what running them needs.

A cost of a warm ``impactbeams run`` that running cached kernels does not need (measured by
benchmarks/bench_startup.py, docs/benchmarks/startup.json): Numba refreshes its target
context before it loads a kernel from the disk cache. It imports and installs every typing
and lowering registry (NumPy's functions, the random generators, cffi, typed containers...),
about 0.5 s of CPU that only a compile uses. A compile refreshes the context itself
(``numba.core.compiler``, and ``BaseContext.get_function`` on a missing lowering), so after
`load_cached_kernels_lean` a cache hit starts Numba's runtime (NRT, which the kernels'
allocations call) and loads the machine code, and a cache miss compiles as before. (No kernel
calls BLAS, whose routines Numba would import ``scipy.linalg`` for: they sum in loops.)

This changes the process it runs in, so the command line, which owns its process, calls
`load_cached_kernels_lean`; the library does not. The kernels' machine code is the same
either way: results are bit for bit those of Numba's own loading (tests/test_startup.py).
"""

from __future__ import annotations


def load_cached_kernels_lean() -> None:
    """Make this process load cached kernels without Numba's registries.

    Safe to call more than once; does nothing on the plain path (`kernels.jit`: taken with a
    Numba whose cache lacks what this relies on, ``Cache._load_overload`` and its I/O guard as
    in Numba 0.68, or asked for): kernels then load as Numba loads them.
    """
    from impactbeams.kernels.jit import plain_numba

    if plain_numba():
        return
    from numba.core import caching
    from numba.core.runtime import nrt

    cache = caching.Cache
    if getattr(cache.load_overload, "lean", False):
        return

    def load_overload(self: caching.Cache, sig: object, target_context: object) -> object:
        nrt.rtsys.initialize(target_context)  # what the refresh would have started
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)
        return None  # an I/O error swallowed by the guard: Numba compiles instead

    load_overload.lean = True  # type: ignore[attr-defined]
    cache.load_overload = load_overload

