"""Time to first impact: the free phase only, stopped at the first gap closure.

Plain-array interface, packed by :mod:`impactbeams.packing` (names in
:mod:`impactbeams.kernels.layout`): ``cells[i]`` with columns ``CELL_COLUMNS``;
``tables[g, FREE]`` the free-phase table of geometry g (rows ``TABLE_ROWS``; its ``event`` row
is the gap weight ``Y_1n(l1) - Y_2n(l2)``); ``geometry[g]`` with fields ``GEOMETRY``.

A cell's gap is ``g(t) = clearance - c_1 F(t) + sum_n event_n q_n(t)``, from the initial state
of docs/model.md (at rest in the uplift shape, :func:`~impactbeams.kernels.forcing.rest_state`),
with each mode driven by ``b_n (F'' + 2 zeta omega_n F')`` (modal damping of the whole
coordinate).
"""

import numpy as np
from numba import prange

from impactbeams.kernels.events import first_root
from impactbeams.kernels.forcing import rest_state
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import (
    CELL_CLEARANCE,
    CELL_F0,
    CELL_GEOMETRY,
    CELL_OMEGA,
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

# rows of the per-mode scratch of the moving modes (private to this kernel)
_WORK_ROWS = ("q_s", "v_s", "omega", "zeta", "weights", "q", "v")
_Q_S, _V_S, _OMEGA, _ZETA, _WEIGHTS, _Q, _V = range(len(_WORK_ROWS))


@kernel
def first_impact_time(cell, table, c1, t_max, work, force):
    """Time (s) of the first gap closure in (0, t_max] for one cell, NaN if none.

    ``table``: the free-phase table of the cell's geometry; ``c1``: beam 1's tip compliance
    (m/N); ``work`` (rows ``_WORK_ROWS``) and the complex ``force``: scratch per mode, reused
    across cells (no heap allocation per cell: allocations serialise threads).
    """
    q_s, v_s, omega, zeta, weights = work[_Q_S], work[_V_S], work[_OMEGA], work[_ZETA], \
        work[_WEIGHTS]
    force_amplitude, forcing_frequency = cell[CELL_F0], cell[CELL_OMEGA]
    # keep only the modes that move: beam 2 rests unless uplifted, so its modes drop out
    active = 0
    last = table.shape[1] - 1
    for j in range(table.shape[1]):
        q0, v0 = rest_state(cell, table[ROW_UNIT1, j], table[ROW_UNIT2, j], table[ROW_DRIVE, j])
        f = drive_amplitude(table[ROW_DRIVE, j], table[ROW_OMEGA, j], cell[CELL_ZETA],
                            force_amplitude, forcing_frequency)
        if q0 != 0.0 or v0 != 0.0 or f != 0 or (j == last and active == 0):
            q_s[active], v_s[active], force[active] = q0, v0, f
            omega[active], weights[active] = table[ROW_OMEGA, j], table[ROW_EVENT, j]
            zeta[active] = cell[CELL_ZETA]
            active += 1
    if force_amplitude == 0.0 and q_s[0] == 0.0 and v_s[0] == 0.0 and active == 1:
        return np.nan  # nothing moves: the gap stays open
    return first_root(q_s[:active], v_s[:active], 0.0, t_max, omega[:active], zeta[:active],
                      force[:active], weights[:active], cell[CELL_CLEARANCE],
                      -c1 * force_amplitude, forcing_frequency, work[_Q, :active],
                      work[_V, :active])


_BLOCK = 256  # cells per unit of parallel work: scratch allocated once per block


def _first_impact_map(cells, tables, geometry, t_max, out):
    """Fill out[i] with the first impact time of cells[i]; each iteration owns its cells.

    Block b takes cells b, b + n_blocks, b + 2 n_blocks, ...: interleaved, so that the costly
    regions of a grid (near resonances and the no-impact boundary) are shared evenly between
    the threads of prange's static schedule.
    """
    n_cells = cells.shape[0]
    n_blocks = (n_cells + _BLOCK - 1) // _BLOCK
    for block in prange(n_blocks):
        work = np.empty((len(_WORK_ROWS), tables.shape[3]))
        force = np.empty(tables.shape[3], dtype=np.complex128)
        for i in range(block, n_cells, n_blocks):
            g = int(cells[i, CELL_GEOMETRY])
            out[i] = first_impact_time(cells[i], tables[g, FREE], geometry[g, GEO_C1], t_max,
                                       work, force)


first_impact_map_parallel, first_impact_map_serial = parallel_kernel(_first_impact_map)
