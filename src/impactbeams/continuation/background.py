"""The second core's share of a continuation: kept points' measures and the checkpoint writes.

A continuation is one thread of Python whose period maps are mostly kernels, which let go of
the GIL. A point's named measures (its peak contact forces, each certified by branch and
bound, the tips' maxima, the impact velocities: a tenth of the stiff stop's time) are read
only when the branch is written, and nothing along the branch waits for them: they are
computed on one other thread while the corrector goes on, from the run the corrector already
made, so that they are the same numbers, bit for bit. The checkpoint log's records are
pickled and written on that thread too, after the measures of the points they hold (one
thread: in the order asked).
"""

from __future__ import annotations

import concurrent.futures
import functools
from collections.abc import Callable, Iterator, Mapping
from typing import Any

Measures = Mapping[str, Any]


@functools.cache
def worker() -> concurrent.futures.ThreadPoolExecutor:
    """The one background thread (started when first asked, for the process's lifetime)."""
    return concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="impactbeams-background")


class Pending(Mapping[str, Any]):
    """Named measures being computed on the background thread: waited for when first read.

    Pickled as the plain dict of its values (a checkpoint's record, written on that thread
    after them, never waits).
    """

    def __init__(self, compute: Callable[[], Measures]) -> None:
        self._future = worker().submit(compute)

    def _values(self) -> Measures:
        return self._future.result()

    def __getitem__(self, key: str) -> Any:
        return self._values()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values())

    def __len__(self) -> int:
        return len(self._values())

    def __reduce__(self) -> tuple[type, tuple[dict[str, Any]]]:
        return dict, (dict(self._values()),)
