"""The package's single place for Numba compile options.

``fastmath`` stays off: event location compares signs and the "no impact" value is NaN,
and ``nnan`` would let LLVM delete the NaN checks.
"""

from numba import njit

_OPTIONS = {"cache": True, "fastmath": False, "error_model": "numpy", "nogil": True}


def kernel(function):
    """Compile a serial kernel with the package's options."""
    return njit(**_OPTIONS)(function)


def parallel_kernel(function):
    """Compile ``function`` twice: parallel (prange over threads) and serial, the same code.

    Returns ``(parallel, serial)``; both give bit-identical results because every prange
    iteration writes only its own output slot.
    """
    return njit(parallel=True, **_OPTIONS)(function), njit(parallel=False, **_OPTIONS)(function)
