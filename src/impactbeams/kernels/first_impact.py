"""Time to first impact: the free phase only, stopped at the first gap closure.

Plain-array interface, packed by :mod:`impactbeams.sweep`:

* ``cells[i]`` = (clearance m, force_amplitude N, omega rad/s, uplift1 m, uplift2 m,
  damping_ratio, geometry index) -- see ``CELL_COLUMNS``;
* ``tables[g]`` = rows ``TABLE_ROWS`` over the 2 n free coordinates of geometry g: natural
  frequency (rad/s), gap weight ``Y_1n(l1)`` / ``-Y_2n(l2)``, drive ``b_n`` with
  ``q_n'' + 2 zeta omega_n q_n' + omega_n^2 q_n = b_n (F'' + 2 zeta omega_n F')`` (modal
  damping of each mode's whole coordinate), uplift projections ``<u_1, Y_n>``, ``<u_2, Y_n>``;
* ``compliance[g]`` = c_1 = l_1^3 / (3 EI_1) (m/N).

A cell's gap is ``g(t) = clearance - c_1 F(t) + sum_n gap_weight_n q_n(t)``, with the initial
state of MODEL.md (at rest in the uplift shape): ``q_n(0) = delta_i <u_i, Y_n>``,
``q_n'(0) = F0 Omega b_n``.
"""

import numpy as np
from numba import prange

from impactbeams.kernels.events import first_root
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.propagation import drive_amplitude

CELL_COLUMNS = ("clearance", "force_amplitude", "omega", "uplift1", "uplift2", "damping_ratio",
                "geometry")
TABLE_ROWS = ("omega", "gap_weight", "drive", "unit1", "unit2")


@kernel
def first_impact_time(cell, table, compliance, t_max, work, force):
    """Time (s) of the first gap closure in (0, t_max] for one cell, NaN if none.

    ``work``: scratch array of shape (8, modes), ``force``: complex scratch of shape (modes,),
    reused across cells (no heap allocation per cell: allocations serialise threads).
    """
    clearance, force_amplitude, forcing_frequency = cell[0], cell[1], cell[2]
    uplift1, uplift2, damping_ratio = cell[3], cell[4], cell[5]
    q_s, v_s, omega, zeta, weights, q, v = work[0], work[1], work[2], work[3], work[4], \
        work[5], work[6]
    # keep only the modes that move: beam 2 rests unless uplifted, so its modes drop out
    active = 0
    for j in range(table.shape[1]):
        q0 = uplift1 * table[3, j] + uplift2 * table[4, j]
        v0 = force_amplitude * forcing_frequency * table[2, j]
        f = drive_amplitude(table[2, j], table[0, j], damping_ratio, force_amplitude,
                            forcing_frequency)
        if q0 != 0.0 or v0 != 0.0 or f != 0 or (j == table.shape[1] - 1 and active == 0):
            q_s[active], v_s[active], force[active] = q0, v0, f
            omega[active], weights[active] = table[0, j], table[1, j]
            zeta[active] = damping_ratio
            active += 1
    if force_amplitude == 0.0 and q_s[0] == 0.0 and v_s[0] == 0.0 and active == 1:
        return np.nan  # nothing moves: the gap stays open
    return first_root(q_s[:active], v_s[:active], 0.0, t_max, omega[:active], zeta[:active],
                      force[:active], weights[:active], clearance,
                      -compliance * force_amplitude, forcing_frequency, q[:active], v[:active])


_BLOCK = 256  # cells per unit of parallel work: scratch allocated once per block


def _first_impact_map(cells, tables, compliance, t_max, out):
    """Fill out[i] with the first impact time of cells[i]; each iteration owns its cells.

    Block b takes cells b, b + n_blocks, b + 2 n_blocks, ...: interleaved, so that the costly
    regions of a grid (near resonances and the no-impact boundary) are shared evenly between
    the threads of prange's static schedule.
    """
    n_cells = cells.shape[0]
    n_blocks = (n_cells + _BLOCK - 1) // _BLOCK
    for block in prange(n_blocks):
        work = np.empty((8, tables.shape[2]))
        force = np.empty(tables.shape[2], dtype=np.complex128)
        for i in range(block, n_cells, n_blocks):
            g = int(cells[i, 6])
            out[i] = first_impact_time(cells[i], tables[g], compliance[g], t_max, work, force)


first_impact_map_parallel, first_impact_map_serial = parallel_kernel(_first_impact_map)
