"""BLAS on one thread wherever a result depends on it: the same bits for any thread count.

OpenBLAS splits a product (and the products inside LAPACK's eigen- and linear solvers)
among its threads when the matrices are large enough, and a split sums in another order:
with ``OPENBLAS_NUM_THREADS=2`` instead of 1 the tied law's overlaps at 40 modes, and the
damped spring law's complex modes, came out different in the last bits, which a rattle's
chaos amplified to other contact counts (issue 32). The set-up's products are small (at most
a few hundred rows), so one thread costs nothing that matters; the kernels sum in loops and
call no BLAS at all. `one_blas_thread` holds every BLAS that NumPy and SciPy loaded to one
thread while a function that builds a result runs (threadpoolctl, which finds and sets each
loaded BLAS library), and gives the user's setting back after the last such call ends.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from typing import Any, TypeVar

Function = TypeVar("Function", bound=Callable[..., Any])


class _Holder:
    """Holds BLAS to one thread while any wrapped call runs, in any thread of the process.

    OpenBLAS's thread count is one setting for the whole process: the first call to enter
    sets it, the last to leave restores it.
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.calls = 0
        self.limit: Any = None  # threadpoolctl's limit while held

    def enter(self) -> None:
        with self.lock:
            if self.calls == 0:
                self.limit = _controller().limit(limits=1, user_api="blas")
            self.calls += 1

    def leave(self) -> None:
        with self.lock:
            self.calls -= 1
            if self.calls == 0:
                self.limit.restore_original_limits()
                self.limit = None


_holder = _Holder()


def one_blas_thread(function: Function) -> Function:
    """Run ``function`` with NumPy's and SciPy's BLAS on one thread."""

    @functools.wraps(function)
    def on_one_thread(*args: Any, **kwargs: Any) -> Any:
        _holder.enter()
        try:
            return function(*args, **kwargs)
        finally:
            _holder.leave()

    return on_one_thread  # type: ignore[return-value]


@functools.cache
def _controller() -> Any:
    """The threadpoolctl controller of the BLAS libraries of NumPy and SciPy (found once)."""
    import numpy  # noqa: F401  (NumPy's BLAS)
    import scipy.linalg  # noqa: F401  (SciPy's, which the set-up's LAPACK calls use)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()
