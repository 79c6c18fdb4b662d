"""The period map of several spring contacts and its exact Jacobian (the monodromy matrix).

``P^p``: p forcing periods of the run of the active sets' phases
(`impactbeams.kernels.several_contacts.run_contacts`, packed by
`impactbeams.active_phases`) from a state z = (q, q') on the section t = 0 to the
state at t = p T. The contacts closed at the start follow from the state: the active set whose
forces are all > 0 with every open contact's physical gap >= 0 (without a dashpot there is
exactly one: the forces solve a linear complementarity problem of the positive definite
``K^-1 + R_N``); with a dashpot an open contact whose gap is < 0 is one released early. The
Jacobian dz(pT)/dz(0) is carried along the recorded phases by
`impactbeams.kernels.contacts_tangent` (each phase's closed-form propagation, the saltation
matrix at every switch): exact up to round-off. The same interface as
`impactbeams.orbits.period_map.PeriodMap` where shooting uses it; its measures are the contacts'
(counts, peak forces, impulses): the tips' maxima and the gap's minima are NaN. SI units.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np

from impactbeams.active_phases import (
    CONTACT_STATUS_NAMES,
    ContactRun,
    PackedContacts,
    contact_quantities,
    gap_rate,
    pack_contacts,
    sample,
)
from impactbeams.blas import one_blas_thread
from impactbeams.kernels import several_contacts as kernel
from impactbeams.kernels.contacts_tangent import carry_contact_tangents, event_at
from impactbeams.kernels.layout import FREE, TIP_COLUMNS, TIP_Y1, TIP_Y2
from impactbeams.kernels.records import Tangent
from impactbeams.orbits.period_map import (
    MAX_EVENTS,
    SAMPLES_PER_PERIOD,
    PeriodMap,
    PeriodMapResult,
    SectionMap,
    check_law,
    directions_of,
    refined,
)
from impactbeams.params import Params, require, require_integer, require_type
from impactbeams.trajectory.episodes import default_separation, episode_count
from impactbeams.trajectory.observables import observables
from impactbeams.trajectory.several import check_contact_runs
from impactbeams.trajectory.start import checked_state


class ContactsPeriodMap(SectionMap):
    """The map z(0) -> z(p T) of ``params`` with several contacts (spring law, Omega > 0).

    ``n_modes`` per beam: default the most any one contact's run recommends (as
    `impactbeams.simulate` of several contacts). ``periods``: p, forcing periods per map.
    Called as `impactbeams.orbits.period_map.PeriodMap` is (``state``, ``directions``,
    ``measures``), with a `PeriodMapResult` whose ``trajectory`` is the run's
    `impactbeams.active_phases.ContactRun`.
    """

    def __init__(self, params: Params, n_modes: int | None = None, periods: int = 1,
                 max_events: int = MAX_EVENTS) -> None:
        require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
        check_law(params)
        require("omega", params.omega, params.omega > 0,
                "a period map needs a forcing period: omega > 0", "rad/s")
        self.periods = require_integer("periods", periods, 1)
        self.max_events = require_integer("max_events", max_events, 1)
        self.params = params
        self.forcing_period = 2.0 * math.pi / params.omega
        self.horizon = self.periods * self.forcing_period
        self.n_modes = check_contact_runs(params, self.horizon, n_modes)
        self.contacts: PackedContacts = pack_contacts(params, self.n_modes, self.horizon,
                                                      self.horizon)
        # contact 0's own run: the free phase (modes, start, section states) all runs share
        self.packed = self.contacts.runs[0]
        self._separation = default_separation(self.packed)

    @one_blas_thread
    def __call__(self, state: np.ndarray, directions: np.ndarray | str | None = None,
                 measures: bool = True) -> PeriodMapResult:
        """P^p(z) from the section state ``state``, with dP^p/dz applied to ``directions``.

        As `PeriodMap.__call__`. ``measures``: the contacts' peak forces and impulses (the
        contacts and episodes are always counted).
        """
        z0 = checked_state(self.packed, state, "state")
        columns = directions_of(directions, self.dimension)
        run = self._run(z0)
        if run.status != "complete":
            raise RuntimeError(f"the period map's run stopped at t = {run.t_end!r} s "
                               f"before {self.horizon!r} s: status {run.status!r}")
        q, v, _ = sample(self.contacts, run, np.array([self.horizon]))
        jacobian = None if columns is None else self._jacobian(run, columns)
        result = PeriodMapResult(np.concatenate([q[0], v[0]]), jacobian, self._onsets(run),
                                 self._episodes(run), *(math.nan,) * 6, run.status, run)
        return self.measured(result) if measures else result

    def at(self, params: Params) -> ContactsPeriodMap:
        """The map of ``params`` with this one's modes, periods and event limit (built anew)."""
        return ContactsPeriodMap(params, self.n_modes, self.periods, self.max_events)

    def measured(self, result: PeriodMapResult) -> PeriodMapResult:
        """``result`` with its measures, read from its run (as `PeriodMap.measured`).

        ``peak_forces``: each contact episode's largest force (an episode: one contact's
        phases closed in a row, cut at the run's ends), in order of contacts then time;
        ``impact_velocities``: the closing contact's physical gap rate at each onset in
        (0, pT); the tips' maxima sampled `SAMPLES_PER_PERIOD` times a period and refined by
        Brent's method; ``interval_gap`` NaN (not built for several contacts).
        """
        if math.isfinite(result.max_tip1):
            return result
        result = self.approach(result)
        run = result.trajectory
        peaks = self._episode_peaks(run)
        times = self._grid()
        tips = self.tip_motions(result, times)
        relative = self._largest(result, times, tips, TIP_Y1, True)
        absolute = (self._largest(result, times, tips, TIP_Y1, False)
                    if self.params.mount.clamps[0] * self.params.base_amplitude else relative)
        beam2 = (self._largest(result, times, tips, TIP_Y2, False)
                 if self.params.partner.has_beam2 else 0.0)
        return dataclasses.replace(
            result, peak_force=float(np.max(peaks[:, 1], initial=0.0)),
            peak_forces=peaks[:, 1], impulse=float(np.sum(run.impulses)), max_tip1=absolute,
            max_tip2=beam2, max_relative_tip1=relative,
            impact_velocities=self._impact_velocities(run))

    def approach(self, result: PeriodMapResult) -> PeriodMapResult:
        """``result`` with what a grazing is read from (as `PeriodMap.approach`).

        ``min_gap``, ``min_gap_time``: the smallest interior local minimum of any contact's
        physical gap while it is open (sampled `SAMPLES_PER_PERIOD` times a period, refined by
        Brent's method); ``least_peak_force``: the smallest contact episode's peak (N).
        """
        if result.approached:
            return result
        min_gap, min_gap_time = self._min_gap(result.trajectory)
        peaks = self._episode_peaks(result.trajectory)
        return dataclasses.replace(
            result, min_gap=min_gap, min_gap_time=min_gap_time, approached=True,
            least_peak_force=float(np.min(peaks[:, 1])) if peaks.size else math.nan)

    def grazing_value(self, result: PeriodMapResult) -> float:
        """The signed grazing value (m) of an `approach`-ed ``result``; NaN if it has none.

        As `PeriodMap.grazing_value` over all contacts: the smallest open gap's interior
        minimum (> 0) or minus the shallowest episode's overlap, its peak force over its
        contact's stiffness (< 0), whichever is nearer 0.
        """
        candidates = [result.min_gap] if math.isfinite(result.min_gap) else []
        peaks = self._episode_peaks(result.trajectory)
        if peaks.size:
            stiffness = self.contacts.contacts.stiffness[peaks[:, 0].astype(int)]
            candidates.append(-float(np.min(peaks[:, 1] / stiffness)))
        return min(candidates, key=abs) if candidates else math.nan

    def least_gap(self, result: PeriodMapResult, contact: int = 0) -> float:
        """The smallest value over the run of ``contact``'s gap read as if it were open (m).

        Its physical gap in the set of the contacts closed but itself (the others' forces
        deflect it through the flexibility the modes miss): while it is open its gap, while
        it is closed the depth it would reach without its own force, so that it passes
        through 0 with one slope where the orbit touches (as `PeriodMap.least_gap`, which it
        is beside contacts that never close). Sampled `SAMPLES_PER_PERIOD` times a period,
        the smallest refined by Brent's method between its neighbours.
        """
        run = result.trajectory
        times = self._grid()
        gap = self._open_gaps(run, times, contact)
        i = min(max(int(np.argmin(gap)), 1), times.size - 2)
        return refined(lambda t: float(self._open_gaps(run, np.array([t]), contact)[0]),
                       times[i - 1], times[i + 1], gap[i], times[i])[0]

    def _open_gaps(self, run: ContactRun, times: np.ndarray, contact: int) -> np.ndarray:
        """``contact``'s physical gap (m) at ``times`` in the sets closed there but itself."""
        q, v, mask = sample(self.contacts, run, times)
        opened = mask & ~(1 << contact)
        return contact_quantities(self.contacts, times, q, v, opened)["gap"][:, contact]

    def tip_motions(self, result: PeriodMapResult, times: np.ndarray) -> np.ndarray:
        """The tips (``kernels.layout`` TIP_* columns; velocities NaN) of ``result``'s run.

        As `impactbeams.simulate` of several contacts reads them: the free coordinates' tips
        plus each closed contact's force through the flexibility the modes miss.
        """
        times = np.asarray(times, dtype=float)
        q, v, mask = sample(self.contacts, result.trajectory, times)
        free = observables(self.packed, np.full(times.size, FREE, dtype=np.int64), times, q, v)
        forces = contact_quantities(self.contacts, times, q, v, mask)["contact_force"]
        springs = [run.dynamics.spring for run in self.contacts.runs]
        out = np.full((times.size, len(TIP_COLUMNS)), math.nan)
        out[:, TIP_Y1] = free["tip_deflection_1"] + forces @ [s.tip_shift1 for s in springs]
        out[:, TIP_Y2] = free["tip_deflection_2"] - forces @ [s.tip_shift2 for s in springs]
        return out

    def _grid(self) -> np.ndarray:
        """``SAMPLES_PER_PERIOD`` equally spaced times a period over the run (s)."""
        return np.linspace(0.0, self.horizon, SAMPLES_PER_PERIOD * self.periods + 1)

    def _largest(self, result: PeriodMapResult, times: np.ndarray, tips: np.ndarray,
                 column: int, clamp: bool) -> float:
        """The largest |tip ``column``| (minus beam 1's clamp if ``clamp``) over the run (m).

        From its samples ``tips`` at ``times``, refined by Brent's method between the largest
        sample's neighbours.
        """

        def size(t: float) -> float:
            at = np.array([t])
            return float(abs(self.tip_motions(result, at)[0, column]
                             - (self.clamp1(at)[0] if clamp else 0.0)))

        sampled, i, lo, hi = self.largest_sample(tips, times, column, clamp)
        return -refined(lambda t: -size(t), lo, hi, -sampled[i], times[i])[0]

    def _gaps(self, run: ContactRun, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each contact's physical gap (m) at ``times`` and whether it is open there."""
        q, v, mask = sample(self.contacts, run, times)
        gaps = contact_quantities(self.contacts, times, q, v, mask)["gap"]
        bits = np.arange(gaps.shape[1])
        return gaps, (mask[:, None] >> bits[None, :]) & 1 == 0

    def _min_gap(self, run: ContactRun) -> tuple[float, float]:
        """The smallest interior minimum of an open contact's gap, and its time (m, s)."""
        times = self._grid()
        gaps, opened = self._gaps(run, times)
        best = (math.nan, math.nan)
        for f in range(gaps.shape[1]):
            g, free = gaps[:, f], opened[:, f]
            inner = (free[1:-1] & free[:-2] & free[2:] & (g[1:-1] <= g[:-2])
                     & (g[1:-1] < g[2:]))
            for i in np.flatnonzero(inner) + 1:
                value = refined(lambda t, f=f: float(self._gaps(run, np.array([t]))[0][0, f]),
                                times[i - 1], times[i + 1], g[i], times[i])
                if not value[0] >= best[0]:
                    best = value
        return best

    def _episode_peaks(self, run: ContactRun) -> np.ndarray:
        """(contact, peak force in N) of each contact episode of ``run``, rows (k, 2)."""
        rows = []
        for f in range(len(self.contacts.runs)):
            closed = (run.mask >> f) & 1 == 1
            starts = np.flatnonzero(closed & ~np.concatenate([[False], closed[:-1]]))
            for start in starts:
                end = start + int(np.argmin(np.append(closed[start:], False)))
                rows.append((f, float(np.max(run.peaks[start:end, f]))))
        return np.array(rows, dtype=float).reshape(-1, 2)

    def _impact_velocities(self, run: ContactRun) -> np.ndarray:
        """The closing contact's physical gap rate (m/s) at each onset in (0, pT), in order."""
        n = len(self.contacts.runs)
        return np.array([gap_rate(self.contacts, int(run.mask[k - 1]), int(run.switched[k]),
                                  run.q[k], run.v[k], float(run.time[k]))
                         for k in range(1, run.time.size)
                         if 0 <= run.switched[k] < n and (run.mask[k] >> run.switched[k]) & 1])

    @one_blas_thread
    def jacobian(self, result: PeriodMapResult, directions: np.ndarray | str) -> np.ndarray:
        """dP^p/dz of an earlier evaluation ``result`` applied to more ``directions``.

        As `PeriodMap.jacobian`: the tangents along ``result``'s recorded run, no new run.
        """
        require("directions", directions, directions is not None,
                "must be 'all' or an array of directions (2 N, k)")
        return self._jacobian(result.trajectory, directions_of(directions, self.dimension))

    def _jacobian(self, run: ContactRun, columns: np.ndarray) -> np.ndarray:
        """dz(pT)/dz(0) @ columns by the tangent kernel on the recorded phases."""
        n = self.packed.q0.size
        rows_q = np.ascontiguousarray(columns[:n].T)
        rows_v = np.ascontiguousarray(columns[n:].T)
        start = self._early(int(run.mask[0]), run.q[0], run.v[0])
        tangent = Tangent(rows_q, rows_v, np.array([run.time[0], 0.0]),
                          np.zeros((1, rows_q.shape[0])), np.zeros(1, dtype=np.int64))
        carry_contact_tangents(*self.contacts.tangent_arrays(), run.arrays(), run.t_end, start,
                               (math.inf, run.t_end, 0, 0), tangent)  # no renormalisation
        return np.hstack([rows_q, rows_v]).T

    def _run(self, z0: np.ndarray) -> ContactRun:
        """The run of the active sets' phases from the section state z0 to p T."""
        n, m = len(self.contacts.runs), self.packed.q0.size
        q0, v0 = z0[:m].copy(), z0[m:].copy()
        size = self.max_events
        recorded = (np.empty(size), np.empty(size, dtype=np.int64),
                    np.empty(size, dtype=np.int64), np.empty((size, m)), np.empty((size, m)),
                    np.empty((size, n)), np.empty((size, n)))
        mask = self.active_mask(z0)
        if self._early(mask, q0, v0):
            raise RuntimeError("the period map's section state lies in a dashpot's early "
                               "release (an open contact's gap < 0): a run of several "
                               "contacts starts with every open gap >= 0")
        count, status, t_end = kernel.run_contacts(*self.contacts.kernel_arrays(),
                                                   self.contacts.early_release, q0, v0, 0.0,
                                                   mask, recorded)
        return ContactRun(*(array[:count] for array in recorded),
                          CONTACT_STATUS_NAMES[status], float(t_end))

    def _events(self, mask: int, q: np.ndarray, v: np.ndarray, t: float = 0.0) -> np.ndarray:
        """Each contact's event function in the set of ``mask`` at (q, q', t): R_f or gap."""
        packed = self.contacts
        a = int(packed.set_of_mask[mask])
        y, y_rate = np.empty(q.size), np.empty(q.size)
        return np.array([event_at(packed.tables, packed.scalars, packed.modes, packed.drives,
                                  packed.lefts, packed.settings, a, f, q, v, t, y, y_rate)[0]
                         for f in range(len(packed.runs))])

    def active_mask(self, z: np.ndarray) -> int:
        """The bit mask of the contacts closed at the section state z (t = 0).

        The first possible set whose forces are all > 0 and open gaps all >= 0; without one
        (a dashpot's early release) the first whose forces are > 0.
        """
        m = self.packed.q0.size
        q, v = z[:m], z[m:]
        forced = None
        for members in self.contacts.members:
            mask = sum(1 << f for f in members)
            events = self._events(mask, q, v)
            closed = np.array([f in members for f in range(events.size)])
            if np.all(events[closed] > 0.0):
                if np.all(events[~closed] >= 0.0):
                    return mask
                forced = mask if forced is None else forced
        return 0 if forced is None else forced

    def _early(self, mask: int, q: np.ndarray, v: np.ndarray) -> int:
        """The open contacts whose gaps are < 0 at (q, q', 0) in the set of ``mask`` (bits)."""
        if not self.contacts.early_release:
            return 0
        events = self._events(mask, q, v)
        return sum(1 << f for f in range(events.size)
                   if not (mask >> f) & 1 and events[f] < 0.0)

    def _onsets(self, run: ContactRun) -> int:
        """Each contact's closings in [0, pT), one closed at the start included."""
        n = len(self.contacts.runs)
        closings = [int(run.switched[k]) < n and (int(run.mask[k]) >> int(run.switched[k])) & 1
                    for k in range(1, run.time.size) if run.time[k] < self.horizon]
        return int(sum(closings)) + bin(int(run.mask[0])).count("1")

    def _episodes(self, run: ContactRun) -> int:
        """Impact episodes in [0, pT): the intervals with a contact closed, grouped.

        As one contact's are (`episode_count`, the default separation).
        """
        closed = [(int(mask) != 0, float(t)) for mask, t in zip(run.mask, run.time,
                                                                 strict=True)]
        onsets, releases = [], []
        for (before, _), (now, t) in itertools.pairwise([(False, 0.0), *closed]):
            if now and not before and t < self.horizon:
                onsets.append(t)
            elif before and not now:
                releases.append(t)
        releases += [math.nan] * (len(onsets) - len(releases))
        return episode_count(onsets, releases[:len(onsets)], self._separation)


def make_period_map(params: Params, n_modes: int | None = None, periods: int = 1,
                    ) -> PeriodMap | ContactsPeriodMap:
    """The period map of ``params``: `PeriodMap` for one contact, `ContactsPeriodMap` for more."""
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    if params.several_contacts:
        return ContactsPeriodMap(params, n_modes, periods)
    return PeriodMap(params, n_modes, periods)
