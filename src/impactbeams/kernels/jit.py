"""The package's single place for Numba compile options, and for how kernels compile.

Every kernel compiles on one of two paths, to the same results:

* the fast path (`impactbeams.kernels.linking`): a kernel called by kernels is compiled once
  per plain signature and only linked into its callers, a ``borrowing_kernel`` compiles
  without reference counts, and a cold run may share its compile with a helper process. It
  uses Numba's compiler internals, tested with Numba 0.68 only;
* the plain path: every kernel a ``numba.njit`` kernel with public options only (no linking,
  no borrowed arrays; no helper process, `impactbeams.compilation`; no lean cache loading,
  `impactbeams.cached_kernels`). Slower to compile and run, the same results
  (docs/architecture.md, "Two paths").

``IMPACTBEAMS_PLAIN_NUMBA=1`` (or `use_plain_numba`) takes the plain path. Otherwise the first
kernel made checks this Numba (its version, then each of `FAST_PATH_INTERNALS`) and takes the
fast path, or the plain one with one warning naming what it missed; ``IMPACTBEAMS_PLAIN_NUMBA=0``
skips the version check (to try the fast path on a Numba newer than the tested one).
``fastmath`` stays off: event location compares signs and the "no impact" value is NaN,
and ``nnan`` would let LLVM delete the NaN checks.
"""

import importlib
import os
import types
import warnings

import numba
from numba import njit

_OPTIONS = {"cache": True, "fastmath": False, "error_model": "numpy", "nogil": True}

PLAIN_NUMBA = "IMPACTBEAMS_PLAIN_NUMBA"  # "1": the plain path; "0": no version check
TESTED_NUMBA = "0.68"  # the Numba release the fast path is tested with (pyproject.toml)
FALLBACK = "impactbeams compiles its kernels as plain Numba kernels"  # the warning's start
# the event of a wait for another process's compile of a kernel (`linking._wait_elsewhere`),
# which the compile report counts as a compile; Numba's own "numba:compile" is a compile here
COMPILE_WAIT = "impactbeams:compile-wait"

# Numba's internals the fast path uses, each looked up before the first kernel is made:
# kernels/linking.py's, then the lean cache loading's (impactbeams.cached_kernels).
# ``dispatcher.`` names an attribute of a Numba dispatcher (a kernel not compiled).
FAST_PATH_INTERNALS = (
    "llvmlite.binding.parse_bitcode",
    "numba.core.compiler.compile_extra",
    "numba.core.compiler.Flags.no_cpython_wrapper",
    "numba.core.compiler.Flags.no_cfunc_wrapper",
    "numba.core.compiler.Flags.no_compile",
    "numba.core.compiler.CompileResult.referenced_envs",
    "numba.core.compiler.CompileResult._find_referenced_environments",
    "numba.core.compiler_lock.global_compiler_lock",
    "numba.core.event.trigger_event",
    "numba.core.serialize.dumps",
    "numba.core.sigutils.normalize_signature",
    "numba.core.typing.make_concrete_template",
    "numba.core.environment.lookup_environment",
    "numba.core.options.TargetOptions.parse_as_flags",
    "numba.core.cpu.CPUTargetOptions._nrt",
    "numba.core.base.BaseContext.insert_user_function",
    "numba.core.codegen.JITCPUCodegen.set_env",
    "numba.core.codegen.JITCodeLibrary._get_module_for_linking",
    "numba.core.codegen.JITCodeLibrary._optimize_final_module",
    "numba.core.codegen.JITCodeLibrary._finalize_final_module",
    "numba.core.codegen.JITCodeLibrary._finalize_dynamic_globals",
    "numba.core.codegen.JITCodeLibrary._verify_declare_only_symbols",
    "numba.core.registry.CPUDispatcher.get_call_template",
    "numba.core.registry.CPUDispatcher.add_overload",
    "numba.core.registry.CPUDispatcher.nopython_signatures",
    "numba.core.registry.CPUDispatcher.targetdescr",
    "dispatcher._compiler.fold_argument_types",
    "dispatcher._compiler.pipeline_class",
    "dispatcher._can_compile",
    "dispatcher._compiling_counter",
    "dispatcher._cache.load_overload",
    "numba.core.caching.Cache._load_overload",
    "numba.core.caching.Cache._guard_against_spurious_io_errors",
    "numba.core.runtime.nrt.rtsys.initialize",
)

_path = None  # "fast" or "plain", chosen when first asked (`plain_numba`)
_fast_kernels = False  # whether a kernel was made on the fast path


def use_plain_numba() -> None:
    """Compile every kernel as a plain ``numba.njit`` kernel, with public options only.

    As ``IMPACTBEAMS_PLAIN_NUMBA=1``, which it sets for the processes this one starts (a
    command, Dask's local workers). Call it before importing a kernel module (any run, sweep or
    simulate imports them): kernels made on the fast path stay as they are, so it refuses then.
    """
    global _path
    if _fast_kernels:
        raise RuntimeError("use_plain_numba: kernels are already made on the fast path: call "
                           "it before a run imports them, or set IMPACTBEAMS_PLAIN_NUMBA=1")
    _path = "plain"
    os.environ[PLAIN_NUMBA] = "1"


def plain_numba() -> bool:
    """Whether kernels compile on the plain path (chosen on the first call, then fixed)."""
    global _path
    if _path is None:
        _path = _choose_path()
    return _path == "plain"


def _choose_path() -> str:
    setting = os.environ.get(PLAIN_NUMBA, "")
    if setting not in ("", "0", "1"):
        raise ValueError(f"{PLAIN_NUMBA} = {setting!r}: allowed are 1 (plain Numba kernels), "
                         "0 (the fast path, on any Numba that has its internals) or unset")
    if setting == "1":
        return "plain"
    missing = _fast_path_missing(check_version=setting != "0")
    if missing is None:
        return "fast"
    warnings.warn(f"{FALLBACK} (slower to compile and to run, the same results): {missing}",
                  RuntimeWarning, stacklevel=2)
    return "plain"


def _fast_path_missing(check_version: bool) -> str | None:
    """Why this Numba cannot take the fast path, or None."""
    version = numba.__version__
    if check_version and not version.startswith(f"{TESTED_NUMBA}."):
        return (f"its fast path is tested with Numba {TESTED_NUMBA} only, this is {version} "
                f"({PLAIN_NUMBA}=0 tries it)")
    for name in FAST_PATH_INTERNALS:
        if not _present(name):
            return f"Numba {version} has no {name}, which its fast path uses"
    return None


def _present(name: str) -> bool:
    """Whether the dotted ``name`` (a module's attribute, at any depth) exists."""
    parts = name.split(".")
    if parts[0] == "dispatcher":
        found, start = njit(_present), 1  # a dispatcher, never compiled
    else:
        for start in range(len(parts) - 1, 0, -1):  # the longest prefix that is a module
            try:
                found = importlib.import_module(".".join(parts[:start]))
                break
            except ImportError:
                continue
        else:
            return False
    for attribute in parts[start:]:
        try:
            found = getattr(found, attribute)
        except AttributeError:
            return False
    return True


def kernel(function):
    """Compile a serial kernel with the package's options.

    The runtime (reference counts, allocations) is named explicitly: Numba compiles a callee
    with the options that it does not name taken from its first caller, so a kernel first
    reached from a ``borrowing_kernel`` would otherwise compile without it.
    """
    return _dispatcher(function, _nrt=True)


def borrowing_kernel(function):
    """A serial kernel that only borrows arrays: compiled without reference counting.

    Numba increfs every array a kernel receives on entry and decrefs it on return (an atomic
    update each, `records`): a per-step kernel of the event search paid some 14 of them per
    step, 29 % of a long run. A kernel that allocates no array and returns none (scalars or
    tuples of them) needs none: its caller holds every array it passes for the whole call. Such
    a kernel compiles without the runtime (``_nrt=False``): an allocation in it fails to
    compile. The kernels it calls keep their own reference counts, so it may call one that
    allocates, but not one that returns an array (that reference would never be released): a
    small kernel returning a record of its arrays is an ``inlined_kernel``, which its caller's
    rules count. On the plain path it is a ``kernel``.
    """
    return _dispatcher(function, _nrt=False)


def _dispatcher(function, **options):
    """``function`` compiled with the package's ``options`` on the chosen path.

    The plain path drops Numba's private options (``_nrt``) and compiles a copy named apart
    (`_plain_copy`).
    """
    global _fast_kernels
    if plain_numba():
        public = {name: value for name, value in options.items() if not name.startswith("_")}
        return njit(**_OPTIONS, **public)(_plain_copy(function))
    from impactbeams.kernels import linking

    _fast_kernels = True
    return linking.linking_kernel(function, njit(**_OPTIONS, **options)(function).targetoptions)


def inlined_kernel(function):
    """A small kernel inlined into its callers' Numba IR (a per-mode body of a hot loop)."""
    if plain_numba():
        function = _plain_copy(function)
    return njit(inline="always", **_OPTIONS)(function)


def _plain_copy(function):
    """``function`` under a name of its own in Numba's disk cache, for the plain path.

    The cache keys a kernel by its name and code, not by how it was compiled: the two paths'
    kernels share neither machine code nor cache files (a plain kernel never loads a fast
    one's, which links its callees, and the other way round).
    """
    return _renamed(function, function.__name__, function.__qualname__ + "_plain")


def _renamed(function, name, qualname):
    """A copy of ``function`` (same code, globals, defaults) under ``name`` and ``qualname``."""
    copy = types.FunctionType(function.__code__, function.__globals__, name,
                              function.__defaults__, function.__closure__)
    copy.__qualname__ = qualname
    return copy


def parallel_kernel(function):
    """Compile ``function`` twice: parallel (prange over threads) and serial, the same code.

    Returns ``(parallel, serial)``; both give bit-identical results because every prange
    iteration writes only its own output slot. The serial one is compiled from a renamed copy:
    Numba's disk cache is keyed by the function's name, not by the ``parallel`` flag, so the
    two would otherwise load each other's machine code.
    """
    serial = _renamed(function, function.__name__ + "_serial",
                      function.__qualname__ + "_serial")
    return _dispatcher(function, parallel=True), _dispatcher(serial, parallel=False)
