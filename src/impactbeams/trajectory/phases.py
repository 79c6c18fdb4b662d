"""The phase loop's driver: run the event kernel for one trajectory, sample its states."""

from __future__ import annotations

import dataclasses

import numpy as np

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.layout import CONTACT
from impactbeams.kernels.spring import to_free
from impactbeams.packing import Packed

_INITIAL_CAPACITY = 4096  # segments; doubled (rerun from t = 0) until max_events


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
    def segment_end(self) -> np.ndarray:
        """End time of every segment (s)."""
        return np.append(self.time[1:], self.t_end)


def run(packed: Packed, max_events: int) -> Trajectory:
    """Run the event kernel; grow its arrays (rerunning from t = 0) up to ``max_events``."""
    capacity = min(_INITIAL_CAPACITY, max_events)
    while True:
        time = np.empty(capacity)
        phase = np.empty(capacity, dtype=np.int64)
        sustained = np.empty(capacity, dtype=np.bool_)
        q, v, end_q, end_v = (np.empty((capacity, packed.q0.size)) for _ in range(4))
        count, status, t_end = dyn.run_events(packed.tables, packed.forces, packed.phase_scalars,
                                              *packed.switching(), packed.settings, packed.q0,
                                              packed.v0, time, phase, sustained, q, v, end_q,
                                              end_v)
        if status != dyn.EVENT_LIMIT or capacity >= max_events:
            break
        capacity = min(2 * capacity, max_events)
    return Trajectory(time[:count], phase[:count], sustained[:count], q[:count], v[:count],
                      end_q[:count], end_v[:count], dyn.STATUS_NAMES[status], float(t_end))


def sample(packed: Packed, trajectory: Trajectory, times: np.ndarray,
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Phase and modal state (q, q') at ascending ``times`` within [0, t_end] (s).

    The states are in the coordinates of ``packed.bases`` (the spring law's: free ones).
    """
    n_coords = trajectory.q.shape[1]
    q, v = np.empty((times.size, n_coords)), np.empty((times.size, n_coords))
    phase = np.empty(times.size, dtype=np.int64)
    dyn.sample_states(packed.tables, packed.forces, packed.dynamics.spring_arrays,
                      packed.drives, packed.settings, trajectory.time,
                      trajectory.phase, trajectory.q, trajectory.v, trajectory.time.size, times,
                      q, v, phase)
    return phase, q, v


def free_states(packed: Packed, phase: np.ndarray, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray]:
    """Recorded segment states (q, q') in the coordinates of ``packed.bases``.

    Only the spring law's contact states change: its contact oscillators back to (q, q').
    """
    if not packed.spring_law:
        return q, v
    q, v = q.copy(), v.copy()
    left, right, modes = packed.dynamics.spring_arrays
    for i in np.flatnonzero(phase == CONTACT):
        y, y_rate = q[i].copy(), v[i].copy()
        to_free(y, y_rate, float(t[i]), right, modes, packed.drives,
                packed.settings["forcing_frequency"], q[i], v[i])
    return q, v
