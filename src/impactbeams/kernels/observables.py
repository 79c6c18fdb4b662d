"""Per-cell observables of the full impact dynamics over [0, t_max], for sweeps.

Plain-array interface, packed by `impactbeams.packing` per geometry g (names in
`impactbeams.kernels.layout`): ``tables[g]`` the phase tables of both phases, ``switching``
the geometries' switching records stacked field by field (`packing.stacked_switching`;
geometry g's is `records.geometry_switching`, its drives empty), ``geometry[g]`` with fields
``GEOMETRY``; ``cells[i]`` with columns ``CELL_COLUMNS``. Each cell's run inputs come from
`cells.cell_run` (as for one simulated run), its observables (``OUT_COLUMNS``) from
`summarize_run`; a status other than 0 (complete) means they cover [0, t_end] only.
"""

from numba import prange

from impactbeams.kernels.cells import cell_run, settings_of
from impactbeams.kernels.dynamics import run_events
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import CELL_GEOMETRY
from impactbeams.kernels.records import geometry_switching, recorded_prefix, segments
from impactbeams.kernels.reductions import summarize_run


@kernel
def cell_observables(cell, tables, switching, geometry, t_max, max_segments, out):
    """Run one cell's dynamics (at most ``max_segments`` phases) and write its OUT_COLUMNS.

    ``switching``: the geometry's switching record (`records.SWITCHING`; the run's drives
    come from the cell).
    """
    _observe(cell_run(cell, tables, geometry, switching, t_max, t_max), max_segments, out)


@kernel
def _observe(run, max_segments, out):
    """``cell_observables`` of the cell's `RunInputs` ``run``."""
    settings = settings_of(run)
    recorded = segments(max_segments, run.q0.size)
    count, status, t_end = run_events(run.tables, run.forces, run.phase_scalars, run.switching,
                                      settings, run.q0, run.v0, recorded)
    summarize_run(run.tables, run.forces, run.phase_scalars, settings,
                  recorded_prefix(recorded, count), status, t_end, out)


def _observables_map(cells, tables, switching, geometry, t_max, max_segments, out):
    """Fill out[i, :] with the observables of cells[i]; each iteration owns row i."""
    for i in prange(cells.shape[0]):
        g = int(cells[i, CELL_GEOMETRY])
        cell_observables(cells[i], tables[g], geometry_switching(switching, g), geometry[g],
                         t_max, max_segments, out[i])


observables_map_parallel, observables_map_serial = parallel_kernel(_observables_map)
