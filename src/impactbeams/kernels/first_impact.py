"""Time to first impact: the free phase only, stopped at the first gap closure.

Plain-array interface, packed by `impactbeams.packing` (names in
`impactbeams.kernels.layout`): ``cells[i]`` with columns ``CELL_COLUMNS``;
``tables[g, FREE]`` the free-phase table of geometry g (rows ``TABLE_ROWS``; its ``event`` row
is the gap weight ``Y_1n(l1) - Y_2n(l2)``); ``geometry[g]`` with fields ``GEOMETRY``.

A cell's gap is ``g(t) = clearance + S sin(Omega t) + sum_n event_n q_n(t)``, from the initial
state of docs/model.md (`forcing.rest_state`), with each mode driven by all drives
(`impactbeams.kernels.drive`: the tip force's ``b_n (F'' + 2 zeta omega_n F')``, the shaker's
``-Gamma_n u_b''``) and S = ``drive.gap_harmonic``.
"""

import numpy as np
from numba import prange

from impactbeams.kernels.drive import base_amplitude, gap_harmonic, mode_drive
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
    CELL_FORCING_FREQUENCY,
    CELL_GEOMETRY,
    CELL_UPLIFT1,
    CELL_UPLIFT2,
    CELL_ZETA,
    FREE,
    GEO_START,
    REST,
    ROW_BASE,
    ROW_DRIVE,
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_UNIT1,
    ROW_UNIT2,
)
from impactbeams.kernels.records import EventFunction, Oscillators
from impactbeams.kernels.rotor import rotor_arrays

# rows of the per-mode scratch of the moving modes (private to this kernel)
_WORK_ROWS = ("q_s", "v_s", "frequency", "zeta", "weights", "q", "v")
_Q_S, _V_S, _FREQUENCY, _ZETA, _WEIGHTS, _Q, _V = range(len(_WORK_ROWS))


# The round-off rule of the map's event search (``events.search_root``): a gap within
# 8 eps of its evaluation scale is touching. Its evaluation sums a handful of terms of that
# scale, each correctly rounded, plus the propagated modes' own few-ulp errors.
TOUCH_TOLERANCE = 8.0


@kernel
def _load_moving_modes(cell, table, work, force, start=REST):
    """Copy the modes that move into the scratch rows; return how many.

    Beam 2 rests unless uplifted or shaken, so its modes drop out; one mode is kept if none
    moves. ``start``: the initial state (``layout.STARTS``, the geometry's ``start``).
    """
    active = 0
    last = table.shape[1] - 1
    for j in range(table.shape[1]):
        f = mode_drive(table[ROW_DRIVE, j], table[ROW_BASE, j], table[ROW_FREQUENCY, j],
                       cell[CELL_ZETA], cell[CELL_F0], base_amplitude(cell),
                       cell[CELL_FORCING_FREQUENCY])
        q0, v0 = rest_state(cell, start, table[ROW_UNIT1, j], table[ROW_UNIT2, j],
                            table[ROW_DRIVE, j], table[ROW_BASE, j], f, table[ROW_FREQUENCY, j],
                            cell[CELL_ZETA])
        if q0 != 0.0 or v0 != 0.0 or f != 0 or (j == last and active == 0):
            work[_Q_S, active], work[_V_S, active], force[active] = q0, v0, f
            work[_FREQUENCY, active], work[_WEIGHTS, active] = table[ROW_FREQUENCY,
                                                                     j], table[ROW_EVENT, j]
            work[_ZETA, active] = cell[CELL_ZETA]
            active += 1
    return active


@kernel
def first_impact_time(cell, table, geo, t_max, t_start, work, force, rotor):
    """Time (s) of the first gap closure in (0, t_max] for one cell, NaN if none.

    ``table``: the free-phase table of the cell's geometry; ``geo``: its geometry row;
    ``t_start``: a time before which the gap is known to stay open (0 if none, see
    ``_column``); ``work`` (rows ``_WORK_ROWS``) and the complex ``force``: scratch per mode,
    reused across cells (no heap allocation per cell: allocations serialise threads).
    Returns ``events.GAVE_UP`` (-inf) if the search reached its step cap.
    """
    active = _load_moving_modes(cell, table, work, force, geo[GEO_START])
    q_s, v_s = work[_Q_S, :active], work[_V_S, :active]
    sine = gap_harmonic(cell, geo)
    if sine == 0.0 and q_s[0] == 0.0 and v_s[0] == 0.0 and force[0] == 0 and active == 1:
        return np.nan  # nothing moves: the gap stays open
    frequencies = work[_FREQUENCY, :active]
    oscillators = Oscillators(frequencies, work[_ZETA, :active], force[:active],
                              cell[CELL_FORCING_FREQUENCY])
    gap = EventFunction(work[_WEIGHTS, :active], cell[CELL_CLEARANCE],
                        complex(sine, 0.0),
                        cell[CELL_FORCING_FREQUENCY])
    return search_root(q_s, v_s, 0.0, t_start, t_max, oscillators, gap, TOUCH_TOLERANCE,
                       step_limit(0.0, t_max, frequencies), work[_Q, :active], work[_V, :active],
                       rotor)


@kernel
def _uplift_stays_below_clearance(cell, table):
    """Whether clearance + u(t) > 0 for all t, u the unforced response to the uplifts.

    Each mode's free motion from rest at q0 has amplitude at most |q0| / sqrt(1 - zeta^2).
    """
    reach = 0.0
    for j in range(table.shape[1]):
        q0 = cell[CELL_UPLIFT1] * table[ROW_UNIT1, j] + cell[CELL_UPLIFT2] * table[ROW_UNIT2, j]
        reach += abs(table[ROW_EVENT, j] * q0) / np.sqrt(1.0 - cell[CELL_ZETA]**2)
    return cell[CELL_CLEARANCE] - reach > 0.0


@kernel
def _walk_order(cells, lo, hi, key, table):
    """Cells lo..hi-1 of a column in order of non-decreasing first impact time, or none.

    Returns ``(first, stride)``, the walk being first, first + stride, ...; stride 0 when the
    column cannot be ordered (each cell is then searched from t = 0). Along the clearance the
    gap is ``clearance + (a response shared by the column)``: it closes later (or never) for a
    larger clearance. Along F0 with U0 = 0 (along U0 with F0 = 0 likewise) it is
    ``clearance + u(t) - F0 h(t)``: if clearance + u > 0 throughout, it closes where
    ``F0 >= (clearance + u) / h``, later for a smaller F0. With both drives the other one's
    response is not bounded here: no order.
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
    other_drive = base_amplitude(cells[lo]) if key == CELL_F0 else cells[lo, CELL_F0]
    if (other_drive != 0.0 or min(cells[lo, key], cells[hi - 1, key]) < 0.0
            or not _uplift_stays_below_clearance(cells[lo], table)):
        return lo, 0
    return (hi - 1, -1) if rising else (lo, 1)


@kernel
def _shared_column(cells, first, stride, count, key, table, geo, t_max, work, force, rotor,
                   out):
    """One column whose cells share one modal response; walked once, level by level.

    Along the clearance the gap is ``clearance + phi(t)``, phi the response of the column's
    forcing and uplifts; along F0 without uplifts or base drive it is
    ``F0 (clearance / F0 + phi(t))``, phi the response to F0 = 1 N (along U0 without uplifts or
    tip force likewise, phi the response to U0 = 1 m). The bounds of phi serve every cell; each
    cell's search starts at the previous cell's impact, with its own level.
    """
    source = cells[first].copy()
    if key != CELL_CLEARANCE:
        source[key] = 1.0
    active = _load_moving_modes(source, table, work, force, geo[GEO_START])
    q_s, v_s, frequencies = work[_Q_S, :active], work[_V_S, :active], work[_FREQUENCY, :active]
    forcing_frequency = source[CELL_FORCING_FREQUENCY]
    oscillators = Oscillators(frequencies, work[_ZETA, :active], force[:active],
                              forcing_frequency)
    weights = work[_WEIGHTS, :active]
    split = split_steady_states(q_s, v_s, 0.0, oscillators, EventFunction(
        weights, 0.0, complex(gap_harmonic(source, geo), 0.0), forcing_frequency))
    bounds = phase_bounds(q_s, v_s, 0.0, t_max, oscillators, split)
    max_steps = step_limit(0.0, t_max, frequencies)
    t_start, t_state = 0.0, np.nan
    i = first
    for _ in range(count):
        if np.isnan(t_start):
            out[i] = np.nan
        else:
            level = cells[i, CELL_CLEARANCE]
            if key != CELL_CLEARANCE:
                level /= cells[i, key]
            gap = EventFunction(weights, level, split.sine_amp, forcing_frequency)
            out[i], t_state = walk(q_s, v_s, 0.0, t_start, t_max, oscillators, gap,
                                   TOUCH_TOLERANCE, max_steps, bounds, t_state, work[_Q, :active],
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
    table, geo = tables[g, FREE], geometry[g]
    i, stride = _walk_order(cells, lo, hi, key, table)
    shared = key == CELL_CLEARANCE or (cells[lo, CELL_UPLIFT1] == 0.0
                                       and cells[lo, CELL_UPLIFT2] == 0.0
                                       and min(cells[lo, key], cells[hi - 1, key]) > 0.0)
    if stride != 0 and shared:
        _shared_column(cells, i, stride, hi - lo, key, table, geo, t_max, work, force, rotor,
                       out)
        return
    t_start = 0.0
    for _ in range(hi - lo):
        if np.isnan(t_start):
            out[i] = np.nan
        else:
            out[i] = first_impact_time(cells[i], table, geo, t_max, t_start, work, force,
                                       rotor)
            if stride != 0:
                t_start = 0.0 if out[i] == GAVE_UP else out[i]  # NaN ends the column
        i = i + stride if stride != 0 else i + 1


_BLOCK = 256  # cells per unit of parallel work: scratch allocated once per block


def _first_impact_map(cells, columns, key, tables, geometry, t_max, out):
    """Fill out[i] with the first impact time of cells[i], column by column.

    Column c is ``cells[columns[c]:columns[c + 1]]``, cells that differ in column ``key`` of
    ``CELL_COLUMNS`` alone (``CELL_F0``, ``CELL_U0`` or ``CELL_CLEARANCE``, axes in which the
    gap is affine);
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
        out[i] = first_impact_time(cells[i], tables[g, FREE], geometry[g], t_max, 0.0,
                                   work, force, rotor)
