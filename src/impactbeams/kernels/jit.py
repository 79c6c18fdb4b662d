"""The package's single place for Numba compile options.

``fastmath`` stays off: event location compares signs and the "no impact" value is NaN,
and ``nnan`` would let LLVM delete the NaN checks.
"""

import types

from numba import njit

_OPTIONS = {"cache": True, "fastmath": False, "error_model": "numpy", "nogil": True}


def kernel(function):
    """Compile a serial kernel with the package's options."""
    return njit(**_OPTIONS)(function)


def inlined_kernel(function):
    """A small kernel inlined into its callers' Numba IR (a per-mode body of a hot loop)."""
    return njit(inline="always", **_OPTIONS)(function)


def parallel_kernel(function):
    """Compile ``function`` twice: parallel (prange over threads) and serial, the same code.

    Returns ``(parallel, serial)``; both give bit-identical results because every prange
    iteration writes only its own output slot. The serial one is compiled from a renamed copy:
    Numba's disk cache is keyed by the function's name, not by the ``parallel`` flag, so the
    two would otherwise load each other's machine code.
    """
    serial = types.FunctionType(function.__code__, function.__globals__,
                                function.__name__ + "_serial", function.__defaults__,
                                function.__closure__)
    serial.__qualname__ = function.__qualname__ + "_serial"
    return njit(parallel=True, **_OPTIONS)(function), njit(parallel=False, **_OPTIONS)(serial)
