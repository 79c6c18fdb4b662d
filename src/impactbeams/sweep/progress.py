"""The progress bar of a sweep, its ETA weighted by the cost model of its chunks.

`impactbeams.progress.Progress` (shared with ``simulate``); the chunks of a long-time
or full-dynamics sweep differ in cost, those of a first-impact map hardly.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from impactbeams.progress import Progress
from impactbeams.sweep.definition import Sweep
from impactbeams.sweep.estimate import chunk_seconds

if TYPE_CHECKING:
    from impactbeams.sweep.plan import Chunking

__all__ = ["Progress", "chunk_progress"]

# chunks beyond which the ETA is not weighted (their costs are evaluated before the run starts)
WEIGHED_CHUNKS = 4096


def chunk_progress(sweep: Sweep, chunking: Chunking, enabled: bool) -> Progress:
    """The progress bar of ``sweep`` run in ``chunking``'s chunks.

    A full-dynamics chunk weighs its expected cost (``estimate.chunk_seconds``), so that the
    ETA holds when the chunks differ in cost (a first-impact map's chunks cost their cells).
    """
    if not (sweep.needs_dynamics and chunking.count <= WEIGHED_CHUNKS):
        return Progress(sweep.size, enabled=enabled)
    weights = [chunk_seconds(sweep, *chunking.bounds(chunk)) for chunk in range(chunking.count)]
    return Progress(sweep.size, enabled=enabled, weights=weights)
