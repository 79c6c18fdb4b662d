"""A sweep's kernel inputs (the per-geometry plan, a chunk's cells) and :func:`compute_chunk`.

The grid is flattened; a chunk is a range of flat cells. Axes over :data:`CELL_PARAMETERS`
change a cell's forcing, initial state or damping only; the other axes change the geometry,
whose modes are computed once per geometry (the plan).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterator

import numpy as np

from impactbeams.kernels import layout
from impactbeams.longtime import LongTime
from impactbeams.params import Params
from impactbeams.sweep.definition import (
    CELL_PARAMETERS,
    DYNAMICS_OBSERVABLES,
    FIRST_IMPACT,
    LYAPUNOV,
    Sweep,
)

MAX_SEGMENTS = 100_000  # phases per cell (per forcing period for the Lyapunov exponent's
# windowed run) in a full-dynamics sweep; more: dynamics_status = 1
# a long run holds this many segments at once (4 arrays of 2 n_modes floats each, per thread)
LONG_RUN_CAPACITY = 2048
MAX_PHASES_PER_PERIOD = 2000  # cap of a long run, per forcing period; more: dynamics_status = 1


@dataclasses.dataclass(frozen=True)
class Plan:
    """What the kernels need per geometry, and how cells map to geometries.

    ``tables``: the free phase of every geometry (first-impact map), or both phases with the
    switching arrays (``overlaps``, ``shifts`` of the tied law's projections; the spring law's
    ``left``, ``right``, ``modes``) when a full-dynamics observable is asked for (see
    kernels.layout). ``fingerprint`` is the sweep's: a plan serves only the
    sweep it was built for.
    """

    fingerprint: str
    base: Params
    tables: np.ndarray  # (geometries, phases, len(TABLE_ROWS), 2 n_modes)
    geometry: np.ndarray  # (geometries, len(GEOMETRY))
    geometry_axes: tuple[int, ...]  # positions of the axes that change the geometry
    switching: tuple[np.ndarray, ...] | None  # a dynamics map's switching arrays


def geometry_axes(sweep: Sweep) -> tuple[int, ...]:
    """Positions of the axes that change the modes: all but the cell parameters' axes.

    A spring-law dynamics map solves its contact phase for the damping ratio, so there the
    damping ratio changes the modes too.
    """
    per_cell = set(CELL_PARAMETERS)
    if sweep.needs_dynamics and "spring" in _laws(sweep):
        per_cell.discard("damping_ratio")
    return tuple(k for k, a in enumerate(sweep.axes) if a.name not in per_cell)


def contact_resolution(sweep: Sweep) -> int | None:
    """n_modes that resolves a spring-law dynamics map's stiffest contact; None otherwise."""
    from impactbeams.compliant import required_modes

    if not sweep.needs_dynamics or "spring" not in _laws(sweep):
        return None
    swept = [axis.max for axis in sweep.axes if axis.name == "contact_stiffness"]
    stiffest = swept[0] if swept else sweep.base.contact_stiffness
    return required_modes(sweep.base.replace(contact_law="spring", contact_stiffness=stiffest))


def _laws(sweep: Sweep) -> set[str]:
    """The contact laws a sweep runs."""
    for axis in sweep.axes:
        if axis.name == "contact_law":
            return set(axis.choices)
    return {sweep.base.contact_law}


def _geometries(sweep: Sweep) -> Iterator[Params]:
    """The parameters of every distinct geometry of the grid, in flat geometry-index order."""
    axes = geometry_axes(sweep)
    for combo in itertools.product(*(range(sweep.axes[k].num) for k in axes)):
        changes = {sweep.axes[k].name: sweep.axes[k].value(i)
                   for k, i in zip(axes, combo, strict=True)}
        yield sweep.params_at(changes)


def _geometry_arrays(params: Params, sweep: Sweep) -> tuple[np.ndarray, ...]:
    """One geometry's packed arrays: (tables, geometry row[, switching arrays])."""
    from impactbeams import packing
    from impactbeams.model import build_free_phase

    if not sweep.needs_dynamics:
        free = build_free_phase(params, sweep.n_modes)
        return packing.free_tables(free), packing.geometry_row(params, free)
    dynamics = packing.dynamics_arrays(params, sweep.n_modes)
    return (dynamics.tables, dynamics.geometry, dynamics.overlap, dynamics.shifts,
            *dynamics.spring_arrays)


def build_plan(sweep: Sweep) -> Plan:
    """The modes of every geometry of ``sweep``, packed for the kernels (SciPy work)."""
    per_geometry = [_geometry_arrays(params, sweep) for params in _geometries(sweep)]
    tables, geometry, *switching = (np.array(arrays) for arrays in zip(*per_geometry,
                                                                        strict=True))
    return Plan(sweep.fingerprint(), sweep.base, tables, geometry, geometry_axes(sweep),
                tuple(switching) or None)


def chunk_cells(sweep: Sweep, plan: Plan, start: int, stop: int) -> np.ndarray:
    """The packed cell rows (kernels.layout.CELL_COLUMNS) of flat cells start..stop."""
    from impactbeams import packing

    index = np.unravel_index(np.arange(start, stop), sweep.shape)
    columns = {name: getattr(plan.base, name) for name in CELL_PARAMETERS}
    for k, axis in enumerate(sweep.axes):
        if axis.name in columns:
            columns[axis.name] = axis.values[index[k]]
    geometry_shape = tuple(sweep.axes[k].num for k in plan.geometry_axes)
    geometry_index = tuple(index[k] for k in plan.geometry_axes)
    columns["geometry"] = (np.ravel_multi_index(geometry_index, geometry_shape)
                           if geometry_shape else 0)
    return packing.cell_rows(columns, stop - start)


MAX_COLUMN_CELLS = 4096  # a first-impact map's columns: at most this many cells each
_AFFINE_AXES = {"force_amplitude": layout.CELL_F0, "clearance": layout.CELL_CLEARANCE}


@dataclasses.dataclass(frozen=True)
class Columns:
    """A chunk's first-impact columns.

    Cells ``start..stop`` (the chunk widened to whole columns), column c being
    ``bounds[c]..bounds[c + 1]`` of them, along the cell column ``key`` (kernels.layout).
    """

    start: int
    stop: int
    bounds: np.ndarray
    key: int


def first_impact_columns(sweep: Sweep, start: int, stop: int) -> Columns:
    """The columns of flat cells ``start..stop`` along the sweep's last axis, if affine.

    The gap is affine in F0 and in the clearance, so a run of cells along such an axis shares
    one modal response (kernels.first_impact). Columns are fixed segments of the grid (at
    most ``MAX_COLUMN_CELLS`` of the last axis), and a chunk is widened to whole columns, so
    that every cell's result is the same for any chunking. Other sweeps: columns of one cell.
    """
    last = sweep.axes[-1] if sweep.axes else None
    if last is None or last.name not in _AFFINE_AXES or last.num < 2:
        return Columns(start, stop, np.arange(stop - start + 1, dtype=np.int64),
                       layout.CELL_F0)
    length = min(last.num, MAX_COLUMN_CELLS)
    flat = np.arange(start, stop)
    row, position = np.divmod(flat, last.num)
    segment_start = row * last.num + position // length * length
    segment_stop = np.minimum(segment_start + length, (row + 1) * last.num)
    first, end = int(segment_start[0]), int(segment_stop[-1])
    edges = np.unique(np.concatenate([segment_start, segment_stop])) - first
    return Columns(first, end, edges.astype(np.int64), _AFFINE_AXES[last.name])


def compute_chunk(sweep: Sweep, start: int, stop: int, parallel: bool = True,
                  plan: Plan | None = None) -> dict[str, np.ndarray]:
    """Observables of the flat cells ``start..stop`` of ``sweep`` (one array per observable).

    Self-contained, so that any process (a Dask worker, say) can compute any chunk; pass the
    sweep's ``plan`` (:func:`build_plan`) to reuse it across chunks. A first-impact-only sweep
    runs the free phase alone; any other observable runs the full dynamics of every cell over
    [0, t_max] (and gives the first impact time from it too), except the long-time ones, which
    run each cell over (transient + sampled) forcing periods (:mod:`impactbeams.longtime`);
    ``dynamics_status`` is then the worse of the runs'.
    """
    from impactbeams.kernels import first_impact, observables

    if plan is None:
        plan = build_plan(sweep)
    if plan.fingerprint != sweep.fingerprint():
        raise ValueError("the plan was built for another sweep")
    if plan.switching is None:
        kernel = (first_impact.first_impact_map_parallel if parallel
                  else first_impact.first_impact_map_serial)
        columns = first_impact_columns(sweep, start, stop)
        cells = chunk_cells(sweep, plan, columns.start, columns.stop)
        out = np.empty(cells.shape[0])
        kernel(cells, columns.bounds, columns.key, plan.tables, plan.geometry, sweep.t_max, out)
        out = out[start - columns.start:stop - columns.start]
        undecided = np.flatnonzero(np.isneginf(out))  # kernels.events.GAVE_UP
        if undecided.size:
            raise RuntimeError(f"{undecided.size} cells of cells {start}..{stop} reached the "
                               f"event search's step cap (first: cell {start + undecided[0]}); "
                               "please report this as a bug")
        return {FIRST_IMPACT: np.ascontiguousarray(out)}
    cells = chunk_cells(sweep, plan, start, stop)
    columns = {}
    if any(name in (FIRST_IMPACT, *DYNAMICS_OBSERVABLES) for name in sweep.observables):
        kernel = (observables.observables_map_parallel if parallel
                  else observables.observables_map_serial)
        out = np.empty((cells.shape[0], len(layout.OUT_COLUMNS)))
        kernel(cells, plan.tables, *plan.switching, plan.geometry, sweep.t_max, MAX_SEGMENTS,
               out)
        columns = dict(zip(layout.OUT_COLUMNS, out.T, strict=True))
    if LYAPUNOV in sweep.observables:
        columns.update(_lyapunov_columns(sweep, plan, cells, parallel, columns))
    if sweep.long_time is not None:
        long_run = _long_run(sweep.long_time, sweep.transient_periods, plan, cells, parallel)
        long_run["dynamics_status"] = np.maximum(
            long_run["dynamics_status"], columns.get("dynamics_status", 0))
        columns.update(long_run)
    return {name: np.ascontiguousarray(columns[name]) for name in sweep.stored}


def _long_run(long_time: LongTime, transient_periods: int, plan: Plan, cells: np.ndarray,
              parallel: bool) -> dict[str, np.ndarray]:
    """The long-time observables of every cell and its run's ``dynamics_status``.

    Each cell runs (transient + sampled) forcing periods, in windows of LONG_RUN_CAPACITY.
    """
    import numba

    from impactbeams.kernels import stroboscope
    from impactbeams.longtime import long_time_values

    kernel = (stroboscope.stroboscope_map_parallel if parallel
              else stroboscope.stroboscope_map_serial)
    omega = cells[:, layout.CELL_OMEGA]
    samples = np.empty((cells.shape[0], long_time.sampled_periods, len(layout.TIP_COLUMNS)))
    summary = np.empty((cells.shape[0], len(layout.STROBOSCOPE_COLUMNS)))
    # cells differ in cost by orders of magnitude (a rattle at every period, or no contact at
    # all): the threads take them one at a time instead of in equal contiguous blocks
    with numba.parallel_chunksize(1):
        kernel(cells, plan.tables, *plan.switching, plan.geometry,
               long_time.sample_times(omega, transient_periods),
               long_time.horizon(omega, transient_periods), LONG_RUN_CAPACITY,
               MAX_PHASES_PER_PERIOD, samples, summary)
    return long_time_values(long_time, transient_periods, omega,
                            cells[:, layout.CELL_CLEARANCE], samples, summary)


def _lyapunov_columns(sweep: Sweep, plan: Plan, cells: np.ndarray, parallel: bool,
                      columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The cells' largest Lyapunov exponents, each from its own windowed run, and the status.

    The status is the worse of that run's and the other observables' run (if any).
    """
    from impactbeams.kernels import lyapunov

    kernel = lyapunov.lyapunov_map_parallel if parallel else lyapunov.lyapunov_map_serial
    out = np.empty((cells.shape[0], 2))
    kernel(cells, plan.tables, *plan.switching, plan.geometry, sweep.t_max,
           sweep.transient_periods, MAX_SEGMENTS, out)
    status = np.maximum(out[:, 1], columns.get("dynamics_status", out[:, 1]))
    return {LYAPUNOV: out[:, 0], "dynamics_status": status}
