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
from impactbeams.sweep.definition import CELL_PARAMETERS, FIRST_IMPACT, Sweep

MAX_SEGMENTS = 100_000  # phases per cell in a full-dynamics sweep; more: dynamics_status = 1
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
        yield sweep.base.replace(**changes) if changes else sweep.base


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


def compute_chunk(sweep: Sweep, start: int, stop: int, parallel: bool = True,
                  plan: Plan | None = None) -> dict[str, np.ndarray]:
    """Observables of the flat cells ``start..stop`` of ``sweep`` (one array per observable).

    Self-contained, so that any process (a Dask worker, say) can compute any chunk; pass the
    sweep's ``plan`` (:func:`build_plan`) to reuse it across chunks. A first-impact-only sweep
    runs the free phase alone; the other observables over [0, t_max] run the full dynamics of
    every cell over [0, t_max] (and give the first impact time from it too); long-time
    observables run each cell over its own horizon, (transient + sampled) forcing periods
    (:mod:`impactbeams.longtime`). ``dynamics_status`` is the worse of the two runs'.
    """
    from impactbeams.kernels import first_impact

    if plan is None:
        plan = build_plan(sweep)
    if plan.fingerprint != sweep.fingerprint():
        raise ValueError("the plan was built for another sweep")
    cells = chunk_cells(sweep, plan, start, stop)
    if plan.switching is None:
        kernel = (first_impact.first_impact_map_parallel if parallel
                  else first_impact.first_impact_map_serial)
        out = np.empty(cells.shape[0])
        kernel(cells, plan.tables, plan.geometry, sweep.t_max, out)
        return {FIRST_IMPACT: out}
    values: dict[str, np.ndarray] = {"dynamics_status": np.zeros(cells.shape[0])}
    if sweep.needs_horizon_run or FIRST_IMPACT in sweep.observables:
        values.update(_horizon_run(sweep, plan, cells, parallel))
    if sweep.long_time is not None:
        long_time = _long_run(sweep.long_time, plan, cells, parallel)
        long_time["dynamics_status"] = np.maximum(values["dynamics_status"],
                                                  long_time["dynamics_status"])
        values.update(long_time)
    return {name: np.ascontiguousarray(values[name]) for name in sweep.stored}


def _horizon_run(sweep: Sweep, plan: Plan, cells: np.ndarray,
                 parallel: bool) -> dict[str, np.ndarray]:
    """The ``OUT_COLUMNS`` of every cell's full dynamics over [0, t_max]."""
    from impactbeams.kernels import observables

    kernel = (observables.observables_map_parallel if parallel
              else observables.observables_map_serial)
    out = np.empty((cells.shape[0], len(layout.OUT_COLUMNS)))
    kernel(cells, plan.tables, *plan.switching, plan.geometry, sweep.t_max, MAX_SEGMENTS, out)
    return dict(zip(layout.OUT_COLUMNS, out.T, strict=True))


def _long_run(long_time: LongTime, plan: Plan, cells: np.ndarray,
              parallel: bool) -> dict[str, np.ndarray]:
    """The long-time observables of every cell (and its run's ``dynamics_status``)."""
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
        kernel(cells, plan.tables, *plan.switching, plan.geometry, long_time.sample_times(omega),
               long_time.horizon(omega), LONG_RUN_CAPACITY, MAX_PHASES_PER_PERIOD, samples,
               summary)
    return long_time_values(long_time, omega, cells[:, layout.CELL_CLEARANCE], samples, summary)
