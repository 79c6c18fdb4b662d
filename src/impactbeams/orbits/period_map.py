"""The period map of the spring law and its exact Jacobian (the monodromy matrix).

``P^p``: p forcing periods of the event-driven run from a state z = (q, q') on the
stroboscopic section t = 0 (`impactbeams.trajectory.start`) to the state at t = p T,
T = 2 pi / Omega. The run is the package's exact one (`impactbeams.kernels.dynamics`), and
the Jacobian dz(pT)/dz(0) is carried by the tangent kernel along the same recorded segments,
with the saltation matrix at every onset (`impactbeams.kernels.tangent.carry_tangents`): exact
up to round-off, the same Jacobian whose one-period version agrees with finite differences of
the nonlinear run (tests/test_lyapunov.py). Columns may be requested as a block of directions
(Newton-Picard needs a few), each costing one tangent propagation.

The tied law has no tangent flow (its switches project onto other bases) and is refused, as
for Lyapunov exponents. SI units throughout.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize_scalar

from impactbeams.blas import one_blas_thread
from impactbeams.contact.spring import recommended_modes
from impactbeams.kernels import contact
from impactbeams.kernels.extrema import (
    gap_extremum,
    interval_gap,
    smallest_free_minimum,
    tip_maximum,
)
from impactbeams.kernels.layout import (
    CONTACT,
    FREE,
    ROW_EVENT,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
    SPRING_DRIVE_ROWS,
    TIP_Y1,
    TIP_Y2,
)
from impactbeams.kernels.peaks import least_peak_force
from impactbeams.kernels.records import Tangent
from impactbeams.kernels.tangent import carry_tangents
from impactbeams.packing import Dynamics, Packed, dynamics_arrays, pack_run
from impactbeams.params import (
    MAX_MODES,
    ParameterError,
    Params,
    require,
    require_integer,
    require_one_contact,
    require_type,
)
from impactbeams.trajectory.episodes import default_separation, episode_count
from impactbeams.trajectory.impacts import contact_measures
from impactbeams.trajectory.phases import (
    Trajectory,
    run,
    sample,
    tips_at,
    tips_of,
)
from impactbeams.trajectory.start import checked_state, final_state, phase_state

# Samples per forcing period of the gap and the tips, before each extremum is refined by
# Brent's method: T / 512 resolves the motion up to 64 Omega (the beams' first modes, which
# carry the gap's and the tips' bulk motion); a local extremum narrower than the spacing may
# be missed.
SAMPLES_PER_PERIOD = 512
MAX_EVENTS = 200_000  # phases per map evaluation
# the first window of a map's run, in phases a period (`phases.run`): the stiff stop's orbits
# have up to 10 contacts a period (21 phases); a longer run goes on in further windows, bit for
# bit
PERIOD_WINDOW = 128
# samples of the gap per segment for its maxima between contacts (a contact's rise, a free
# interval's height): each refined at the root of the gap's rate
INTERVAL_SAMPLES = 16


@dataclasses.dataclass(frozen=True)
class PeriodMapResult:
    """One evaluation of the period map from the section state z0 (SI units).

    ``state``: z(pT) = (q, q') (2 N values). ``jacobian``: dz(pT)/dz(0) times the requested
    directions, (2 N, k) (all of it, k = 2 N, for ``directions="all"``; None if none asked).
    ``contacts``, ``episodes``: contact phases and impact episodes (default episode
    separation) that start in [0, pT). ``min_gap``, ``min_gap_time``: the smallest local
    minimum of the gap g (m, s) inside the free phases (the approach to grazing; NaN, NaN if
    the gap has no interior minimum), located to round-off in t. ``peak_force`` (N) and
    ``impulse`` (N s, summed) of the contacts, 0 without contact. ``max_tip1``,
    ``max_tip2``: max |y1(l1)|, max |y2(l2)| (m) over [0, pT]. ``status``: the run's
    (``dynamics.STATUS_NAMES``). ``trajectory``: the recorded segments.
    ``peak_forces`` (N): each contact phase's peak force, in order (empty without measures).
    ``least_peak_force`` (N): the smallest of them (NaN without contact), also without the
    other measures: a continuation's grazing value reads it at every corrected point.
    ``impact_velocities``
    (m/s): the gap's rate dg/dt at each contact's onset in (0, pT), in order (< 0: closing;
    empty without measures; a contact under way at t = 0 had its onset before).
    ``max_relative_tip1`` (m): max |y1(l1) - u_b1| over [0, pT], beam 1's
    tip relative to its clamp (u_b1 = U0 sin(Omega t) if the shaker carries that clamp, else
    0: then it is ``max_tip1``; NaN without measures).
    """

    state: np.ndarray
    jacobian: np.ndarray | None
    contacts: int
    episodes: int
    min_gap: float
    min_gap_time: float
    peak_force: float
    impulse: float
    max_tip1: float
    max_tip2: float
    status: str
    trajectory: Trajectory
    peak_forces: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    least_peak_force: float = math.nan
    approached: bool = False
    impact_velocities: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    max_relative_tip1: float = math.nan
    interval_gap: float = math.nan


class SectionMap:
    """What every period map has from its (first contact's) packed run ``packed``."""

    packed: Packed
    params: Params

    @property
    def dimension(self) -> int:
        """Size of a section state z = (q, q'): 2 N."""
        return 2 * self.packed.q0.size

    def rest_state(self) -> np.ndarray:
        """The run's initial state of ``params.start`` (and uplifts) as a section state."""
        return np.concatenate([self.packed.q0, self.packed.v0])

    def clamp1(self, times: np.ndarray) -> np.ndarray:
        """Beam 1's clamp position u_b1 (m) at ``times``: U0 sin(Omega t) if it moves, else 0."""
        moves1, _ = self.params.mount.clamps
        return moves1 * self.params.base_amplitude * np.sin(self.params.omega * times)

    def largest_sample(self, tips: np.ndarray, times: np.ndarray, column: int, clamp: bool,
                       ) -> tuple[np.ndarray, int, float, float]:
        """The samples |tip ``column``| (m), their largest's index and neighbours' times (s).

        Minus beam 1's clamp if ``clamp``; a maximum is refined between the neighbours.
        """
        sampled = np.abs(tips[:, column] - (self.clamp1(times) if clamp else 0.0))
        i = int(np.argmax(sampled))
        return sampled, i, times[max(i - 1, 0)], times[min(i + 1, times.size - 1)]

    def least_gap(self, result: PeriodMapResult, contact: int = 0) -> float:
        """The smallest value over ``result``'s run of ``contact``'s gap as if it were open (m).

        Each map's own (`PeriodMap`, `ContactsPeriodMap`): a section map without contacts has
        none.
        """
        raise NotImplementedError

    def grazing_contact(self, result: PeriodMapResult) -> int:
        """The contact whose `least_gap` on ``result``'s run is nearest 0: the one that grazes."""
        return min(range(len(self.params.each_contact())),
                   key=lambda contact: abs(self.least_gap(result, contact)))


class PeriodMap(SectionMap):
    """The map z(0) -> z(p T) of ``params`` (spring law, Omega > 0) with ``n_modes`` per beam.

    ``n_modes``: default the number that resolves the contact (as in `simulate`). ``periods``:
    p, forcing periods per map. Call it with a section state z = (q, q') (2 N values,
    ``dimension``); see `__call__`.
    """

    def __init__(self, params: Params, n_modes: int | None = None, periods: int = 1,
                 max_events: int = MAX_EVENTS) -> None:
        require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
        check_law(params)
        require_one_contact(params, "PeriodMap (several: orbits.contacts_map.ContactsPeriodMap)")
        self.periods = require_integer("periods", periods, 1)
        if n_modes is None:
            n_modes = recommended_modes(params)
        self.n_modes = require_integer("n_modes", n_modes, 1, MAX_MODES)
        self.max_events = require_integer("max_events", max_events, 1)
        self._pack(params, geometry_arrays)
        # the episodes' separation (s): the geometry's, which `at` keeps
        self._separation = default_separation(self.packed)

    def at(self, params: Params) -> PeriodMap:
        """The map of ``params``: this one's but for the cell's parameters (``CELL_ONLY``).

        The same map as ``PeriodMap(params, self.n_modes, self.periods, self.max_events)``,
        bit for bit, built on this one's geometry (a continuation in Omega, F0, U0 or the
        clearance asks for a map at every corrector iterate and parameter difference).
        """
        changed = copy.copy(self)
        changed._pack(params, lambda _, __: dataclasses.replace(self.packed.dynamics,
                                                                 params=params))
        return changed

    def _pack(self, params: Params,
              geometry: Callable[[Params, int], Dynamics]) -> None:
        """Set ``params``, the horizon and the packed run, on ``geometry(params, n_modes)``."""
        require("omega", params.omega, params.omega > 0,
                "a period map needs a forcing period: omega > 0", "rad/s")
        self.params = params
        self.forcing_period = 2.0 * math.pi / params.omega
        self.horizon = self.periods * self.forcing_period
        self._times: np.ndarray | None = None  # the sample grid, built when first asked
        self.packed: Packed = pack_run(params, self.n_modes, self.horizon, self.horizon,
                                       geometry(params, self.n_modes))

    @one_blas_thread
    def __call__(self, state: np.ndarray, directions: np.ndarray | str | None = None,
                 measures: bool = True) -> PeriodMapResult:
        """P^p(z) from the section state ``state``, with dP^p/dz applied to ``directions``.

        ``directions``: None (no Jacobian), ``"all"`` (the monodromy matrix, 2 N tangent
        propagations) or an array (2 N, k) of k directions (k tangent propagations).
        ``measures``: also the gap's minimum, the contacts' peak force and impulse and the
        tips' maxima (else NaN; the contacts are always counted). ParameterError for a state
        of the wrong size or not finite; RuntimeError if the run does not complete (an
        event or search limit).
        """
        z0 = checked_state(self.packed, state, "state")
        columns = directions_of(directions, self.dimension)
        start = phase_state(self.packed, z0)
        trajectory = run(self.packed, self.max_events, start=start,
                         window=PERIOD_WINDOW * self.periods)
        if trajectory.status != "complete":
            raise RuntimeError(f"the period map's run stopped at t = {trajectory.t_end!r} s "
                               f"before {self.horizon!r} s: status {trajectory.status!r}")
        end = final_state(self.packed, trajectory)
        jacobian = None if columns is None else self._jacobian(trajectory, columns)
        onsets = trajectory.time[trajectory.phase == CONTACT]
        contacts = int(np.count_nonzero(onsets < self.horizon))
        result = PeriodMapResult(end, jacobian, contacts, self._episodes(trajectory),
                                 *(math.nan,) * 6, trajectory.status, trajectory)
        return self.measured(result) if measures else result

    def measured(self, result: PeriodMapResult) -> PeriodMapResult:
        """``result`` (an evaluation of this map) with its measures, read from its run.

        The same values as ``measures=True`` in `__call__` gives, without a second run: a
        continuation reads them once its corrector has converged on a run without them.
        """
        if math.isfinite(result.max_tip1):
            return result
        result = self.approach(result)
        peaks, impulses, velocities = contact_measures(self.packed, result.trajectory)
        max_tip1, max_tip2, relative = self._tip_maxima(result.trajectory)
        return dataclasses.replace(
            result, peak_force=float(np.max(peaks, initial=0.0)), peak_forces=peaks,
            impulse=float(np.sum(impulses)), max_tip1=max_tip1, max_tip2=max_tip2,
            impact_velocities=velocities[self._onsets(result.trajectory)],
            max_relative_tip1=relative)

    def approach(self, result: PeriodMapResult) -> PeriodMapResult:
        """``result`` with what a grazing is read from: the gap's minima and the least peak force.

        ``min_gap``, ``min_gap_time``, ``interval_gap`` and ``least_peak_force`` only (the
        other measures stay NaN): a continuation reads them at every corrected point, and its
        measures only at the points it keeps.
        """
        if result.approached:
            return result
        min_gap, min_gap_time = self._min_gap(result.trajectory)
        return dataclasses.replace(result, min_gap=min_gap, min_gap_time=min_gap_time,
                                   least_peak_force=self._least_peak_force(result.trajectory),
                                   approached=True,
                                   interval_gap=self._interval_gap(result.trajectory))

    def least_gap(self, result: PeriodMapResult, contact: int = 0) -> float:
        """The smallest value over the run of the gap read from the free coordinates (m).

        (``contact``: 0, the map's one.)

        In free flight it is the gap. In a contact the free coordinates leave out the
        contact force's static part: the value is the overlap times -(1 + that part's
        compliance times the stiffness), the depth the tips would reach without the contact
        (quasi-statically), so that it passes through 0 where the orbit touches with the
        slope it has on the free side (the signed grazing value, minus the overlap on the
        contact side, changes its slope there by that factor). Sampled as the gap's
        minimum (`SAMPLES_PER_PERIOD`) and refined at the root of its rate.
        """
        times = self._grid()
        gap = self._gap(result.trajectory, times)[0]
        i = min(max(int(np.argmin(gap)), 1), times.size - 2)
        lo, hi = times[i - 1], times[i + 1]
        stationary = self._stationary(result.trajectory, lo, hi, True)
        if stationary is not None and stationary[1] <= gap[i]:
            return stationary[1]
        return refined(lambda t: self._gap(result.trajectory, np.array([t]))[0][0],
                             lo, hi, gap[i], times[i])[0]

    def grazing_value(self, result: PeriodMapResult) -> float:
        """The signed grazing value (m) of an `approach`-ed ``result``; NaN if it has none.

        The smallest local minimum of the gap in free flight (> 0) or minus the overlap of the
        shallowest contact, its peak force over the contact stiffness (< 0), whichever is
        nearer 0 (`impactbeams.continuation.beams`).
        """
        candidates = [result.min_gap] if math.isfinite(result.min_gap) else []
        if result.contacts:
            candidates.append(-result.least_peak_force / self.params.contact_stiffness)
        return min(candidates, key=abs) if candidates else math.nan

    def _least_peak_force(self, trajectory: Trajectory) -> float:
        """The smallest contact phase's peak force (N); NaN without contact."""
        k = np.flatnonzero(trajectory.phase == CONTACT)
        if not k.size:
            return math.nan
        packed = self.packed
        return least_peak_force(packed.tables[CONTACT], packed.forces[CONTACT],
                                packed.phase_scalars[CONTACT], packed.settings,
                                trajectory.q[k], trajectory.v[k], trajectory.time[k],
                                trajectory.segment_end[k])

    def _interval_gap(self, trajectory: Trajectory) -> float:
        """The gap's local maximum nearest 0 between contacts (m); NaN if there is none.

        The height of a free interval between two contacts (> 0; where it reaches 0 the two
        contacts merge) or the highest interior rise of the gap within a contact (< 0; where
        it reaches 0 the contact splits in two). Within a contact the gap is read from the
        free coordinates, which leave out the contact force's static part: it is the
        overlap times -(1 + that part's compliance times the stiffness), of the same sign and
        zero where the overlap is. Each segment is sampled ``INTERVAL_SAMPLES`` times and the
        value nearest 0 refined at the root of the gap's rate.
        """
        packed = self.packed
        return interval_gap(packed.tables, packed.forces, packed.phase_scalars,
                            packed.switching, packed.settings,
                            trajectory.segments, trajectory.segment_end, self.params.omega,
                            INTERVAL_SAMPLES)

    def _stationary(self, trajectory: Trajectory, lo: float, hi: float, minimum: bool,
                    ) -> tuple[float, float] | None:
        """The gap's minimum (``minimum``) or maximum in (lo, hi): its time (s) and value (m).

        Brent's method on the gap's rate: a simple root, found to round-off in some 10
        samples of the run. None if the rate does not change sign that way between the ends.
        """
        packed = self.packed
        t, value = gap_extremum(packed.tables, packed.forces, packed.phase_scalars,
                                packed.switching, packed.settings,
                                trajectory.segments, self.params.omega, lo, hi,
                                1.0 if minimum else -1.0, 1e-14 * max(hi, 1.0))
        return None if math.isnan(t) else (t, value)

    @staticmethod
    def _onsets(trajectory: Trajectory) -> np.ndarray:
        """Which contact phases of ``trajectory`` have their onset in it.

        All but a contact under way at its start, whose onset came before.
        """
        return np.flatnonzero(trajectory.phase == CONTACT) > 0

    @one_blas_thread
    def jacobian(self, result: PeriodMapResult, directions: np.ndarray | str) -> np.ndarray:
        """dP^p/dz of an earlier evaluation ``result`` applied to more ``directions``.

        The tangent propagation along ``result``'s recorded run: no new run (a Newton-Picard
        step, or a bordered system of a continuation, asks for directions it only knows once
        it has the residual). ``directions`` as in `__call__`, not None.
        """
        require("directions", directions, directions is not None,
                "must be 'all' or an array of directions (2 N, k)")
        return self._jacobian(result.trajectory, directions_of(directions, self.dimension))

    def _jacobian(self, trajectory: Trajectory, columns: np.ndarray) -> np.ndarray:
        """dz(pT)/dz(0) @ columns by the tangent kernel on the recorded segments."""
        packed, n = self.packed, self.packed.q0.size
        rows_q = np.ascontiguousarray(columns[:n].T)
        rows_v = np.ascontiguousarray(columns[n:].T)
        rows_q, rows_v = self._switched(rows_q, rows_v, int(trajectory.phase[0]), CONTACT)
        state = Tangent(rows_q, rows_v, np.zeros(2), np.zeros((1, rows_q.shape[0])),
                        np.zeros(1, np.int64))
        carry_tangents(packed.tables, packed.phase_scalars, packed.switching,
                       packed.settings, trajectory.segments, trajectory.t_end,
                       (math.inf, self.horizon, 0, 0), state)
        rows_q, rows_v = self._switched(state.q, state.v, int(trajectory.phase[-1]), FREE)
        return np.hstack([rows_q, rows_v]).T

    def _switched(self, rows_q: np.ndarray, rows_v: np.ndarray, phase: int, to_phase: int,
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Tangent rows into ``to_phase``'s coordinates if the run is in contact there."""
        if phase != CONTACT:
            return rows_q, rows_v
        no_drive = np.zeros((len(SPRING_DRIVE_ROWS), rows_q.shape[1]), complex)
        out_q, out_v = np.empty_like(rows_q), np.empty_like(rows_v)
        contact.tangent_switch(rows_q, rows_v, to_phase, self.packed.switching,
                               no_drive, out_q, out_v)
        return out_q, out_v

    def _episodes(self, trajectory: Trajectory) -> int:
        """The impact episodes that start in [0, pT): `episode_labels`' count."""
        # on the segments' lists: a run has a few dozen, where each NumPy call costs more
        times, phases = trajectory.time.tolist(), trajectory.phase.tolist()
        onsets = [k for k, phase in enumerate(phases) if phase == CONTACT
                  and times[k] < self.horizon]
        releases = [times[k + 1] if k + 1 < len(times) else math.nan for k in onsets]
        return episode_count([times[k] for k in onsets], releases, self._separation)

    def _tip_maxima(self, trajectory: Trajectory) -> tuple[float, float, float]:
        """The largest |y1|, |y2| and |y1 - u_b1| (m): the run sampled on the grid, then refined.

        Without beam 2 (a stop) y2 is 0 throughout; with beam 1's clamp at rest y1 - u_b1 is y1.
        """
        times = self._grid()
        phase, q, v = sample(self.packed, trajectory, times, grid=True)
        tips = tips_of(self.packed, phase, times, q, v)
        relative = self._largest(trajectory, times, tips, TIP_Y1, True)
        moves1, _ = self.params.mount.clamps
        absolute = (self._largest(trajectory, times, tips, TIP_Y1, False)
                    if moves1 * self.params.base_amplitude else relative)
        beam2 = (self._largest(trajectory, times, tips, TIP_Y2, False)
                 if self.params.partner.has_beam2 else 0.0)
        return absolute, beam2, relative

    def _largest(self, trajectory: Trajectory, times: np.ndarray, tips: np.ndarray,
                 column: int, clamp: bool) -> float:
        """The largest |tip ``column``| (minus beam 1's clamp if ``clamp``) over the run (m).

        From its samples ``tips`` at ``times``: the largest refined at the root of its rate
        between the sample's neighbours (`kernels.extrema.tip_maximum`, Brent's method in one
        call), or by minimising its negative where the rate does not change sign that way there.
        """

        def size(t: float) -> float:
            at = np.array([t])
            return float(abs(self._tips(trajectory, at)[0, column]
                             - (self.clamp1(at)[0] if clamp else 0.0)))

        sampled, i, lo, hi = self.largest_sample(tips, times, column, clamp)
        packed = self.packed
        t, value = tip_maximum(packed.tables, packed.forces, packed.phase_scalars,
                               packed.switching, packed.settings,
                               trajectory.segments, column, float(clamp), lo, hi,
                               1e-14 * max(hi, 1.0))
        if not math.isnan(t):
            return max(value, float(sampled[i]))
        value, _ = refined(lambda t: -size(t), lo, hi, -sampled[i], times[i])
        return -value

    def _grid(self) -> np.ndarray:
        """``SAMPLES_PER_PERIOD`` equally spaced times a period over the run (s), read only."""
        if self._times is None:
            self._times = np.linspace(0.0, self.horizon, SAMPLES_PER_PERIOD * self.periods + 1)
        return self._times

    def _gap(self, trajectory: Trajectory, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The gap (m) at ``times`` and whether each lies in a free phase."""
        phase, q, _ = sample(self.packed, trajectory, times)
        return self._gap_of(times, q), phase == FREE

    def _gap_of(self, times: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The gap (m) of the sampled free coordinates ``q`` at ``times``."""
        scalars = self.packed.phase_scalars[FREE]
        omega_t = self.params.omega * times
        return (scalars[SCALAR_CONST] + scalars[SCALAR_SINE] * np.sin(omega_t)
                + scalars[SCALAR_COSINE] * np.cos(omega_t)
                + q @ self.packed.tables[FREE, ROW_EVENT])

    def _min_gap(self, trajectory: Trajectory) -> tuple[float, float]:
        """The smallest interior minimum of the gap in free flight, and its time (m, s).

        Sampled on the grid, refined at the root of the gap's rate between the sample's
        neighbours (`kernels.extrema.smallest_free_minimum`), or by minimising the gap where
        the rate does not change sign there. (NaN, NaN) without such a minimum.
        """
        packed = self.packed
        t, value, sample_t, sample_value, lo, hi = smallest_free_minimum(
            packed.tables, packed.forces, packed.phase_scalars,
            packed.switching, packed.settings, trajectory.segments,
            self.params.omega, self._grid())
        if math.isnan(sample_t):
            return math.nan, math.nan
        if not math.isnan(t):
            return (value, t) if value < sample_value else (sample_value, sample_t)
        return refined(lambda t: self._gap(trajectory, np.array([t]))[0][0],
                             lo, hi, sample_value, sample_t)

    def tip_motions(self, result: PeriodMapResult, times: np.ndarray) -> np.ndarray:
        """The tips' motion (``kernels.layout`` TIP_* columns) of ``result``'s run at ``times``."""
        return self._tips(result.trajectory, np.asarray(times, dtype=float))

    def _tips(self, trajectory: Trajectory, times: np.ndarray) -> np.ndarray:
        return tips_at(self.packed, trajectory, times)

def refined(function: Callable[[float], float], lo: float, hi: float, best: float,
            best_t: float) -> tuple[float, float]:
    """The minimum of ``function`` on [lo, hi] by Brent's method, or the sample if lower."""
    result = minimize_scalar(function, bounds=(lo, hi), method="bounded",
                             options={"xatol": 1e-14 * max(hi, 1.0)})
    if result.fun < best:
        return float(result.fun), float(result.x)
    return best, best_t


# the cell's parameters (`packing.cell_rows`) that the geometry's arrays do not depend on; the
# damping ratio is one too, but the spring law's contact modes are solved for it
CELL_ONLY = ("clearance", "force_amplitude", "omega", "uplift1", "uplift2", "base_amplitude")
GEOMETRIES = 4  # geometries whose arrays are kept


def geometry_arrays(params: Params, n_modes: int) -> Dynamics:
    """`packing.dynamics_arrays` of ``params``, reused while only the cell's parameters change.

    Along a branch in Omega, F0, U0 or the clearance the modes and the spring law's contact
    phase (an eigenproblem, the larger part of building a map at 32 modes) stay the same. The
    arrays are built with the cell's parameters at their defaults and found again by the
    other parameters' values (a continuation asks for a map at every corrector iterate: a
    `Params` copy per look-up cost more than the run at 16 modes).
    """
    key = (n_modes, *(value for name, value in params.as_dict().items()
                      if name not in CELL_ONLY))
    dynamics = _GEOMETRY_CACHE.pop(key, None)
    if dynamics is None:
        dynamics = dynamics_arrays(params.replace(**_cell_defaults()), n_modes)
        if len(_GEOMETRY_CACHE) >= GEOMETRIES:
            _GEOMETRY_CACHE.pop(next(iter(_GEOMETRY_CACHE)))
    _GEOMETRY_CACHE[key] = dynamics  # last used last
    return dataclasses.replace(dynamics, params=params)


_GEOMETRY_CACHE: dict[tuple, Dynamics] = {}


@functools.cache
def _cell_defaults() -> dict[str, float]:
    """The default values of the cell's parameters (``CELL_ONLY``)."""
    defaults = Params()
    return {name: getattr(defaults, name) for name in CELL_ONLY}


def directions_of(directions: np.ndarray | str | None, dimension: int) -> np.ndarray | None:
    """A period map's ``directions`` checked, as columns (``dimension``, k); None stays None."""
    if directions is None:
        return None
    if isinstance(directions, str):
        require("directions", directions, directions == "all",
                "must be None, 'all' or an array of directions (2 N, k)")
        return np.eye(dimension)
    array = np.asarray(directions, dtype=float)
    if array.ndim == 1:
        array = array[:, None]
    require("directions", array.shape, array.ndim == 2 and array.shape[0] == dimension
            and array.shape[1] >= 1 and bool(np.all(np.isfinite(array))),
            f"must be a finite array of shape ({dimension}, k), k >= 1")
    return array


def check_law(params: Params) -> None:
    """Raise ParameterError unless the law has tangent dynamics (the spring law)."""
    if not params.law.tangent_flow:
        raise ParameterError("periodic orbits need the spring contact law: the tied law's "
                             "projections, instantaneous impacts and accumulations are not a "
                             "flow whose linearisation converges in n_modes (docs/model.md)")
