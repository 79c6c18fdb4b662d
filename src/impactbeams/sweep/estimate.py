"""What a sweep costs to run: its wall time from `impactbeams.costs`' model, and its disk.

Apart from the definition (`impactbeams.sweep.definition`, which refuses a grid too large for
memory with `definition.expected_memory`) and from the plan (`impactbeams.sweep.plan`, whose
way of running a map, by columns or cell by cell, sets the time): both import nothing of
this module.
"""

from __future__ import annotations

import os

import numpy as np

from impactbeams import costs
from impactbeams.params import Params
from impactbeams.preflight import Cost
from impactbeams.sweep.definition import (
    CONTACT_OBSERVABLES,
    DYNAMICS_OBSERVABLES,
    FIRST_IMPACT,
    LYAPUNOV,
    Sweep,
    contact_sweeps,
    expected_memory,
    geometry_count,
    stored_values,
)
from impactbeams.sweep.plan import by_columns


def expected_cost(sweep: Sweep, threads: int | None = None, in_memory: bool = False) -> Cost:
    """Peak memory and wall time of running ``sweep`` on ``threads`` (default: all cores).

    Memory: `definition.expected_memory` (``in_memory``: the map held, not streamed); time:
    `expected_seconds`.
    """
    return Cost(expected_memory(sweep, threads, in_memory), expected_seconds(sweep, threads))


# cells of the grid at which a sweep's cost is evaluated (a regular sub-grid)
COST_SAMPLES = 64


def expected_seconds(sweep: Sweep, threads: int | None = None) -> float:
    """Wall time (s) of computing ``sweep`` on ``threads``: `impactbeams.costs`' model.

    The set-up of every geometry, then the cells over the threads: a first-impact map's cost
    per cell, or the full dynamics' per cycle of each run (over t_max for the dynamics
    observables, again for the Lyapunov exponent, and over the long run's periods), averaged
    over a regular sub-grid of at most ``COST_SAMPLES`` cells (several contacts: `cell_seconds`;
    a first-impact map of several, the sum of each contact's own map's). Start-up and compile
    are apart (``costs.START_UP``, ``costs.COMPILE``).
    """
    threads = threads or os.cpu_count() or 1
    if not sweep.needs_dynamics and sweep.base.several_contacts:
        # the first contact among several: each contact's own map (`plan._first_contact`)
        return sum(expected_seconds(each, threads) for each in contact_sweeps(sweep))
    set_up = costs.geometry_seconds(geometry_count(sweep), sweep.n_modes)
    if not sweep.needs_dynamics and by_columns(sweep):
        return set_up + costs.first_impact_seconds(sweep.size, sweep.n_modes) / costs.speedup(
            threads)
    return set_up + sweep.size * float(np.mean(cell_seconds(sweep, sample_points(sweep)))
                                       ) / costs.speedup(threads)


def cell_seconds(sweep: Sweep, points: list[Params]) -> np.ndarray:
    """Seconds on one core of the cells with parameters ``points``.

    Full dynamics, or first impacts searched cell by cell (a map not run by columns). A cell
    of several contacts (`impactbeams.active_phases.cell_observables`) costs, in each of its
    runs (over t_max for the dynamics observables and the Lyapunov exponent, one; the long
    run, another), ``costs.CONTACT_CELL`` per contact (packing its run and the active sets'
    functions, and reading the run in Python), and the events of each contact's own run
    (`Params.each_contact`) as one contact's cell of them.
    """
    if points and points[0].several_contacts:
        runs = (any(name in (FIRST_IMPACT, *DYNAMICS_OBSERVABLES, *CONTACT_OBSERVABLES,
                             LYAPUNOV) for name in sweep.observables)
                + (sweep.long_time is not None))
        return np.array([runs * costs.CONTACT_CELL * len(point.contacts)
                         + float(np.sum(_run_seconds(sweep, point.each_contact())))
                         for point in points])
    return _run_seconds(sweep, points)


def _run_seconds(sweep: Sweep, points: list[Params] | tuple[Params, ...]) -> np.ndarray:
    """`cell_seconds` of one contact's cells (one law may differ from point to point)."""
    seconds = np.zeros(len(points))
    for law in set(point.law for point in points):
        index = [k for k, point in enumerate(points) if point.law == law]
        rows = [costs.run_values(points[k], sweep.n_modes) for k in index]
        values = {name: np.array([row[name] for row in rows]) for name in rows[0]}
        if not sweep.needs_dynamics:
            seconds[index] += costs.cell_search_seconds(values, sweep.n_modes, sweep.t_max)
        elif any(name in (FIRST_IMPACT, *DYNAMICS_OBSERVABLES, *CONTACT_OBSERVABLES)
                 for name in sweep.observables):
            seconds[index] += costs.dynamics_seconds(values, law, sweep.n_modes, sweep.t_max,
                                                     "dynamics", sweep.base.partner)
        if LYAPUNOV in sweep.observables:
            seconds[index] += costs.dynamics_seconds(values, law, sweep.n_modes, sweep.t_max,
                                                     "lyapunov", sweep.base.partner)
        if sweep.long_time is not None:
            horizon = sweep.long_time.horizon(values["omega"], sweep.transient_periods)
            seconds[index] += costs.dynamics_seconds(values, law, sweep.n_modes, horizon,
                                                     "long_time", sweep.base.partner)
    return seconds


def chunk_seconds(sweep: Sweep, start: int, stop: int, limit: int = 4) -> float:
    """Expected seconds on one core of a full-dynamics sweep's flat cells start..stop.

    From ``limit`` cells spread over them (`cell_seconds`): weights of a progress bar.
    """
    return (stop - start) * float(np.mean(cell_seconds(sweep, sample_points(sweep, start, stop,
                                                                            limit))))


def sample_points(sweep: Sweep, start: int = 0, stop: int | None = None,
                  limit: int = COST_SAMPLES) -> list[Params]:
    """Parameters of at most ``limit`` cells spread evenly over the flat cells start..stop."""
    stop = sweep.size if stop is None else stop
    count = min(limit, stop - start)
    # Python integers: a grid may have more cells than int64 holds (it is refused afterwards)
    flat = sorted({start + (stop - 1 - start) * k // max(count - 1, 1) for k in range(count)})
    return [sweep.params_at({axis.name: axis.value(i) for axis, i in
                             zip(sweep.axes, _axis_indices(sweep, cell), strict=True)})
            for cell in flat]


def _axis_indices(sweep: Sweep, cell: int) -> list[int]:
    """The index along each axis of flat ``cell`` (a stepped sweep's direction left out)."""
    return _grid_index(cell, sweep.shape)[-len(sweep.axes):]


def _grid_index(cell: int, shape: tuple[int, ...]) -> list[int]:
    """The index along each axis of flat (C-order) ``cell`` of a grid of ``shape``."""
    index = []
    for length in reversed(shape):
        cell, along = divmod(cell, length)
        index.append(along)
    return index[::-1]


def expected_file_size(sweep: Sweep) -> int:
    """Disk space (bytes) a run of ``sweep`` needs at its peak.

    The finished chunks under ``OUT.nc.partial/`` and the netCDF file: 8 bytes per cell and
    stored value each.
    """
    return sweep.size * (16 * stored_values(sweep) + 1)
