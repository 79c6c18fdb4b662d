"""Time to first impact: the free phase only, stopped at the first gap closure.

Plain-array interface, packed by :mod:`impactbeams.sweep`:

* ``cells[i]`` = (clearance m, force_amplitude N, omega rad/s, uplift1 m, uplift2 m,
  damping_ratio, geometry index) -- see ``CELL_COLUMNS``;
* ``tables[g]`` = rows ``TABLE_ROWS`` over the 2 n free coordinates of geometry g: natural
  frequency (rad/s), gap weight ``Y_1n(l1)`` / ``-Y_2n(l2)``, drive ``b_n`` with
  ``q_n'' + omega_n^2 q_n = b_n F''``, uplift projections ``<u_1, Y_n>``, ``<u_2, Y_n>``;
* ``compliance[g]`` = c_1 = l_1^3 / (3 EI_1) (m/N).

A cell's gap is ``g(t) = clearance - c_1 F(t) + sum_n gap_weight_n q_n(t)``, with the initial
state of MODEL.md (at rest in the uplift shape): ``q_n(0) = delta_i <u_i, Y_n>``,
``q_n'(0) = F0 Omega b_n``.
"""

import numpy as np
from numba import prange

from impactbeams.kernels.events import first_root
from impactbeams.kernels.jit import kernel, parallel_kernel

CELL_COLUMNS = ("clearance", "force_amplitude", "omega", "uplift1", "uplift2", "damping_ratio",
                "geometry")
TABLE_ROWS = ("omega", "gap_weight", "drive", "unit1", "unit2")


@kernel
def first_impact_time(cell, table, compliance, t_max):
    """Time (s) of the first gap closure in (0, t_max] for one cell, NaN if none."""
    clearance, force_amplitude, forcing_frequency = cell[0], cell[1], cell[2]
    uplift1, uplift2, zeta = cell[3], cell[4], cell[5]
    omega, weights, drive = table[0], table[1], table[2]
    q_all = uplift1 * table[3] + uplift2 * table[4]
    v_all = force_amplitude * forcing_frequency * drive
    f_all = -forcing_frequency * forcing_frequency * force_amplitude * drive
    active = np.nonzero((q_all != 0.0) | (v_all != 0.0) | (f_all != 0.0))[0]
    if active.size == 0 and force_amplitude == 0.0:
        return np.nan  # nothing moves: the gap stays open
    if active.size == 0:  # only the quasi-static term moves; keep one idle mode for the bounds
        active = np.zeros(1, dtype=np.int64)
    q = np.empty(active.size)
    v = np.empty(active.size)
    return first_root(q_all[active], v_all[active], 0.0, t_max, omega[active], zeta,
                      f_all[active], weights[active], clearance, -compliance * force_amplitude,
                      forcing_frequency, q, v)


def _first_impact_map(cells, tables, compliance, t_max, out):
    """Fill out[i] with the first impact time of cells[i]; each iteration owns out[i]."""
    for i in prange(cells.shape[0]):
        g = int(cells[i, 6])
        out[i] = first_impact_time(cells[i], tables[g], compliance[g], t_max)


first_impact_map_parallel, first_impact_map_serial = parallel_kernel(_first_impact_map)
