"""Basins of attraction: which attractor the run from each initial state settles on.

At fixed parameters, every initial state is a section state z = (q, q') at t = 0, forcing
phase 0 (`impactbeams.trajectory.start`). By default they fill a plane of beam 1's first free
mode, shown as the tip deflection y (m) and tip velocity v (m/s) it gives: q_1 = y / Y_1(l1),
q_1' = v / Y_1(l1) added to the rest state (the state `start = "rest"` starts from: no
deflection, no velocity in the absolute frame), every other coordinate at rest. ``coordinates
= (i, j)`` spans the plane of z[i] and z[j] instead (modal units), and ``initial_states``
takes any states. `basin_stability` draws random states in a box of the plane.

Each cell runs until its stroboscopic samples settle (`impactbeams.orbits.basin_cells`) and is
labelled by the attractor they settle on: its period, its contacts per orbit and its samples,
matched within ``Settling.match_tolerance`` against the orbits given (``attractors``, e.g.
`impactbeams.periodic_orbit`'s) and then those found, in the order of the cells. Each found
attractor is run on from its first cell until it repeats to ``Settling.state_tolerance``: its
state, its tip amplitude and (spring law) its Floquet multipliers, from the period map's exact
Jacobian, describe it.

With several contacts the cells run on the active sets' phases, cell by cell
(`impactbeams.orbits.basin_contacts`), labelled and described the same way.

Cells run in chunks, in parallel threads (the kernels release the GIL) or one Dask task each
(``client``); with an ``output`` file each finished chunk is saved under ``OUT.nc.partial/`` at
once, so an interrupted run loses no finished chunk and the same call resumes it.

Basin fractions: the share f of the n initial states on each attractor, its standard error
sqrt(f (1 - f) / n) and the Wilson score interval at ``CONFIDENCE``: the sampling error of
random states (`basin_stability`); for a grid they are a guide only, refining it is the check.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import hashlib
import json
import math
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from impactbeams.io import write_netcdf, write_npz, write_text, writing
from impactbeams.kernels.layout import TIP_Y1
from impactbeams.lock import output_lock
from impactbeams.orbits.basin_cells import (
    STOPPED,
    CellRunner,
    Cells,
    Settling,
    distance,
    periodic,
)
from impactbeams.orbits.contacts_map import make_period_map
from impactbeams.packing import Packed, pack_run
from impactbeams.params import (
    MAX_MODES,
    ParameterError,
    Params,
    is_integer,
    is_path,
    require,
    require_integer,
    require_type,
)
from impactbeams.progress import Progress
from impactbeams.trajectory.phases import Trajectory
from impactbeams.trajectory.start import checked_state
from impactbeams.variables import (
    BASIN_LABELS,
    attributes,
    global_attributes,
    validate,
)

if TYPE_CHECKING:
    import xarray as xr
    from distributed import Client

    from impactbeams.orbits.shooting import PeriodicOrbit

CONFIDENCE = 0.95  # of the basin fractions' Wilson intervals
DEFAULT_CHUNK_CELLS = 16
AMPLITUDE_SAMPLES = 256  # per forcing period, for an attractor's tip amplitude
TIP_PLANE = ("start_tip_deflection", "start_tip_velocity")
RECORD = "run.json"
# what computes a basin map beyond a sweep's numeric code: a change makes saved chunks stale
BASIN_CODE = ("orbits/basin_cells.py", "orbits/basin_contacts.py", "orbits/contacts_map.py",
              "active_phases.py", "trajectory/phases.py", "trajectory/start.py", "longtime.py")


@dataclasses.dataclass(frozen=True)
class Attractor:
    """One attractor: period p, contacts per orbit, its p samples x (p, 4) and where it is.

    ``start``: the state (q, q', phase; several contacts: the closed ones' bit mask) of a run
    on it, on the section; ``given``: a caller's
    orbit. After `describe`: ``state`` (free z), ``amplitude`` (m), ``multipliers``,
    ``residual`` (the samples' relative change over the last period run).
    """

    period: int
    contacts: int
    samples: np.ndarray
    start: tuple[np.ndarray, np.ndarray, int]
    given: bool
    state: np.ndarray | None = None
    amplitude: float = math.nan
    multipliers: np.ndarray | None = None
    residual: float = math.nan

    def same(self, period: int, contacts: int, samples: np.ndarray, tolerance: float) -> bool:
        """Whether a settled run (period, contacts, samples) is on this attractor."""
        return (period == self.period and contacts == self.contacts
                and distance(samples, self.samples) <= tolerance)


def basins(params: Params, axes: tuple[ArrayLike, ArrayLike] | None = None, *,
           coordinates: tuple[int, int] | None = None, initial_states: ArrayLike | None = None,
           n_modes: int | None = None, attractors: Sequence[PeriodicOrbit] = (),
           settling: Settling | None = None, output: str | Path | None = None,
           chunk_cells: int | None = None, workers: int | None = None,
           progress: bool = False, client: Client | None = None) -> xr.Dataset:
    """The basins of attraction of ``params`` over a plane of initial states (module doc).

    Args:
        params: the model, omega > 0, ``start = "rest"`` and no uplifts (the states replace
            them).
        axes: the plane's two axes, 1-D arrays: the tip deflection (m) and tip velocity (m/s)
            of beam 1's first free mode, or with ``coordinates`` the values of z[i] and z[j]
            (kg^1/2 m^1/2 for a displacement, kg^1/2 m^1/2 / s for a velocity) added to the
            rest state. Not with ``initial_states``.
        coordinates: (i, j), indices into z = (q, q') of 2 N values; None: the tip plane.
        initial_states: an array (cells, 2 N) of section states instead of a plane.
        n_modes: modes per beam (default: as `simulate`'s, the number that resolves a spring
            contact, else 5).
        attractors: periodic orbits of ``params`` with ``n_modes`` (`periodic_orbit`'s), the
            first labels; others found are added after them.
        settling: when a cell has settled, and when two share an attractor (`Settling`).
        output: a netCDF file written when complete; chunks are kept for a resume meanwhile.
        chunk_cells: cells per chunk (default 16).
        workers: threads running chunks (default: Numba's thread count).
        progress: a progress bar on stderr.
        client: a ``dask.distributed`` Client: each chunk one task on its cluster (the model
            packed on the worker, the same bits), instead of threads here.

    Returns the Dataset: ``basin`` (the label of each cell: an index along ``attractor``, or
    -1 not settled, -2 stopped), ``settle_periods``, the attractors' table and the basin
    fractions (see `impactbeams.variables`).
    """
    setup = _Setup.checked(params, n_modes, settling, attractors, chunk_cells, workers, output,
                           progress, client)
    if initial_states is not None:
        require("axes", axes, axes is None, "leave it None with initial_states")
        require("coordinates", coordinates, coordinates is None,
                "leave it None with initial_states (they are whole states)")
        states = _rows(initial_states, setup.dimension)
        return setup.run(states, _cell_coords(states, {}), "list of initial states")
    require("axes", axes, axes is not None, "give the plane's two axes, or initial_states")
    plane = Plane.checked(setup, coordinates)
    first, second = (_axis(name, values) for name, values in zip(plane.names, axes, strict=True)
                     ) if _pair(axes) else _refuse_axes(axes)
    a, b = np.meshgrid(first, second, indexing="ij")
    states = plane.states(a.ravel(), b.ravel())
    coords = {name: (name, values, plane.attributes(k))
              for k, (name, values) in enumerate(zip(plane.names, (first, second),
                                                     strict=True))}
    return setup.run(states, coords, f"plane {plane.names[0]} x {plane.names[1]}",
                     shape=(first.size, second.size))


def basin_stability(params: Params, samples: int, box: tuple[tuple[float, float],
                                                               tuple[float, float]], *,
                    coordinates: tuple[int, int] | None = None, seed: int = 0,
                    n_modes: int | None = None, attractors: Sequence[PeriodicOrbit] = (),
                    settling: Settling | None = None, output: str | Path | None = None,
                    chunk_cells: int | None = None, workers: int | None = None,
                    progress: bool = False, client: Client | None = None) -> xr.Dataset:
    """Basin stability: the basins of ``samples`` random initial states in a box of the plane.

    ``box``: ((low, high), (low, high)) of the plane's two axes (as `basins`' ``axes``),
    sampled uniformly with NumPy's default generator from ``seed``. The fractions'
    ``basin_fraction_low`` / ``_high`` are Wilson score intervals at ``CONFIDENCE``; the
    Dataset is along ``cell``, with each state's plane values and whole state. Other
    arguments as `basins`'.
    """
    samples = require_integer("samples", samples, 1)
    require_type("seed", seed, is_integer(seed) and seed >= 0, "an integer >= 0")
    setup = _Setup.checked(params, n_modes, settling, attractors, chunk_cells, workers, output,
                           progress, client)
    plane = Plane.checked(setup, coordinates)
    bounds = _box(box, plane.names)
    rng = np.random.default_rng(int(seed))
    a, b = (rng.uniform(low, high, samples) for low, high in bounds)
    states = plane.states(a, b)
    drawn = {name: ("cell", values, plane.attributes(k))
             for k, (name, values) in enumerate(zip(plane.names, (a, b), strict=True))}
    return setup.run(states, _cell_coords(states, drawn),
                     f"{samples} random states in {plane.names[0]} {bounds[0]} x "
                     f"{plane.names[1]} {bounds[1]} (seed {seed})")


@dataclasses.dataclass(frozen=True)
class Plane:
    """The plane of initial states: z = rest + a e_i + b e_j (``coordinates`` (i, j)).

    The tip plane (``coordinates`` None): i, j are beam 1's first mode's q and q', and a, b
    the tip deflection (m) and velocity (m/s), divided by that mode's tip value Y_1(l1).
    """

    rest: np.ndarray
    coordinates: tuple[int, int] | None
    tip: float  # Y_1(l1), per unit of q_1

    @classmethod
    def checked(cls, setup: _Setup, coordinates: object) -> Plane:
        """The plane of ``setup``'s model; ParameterError for bad ``coordinates``."""
        n, tip = setup.dimension // 2, float(setup.packed.dynamics.free.tip1[0])
        if coordinates is not None:
            valid = (isinstance(coordinates, (tuple, list)) and len(coordinates) == 2
                     and all(is_integer(c) and 0 <= c < 2 * n for c in coordinates)
                     and coordinates[0] != coordinates[1])
            require("coordinates", coordinates, valid,
                    f"must be two different indices from 0 to {2 * n - 1} into z = (q, q')")
            coordinates = (int(coordinates[0]), int(coordinates[1]))
        return cls(setup.rest, coordinates, tip)

    @property
    def indices(self) -> tuple[int, int]:
        """(i, j): the coordinates of z the plane moves."""
        return self.coordinates or (0, self.rest.size // 2)

    @property
    def names(self) -> tuple[str, str]:
        """The axes' names: ``start_tip_deflection``, ``..._velocity`` or ``start_z{i}``."""
        if self.coordinates is None:
            return TIP_PLANE
        return f"start_z{self.coordinates[0]}", f"start_z{self.coordinates[1]}"

    def attributes(self, k: int) -> dict[str, str]:
        """The CF attributes of axis k."""
        if self.coordinates is None:
            return attributes(TIP_PLANE[k])
        index, n = self.coordinates[k], self.rest.size // 2
        kind = "displacement q" if index < n else "velocity dq/dt"
        return {"units": "kg^1/2 m^1/2" + ("" if index < n else " s-1"),
                "long_name": f"initial free modal {kind} of coordinate {index % n}",
                "description": f"z[{index}] at t = 0 added to the rest state, every other "
                               "coordinate at rest"}

    def states(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The section states (cells, 2 N) of the plane's points (a, b)."""
        scale = 1.0 if self.coordinates is not None else 1.0 / self.tip
        states = np.repeat(self.rest[None, :], a.size, axis=0)
        i, j = self.indices
        states[:, i] += scale * a
        states[:, j] += scale * b
        return states


@dataclasses.dataclass
class _Setup:
    """What every basin run checks first, and runs the cells with."""

    params: Params
    n_modes: int
    settling: Settling
    given: list[PeriodicOrbit]
    chunk_cells: int
    workers: int
    output: Path | None
    progress: bool
    runner: CellRunner
    client: Client | None = None

    @classmethod
    def checked(cls, params: object, n_modes: object, settling: object, attractors: object,
                chunk_cells: object, workers: object, output: object,
                progress: object, client: object = None) -> _Setup:
        """Every common argument checked, one line each (ParameterError), before any run."""
        require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
        require("omega", params.omega, params.omega > 0,
                "basins are of the forced response: omega > 0", "rad/s")
        require("start", params.start, params.start == "rest",
                "the initial states replace params.start: leave it 'rest'")
        for uplift in ("uplift1", "uplift2"):
            require(uplift, getattr(params, uplift), getattr(params, uplift) == 0.0,
                    "the initial states replace the uplifts: leave it 0", "m")
        n_modes = require_integer("n_modes", default_modes(params) if n_modes is None
                                  else n_modes, 1, MAX_MODES)
        settling = Settling() if settling is None else settling
        require_type("settling", settling, isinstance(settling, Settling),
                     "None or an impactbeams.orbits.Settling")
        require("block_periods", settling.block_periods,
                settling.block_periods >= settling.max_period,
                f"must be at least max_period = {settling.max_period}")
        chunk_cells = require_integer("chunk_cells", DEFAULT_CHUNK_CELLS if chunk_cells is None
                                      else chunk_cells, 1)
        workers = require_integer("workers", _threads() if workers is None else workers, 1)
        require_type("output", output, output is None or is_path(output),
                     "None or the path of a netCDF file (str or pathlib.Path)")
        require_type("progress", progress, isinstance(progress, bool), "True or False")
        if client is not None:
            from impactbeams.sweep.dask_runner import require_dask

            require_type("client", client, isinstance(client, require_dask().Client),
                         "None or a dask.distributed Client")
        runner = cell_runner(params, n_modes, settling)
        given = _given(attractors, params, n_modes, settling)
        return cls(params, n_modes, settling, given, chunk_cells, workers,
                   None if output is None else Path(output), progress, runner, client)

    @property
    def packed(self) -> Packed:
        """The run of one block (several contacts: the first contact's, their free phase)."""
        return self.runner.packed

    @property
    def dimension(self) -> int:
        return 2 * self.packed.q0.size

    @property
    def rest(self) -> np.ndarray:
        return np.concatenate([self.packed.q0, self.packed.v0])

    def run(self, states: np.ndarray, coords: dict, plane: str,
            shape: tuple[int, ...] | None = None) -> xr.Dataset:
        """The cells of ``states`` run, labelled and described; written to ``output``."""
        shape = (states.shape[0],) if shape is None else shape
        for z in states:  # finite, and within the small-deflection limit: before any run
            checked_state(self.packed, z)
        identity = self._identity(states)
        if self.output is None:
            cells = self._cells(states, None)
            return self._dataset(states, cells, coords, shape, plane, identity)
        with output_lock(self.output):
            finished = _finished(self.output, identity)
            if finished is not None:
                return finished
            store = _ChunkStore(self.output, identity, self.chunk_cells)
            cells = self._cells(states, store)
            dataset = self._dataset(states, cells, coords, shape, plane, identity)
            write_netcdf(dataset, self.output)
            store.remove()
        return dataset

    def _identity(self, states: np.ndarray) -> dict[str, str]:
        """The run's fingerprint (model, states, settling, given orbits) and code digest."""
        from impactbeams.sweep.plan import NUMERIC_CODE, code_digest

        digest = hashlib.sha256(json.dumps(
            {"params": self.params.as_dict(), "n_modes": self.n_modes,
             "settling": dataclasses.asdict(self.settling)}, sort_keys=True,
            default=str).encode())
        digest.update(np.ascontiguousarray(states).tobytes())
        for orbit in self.given:
            digest.update(np.ascontiguousarray(orbit.state).tobytes())
        return {"basin_fingerprint": digest.hexdigest()[:16],
                "code_digest": code_digest(patterns=(*NUMERIC_CODE, *BASIN_CODE))}

    def _cells(self, states: np.ndarray, store: _ChunkStore | None) -> Cells:
        """Every cell settled, chunk by chunk (the saved ones loaded)."""
        bounds = [(start, min(start + self.chunk_cells, states.shape[0]))
                  for start in range(0, states.shape[0], self.chunk_cells)]
        bar = Progress(states.shape[0], enabled=self.progress)
        done: dict[int, Cells] = {}
        for chunk, (start, stop) in enumerate(bounds):
            saved = None if store is None else store.load(chunk, stop - start)
            if saved is not None:
                done[chunk] = saved
                bar.update(stop - start, computed=False)
        pending = {chunk: states[slice(*bounds[chunk])] for chunk in range(len(bounds))
                   if chunk not in done}
        run = (_on_threads(self.runner, pending, self.workers) if self.client is None else
               _on_cluster(self, pending))
        with contextlib.closing(run):  # an error or an interrupt: the pending ones cancelled
            for chunk, cells in run:
                done[chunk] = cells
                if store is not None:  # saved at once: an interrupt after it loses nothing
                    store.save(chunk, cells)
                bar.update(bounds[chunk][1] - bounds[chunk][0])
        return Cells(*(np.concatenate([getattr(done[chunk], field.name)
                                       for chunk in range(len(bounds))])
                       for field in dataclasses.fields(Cells)))

    def _dataset(self, states: np.ndarray, cells: Cells, coords: dict,
                 shape: tuple[int, ...], plane: str, identity: dict[str, str]) -> xr.Dataset:
        """Label the cells, describe the attractors, and the Dataset of it all."""
        runner = self.runner
        known = [_given_attractor(runner, orbit) for orbit in self.given]
        labels = _labels(cells, known, self.settling.match_tolerance)
        known = [attractor if attractor.given else _described(runner, attractor, self)
                 for attractor in known]
        labels, known = _merged(labels, known, self.settling.match_tolerance)
        _resettled(runner, states, cells, labels, known)
        return _basin_dataset(self, states, cells, labels, known, coords, shape, plane,
                              identity)


def _on_threads(runner: CellRunner, pending: dict[int, np.ndarray],
                workers: int) -> Iterator[tuple[int, Cells]]:
    """Each pending chunk's cells, run on ``workers`` threads, as they finish."""
    pool = concurrent.futures.ThreadPoolExecutor(workers)
    try:
        futures = {pool.submit(runner.run_cells, states): chunk
                   for chunk, states in pending.items()}
        for future in concurrent.futures.as_completed(futures):
            yield futures[future], future.result()
    finally:  # the chunks not started are not run
        pool.shutdown(wait=True, cancel_futures=True)


def _on_cluster(setup: _Setup, pending: dict[int, np.ndarray]) -> Iterator[tuple[int, Cells]]:
    """Each pending chunk's cells, one Dask task each, as they finish."""
    from distributed import as_completed

    futures = {setup.client.submit(run_chunk, setup.params, setup.n_modes, setup.settling,
                                   states, pure=False): chunk
               for chunk, states in pending.items()}
    try:
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        setup.client.cancel(list(futures))


def run_chunk(params: Params, n_modes: int, settling: Settling, states: np.ndarray) -> Cells:
    """A chunk's cells on a Dask worker: the model packed there, as `basins` packs it."""
    return cell_runner(params, n_modes, settling).run_cells(states)


def cell_runner(params: Params, n_modes: int, settling: Settling) -> CellRunner:
    """The runner of cells: of one block of ``settling.block_periods`` forcing periods.

    One contact: the packed run and one kernel call a chunk (`CellRunner`); several: the
    active sets' phases, cell by cell (`impactbeams.orbits.basin_contacts`).
    """
    if params.several_contacts:
        from impactbeams.orbits.basin_contacts import ContactCellRunner

        return ContactCellRunner(params, n_modes, settling)
    horizon = settling.block_periods * (2.0 * math.pi / params.omega)  # the last sample
    return CellRunner(pack_run(params, n_modes, horizon, horizon), settling)


def default_modes(params: Params) -> int:
    """The modes per beam of a basin map when none is given: the most any contact's run needs.

    As `impactbeams.simulate`'s (one contact: `impactbeams.contact.recommended_modes`).
    """
    from impactbeams.contact.spring import recommended_modes

    return max(recommended_modes(run) for run in params.each_contact())


def _threads() -> int:
    import numba

    return numba.get_num_threads()


def _given(attractors: object, params: Params, n_modes: int,
           settling: Settling) -> list[PeriodicOrbit]:
    """The caller's orbits, checked: of ``params`` with ``n_modes``, periods in range."""
    from impactbeams.orbits.shooting import PeriodicOrbit

    require_type("attractors", attractors, isinstance(attractors, (list, tuple)) and all(
        isinstance(orbit, PeriodicOrbit) for orbit in attractors),
        "a list of impactbeams.orbits.PeriodicOrbit (periodic_orbit's)")
    for k, orbit in enumerate(attractors):
        require(f"attractors[{k}]", "an orbit of other parameters", orbit.params == params
                and orbit.n_modes == n_modes, f"must be an orbit of these params with n_modes "
                f"= {n_modes} (it has n_modes = {orbit.n_modes})")
        require(f"attractors[{k}].period", orbit.period, orbit.period <= settling.max_period,
                f"must be at most settling.max_period = {settling.max_period}")
    return list(attractors)


def _given_attractor(runner: CellRunner, orbit: PeriodicOrbit) -> Attractor:
    """A given orbit's attractor: one block from its state gives its samples and contacts."""
    start = runner.start(orbit.state)
    result = None if start is None else runner.block(start)
    if result is None:
        raise ParameterError("attractors: a given orbit's run from its state stopped early")
    trajectory, x, _, _ = result
    order = np.argsort(-np.abs(orbit.multipliers), kind="stable")
    return Attractor(orbit.period, runner.contacts(trajectory, orbit.period),
                     x[-orbit.period:], start, True, orbit.state,
                     _amplitude(runner, trajectory, orbit.period), orbit.multipliers[order],
                     float(orbit.residual))


def _amplitude(runner: CellRunner, trajectory: Trajectory, period: int) -> float:
    """Max |y1| (m) over the last ``period`` forcing periods of a block, densely sampled."""
    t_end = runner.times[-1]
    times = np.linspace(t_end - period * runner.forcing_period, t_end,
                        AMPLITUDE_SAMPLES * period + 1)
    return float(np.abs(runner.tips(trajectory, times)[:, TIP_Y1]).max())


def _labels(cells: Cells, known: list[Attractor], tolerance: float) -> np.ndarray:
    """Each cell's attractor (appending the new ones to ``known``) or its status code."""
    labels = np.where(cells.status != 0, cells.status, 0).astype(np.int32)
    for i in np.flatnonzero(cells.status == 0):
        p, contacts = int(cells.period[i]), int(cells.contacts[i])
        x = cells.samples[i, :p]
        match = next((k for k, attractor in enumerate(known)
                      if attractor.same(p, contacts, x, tolerance)), None)
        if match is None:
            start = (cells.end_q[i], cells.end_v[i], int(cells.end_phase[i]))
            known.append(Attractor(p, contacts, x, start, False))
            match = len(known) - 1
        labels[i] = match
    return labels


def _described(runner: CellRunner, attractor: Attractor, setup: _Setup) -> Attractor:
    """A found attractor run on until it repeats to ``state_tolerance``; its description."""
    s, p = setup.settling, attractor.period
    start, residual, run = attractor.start, math.inf, 0
    while residual > s.state_tolerance and run < s.max_periods:
        result = runner.block(start)
        if result is None:
            break
        trajectory, x, start, z = result
        run += s.block_periods
        step = np.abs(x[p:] - x[:-p]).max(axis=-1)
        residual = float(step[-1] / np.abs(x).max())
    if result is None:  # kept as first seen: the run on stopped (an event limit)
        return attractor
    # the smallest period of the converged samples: a slow transient can repeat after several
    # periods within the settling tolerance (the free modes' phase advance per period near a
    # whole turn), and a cell then settles on a multiple of the attractor's true period
    p = periodic(x[-s.window:], s) or p
    residual = float(np.abs(x[p:] - x[:-p]).max(axis=-1)[-1] / np.abs(x).max())
    return dataclasses.replace(attractor, period=p, contacts=runner.contacts(trajectory, p),
                               samples=x[-p:], start=start, state=z,
                               amplitude=_amplitude(runner, trajectory, p), residual=residual,
                               multipliers=_multipliers(setup, z, p))


def _resettled(runner: CellRunner, states: np.ndarray, cells: Cells, labels: np.ndarray,
               known: list[Attractor]) -> None:
    """The settle periods of cells that settled on a multiple of their attractor's period.

    A slow transient can repeat after a few periods within the tolerance sooner than after
    one: such cells run again, testing their attractor's period alone, so that
    ``settle_periods`` counts the periods until the samples repeat with the attractor's.
    """
    periods = np.array([attractor.period for attractor in known], dtype=np.int32)
    settled = np.flatnonzero(labels >= 0)
    again = settled[cells.period[settled] != periods[labels[settled]]]
    if again.size:
        redone = runner.run_cells(states[again], periods[labels[again]])
        cells.settle_periods[again] = redone.settle_periods


def _multipliers(setup: _Setup, z: np.ndarray, period: int) -> np.ndarray | None:
    """The Floquet multipliers at z (by decreasing modulus); None without a tangent flow."""
    if not setup.params.law.tangent_flow or not np.all(np.isfinite(z)):
        return None
    period_map = make_period_map(setup.params, setup.n_modes, period)
    mu = np.linalg.eigvals(period_map(z, directions="all", measures=False).jacobian)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _merged(labels: np.ndarray, known: list[Attractor],
            tolerance: float) -> tuple[np.ndarray, list[Attractor]]:
    """Found attractors that turn out the same once run on (a cell settled slowly) merged."""
    kept: list[Attractor] = []
    mapping = np.arange(len(known))
    for k, attractor in enumerate(known):
        same = next((m for m, other in enumerate(kept) if other.same(
            attractor.period, attractor.contacts, attractor.samples, tolerance)), None)
        if same is None or attractor.given:
            kept.append(attractor)
            same = len(kept) - 1
        mapping[k] = same
    merged = labels.copy()
    merged[labels >= 0] = mapping[labels[labels >= 0]]
    return merged, kept


def _rows(states: ArrayLike, dimension: int) -> np.ndarray:
    """``initial_states`` as rows of 2 N numbers (checked one by one afterwards)."""
    try:
        array = np.asarray(states, dtype=float)
    except (TypeError, ValueError):
        array = np.empty((0, 0))
    require("initial_states", f"{states!r:.60}", array.ndim == 2
            and array.shape[0] >= 1 and array.shape[1] == dimension,
            f"must be an array (cells, {dimension}) of section states z = (q, q')")
    return array


def _pair(axes: object) -> bool:
    return isinstance(axes, (tuple, list)) and len(axes) == 2


def _refuse_axes(axes: object) -> tuple[np.ndarray, np.ndarray]:
    raise ParameterError(f"axes = {axes!r:.60} is not allowed: must be a pair of 1-D arrays "
                         "(the plane's two axes)")


def _axis(name: str, values: ArrayLike) -> np.ndarray:
    """One axis of the plane: at least one finite number, strictly increasing."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        array = np.array([np.nan])
    require(name, f"{values!r:.60}", array.ndim == 1 and array.size >= 1
            and bool(np.all(np.isfinite(array))) and bool(np.all(np.diff(array) > 0)),
            "must be a 1-D array of finite, strictly increasing values")
    return array


def _box(box: object, names: tuple[str, str]) -> tuple[tuple[float, float], ...]:
    """The sampled box ((low, high), (low, high)), each finite with low < high."""
    valid = _pair(box) and all(_pair(side) for side in box)
    require("box", f"{box!r:.60}", valid, f"must be ((low, high), (low, high)) of {names[0]} "
            f"and {names[1]}")
    bounds = []
    for name, (low, high) in zip(names, box, strict=True):
        ok = all(isinstance(v, (int, float)) and math.isfinite(v) for v in (low, high))
        require(f"box of {name}", (low, high), ok and low < high,
                "must be finite numbers with low < high")
        bounds.append((float(low), float(high)))
    return tuple(bounds)


def _cell_coords(states: np.ndarray, drawn: dict) -> dict:
    """The coordinates of a list of states: ``cell`` and the plane's values if drawn in one."""
    return {"cell": ("cell", np.arange(states.shape[0], dtype=np.int64), attributes("cell")),
            **drawn}


def wilson(count: np.ndarray, total: int, confidence: float = CONFIDENCE,
           ) -> tuple[np.ndarray, np.ndarray]:
    """The Wilson score interval of a binomial proportion, count successes in ``total``."""
    from scipy.stats import norm

    z = float(norm.ppf(0.5 + confidence / 2.0))
    f = np.asarray(count, dtype=float) / total
    centre = (f + z * z / (2 * total)) / (1 + z * z / total)
    half = z / (1 + z * z / total) * np.sqrt(f * (1 - f) / total + z * z / (4 * total**2))
    return centre - half, centre + half


def _basin_dataset(setup: _Setup, states: np.ndarray, cells: Cells, labels: np.ndarray,
                   known: list[Attractor], coords: dict, shape: tuple[int, ...], plane: str,
                   identity: dict[str, str]) -> xr.Dataset:
    """The labels, settle periods, attractors' table and fractions as a Dataset."""
    import xarray as xr

    s, n, total = setup.settling, setup.dimension // 2, labels.size
    dims = tuple(coords) if "cell" not in coords else ("cell",)
    data = {"basin": (dims, labels.reshape(shape), attributes("basin")),
            "settle_periods": (dims, cells.settle_periods.reshape(shape),
                               attributes("settle_periods")),
            # each state whole: simulate(params, ..., initial_state=...) of a cell reruns it
            "start_displacement": ((*dims, "coordinate"), states[:, :n].reshape(*shape, n),
                                   attributes("start_displacement")),
            "start_velocity": ((*dims, "coordinate"), states[:, n:].reshape(*shape, n),
                               attributes("start_velocity"))}
    count = np.array([np.count_nonzero(labels == k) for k in range(len(known))])
    fraction = count / total
    low, high = wilson(count, total)
    sections = np.full((len(known), s.max_period, 2), np.nan)
    multipliers = np.full((len(known), 2 * n), np.nan + 0j)
    state = np.full((len(known), 2 * n), np.nan)
    for k, attractor in enumerate(known):
        sections[k, :attractor.period] = attractor.samples[:, [0, 2]]
        if attractor.multipliers is not None:
            multipliers[k, :attractor.multipliers.size] = attractor.multipliers
        if attractor.state is not None:
            state[k] = attractor.state
    sections[..., 1] *= setup.params.omega
    table = {
        "attractor_period": [a.period for a in known],
        "attractor_contacts": [a.contacts for a in known],
        "attractor_amplitude": [a.amplitude for a in known],
        "attractor_given": [int(a.given) for a in known],
        "attractor_residual": [a.residual for a in known],
        "basin_fraction": fraction, "basin_fraction_error": np.sqrt(fraction * (1 - fraction)
                                                                    / total),
        "basin_fraction_low": low, "basin_fraction_high": high}
    for name, values in table.items():
        dtype = np.dtype(_dtype(name))
        data[name] = ("attractor", np.asarray(values, dtype).reshape(len(known)),
                      attributes(name))
    data.update({
        "attractor_displacement": (("attractor", "coordinate"), state[:, :n],
                                   attributes("attractor_displacement")),
        "attractor_velocity": (("attractor", "coordinate"), state[:, n:],
                               attributes("attractor_velocity")),
        "attractor_section_deflection1": (("attractor", "section"), sections[..., 0],
                                          attributes("attractor_section_deflection1")),
        "attractor_section_velocity1": (("attractor", "section"), sections[..., 1],
                                        attributes("attractor_section_velocity1")),
        "attractor_multiplier_real": (("attractor", "multiplier"), multipliers.real,
                                      attributes("attractor_multiplier_real")),
        "attractor_multiplier_imag": (("attractor", "multiplier"), multipliers.imag,
                                      attributes("attractor_multiplier_imag")),
    })
    all_coords = {
        **coords,
        "attractor": ("attractor", np.arange(len(known), dtype=np.int64),
                      attributes("attractor")),
        "coordinate": ("coordinate", np.arange(n, dtype=np.int64), attributes("coordinate")),
        "section": ("section", np.arange(s.max_period, dtype=np.int64), attributes("section")),
        "multiplier": ("multiplier", np.arange(2 * n, dtype=np.int64), attributes("multiplier")),
    }
    run = {f"settle_{key}" if key in ("tolerance", "window") else key: value
           for key, value in dataclasses.asdict(s).items()}
    outcome = {f"{name}_fraction": float(np.count_nonzero(labels == code) / total)
               for code, name in BASIN_LABELS.items()}
    dataset = xr.Dataset(data, coords=all_coords, attrs=global_attributes(
        "Basins of attraction", f"basins over a {plane}", setup.params.as_dict(),
        n_modes=setup.n_modes, basin_initial_states=plane, basin_confidence=CONFIDENCE,
        cells=total, **run, **outcome, **identity))
    validate(dataset)
    return dataset


def _dtype(name: str) -> str:
    from impactbeams.variables import VARIABLES

    return VARIABLES[name].dtype


class _ChunkStore:
    """Finished chunks of one basin run, one ``.npz`` each, under ``OUT.nc.partial/``."""

    def __init__(self, output: Path, identity: dict[str, str], chunk_cells: int) -> None:
        self.directory = output.with_name(output.name + ".partial")
        record = self.directory / RECORD
        wanted = {**identity, "chunk_cells": chunk_cells}
        if record.exists():
            try:
                saved = json.loads(record.read_text())
            except (OSError, ValueError):
                saved = None
            if saved != wanted:
                raise ParameterError(f"{self.directory} holds a partial run of other basins, "
                                     "code or chunk_cells: delete it or choose another output")
            return
        with writing(self.directory):
            self.directory.mkdir(parents=True, exist_ok=True)
        write_text(record, json.dumps(wanted))

    def _path(self, chunk: int) -> Path:
        return self.directory / f"chunk_{chunk:06d}.npz"

    def load(self, chunk: int, size: int) -> Cells | None:
        """The saved cells of ``chunk``, None if not saved; a damaged file is an error."""
        path = self._path(chunk)
        if not path.exists():
            return None
        try:
            with np.load(path) as archive:
                cells = Cells(*(archive[field.name] for field in dataclasses.fields(Cells)))
        except (OSError, ValueError, KeyError, EOFError) as error:
            raise ParameterError(f"saved chunk {path} is damaged ({type(error).__name__}): "
                                 f"delete it to compute its cells again") from None
        if cells.period.shape != (size,):
            raise ParameterError(f"saved chunk {path} holds {cells.period.shape[0]} cells, not "
                                 f"{size}: delete {self.directory}")
        return cells

    def save(self, chunk: int, cells: Cells) -> None:
        write_npz(self._path(chunk), cells.arrays())

    def remove(self) -> None:
        import shutil

        shutil.rmtree(self.directory, ignore_errors=True)


def _finished(output: Path, identity: dict[str, str]) -> xr.Dataset | None:
    """The complete ``output`` of this run (loaded), None if absent; anything else: an error."""
    if not output.exists():
        return None
    import xarray as xr

    try:
        with xr.open_dataset(output) as dataset:
            found = {key: dataset.attrs.get(key) for key in identity}
            if found == identity:
                return dataset.load()
    except (OSError, ValueError) as error:
        raise ParameterError(f"{output} exists and is not a readable netCDF file ({error}): "
                             "delete it or choose another output") from None
    raise ParameterError(f"{output} exists and holds a different result: delete it or choose "
                         "another output")


__all__ = ["CONFIDENCE", "STOPPED", "Plane", "Settling", "basin_stability", "basins", "wilson"]
