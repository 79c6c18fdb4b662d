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
(counts, peak forces, impulses, each contact's gap minima and interval value). SI units.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterable

import numpy as np

from impactbeams.active_phases import (
    CONTACT_STATUS_NAMES,
    ContactRun,
    PackedContacts,
    contact_quantities,
    gap_rate,
    pack_contacts,
    sample,
    tip_motions,
)
from impactbeams.blas import one_blas_thread
from impactbeams.kernels import several_contacts as kernel
from impactbeams.kernels.contacts_tangent import carry_contact_tangents, event_at
from impactbeams.kernels.layout import TIP_Y1, TIP_Y2
from impactbeams.kernels.records import Tangent
from impactbeams.orbits.period_map import (
    INTERVAL_SAMPLES,
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
        Brent's method.
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
        Brent's method); ``least_peak_force``: the smallest contact episode's peak (N);
        ``interval_gap``: `_interval_gap`.
        """
        if result.approached:
            return result
        min_gap, min_gap_time = self._min_gap(result.trajectory)
        peaks = self._episode_peaks(result.trajectory)
        return dataclasses.replace(
            result, min_gap=min_gap, min_gap_time=min_gap_time, approached=True,
            least_peak_force=float(np.min(peaks[:, 1])) if peaks.size else math.nan,
            interval_gap=self._interval_gap(result.trajectory))

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
        """The tips (``kernels.layout`` TIP_* columns) of ``result``'s run at ``times`` (s).

        As `impactbeams.simulate` of several contacts reads them
        (`active_phases.tip_motions`): the free coordinates' tips plus each closed contact's
        force through the flexibility the modes miss, the velocities with its rate.
        """
        times = np.asarray(times, dtype=float)
        q, v, mask = sample(self.contacts, result.trajectory, times)
        forces = contact_quantities(self.contacts, times, q, v, mask)["contact_force"]
        motions = tip_motions(self.contacts, times, q, v, mask, forces)
        return np.column_stack([motions[name] for name in (
            "tip_deflection_1", "tip_deflection_2", "tip_velocity_1", "tip_velocity_2")])

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

    def _interval_values(self, run: ContactRun, times: np.ndarray, masks: np.ndarray,
                         ) -> np.ndarray:
        """Each contact's interval function (m) at ``times`` in the sets of ``masks``, (k, n).

        An open contact's physical gap; a closed one's -R_f (1/k_f + r_f): its force over
        its stiffness in series with the flexibility the modes miss at it, the overlap it
        would have alone, which is 0 where R_f is (its release) and, closed alone without a
        dashpot, its modal gap: the single contact's gap read from the free coordinates.
        """
        q, v, _ = sample(self.contacts, run, times)
        quantities = contact_quantities(self.contacts, times, q, v, masks)
        closed = (masks[:, None] >> np.arange(len(self.contacts.runs))) & 1 == 1
        springs = self.contacts.contacts
        compliance = 1.0 / springs.stiffness + np.diag(springs.residual)
        return np.where(closed, -quantities["contact_force"] * compliance, quantities["gap"])

    def _interval_gap(self, run: ContactRun) -> float:
        """The interval value (m): a contact's gap's local maximum nearest 0 between its closings.

        As `PeriodMap._interval_gap`, per contact on `_interval_values` (so that where every
        other contact stays open it is the single contact's): the height of a free interval
        between two of its closings (> 0, the period's ends joined) or the interior rises
        within its closed phases (< 0: where one
        reaches 0 the contact splits), each phase sampled ``INTERVAL_SAMPLES`` times; the
        sample nearest 0 of all contacts, refined by Brent's method between its neighbours.
        NaN without a candidate.
        """
        ends = np.append(run.time[1:], run.t_end)
        times = np.linspace(run.time, ends, INTERVAL_SAMPLES, axis=1)
        masks = np.repeat(run.mask, INTERVAL_SAMPLES)
        values = self._interval_values(run, times.ravel(), masks).reshape(
            *times.shape, -1)
        best = None  # (|sample|, phase, sample, contact)
        for f in range(values.shape[2]):
            for k, i in self._interval_candidates((run.mask >> f) & 1 == 1, ends > run.time,
                                                  values[:, :, f]):
                if best is None or abs(values[k, i, f]) < best[0]:
                    best = (abs(values[k, i, f]), k, i, f)
        if best is None:
            return math.nan
        _, k, i, f = best
        phase_mask = run.mask[k:k + 1]
        lo, hi = times[k, max(i - 1, 0)], times[k, min(i + 1, INTERVAL_SAMPLES - 1)]
        if not hi > lo:  # a phase of no duration: its samples are one state
            return float(values[k, i, f])

        def depth(t: float) -> float:  # minus the function: its maximum is a minimum
            return -float(self._interval_values(run, np.array([t]), phase_mask)[0, f])

        return -refined(depth, lo, hi, -values[k, i, f], times[k, i])[0]

    @staticmethod
    def _interval_candidates(closed: np.ndarray, lasting: np.ndarray, values: np.ndarray,
                             ) -> list[tuple[int, int]]:
        """(phase, sample) of one contact's candidate maxima between its closings.

        ``closed``, ``lasting``: whether it is closed in each phase and the phase lasts;
        ``values``: its samples (phases, samples). As `kernels.extrema.interval_gap`: each
        lasting closed phase's interior sample maxima, then each free interval's (its open
        phases in a row, the period's ends joined, closed on both sides) highest sample,
        also at a phase's end (the kernel leaves those out: there a free interval of almost
        no duration, at a merge, has its height, about 0, in every sample).
        """
        found = [(k, i) for k in np.flatnonzero(closed & lasting)
                 for i in range(1, values.shape[1] - 1)
                 if values[k, i - 1] < values[k, i] >= values[k, i + 1]]
        if not closed.any():
            return found
        first = int(np.argmax(closed))  # the free intervals from the first closing, cyclic
        phases = np.roll(np.arange(closed.size), -first)
        free = np.roll(~closed, -first)
        starts = np.flatnonzero(free & ~np.concatenate([[False], free[:-1]]))
        for start in starts:
            span = phases[start:start + int(np.argmin(np.append(free[start:], False)))]
            k = span[int(np.argmax(values[span].max(axis=1)))]
            found.append((k, int(np.argmax(values[k]))))
        return found

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
        start = self.early_released(int(run.mask[0]), run.q[0], run.v[0])
        tangent = Tangent(rows_q, rows_v, np.array([run.time[0], 0.0]),
                          np.zeros((1, rows_q.shape[0])), np.zeros(1, dtype=np.int64))
        carry_contact_tangents(*self.contacts.tangent_arguments(), run.arrays(), run.t_end, start,
                               (math.inf, run.t_end, 0, 0), tangent)  # no renormalisation
        return np.hstack([rows_q, rows_v]).T

    def _run(self, z0: np.ndarray) -> ContactRun:
        """The run of the active sets' phases from the section state z0 to p T.

        An open contact whose gap is < 0 at the start was released early by its dashpot: the
        run follows it as after its release (`kernels.several_contacts.resume_contacts`).
        """
        n, m = len(self.contacts.runs), self.packed.q0.size
        q0, v0 = z0[:m].copy(), z0[m:].copy()
        size = self.max_events
        recorded = (np.empty(size), np.empty(size, dtype=np.int64),
                    np.empty(size, dtype=np.int64), np.empty((size, m)), np.empty((size, m)),
                    np.empty((size, n)), np.empty((size, n)))
        mask = self.active_mask(z0)
        count, status, t_end = kernel.resume_contacts(
            self.contacts.active_sets, self.contacts.settings, self.contacts.early_release, q0,
            v0, 0.0, mask, self.early_released(mask, q0, v0), recorded)
        return ContactRun(*(array[:count] for array in recorded),
                          CONTACT_STATUS_NAMES[status], float(t_end))

    def _events(self, mask: int, q: np.ndarray, v: np.ndarray, t: float = 0.0,
                functions: Iterable[int] | None = None) -> np.ndarray:
        """Event ``functions`` of the set of ``mask`` at (q, q', t); default each contact's.

        Function f < n: contact f's R_f if closed, its gap if open; n + f: minus the force
        open contact f would have with it added (`active_phases.pack_contacts`).
        """
        packed = self.contacts
        a = int(packed.set_of_mask[mask])
        y, y_rate = np.empty(q.size), np.empty(q.size)
        return np.array([event_at(packed.active_sets, packed.settings, a, f, q, v, t, y, y_rate)[0]
                         for f in (range(len(packed.runs)) if functions is None
                                   else functions)])

    def active_mask(self, z: np.ndarray) -> int:
        """The bit mask of the contacts closed at the section state z (t = 0).

        The first possible set whose forces are all > 0 and open gaps all >= 0; without one
        (a dashpot's early release) the first whose forces are > 0 and whose open contacts
        with a gap < 0 would pull if closed (the force each would have with it added is
        <= 0: released early, as one contact's `phase_state` starts free where g < 0 and
        -k g - c g' <= 0); without one either, the first whose forces are > 0.
        """
        m = self.packed.q0.size
        q, v = z[:m], z[m:]
        released = forced = None
        for members in self.contacts.members:
            mask = sum(1 << f for f in members)
            events = self._events(mask, q, v)
            closed = np.array([f in members for f in range(events.size)])
            if np.all(events[closed] > 0.0):
                if np.all(events[~closed] >= 0.0):
                    return mask
                if released is None and self._pulls(mask, events, q, v):
                    released = mask
                forced = mask if forced is None else forced
        return next(mask for mask in (released, forced, 0) if mask is not None)

    def _pulls(self, mask: int, events: np.ndarray, q: np.ndarray, v: np.ndarray) -> bool:
        """Whether each open contact of ``mask`` whose gap (``events``) is < 0 would pull.

        Its force in the set with it added is <= 0 (function n + f of the set, minus that
        force, >= 0); a contact that cannot close with the set's (the other side of a
        two-sided stop) is not asked.
        """
        n = events.size
        overlapping = [f for f in range(n) if not (mask >> f) & 1 and events[f] < 0.0
                       and self.contacts.set_of_mask[mask | 1 << f] >= 0]
        return all(self._events(mask, q, v, functions=(n + f,))[0] >= 0.0 for f in overlapping)

    def early_released(self, mask: int, q: np.ndarray, v: np.ndarray) -> int:
        """The open contacts whose gaps are < 0 at (q, q', 0) in the set of ``mask`` (bits).

        With a dashpot: the contacts released early, which the run starts in.
        """
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
