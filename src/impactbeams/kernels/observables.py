"""Per-cell observables of the full impact dynamics over [0, t_max], for sweeps.

Plain-array interface, packed by `impactbeams.packing` per geometry g (names in
`impactbeams.kernels.layout`): ``tables[g]`` the phase tables of both phases,
``overlaps[g]`` = <Z_m, Y_n>, ``shifts[g]`` the static shifts of both phases (tied law),
``spring_left[g]``, ``spring_right[g]``, ``spring_modes[g]`` (spring law; see
`impactbeams.kernels.contact_spring`), ``geometry[g]`` with fields ``GEOMETRY``; ``cells[i]`` with
columns ``CELL_COLUMNS``. Each cell's run inputs come from
`cells.cell_run` (as for one simulated run), its observables
(``OUT_COLUMNS``) from `summarize_run`; a status other
than 0 (complete) means they cover [0, t_end] only.
"""

from numba import prange

from impactbeams.kernels.cells import cell_run, settings_of
from impactbeams.kernels.dynamics import run_events
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import CELL_GEOMETRY
from impactbeams.kernels.records import recorded_prefix, segments
from impactbeams.kernels.reductions import summarize_run


@kernel
def cell_observables(cell, tables, overlap, shifts, spring, geometry, t_max, max_segments, out):
    """Run one cell's dynamics (at most ``max_segments`` phases) and write its OUT_COLUMNS."""
    _observe(cell_run(cell, tables, geometry, spring, t_max, t_max), overlap, shifts, spring,
             max_segments, out)


@kernel
def _observe(run, overlap, shifts, spring, max_segments, out):
    """``cell_observables`` of the cell's `RunInputs` ``run``."""
    settings = settings_of(run)
    recorded = segments(max_segments, run.q0.size)
    count, status, t_end = run_events(run.tables, run.forces, run.phase_scalars, overlap, shifts,
                                      spring, run.drives, settings, run.q0, run.v0, recorded)
    summarize_run(run.tables, run.forces, run.phase_scalars, settings,
                  recorded_prefix(recorded, count), status, t_end, out)


def _observables_map(cells, tables, overlaps, shifts, spring_left, spring_right, spring_modes,
                     geometry, t_max, max_segments, out):
    """Fill out[i, :] with the observables of cells[i]; each iteration owns row i."""
    for i in prange(cells.shape[0]):
        g = int(cells[i, CELL_GEOMETRY])
        spring = (spring_left[g], spring_right[g], spring_modes[g])
        cell_observables(cells[i], tables[g], overlaps[g], shifts[g], spring, geometry[g],
                         t_max, max_segments, out[i])


observables_map_parallel, observables_map_serial = parallel_kernel(_observables_map)
