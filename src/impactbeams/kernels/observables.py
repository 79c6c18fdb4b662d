"""Per-cell observables of the full impact dynamics over [0, t_max], for sweeps.

Plain-array interface, packed by :mod:`impactbeams.sweep` per geometry g:

* ``tables[g]``: rows as in :mod:`impactbeams.kernels.dynamics` for both phases (the damping
  ratio row and the complex drive amplitudes are filled here for each cell);
* ``overlaps[g]`` = <Z_m, Y_n>; ``shifts[g]`` = static shifts of both phases;
* ``units[g]`` = (<u_1, Y_n>, <u_2, Y_n>) of the free phase;
* ``geometry[g]`` = (c1 m/N, c2 m/N, accumulation time s).

``cells[i]`` as in :mod:`impactbeams.kernels.first_impact`. Output columns ``OUT_COLUMNS``:
first impact time (s, NaN if none), number of impacts (contact onsets), largest contact
force (N, 0 if no impact), mean coefficient of restitution (NaN if no impact separated),
fraction of [0, t_max] in contact, and the run status (0 complete, 1 event limit,
2 stuck: observables then cover [0, t_end] only).
"""


import numpy as np
from numba import prange

from impactbeams.kernels.dynamics import (
    CONTACT,
    ROW_DRIVE,
    ROW_EVENT,
    ROW_OMEGA,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_SINE,
    peak_force,
    run_events,
)
from impactbeams.kernels.events import event_value
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.propagation import drive_amplitudes

OUT_COLUMNS = ("first_impact_time", "impact_count", "max_contact_force", "mean_restitution",
               "contact_fraction", "dynamics_status")


@kernel
def _cell_setup(cell, tables, units, geometry, t_max):
    """The dynamics kernel's tables, drives, phase scalars, settings and initial state."""
    clearance, force_amplitude, forcing_frequency = cell[0], cell[1], cell[2]
    c1, c2, accumulation = geometry[0], geometry[1], geometry[2]
    total = c1 + c2
    local = tables.copy()
    forces = np.empty((2, tables.shape[2]), dtype=np.complex128)
    for phase in range(2):
        local[phase, ROW_ZETA] = cell[5]
        forces[phase] = drive_amplitudes(tables[phase, ROW_DRIVE], tables[phase, ROW_OMEGA],
                                         local[phase, ROW_ZETA], force_amplitude,
                                         forcing_frequency)
    scalars = np.array([[clearance, -c1 * force_amplitude, 1.0],
                        [-clearance / total, c1 * force_amplitude / total, c2 / total]])
    settings = np.array([clearance, c1, c2, force_amplitude, forcing_frequency, t_max, t_max,
                         accumulation])
    q0 = cell[3] * units[0] + cell[4] * units[1]
    v0 = force_amplitude * forcing_frequency * tables[0, ROW_DRIVE]
    return local, forces, scalars, settings, q0, v0


@kernel
def _gap_rate(table, scalars, q, v, t, forcing_frequency):
    """dg/dt (m/s) of the free phase at time t from its modal state."""
    _, slope = event_value(q, v, t, table[ROW_EVENT], scalars[SCALAR_CONST],
                           scalars[SCALAR_SINE], forcing_frequency)
    return slope


@kernel
def cell_observables(cell, tables, overlap, shifts, units, geometry, t_max, max_segments, out):
    """Run one cell's dynamics and write its OUT_COLUMNS into ``out``."""
    local, forces, scalars, settings, q0, v0 = _cell_setup(cell, tables, units, geometry, t_max)
    n = q0.size
    seg_time = np.empty(max_segments)
    seg_phase = np.empty(max_segments, dtype=np.int64)
    seg_sustained = np.empty(max_segments, dtype=np.bool_)
    seg_q, seg_v = np.empty((max_segments, n)), np.empty((max_segments, n))
    end_q, end_v = np.empty((max_segments, n)), np.empty((max_segments, n))
    count, status, t_end = run_events(local, forces, scalars, overlap, shifts, settings, q0, v0,
                                      seg_time, seg_phase, seg_sustained, seg_q, seg_v,
                                      end_q, end_v)
    impacts, in_contact, largest = 0, 0.0, 0.0
    separation_sum, approach_sum = 0.0, 0.0
    forcing_frequency = cell[2]
    for k in range(count):
        if seg_phase[k] != CONTACT:
            continue
        impacts += 1
        t_start = seg_time[k]
        t_stop = seg_time[k + 1] if k + 1 < count else t_end
        in_contact += t_stop - t_start
        force, _ = peak_force(local[CONTACT], forces[CONTACT], scalars[CONTACT], settings,
                              seg_q[k], seg_v[k], t_start, t_stop)
        largest = max(largest, force)
        if k + 1 < count and k >= 1:
            onset = _gap_rate(local[0], scalars[0], end_q[k - 1], end_v[k - 1], t_start,
                              forcing_frequency)
            release = _gap_rate(local[0], scalars[0], seg_q[k + 1], seg_v[k + 1], t_stop,
                                forcing_frequency)
            if onset < 0.0:
                separation_sum += release
                approach_sum -= onset
    out[0] = seg_time[1] if count > 1 else np.nan
    out[1] = impacts
    out[2] = largest
    # approach-speed-weighted mean, sum(-dg/dt at separation) / sum(dg/dt at onset): impacts
    # with a near-zero approach speed (whose own ratio e is a truncation artefact, any size)
    # barely count
    out[3] = separation_sum / approach_sum if approach_sum > 0.0 else np.nan
    out[4] = in_contact / t_max
    out[5] = status


def _observables_map(cells, tables, overlaps, shifts, units, geometry, t_max, max_segments,
                     out):
    """Fill out[i, :] with the observables of cells[i]; each iteration owns row i."""
    for i in prange(cells.shape[0]):
        g = int(cells[i, 6])
        cell_observables(cells[i], tables[g], overlaps[g], shifts[g], units[g], geometry[g],
                         t_max, max_segments, out[i])


observables_map_parallel, observables_map_serial = parallel_kernel(_observables_map)
