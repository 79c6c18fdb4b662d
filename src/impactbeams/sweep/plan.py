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

from impactbeams.params import Params
from impactbeams.sweep.definition import CELL_PARAMETERS, FIRST_IMPACT, Sweep

MAX_SEGMENTS = 100_000  # phases per cell in a full-dynamics sweep; more: dynamics_status = 1


@dataclasses.dataclass(frozen=True)
class Plan:
    """What the kernels need per geometry, and how cells map to geometries.

    Free-phase tables always (the first-impact kernel); the contact phase and projections only
    when a full-dynamics observable is asked for (see kernels.observables for the layout).
    ``fingerprint`` is the sweep's: a plan serves only the sweep it was built for.
    """

    fingerprint: str
    base: Params
    tables: np.ndarray  # (geometries, len(TABLE_ROWS), 2 n_modes)
    compliance: np.ndarray  # (geometries,) c_1 in m/N
    geometry_axes: tuple[int, ...]  # positions of the axes that change the geometry
    dynamics: tuple[np.ndarray, ...] | None  # (tables, overlaps, shifts, units, geometry)


def _geometries(sweep: Sweep) -> Iterator[Params]:
    """The parameters of every distinct geometry of the grid, in flat geometry-index order."""
    geometry_axes = [k for k, a in enumerate(sweep.axes) if a.name not in CELL_PARAMETERS]
    for combo in itertools.product(*(range(sweep.axes[k].num) for k in geometry_axes)):
        changes = {sweep.axes[k].name: float(sweep.axes[k].values[i])
                   for k, i in zip(geometry_axes, combo, strict=True)}
        yield sweep.base.replace(**changes) if changes else sweep.base


def _dynamics_tables(params: Params, n_modes: int) -> tuple[np.ndarray, ...]:
    """One geometry's arrays for kernels.observables (both phases, projections)."""
    from impactbeams.model import build_model
    from impactbeams.packing import phase_tables

    model = build_model(params, n_modes)
    tables, shifts, accumulation = phase_tables(model)
    geometry = np.array([*params.tip_compliance, accumulation])
    units = np.array([model.free.unit1, model.free.unit2])
    return tables, model.overlap, shifts, units, geometry


def build_plan(sweep: Sweep) -> Plan:
    """The modes of every geometry of ``sweep``, packed for the kernels (SciPy work)."""
    from impactbeams.model import build_free_phase

    tables, compliance, dynamics = [], [], []
    for params in _geometries(sweep):
        free = build_free_phase(params, sweep.n_modes)
        tables.append([free.omega, free.tip1 - free.tip2, free.drive, free.unit1, free.unit2])
        compliance.append(params.tip_compliance[0])
        if sweep.needs_dynamics:
            dynamics.append(_dynamics_tables(params, sweep.n_modes))
    geometry_axes = tuple(k for k, a in enumerate(sweep.axes) if a.name not in CELL_PARAMETERS)
    stacked = tuple(np.array(arrays) for arrays in zip(*dynamics, strict=True)) or None
    return Plan(sweep.fingerprint(), sweep.base, np.array(tables), np.array(compliance),
                geometry_axes, stacked)


def chunk_cells(sweep: Sweep, plan: Plan, start: int, stop: int) -> np.ndarray:
    """The packed cell rows (see kernels.first_impact.CELL_COLUMNS) of flat cells start..stop."""
    index = np.unravel_index(np.arange(start, stop), sweep.shape)
    cells = np.empty((stop - start, len(CELL_PARAMETERS) + 1))
    for column, name in enumerate(CELL_PARAMETERS):
        cells[:, column] = getattr(plan.base, name)
        for k, axis in enumerate(sweep.axes):
            if axis.name == name:
                cells[:, column] = axis.values[index[k]]
    geometry_shape = tuple(sweep.axes[k].num for k in plan.geometry_axes)
    geometry_index = tuple(index[k] for k in plan.geometry_axes)
    cells[:, -1] = np.ravel_multi_index(geometry_index, geometry_shape) if geometry_shape else 0
    return cells


def compute_chunk(sweep: Sweep, start: int, stop: int, parallel: bool = True,
                  plan: Plan | None = None) -> dict[str, np.ndarray]:
    """Observables of the flat cells ``start..stop`` of ``sweep`` (one array per observable).

    Self-contained, so that any process (a Dask worker, say) can compute any chunk; pass the
    sweep's ``plan`` (:func:`build_plan`) to reuse it across chunks. A first-impact-only sweep
    runs the free phase alone; any other observable runs the full dynamics of every cell over
    [0, t_max] (and gives the first impact time from it too).
    """
    from impactbeams.kernels import first_impact, observables

    if plan is None:
        plan = build_plan(sweep)
    if plan.fingerprint != sweep.fingerprint():
        raise ValueError("the plan was built for another sweep")
    cells = chunk_cells(sweep, plan, start, stop)
    if plan.dynamics is None:
        kernel = (first_impact.first_impact_map_parallel if parallel
                  else first_impact.first_impact_map_serial)
        out = np.empty(cells.shape[0])
        kernel(cells, plan.tables, plan.compliance, sweep.t_max, out)
        return {FIRST_IMPACT: out}
    kernel = (observables.observables_map_parallel if parallel
              else observables.observables_map_serial)
    out = np.empty((cells.shape[0], len(observables.OUT_COLUMNS)))
    kernel(cells, *plan.dynamics, sweep.t_max, MAX_SEGMENTS, out)
    columns = dict(zip(observables.OUT_COLUMNS, out.T, strict=True))
    return {name: np.ascontiguousarray(columns[name]) for name in sweep.stored}
