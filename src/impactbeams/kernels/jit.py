"""The package's single place for Numba compile options.

``fastmath`` stays off: event location compares signs and the "no impact" value is NaN,
and ``nnan`` would let LLVM delete the NaN checks.
"""

import types

from numba import njit, typeof
from numba.core import types as numba_types
from numba.core.registry import CPUDispatcher

_OPTIONS = {"cache": True, "fastmath": False, "error_model": "numpy", "nogil": True}


class _Kernel(CPUDispatcher):
    """A dispatcher that one kernel calling another compiles once per plain signature.

    Numba types a call between kernels with its constant arguments as literals
    (``Literal[bool](True)``) and an omitted argument as its default: each combination would be
    compiled as its own specialisation, with every kernel it calls (``find_switch`` twice, for
    example). Typed by their plain types (the default's type for an omitted argument), the
    calls share one compile; the values are passed at run time, and the results are the same.
    """

    def get_call_template(self, args, kws):
        pysig, folded = self._compiler.fold_argument_types(args, kws)
        return super().get_call_template(tuple(map(_plain_type, folded)), {})


def _plain_type(argument):
    if isinstance(argument, numba_types.Omitted):
        return typeof(argument.value)
    return numba_types.unliteral(argument)


def kernel(function):
    """Compile a serial kernel with the package's options."""
    options = njit(**_OPTIONS)(function).targetoptions  # the options as njit completes them
    dispatcher = _Kernel(py_func=function, locals={}, targetoptions=options)
    dispatcher.enable_caching()
    return dispatcher


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
