"""The cells of a basin map with several contacts: each run in blocks until its samples settle.

The steps are one contact's (`impactbeams.orbits.basin_cells`, whose module doc describes
them) on the run of the active sets' phases (`impactbeams.kernels.several_contacts`, packed
by `impactbeams.active_phases`), the run `impactbeams.simulate` of several contacts makes: a
block of ``Settling.block_periods`` forcing periods from t = 0, its stroboscopic samples
x = (y1, y2, v1 / Omega, v2 / Omega) (m; the tips as `simulate` gives them: the free modes'
plus what the closed forces move each tip through the flexibility the modes miss), the period
tests of `impactbeams.kernels.basins` over the last ``Settling.window`` samples, the next block
from the state the last one ended in: its free state (q, q') with the contacts closed then (a
dashpot's contact released early, its gap still closed, goes on as released: the run's own
rule). A cell starts with the contacts its section state closes
(`ContactsPeriodMap.active_mask`, as `impactbeams.periodic_orbit`'s map; inside a dashpot's
early release where no set fits), so that a given orbit's state runs on its orbit.

A cell runs in Python around the kernel's run (one call a block): the kernel's part releases
the GIL, so chunks on threads overlap only there. Its contacts per orbit are every contact's
onsets over its last p periods (several contacts' ``impact_count``).
"""

from __future__ import annotations

import numpy as np

from impactbeams.active_phases import (
    CONTACT_STATUS_NAMES,
    ContactRun,
    contact_quantities,
    sample,
    tip_motions,
)
from impactbeams.kernels import several_contacts as kernel
from impactbeams.kernels.basins import NOT_SETTLED, STOPPED, period_of, settled_from
from impactbeams.kernels.layout import TIP_COLUMNS, TIP_V1, TIP_V2, TIP_Y1, TIP_Y2
from impactbeams.orbits.basin_cells import CellRunner, Cells, Settling
from impactbeams.orbits.contacts_map import ContactsPeriodMap
from impactbeams.params import Params

_TIPS = {"tip_deflection_1": TIP_Y1, "tip_deflection_2": TIP_Y2, "tip_velocity_1": TIP_V1,
         "tip_velocity_2": TIP_V2}


class ContactCellRunner(CellRunner):
    """Runs cells of ``params``' several contacts, ``n_modes`` per beam (as `CellRunner`).

    A start is (q, q', the bit mask of the contacts closed) at t = 0, the free state.
    """

    def __init__(self, params: Params, n_modes: int, settling: Settling) -> None:
        self.map = ContactsPeriodMap(params, n_modes, settling.block_periods)
        super().__init__(self.map.packed, settling)
        self.packed_contacts = self.map.contacts

    def start(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """The run's start from the section state z: the contacts it closes (never refused)."""
        m = z.size // 2
        return z[:m].copy(), z[m:].copy(), self.map.active_mask(z)

    def block(self, start: tuple[np.ndarray, np.ndarray, int]) -> tuple[
            ContactRun, np.ndarray, tuple[np.ndarray, np.ndarray, int], np.ndarray] | None:
        """One block from ``start``; None if its run stopped early (as `CellRunner.block`)."""
        run = self._run(start)
        if run.status != "complete":
            return None
        q, v, mask = sample(self.packed_contacts, run, self.times)
        tips = self._tips(q, v, mask, self.times)
        x = np.stack([tips[:, TIP_Y1], tips[:, TIP_Y2], tips[:, TIP_V1] / self.omega,
                      tips[:, TIP_V2] / self.omega], axis=-1)
        return run, x, (q[-1], v[-1], int(mask[-1])), np.concatenate([q[-1], v[-1]])

    def _run(self, start: tuple[np.ndarray, np.ndarray, int]) -> ContactRun:
        """A block's run from ``start``, its open contacts' early releases read off the state."""
        q, v, mask = start
        n, m = len(self.packed_contacts.runs), q.size
        size = self.max_events
        recorded = (np.empty(size), np.empty(size, dtype=np.int64),
                    np.empty(size, dtype=np.int64), np.empty((size, m)), np.empty((size, m)),
                    np.empty((size, n)), np.empty((size, n)))
        packed = self.packed_contacts
        count, status, t_end = kernel.resume_contacts(
            packed.active_sets, packed.settings, packed.early_release, q, v, 0.0, mask,
            self.map.early_released(mask, q, v), recorded)
        return ContactRun(*(array[:count] for array in recorded),
                          CONTACT_STATUS_NAMES[status], float(t_end))

    def _tips(self, q: np.ndarray, v: np.ndarray, mask: np.ndarray,
              times: np.ndarray) -> np.ndarray:
        """The tips (TIP_* columns of `kernels.layout`) at sampled states, as `simulate`'s."""
        forces = contact_quantities(self.packed_contacts, times, q, v, mask)["contact_force"]
        motions = tip_motions(self.packed_contacts, times, q, v, mask, forces)
        out = np.full((times.size, len(TIP_COLUMNS)), np.nan)
        for name, column in _TIPS.items():
            out[:, column] = motions[name]
        return out

    def tips(self, trajectory: ContactRun, times: np.ndarray) -> np.ndarray:
        """The tips' motion (TIP_* columns) of a block at ``times`` (s)."""
        times = np.ascontiguousarray(times, dtype=float)
        return self._tips(*sample(self.packed_contacts, trajectory, times), times)

    def contacts(self, trajectory: ContactRun, period: int) -> int:
        """Every contact's onsets in the last ``period`` forcing periods of a block."""
        n = len(self.packed_contacts.runs)
        switched, mask = trajectory.switched[1:], trajectory.mask[1:]
        closing = (switched < n) & ((mask >> np.clip(switched, 0, n - 1)) & 1 == 1)
        window_start = self.times[-1] - period * self.forcing_period
        return int(np.count_nonzero(closing & (trajectory.time[1:] >= window_start)))

    def run_cells(self, states: np.ndarray, periods: np.ndarray | None = None) -> Cells:
        """Every section state of ``states`` (cells, 2 N) run until it settles.

        Cell by cell (`settle`); ``periods`` as `CellRunner.run_cells`'.
        """
        s, count, n = self.settling, states.shape[0], self.packed.q0.size
        out = Cells(np.zeros(count, np.int32), np.zeros(count, np.int32),
                    np.zeros(count, np.int32), np.zeros(count, np.int32),
                    np.full((count, s.max_period, 4), np.nan), np.full((count, n), np.nan),
                    np.full((count, n), np.nan), np.full(count, -1, np.int32))
        known = np.zeros(count, np.int32) if periods is None else np.asarray(periods, np.int32)
        for i in range(count):
            self.settle(np.asarray(states[i], dtype=float), int(known[i]), out, i)
        return out

    def settle(self, z: np.ndarray, known: int, out: Cells, i: int) -> None:
        """Cell i from z run in blocks until it settles: row i of ``out``.

        As `kernels.basins.settle_cells` does a cell (the same period tests); ``known`` > 0:
        that period alone.
        """
        s, block = self.settling, self.times.size
        history = np.empty((s.max_periods + block, 4))
        start, run = self.start(z), 0
        while run < s.max_periods:
            result = self.block(start)
            if result is None:
                out.status[i], out.settle_periods[i] = STOPPED, run
                return
            trajectory, history[run:run + block], start, _ = result
            run += block
            p = period_of(history, run - s.window, run, known, s.tolerance,
                          s.max_period) if run >= s.window else 0
            if p:
                out.period[i], out.contacts[i] = p, self.contacts(trajectory, p)
                out.settle_periods[i] = settled_from(history, run, p, s.tolerance)
                out.samples[i, :p] = history[run - p:run]
                break
        out.end_q[i], out.end_v[i], out.end_phase[i] = start
        if not out.period[i]:
            out.status[i], out.settle_periods[i] = NOT_SETTLED, run


__all__ = ["ContactCellRunner"]
