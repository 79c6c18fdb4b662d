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
from impactbeams.params import Params
from impactbeams.sweep.definition import CELL_PARAMETERS, FIRST_IMPACT, Sweep

MAX_SEGMENTS = 100_000  # phases per cell in a full-dynamics sweep; more: dynamics_status = 1


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
    if plan.switching is None:
        kernel = (first_impact.first_impact_map_parallel if parallel
                  else first_impact.first_impact_map_serial)
        out = np.empty(cells.shape[0])
        kernel(cells, plan.tables, plan.geometry, sweep.t_max, out)
        return {FIRST_IMPACT: out}
    kernel = (observables.observables_map_parallel if parallel
              else observables.observables_map_serial)
    out = np.empty((cells.shape[0], len(layout.OUT_COLUMNS)))
    kernel(cells, plan.tables, *plan.switching, plan.geometry, sweep.t_max, MAX_SEGMENTS, out)
    columns = dict(zip(layout.OUT_COLUMNS, out.T, strict=True))
    return {name: np.ascontiguousarray(columns[name]) for name in sweep.stored}
