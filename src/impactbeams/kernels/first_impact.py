"""Time to first impact: the free phase only, stopped at the first gap closure.

Plain-array interface, packed by `impactbeams.packing` (names in
`impactbeams.kernels.layout`): ``cells[i]`` with columns ``CELL_COLUMNS``;
``tables[g, FREE]`` the free-phase table of geometry g (rows ``TABLE_ROWS``; its ``event`` row
is the gap weight ``Y_1n(l1) - Y_2n(l2)``); ``geometry[g]`` with fields ``GEOMETRY``.

A cell's gap is ``g(t) = clearance - c_1 F(t) + sum_n event_n q_n(t)``, from the initial state
of docs/model.md (at rest in the uplift shape, `rest_state`),
with each mode driven by ``b_n (F'' + 2 zeta omega_n F')`` (modal damping of the whole
coordinate).
"""

import numpy as np
from numba import prange

from impactbeams.kernels.events import (
    GAVE_UP,
    phase_bounds,
    search_root,
    split_steady_states,
    step_limit,
    walk,
)
from impactbeams.kernels.forcing import rest_state
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import (
    CELL_CLEARANCE,
    CELL_F0,
    CELL_GEOMETRY,
    CELL_OMEGA,
    CELL_UPLIFT1,
    CELL_UPLIFT2,
    CELL_ZETA,
    FREE,
    GEO_C1,
    ROW_DRIVE,
    ROW_EVENT,
    ROW_OMEGA,
    ROW_UNIT1,
    ROW_UNIT2,
)
from impactbeams.kernels.propagation import drive_amplitude
from impactbeams.kernels.rotor import rotor_arrays

# rows of the per-mode scratch of the moving modes (private to this kernel)
_WORK_ROWS = ("q_s", "v_s", "omega", "zeta", "weights", "q", "v")
_Q_S, _V_S, _OMEGA, _ZETA, _WEIGHTS, _Q, _V = range(len(_WORK_ROWS))


# The round-off rule of the map's event search (``events.search_root``): a gap within
# 8 eps of its evaluation scale is touching. Its evaluation sums a handful of terms of that
# scale, each correctly rounded, plus the propagated modes' own few-ulp errors.
TOUCH_TOLERANCE = 8.0


@kernel
def _load_moving_modes(cell, table, work, force):
    """Copy the modes that move into the scratch rows; return how many.

    Beam 2 rests unless uplifted, so its modes drop out; one mode is kept if none moves.
    """
    active = 0
    last = table.shape[1] - 1
    for j in range(table.shape[1]):
        q0, v0 = rest_state(cell, table[ROW_UNIT1, j], table[ROW_UNIT2, j], table[ROW_DRIVE, j])
        f = drive_amplitude(table[ROW_DRIVE, j], table[ROW_OMEGA, j], cell[CELL_ZETA],
                            cell[CELL_F0], cell[CELL_OMEGA])
        if q0 != 0.0 or v0 != 0.0 or f != 0 or (j == last and active == 0):
            work[_Q_S, active], work[_V_S, active], force[active] = q0, v0, f
            work[_OMEGA, active], work[_WEIGHTS, active] = table[ROW_OMEGA, j], table[ROW_EVENT, j]
            work[_ZETA, active] = cell[CELL_ZETA]
            active += 1
    return active


@kernel
def first_impact_time(cell, table, c1, t_max, t_start, work, force, rotor):
    """Time (s) of the first gap closure in (0, t_max] for one cell, NaN if none.

    ``table``: the free-phase table of the cell's geometry; ``c1``: beam 1's tip compliance
    (m/N); ``t_start``: a time before which the gap is known to stay open (0 if none, see
    ``_column``); ``work`` (rows ``_WORK_ROWS``) and the complex ``force``: scratch per mode,
    reused across cells (no heap allocation per cell: allocations serialise threads).
    Returns ``events.GAVE_UP`` (-inf) if the search reached its step cap.
    """
    active = _load_moving_modes(cell, table, work, force)
    q_s, v_s = work[_Q_S, :active], work[_V_S, :active]
    if cell[CELL_F0] == 0.0 and q_s[0] == 0.0 and v_s[0] == 0.0 and active == 1:
        return np.nan  # nothing moves: the gap stays open
    omega = work[_OMEGA, :active]
    return search_root(q_s, v_s, 0.0, t_start, t_max, omega, work[_ZETA, :active],
                       force[:active], work[_WEIGHTS, :active], cell[CELL_CLEARANCE],
                       -c1 * cell[CELL_F0], cell[CELL_OMEGA], TOUCH_TOLERANCE,
                       step_limit(0.0, t_max, omega), work[_Q, :active], work[_V, :active],
                       rotor)


@kernel
def _uplift_stays_below_clearance(cell, table, c1, work, force):
    """Whether clearance + u(t) > 0 for all t, u the unforced response to the uplifts.

    Each mode's free motion from rest at q0 has amplitude at most |q0| / sqrt(1 - zeta^2).
    """
    active = _load_moving_modes(cell, table, work, force)
    reach = 0.0
    for j in range(active):
        reach += abs(work[_WEIGHTS, j] * work[_Q_S, j]) / np.sqrt(1.0 - work[_ZETA, j]**2)
    return cell[CELL_CLEARANCE] - reach > 0.0


@kernel
def _walk_order(cells, lo, hi, key, table, c1, work, force):
    """Cells lo..hi-1 of a column in order of non-decreasing first impact time, or none.

    Returns ``(first, stride)``, the walk being first, first + stride, ...; stride 0 when the
    column cannot be ordered (each cell is then searched from t = 0). Along the clearance the
    gap is ``clearance + (a response shared by the column)``: it closes later (or never) for a
    larger clearance. Along F0 it is ``clearance + u(t) - F0 h(t)``: if clearance + u > 0
    throughout, it closes where ``F0 >= (clearance + u) / h``, later for a smaller F0.
    """
    if hi - lo < 2:
        return lo, 0
    rising = cells[lo + 1, key] > cells[lo, key]
    for i in range(lo + 1, hi):
        step = cells[i, key] - cells[i - 1, key]
        if step == 0.0 or (step > 0.0) != rising:
            return lo, 0
    if key == CELL_CLEARANCE:
        return (lo, 1) if rising else (hi - 1, -1)
    if min(cells[lo, key], cells[hi - 1, key]) < 0.0 or not _uplift_stays_below_clearance(
            cells[lo], table, c1, work, force):
        return lo, 0
    return (hi - 1, -1) if rising else (lo, 1)


@kernel
def _shared_column(cells, first, stride, count, key, table, c1, t_max, work, force, rotor,
                   out):
    """One column whose cells share one modal response; walked once, level by level.

    Along the clearance the gap is ``clearance + phi(t)``, phi the response of the column's
    forcing and uplifts; along F0 without uplifts it is ``F0 (clearance / F0 + phi(t))``,
    phi the response to F0 = 1 N. The bounds of phi serve every cell; each cell's search
    starts at the previous cell's impact, with its own level.
    """
    source = cells[first].copy()
    if key == CELL_F0:
        source[CELL_F0] = 1.0
    active = _load_moving_modes(source, table, work, force)
    q_s, v_s, omega = work[_Q_S, :active], work[_V_S, :active], work[_OMEGA, :active]
    zeta, weights, drives = work[_ZETA, :active], work[_WEIGHTS, :active], force[:active]
    sine_amp = split_steady_states(q_s, v_s, 0.0, omega, zeta, drives, weights,
                                   complex(-c1 * source[CELL_F0], 0.0), source[CELL_OMEGA])
    bounds = phase_bounds(q_s, v_s, 0.0, t_max, omega, zeta, drives, weights, sine_amp,
                          source[CELL_OMEGA])
    max_steps = step_limit(0.0, t_max, omega)
    t_start, t_state = 0.0, np.nan
    i = first
    for _ in range(count):
        if np.isnan(t_start):
            out[i] = np.nan
        else:
            level = cells[i, CELL_CLEARANCE]
            if key == CELL_F0:
                level /= cells[i, CELL_F0]
            out[i], t_state = walk(q_s, v_s, 0.0, t_start, t_max, omega, zeta, drives, weights,
                                   level, sine_amp, source[CELL_OMEGA], TOUCH_TOLERANCE,
                                   max_steps, bounds, t_state, work[_Q, :active],
                                   work[_V, :active], rotor)
            t_start = 0.0 if out[i] == GAVE_UP else out[i]  # NaN ends the column
        i += stride


@kernel
def _column(cells, lo, hi, key, tables, geometry, t_max, work, force, rotor, out):
    """Fill out[lo:hi], one column, each search starting where the previous closed.

    In walk order the first impact time does not decrease, so each cell's gap stays open until
    the previous cell's impact, and once a cell has none neither has any after it. A column
    that cannot be ordered is searched cell by cell from t = 0.
    """
    g = int(cells[lo, CELL_GEOMETRY])
    table, c1 = tables[g, FREE], geometry[g, GEO_C1]
    i, stride = _walk_order(cells, lo, hi, key, table, c1, work, force)
    shared = key == CELL_CLEARANCE or (cells[lo, CELL_UPLIFT1] == 0.0
                                       and cells[lo, CELL_UPLIFT2] == 0.0
                                       and min(cells[lo, key], cells[hi - 1, key]) > 0.0)
    if stride != 0 and shared:
        _shared_column(cells, i, stride, hi - lo, key, table, c1, t_max, work, force, rotor,
                       out)
        return
    t_start = 0.0
    for _ in range(hi - lo):
        if np.isnan(t_start):
            out[i] = np.nan
        else:
            out[i] = first_impact_time(cells[i], table, c1, t_max, t_start, work, force,
                                       rotor)
            if stride != 0:
                t_start = 0.0 if out[i] == GAVE_UP else out[i]  # NaN ends the column
        i = i + stride if stride != 0 else i + 1


_BLOCK = 256  # cells per unit of parallel work: scratch allocated once per block


def _first_impact_map(cells, columns, key, tables, geometry, t_max, out):
    """Fill out[i] with the first impact time of cells[i], column by column.

    Column c is ``cells[columns[c]:columns[c + 1]]``, cells that differ in column ``key`` of
    ``CELL_COLUMNS`` alone (``CELL_F0`` or ``CELL_CLEARANCE``, axes in which the gap is affine);
    columns of one cell are searched on their own. Block b takes columns b, b + n_blocks, ...:
    interleaved, so that the costly regions of a grid (near resonances and the no-impact
    boundary) are shared evenly between the threads of prange's static schedule. Each
    iteration owns its columns, so the result does not depend on the number of threads.
    """
    n_columns = columns.size - 1
    n_blocks = min(n_columns, (cells.shape[0] + _BLOCK - 1) // _BLOCK)
    for block in prange(n_blocks):
        work = np.empty((len(_WORK_ROWS), tables.shape[3]))
        force = np.empty(tables.shape[3], dtype=np.complex128)
        rotor = rotor_arrays(tables.shape[3])
        for c in range(block, n_columns, n_blocks):
            _column(cells, columns[c], columns[c + 1], key, tables, geometry, t_max, work,
                    force, rotor, out)


first_impact_map_parallel, first_impact_map_serial = parallel_kernel(_first_impact_map)


@kernel
def first_impact_cells(cells, tables, geometry, t_max, out):
    """``out[i]``: each cell searched on its own from t = 0 (the reference for the columns)."""
    work = np.empty((len(_WORK_ROWS), tables.shape[3]))
    force = np.empty(tables.shape[3], dtype=np.complex128)
    rotor = rotor_arrays(tables.shape[3])
    for i in range(cells.shape[0]):
        g = int(cells[i, CELL_GEOMETRY])
        out[i] = first_impact_time(cells[i], tables[g, FREE], geometry[g, GEO_C1], t_max, 0.0,
                                   work, force, rotor)
