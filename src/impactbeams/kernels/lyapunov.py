"""The largest Lyapunov exponent of every cell of a map, each run in bounded memory.

A cell's spring-law run goes one renormalisation interval (forcing period) at a time:
``run_events`` from the previous window's end state, then the tangent vector through the
window's segments (`carry_tangents`), so that memory
depends on the events per window, not on the horizon. Restarting the event search at each
window changes the run at round-off only (a chaotic run then follows another trajectory of
the same attractor: the exponent is the same to its statistical error). Plain arrays packed
per geometry as for `impactbeams.kernels.observables`; SI units.
"""

import math

import numpy as np
from numba import prange

from impactbeams.kernels.cells import cell_run, settings_of
from impactbeams.kernels.contact import has_tangent_flow
from impactbeams.kernels.dynamics import COMPLETE, EVENT_LIMIT, run_events
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import (
    CELL_FORCING_FREQUENCY,
    CELL_GEOMETRY,
    FREE,
    GEO_LAW,
    ROW_FREQUENCY,
)
from impactbeams.kernels.records import geometry_switching, recorded_prefix, segments
from impactbeams.kernels.tangent import (
    carry_tangents,
    interval_count,
    lyapunov_schedule,
    new_tangent,
    renormalization_time,
)

_INITIAL_CAPACITY = 256  # segments per window; doubled as needed up to max_segments


@kernel
def cell_exponent(cell, tables, switching, geometry, t_max, transient, max_segments):
    """Largest Lyapunov exponent (1/s) of one cell's spring-law run over [0, t_max].

    Averaged over the complete forcing periods after the first ``transient``; each window
    (one period) may hold up to ``max_segments`` phases. Returns ``(exponent, status)``:
    NaN if no period after the transient completed (or a law without a tangent flow, the
    tied one); a status other than ``COMPLETE`` (a window over ``max_segments`` phases, or
    stuck) ends the run there and the exponent covers the periods before.
    ``switching``: the geometry's switching record (`records.SWITCHING`; the run's drives
    come from the cell).
    """
    if not has_tangent_flow(geometry[GEO_LAW]):
        return np.nan, COMPLETE
    schedule = lyapunov_schedule(cell[CELL_FORCING_FREQUENCY], tables[FREE, ROW_FREQUENCY], t_max,
                                 transient)
    return _exponent(cell_run(cell, tables, geometry, switching, t_max, schedule[0]), t_max,
                     schedule, max_segments)


@kernel
def _exponent(run, t_max, schedule, max_segments):
    """``cell_exponent`` of the cell's `RunInputs` ``run``, renormalised on ``schedule``."""
    settings = settings_of(run)
    interval = schedule[0]
    tangent = new_tangent(1, run.tables[FREE, ROW_FREQUENCY], 1)
    capacity = min(_INITIAL_CAPACITY, max_segments)
    recorded = segments(capacity, run.q0.size)
    q, v = run.q0, run.v0
    phase, t, status = FREE, 0.0, COMPLETE
    for window in range(1, interval_count(t_max, interval) + 1):
        settings.t_max = renormalization_time(window, interval, t_max)
        while True:
            count, status, _ = run_events(run.tables, run.forces, run.phase_scalars,
                                          run.switching, settings, q, v, recorded, t, phase)
            if status != EVENT_LIMIT or capacity >= max_segments:
                break
            capacity = min(2 * capacity, max_segments)
            recorded = segments(capacity, run.q0.size)
        if status != COMPLETE:
            break
        t = settings.t_max
        carry_tangents(run.tables, run.phase_scalars, run.switching, settings,
                       recorded_prefix(recorded, count), t, schedule, tangent)
        q, v = recorded.end_q[count - 1].copy(), recorded.end_v[count - 1].copy()
        phase = recorded.phase[count - 1]
    sums, counts = tangent.sums, tangent.counts
    if counts[0] == 0:
        return math.nan, status
    return sums[0, 0] / (counts[0] * interval), status


def _lyapunov_map(cells, tables, switching, geometry, t_max, transient, max_segments, out):
    """out[i] = (exponent (1/s), status) of cells[i]; each iteration owns row i."""
    for i in prange(cells.shape[0]):
        g = int(cells[i, CELL_GEOMETRY])
        out[i, 0], out[i, 1] = cell_exponent(cells[i], tables[g], geometry_switching(switching, g),
                                             geometry[g], t_max, transient, max_segments)


lyapunov_map_parallel, lyapunov_map_serial = parallel_kernel(_lyapunov_map)
