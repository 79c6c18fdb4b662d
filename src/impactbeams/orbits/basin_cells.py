"""The cells of a basin map: each run from its initial state until its samples settle.

A cell starts from a section state z = (q, q') at t = 0 (forcing phase 0) and runs in blocks of
``Settling.block_periods`` forcing periods T = 2 pi / Omega on the package's exact event-driven
run (the kernels `simulate` uses; a chunk of cells in one call of
`impactbeams.kernels.basins.settle_cells`, one block of an attractor's run on here,
`CellRunner.block`). After each block its
stroboscopic samples, the tips' motion at t = k T, are tested for a period as the long-time
response's are (`impactbeams.longtime.response_period`) over the last ``Settling.window``
samples; the next block starts from the state the last one ended in, on the section again
(the forcing is T-periodic, so the run restarts at t = 0 with the same state and phase).

A settled cell records its period p, its contacts per orbit (contact onsets over its last p
periods), its last p samples and its end state; its label is given later, by matching these
against the attractors found so far (`impactbeams.orbits.basin_map`), so that the labels do not
depend on the order in which chunks of cells finish.

A sample is x = (y1, y2, v1 / Omega, v2 / Omega) (m), as in `response_period`: tip deflections
and velocities over Omega, displacement amplitudes; y2 is the stop's 0 without beam 2.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from impactbeams.kernels.basins import NOT_SETTLED, STOPPED, settle_cells
from impactbeams.kernels.layout import CONTACT, TIP_V1, TIP_V2, TIP_Y1, TIP_Y2
from impactbeams.longtime import DEFAULT_PERIOD_TOLERANCE, response_period
from impactbeams.packing import Packed, section_gap
from impactbeams.params import is_integer, is_real, require
from impactbeams.sweep.plan import MAX_PHASES_PER_PERIOD
from impactbeams.trajectory.phases import Trajectory, run, sample, tips_at, tips_of
from impactbeams.trajectory.start import phase_state

# the label of a cell whose samples did not settle within Settling.max_periods: NOT_SETTLED;
# of a cell whose run stopped before its horizon (the event limit), or whose start the tied law
# refuses (the tips overlap at t = 0: the tied law starts from an open gap only): STOPPED


@dataclasses.dataclass(frozen=True)
class Settling:
    """When a cell has settled on an attractor, and when two cells share one.

    Attributes:
        block_periods: forcing periods run between two tests of the samples.
        window: the last samples tested for a period (>= 2 max_period).
        tolerance: the samples repeat with period p to this fraction of their scale (the
            largest |x| over the window), as `impactbeams.longtime.response_period`: a stable
            orbit is recognised once its transient has decayed by 1 / tolerance.
        max_period: the largest period looked for, in forcing periods.
        max_periods: forcing periods a cell may run before it is labelled ``NOT_SETTLED``.
        match_tolerance: two settled cells (or a cell and a given orbit) are on the same
            attractor if their periods and contacts per orbit are equal and their sets of p
            samples lie within this fraction of the larger scale of the two (Hausdorff
            distance, max norm): far above the leftover of the transient (tolerance / (1 - r)
            for a transient decaying by r per period), far below the distance of distinct
            attractors (a sizeable fraction of the scale).
        state_tolerance: an attractor's reported state is its first cell's end state run on
            until it repeats after p periods to this fraction of its largest coordinate.
    """

    block_periods: int = 24
    window: int = 24
    tolerance: float = DEFAULT_PERIOD_TOLERANCE
    max_period: int = 8
    max_periods: int = 1200
    match_tolerance: float = 1e-2
    state_tolerance: float = 1e-10

    def __post_init__(self) -> None:
        for name in ("block_periods", "window", "max_period", "max_periods"):
            value = getattr(self, name)
            require(name, value, is_integer(value) and value >= 1, "must be an integer >= 1")
            object.__setattr__(self, name, int(value))
        for name in ("tolerance", "match_tolerance", "state_tolerance"):
            value = getattr(self, name)
            require(name, value, is_real(value) and 0.0 < value < 1.0,
                    "must be a number between 0 and 1 (relative to the samples' scale)")
            object.__setattr__(self, name, float(value))
        require("window", self.window, self.window >= 2 * self.max_period,
                f"must be at least 2 max_period = {2 * self.max_period} (a period is seen to "
                "repeat over each of its samples)")
        require("max_periods", self.max_periods, self.max_periods >= self.window,
                f"must be at least window = {self.window}")


@dataclasses.dataclass(frozen=True)
class Cells:
    """What the settled runs of a chunk of cells give, one row per cell (SI units).

    ``period``: p (forcing periods; 0 if not settled); ``contacts``: contact onsets over the
    last p periods; ``settle_periods``: the forcing periods before the samples repeat with
    period p (the transient; the periods run if not settled); ``status``: 0 settled,
    ``NOT_SETTLED`` or ``STOPPED``; ``samples``: the last p samples x, (cells, max_period, 4),
    NaN beyond p; ``end_q``, ``end_v``, ``end_phase``: the state at the end of the last block,
    in that phase's coordinates (the start of a run that continues it; several contacts: the
    free coordinates and the bit mask of the contacts closed, `basin_contacts`).
    """

    period: np.ndarray
    contacts: np.ndarray
    settle_periods: np.ndarray
    status: np.ndarray
    samples: np.ndarray
    end_q: np.ndarray
    end_v: np.ndarray
    end_phase: np.ndarray

    def arrays(self) -> dict[str, np.ndarray]:
        """The fields by name (a chunk saved for a resume)."""
        return {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}


class CellRunner:
    """Runs cells of ``packed`` (a run of ``Settling.block_periods`` forcing periods)."""

    def __init__(self, packed: Packed, settling: Settling) -> None:
        self.packed, self.settling = packed, settling
        self.omega = packed.params.omega
        self.forcing_period = 2.0 * math.pi / self.omega
        self.times = self.forcing_period * np.arange(1, settling.block_periods + 1)
        self.max_events = MAX_PHASES_PER_PERIOD * settling.block_periods  # a sweep's cap

    def start(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, int] | None:
        """The run's start from the section state z; None if the tied law refuses it."""
        if not self.packed.spring_law and not section_gap(self.packed, z)[0] > 0.0:
            return None
        return phase_state(self.packed, z)

    def block(self, start: tuple[np.ndarray, np.ndarray, int]) -> tuple[
            Trajectory, np.ndarray, tuple[np.ndarray, np.ndarray, int], np.ndarray] | None:
        """One block from ``start``; None if its run stopped early.

        Its run, its samples x (block_periods, 4), its end state (q, q', phase) to start the
        next block from, and that state as free coordinates z = (q, q') (NaN for a tied
        contact, whose coordinates are the contact modes').
        """
        trajectory = run(self.packed, self.max_events, start=start)
        if trajectory.status != "complete":
            return None
        phase, q, v = sample(self.packed, trajectory, self.times)
        tips = tips_of(self.packed, phase, self.times, q, v)
        x = np.stack([tips[:, TIP_Y1], tips[:, TIP_Y2], tips[:, TIP_V1] / self.omega,
                      tips[:, TIP_V2] / self.omega], axis=-1)
        z = np.concatenate([q[-1], v[-1]])
        if self.packed.spring_law:  # sampled in the free coordinates: into the end phase's
            return trajectory, x, phase_state(self.packed, z), z
        end = (q[-1], v[-1], int(phase[-1]))
        return trajectory, x, end, z if phase[-1] != CONTACT else np.full(z.size, np.nan)

    def tips(self, trajectory: Trajectory, times: np.ndarray) -> np.ndarray:
        """The tips' motion (TIP_* columns of `kernels.layout`) of a block at ``times`` (s)."""
        return tips_at(self.packed, trajectory, times)

    def contacts(self, trajectory: Trajectory, period: int) -> int:
        """Contact onsets in the last ``period`` forcing periods of a block."""
        onsets = trajectory.time[1:][trajectory.phase[1:] == CONTACT]
        window_start = self.times[-1] - period * self.forcing_period
        return int(np.count_nonzero(onsets >= window_start))

    def run_cells(self, states: np.ndarray, periods: np.ndarray | None = None) -> Cells:
        """Every section state of ``states`` (cells, 2 N) run until it settles.

        One kernel call for them all (`kernels.basins.settle_cells`: no Python between cells,
        so that chunks on threads run in parallel). ``periods``: each cell's known period (its
        attractor's), tested alone; None: the smallest that repeats (`periodic`).
        """
        s, packed, n = self.settling, self.packed, self.packed.q0.size
        count = states.shape[0]
        out = Cells(np.zeros(count, np.int32), np.zeros(count, np.int32),
                    np.zeros(count, np.int32), np.zeros(count, np.int32),
                    np.full((count, s.max_period, 4), np.nan), np.full((count, n), np.nan),
                    np.full((count, n), np.nan), np.full(count, -1, np.int32))
        known = np.zeros(count, np.int32) if periods is None else np.asarray(periods, np.int32)
        settle_cells(packed.tables, packed.forces, packed.phase_scalars, packed.switching,
                     packed.settings, np.ascontiguousarray(states, dtype=np.float64), known,
                     self.times, self.omega, self.forcing_period, s.window, s.tolerance,
                     s.max_period, s.max_periods, self.max_events, *out.arrays().values())
        return out


def periodic(x: np.ndarray, settling: Settling) -> int:
    """The period of the samples x (samples, 4), 0 if none (`response_period`)."""
    y1, y2, v1, v2 = x.T
    return int(response_period(y1, y2, v1, v2, 1.0, settling.tolerance, settling.max_period))


def distance(a: np.ndarray, b: np.ndarray) -> float:
    """Hausdorff distance (max norm) of two sets of samples (k, 4), relative to their scale."""
    apart = np.max(np.abs(a[:, None, :] - b[None, :, :]), axis=-1)
    hausdorff = max(apart.min(axis=1).max(), apart.min(axis=0).max())
    scale = max(np.abs(a).max(), np.abs(b).max())
    if scale == 0.0:  # both at rest (no drive): the same state
        return 0.0
    return float(hausdorff / scale)


__all__ = ["NOT_SETTLED", "STOPPED", "CellRunner", "Cells", "Settling", "distance", "periodic"]
