"""The phase loop's driver: run the event kernel for one trajectory, sample its states."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

import numpy as np

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.layout import FREE
from impactbeams.kernels.records import Segments, segments
from impactbeams.kernels.stroboscope import tip_motions
from impactbeams.packing import Packed

_WINDOW = 1024  # segments of the first window of a run; then about WINDOW_SECONDS each
WINDOW_SECONDS = 0.5  # wall time per window (s): how often a run reports its progress
_MIN_WINDOW = 256  # segments


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """Recorded phase segments of one run (SI units).

    Segment k starts at ``time[k]`` in ``phase[k]`` (0 free, 1 contact; ``sustained[k]`` for a
    contact entered by the accumulation rule) with modal state
    ``q[k], v[k]`` (after the switching projection) and ends at ``time[k + 1]`` (or ``t_end``)
    in state ``end_q[k], end_v[k]`` (before the next projection). ``status`` is one of
    ``dynamics.STATUS_NAMES``.
    """

    time: np.ndarray
    phase: np.ndarray
    sustained: np.ndarray
    q: np.ndarray
    v: np.ndarray
    end_q: np.ndarray
    end_v: np.ndarray
    status: str
    t_end: float

    @property
    def segments(self) -> Segments:
        """The recorded segments as the kernels' `records.Segments` record."""
        return Segments(self.time, self.phase, self.sustained, self.q, self.v, self.end_q,
                        self.end_v)

    @property
    def segment_end(self) -> np.ndarray:
        """End time of every segment (s)."""
        return np.append(self.time[1:], self.t_end)


def run(packed: Packed, max_events: int,
        report: Callable[[float, int], None] | None = None,
        start: tuple[np.ndarray, np.ndarray, int] | None = None,
        window: int | None = None) -> Trajectory:
    """Run the event kernel, in windows of segments, up to ``max_events`` segments.

    ``start``: the state ``(q, q', phase)`` at t = 0 in that phase's coordinates
    (`impactbeams.trajectory.start.phase_state`); default ``(packed.q0, packed.v0, FREE)``.
    ``window``: the segments of the first window (default ``_WINDOW``), and of the arrays at
    first: a run that ends within it is one call of the kernel. A run known to be short asks
    for less (a period map's dozen segments: arrays for a thousand cost more in fresh pages
    than its kernel takes, 30 of 130 us on the stiff stop's map).

    Each window ends where the run can resume exactly (``stroboscope.resume_point``: a free
    segment after a contact of positive length, where no history carries over), so that the
    segments are bit for bit those of one uninterrupted run; ``report(t, phases)`` is called
    after each window with the simulated time reached (s) and the phases recorded before it.
    The arrays grow by doubling.
    """
    from impactbeams.kernels.stroboscope import resume_point

    window = _WINDOW if window is None else window
    arrays = segments(min(window, max_events), packed.q0.size)
    q0, v0, phase0 = (packed.q0, packed.v0, FREE) if start is None else start
    first = 0
    t0 = 0.0
    while True:
        stop = min(first + window, max_events)
        if stop > arrays.time.size:
            arrays = _grown(arrays, min(max(2 * arrays.time.size, stop), max_events))
        views = Segments(*(array[first:stop] for array in arrays))
        began = time.perf_counter()
        count, status, t_end = dyn.run_events(packed.tables, packed.forces,
                                              packed.phase_scalars, packed.switching,
                                              packed.settings, q0, v0, views, t0, phase0)
        if status != dyn.EVENT_LIMIT or stop >= max_events:
            break
        resume = resume_point(views.time, views.phase, count)
        if resume == 0:  # no point to resume from in this window: run it longer
            window *= 2
            continue
        first += resume
        q0, v0, t0 = arrays.q[first].copy(), arrays.v[first].copy(), float(arrays.time[first])
        phase0 = FREE  # a resume point is a free segment
        window = _next_window(window, resume, time.perf_counter() - began)
        if report is not None:
            report(t0, first)
    count += first
    time_, phase, sustained, q, v, end_q, end_v = (array[:count] for array in arrays)
    return Trajectory(time_, phase, sustained, q, v, end_q, end_v, dyn.STATUS_NAMES[status],
                      float(t_end))


def _grown(arrays: Segments, capacity: int) -> Segments:
    grown = segments(capacity, arrays.q.shape[1])
    for old, new in zip(arrays, grown, strict=True):
        new[:old.shape[0]] = old
    return grown


def _next_window(window: int, kept: int, seconds: float) -> int:
    """Segments of the next window: about WINDOW_SECONDS at the last window's pace."""
    pace = kept / max(seconds, 1e-6)  # segments per second
    return int(min(max(pace * WINDOW_SECONDS, _MIN_WINDOW), 4 * window))



def sample(packed: Packed, trajectory: Trajectory, times: np.ndarray, grid: bool = False,
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Phase and modal state (q, q') at ascending ``times`` within [0, t_end] (s).

    The states are in the coordinates of ``packed.bases`` (the spring law's: free ones).
    ``grid``: the times are equally spaced (at least two), and the states are wanted to find
    where to look closer (`kernels.dynamics.sample_grid`: some ten times cheaper, a few ulps
    less exact), not as results.
    """
    n_coords = trajectory.q.shape[1]
    q, v = np.empty((times.size, n_coords)), np.empty((times.size, n_coords))
    phase = np.empty(times.size, dtype=np.int64)
    sampler = dyn.sample_grid if grid else dyn.sample_states
    sampler(packed.tables, packed.forces, packed.switching, packed.settings, trajectory.segments,
            times, q, v, phase)
    return phase, q, v


def sample_segments(packed: Packed, trajectory: Trajectory, count: int,
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(q, q') at ``count`` equally spaced times over each segment, from its start to its end.

    Rows ``k * count`` to ``(k + 1) * count - 1`` are segment k's, as `sample` gives them at
    ``np.linspace(time[k], segment_end[k], count)`` to a few ulps of the motion's size a
    step (`kernels.dynamics.sample_segments`): where to look closer, not results.
    """
    n_coords = trajectory.q.shape[1]
    q = np.empty((trajectory.time.size * count, n_coords))
    v = np.empty_like(q)
    dyn.sample_segments(packed.tables, packed.forces, packed.switching, packed.settings,
                        trajectory.segments, trajectory.segment_end, count, q, v)
    return q, v


def tips_of(packed: Packed, phase: np.ndarray, times: np.ndarray, q: np.ndarray,
            v: np.ndarray) -> np.ndarray:
    """The tips' motion (``kernels.layout`` TIP_* columns) of sampled states at ``times``."""
    out = np.empty((times.size, 4))
    tip_motions(packed.tables, packed.forces, packed.phase_scalars, packed.settings, phase,
                times, q, v, out)
    return out


def tips_at(packed: Packed, trajectory: Trajectory, times: np.ndarray) -> np.ndarray:
    """The tips' motion (TIP_* columns) of ``trajectory`` at ascending ``times`` (s)."""
    phase, q, v = sample(packed, trajectory, times)
    return tips_of(packed, phase, times, q, v)


def free_states(packed: Packed, phase: np.ndarray, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray]:
    """Recorded segment states (q, q') in the coordinates of ``packed.bases``.

    Only the spring law's contact states change: its contact oscillators back to (q, q').
    """
    q_out, v_out = np.empty_like(q), np.empty_like(v)
    dyn.observed_states(phase, np.asarray(t, dtype=np.float64), q, v, packed.switching,
                        packed.settings, q_out, v_out)
    return q_out, v_out
