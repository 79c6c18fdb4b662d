"""A run's inputs that depend on its cell (forcing, damping, clearance, uplifts): one formula each.

Called by `impactbeams.packing` for one run (`run_inputs` on a cell row packed from
the parameters) and by the map kernels for each cell of a grid, so that a sweep cell and a
simulated run with the same parameters get the same bits. Arrays and fields are named in
`impactbeams.kernels.layout`; SI units.
"""

import numpy as np

from impactbeams.kernels.contact import keeps_free_coordinates
from impactbeams.kernels.contact_spring import spring_drives
from impactbeams.kernels.drive import (
    base_amplitude,
    gap_harmonic,
    mode_drives,
    rest_velocity,
    steady_state,
)
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import (
    CELL_CLEARANCE,
    CELL_F0,
    CELL_FORCING_FREQUENCY,
    CELL_UPLIFT1,
    CELL_UPLIFT2,
    CELL_ZETA,
    CONTACT,
    DRIVE_EQUILIBRIUM,
    FREE,
    GEO_ACCUMULATION,
    GEO_C1,
    GEO_C2,
    GEO_DAMPING,
    GEO_LAW,
    GEO_RESIDUAL1,
    GEO_RESIDUAL2,
    GEO_SHAKER1,
    GEO_SHAKER2,
    GEO_SIDE,
    GEO_START,
    GEO_STIFFNESS,
    PHASE_SCALARS,
    ROW_BASE,
    ROW_DRIVE,
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_UNIT1,
    ROW_UNIT2,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_LOAD_RATE,
    SCALAR_SINE,
    SETTINGS_DTYPE,
    SPRING_DRIVE_ROWS,
    STEADY,
)
from impactbeams.kernels.records import SWITCH_OVERLAP, SWITCH_SHIFTS, SWITCH_SPRING


@kernel
def rest_state(cell, start, unit1, unit2, drive, base, force, frequencies, zeta):
    """A mode's initial state (q, q') (docs/model.md), with the uplifts added to either start.

    ``start`` (``layout.STARTS``): ``REST``, at rest in the absolute frame (``rest_velocity``),
    or ``STEADY``, on the no-contact steady response to every drive; the uplifts add
    ``q = delta_1 <u_1, Y> + delta_2 <u_2, Y>``. ``unit1``, ``unit2``, ``drive``, ``base``,
    ``frequencies``, ``zeta``: the mode's free-phase table entries; ``force``: its drive amplitude.
    """
    q = cell[CELL_UPLIFT1] * unit1 + cell[CELL_UPLIFT2] * unit2
    if start == STEADY:
        q_steady, v_steady = steady_state(force, frequencies, zeta, cell[CELL_FORCING_FREQUENCY])
        return q + q_steady, v_steady
    return q, rest_velocity(cell, drive, base)


@kernel
def rest_states(cell, geometry, table, force):
    """``rest_state`` of every mode of a free-phase ``table`` (zeta already the cell's)."""
    q0, v0 = np.empty(force.size), np.empty(force.size)
    for j in range(force.size):
        q0[j], v0[j] = rest_state(cell, geometry[GEO_START], table[ROW_UNIT1, j],
                                  table[ROW_UNIT2, j], table[ROW_DRIVE, j], table[ROW_BASE, j],
                                  force[j], table[ROW_FREQUENCY, j], table[ROW_ZETA, j])
    return q0, v0


@kernel
def phase_scalars(cell, geometry):
    """``PHASE_SCALARS`` of both phases: the event functions' constants and load rates.

    Free: ``g = clearance + S sin(Omega t) + ...`` (``drive.gap_harmonic``); tied contact:
    ``R = -(clearance + S sin(Omega t)) / (c1 + c2) + ...``, with the tip force alone
    ``(c1 F - clearance) / (c1 + c2)``.
    """
    clearance = cell[CELL_CLEARANCE]
    c1, c2 = geometry[GEO_C1], geometry[GEO_C2]
    total = c1 + c2
    sine = gap_harmonic(cell, geometry)
    out = np.empty((2, len(PHASE_SCALARS)))
    out[FREE, SCALAR_CONST] = clearance
    out[FREE, SCALAR_SINE] = sine
    out[FREE, SCALAR_COSINE] = 0.0
    out[FREE, SCALAR_LOAD_RATE] = 1.0
    out[CONTACT, SCALAR_CONST] = -clearance / total
    out[CONTACT, SCALAR_SINE] = -sine / total
    out[CONTACT, SCALAR_COSINE] = 0.0
    out[CONTACT, SCALAR_LOAD_RATE] = c2 / total
    return out


@kernel
def settings(cell, geometry, t_max, search_span):
    """The run's settings as a one-element array of ``SETTINGS_DTYPE`` (t_max, search_span in s).

    The kernels take its element, a record read by field name.
    """
    out = np.empty(1, dtype=SETTINGS_DTYPE)
    record = out[0]
    record.clearance = cell[CELL_CLEARANCE]
    record.c1 = geometry[GEO_C1]
    record.c2 = geometry[GEO_C2]
    record.force_amplitude = cell[CELL_F0]
    record.forcing_frequency = cell[CELL_FORCING_FREQUENCY]
    record.t_max = t_max
    record.search_span = search_span
    record.accumulation = geometry[GEO_ACCUMULATION]
    record.contact_law = geometry[GEO_LAW]
    record.contact_stiffness = geometry[GEO_STIFFNESS]
    record.contact_damping = geometry[GEO_DAMPING]
    record.residual1 = geometry[GEO_RESIDUAL1]
    record.residual2 = geometry[GEO_RESIDUAL2]
    record.side = geometry[GEO_SIDE]
    record.base_amplitude = base_amplitude(cell)
    record.shaker1 = geometry[GEO_SHAKER1]
    record.shaker2 = geometry[GEO_SHAKER2]
    return out


@kernel
def spring_contact_inputs(cell, tables, geometry, switching, forces, scalars):
    """The spring law's per-run contact phase: oscillator drives, event scalars, mode drives.

    Writes the oscillators' drive amplitudes into ``forces[CONTACT]`` and the contact force's
    constant and harmonic parts into ``scalars[CONTACT]``; returns the complex modes' drives
    (rows ``SPRING_DRIVE_ROWS``). With the gap weights w and the gap's harmonic term S
    (``scalars[FREE]``), the contact phase's modal drive is the free one plus
    ``-S (k_e + i c_e Omega) w`` (harmonic) and ``-k_e clearance w``; ``switching``: the
    geometry's switching record (`records.SWITCHING`), whose spring arrays the drives are of.
    """
    left, _, modes = switching[SWITCH_SPRING]
    weights = tables[FREE, ROW_EVENT]
    stiffness, damping = geometry[GEO_STIFFNESS], geometry[GEO_DAMPING]
    forcing_frequency = cell[CELL_FORCING_FREQUENCY]
    harmonic = -scalars[FREE, SCALAR_SINE] * complex(stiffness, damping * forcing_frequency)
    drives = spring_drives(left, modes, forces[FREE] + harmonic * weights,
                           -stiffness * cell[CELL_CLEARANCE] * weights, forcing_frequency,
                           forces[CONTACT])
    force_weights = tables[CONTACT, ROW_EVENT]
    constant = -stiffness * cell[CELL_CLEARANCE]
    for j in range(force_weights.size):
        constant += force_weights[j] * drives[DRIVE_EQUILIBRIUM, j].real
    scalars[CONTACT, SCALAR_CONST] = constant
    scalars[CONTACT, SCALAR_SINE] = harmonic.real
    scalars[CONTACT, SCALAR_COSINE] = harmonic.imag
    scalars[CONTACT, SCALAR_LOAD_RATE] = 1.0
    return drives


@kernel
def run_inputs(cell, tables, geometry, switching, t_max, search_span):
    """Everything the dynamics kernel needs for one run of ``cell`` in its geometry.

    Returns (tables with the cell's damping ratios added to the modes' own, complex drive
    amplitudes ``forces``,
    phase scalars, settings, q0, q0', the run's switching record: the geometry's
    ``switching`` with the spring law's mode drives); ``tables`` of the geometry is left
    unchanged. In the spring law the contact oscillators' damping ratios come with the
    geometry's spring modes (solved for the cell's damping ratio).
    """
    spring_law = keeps_free_coordinates(geometry[GEO_LAW])
    damped = tables.copy()
    forces = np.empty((tables.shape[0], tables.shape[2]), dtype=np.complex128)
    scalars = phase_scalars(cell, geometry)
    for phase in range(tables.shape[0]):
        if phase == CONTACT and spring_law:
            continue
        # the modes' own damping ratios (a user structure's, else 0) plus the cell's, mode by
        # mode: an array assigned to the row would compile Numba's string formatting
        for j in range(tables.shape[2]):
            damped[phase, ROW_ZETA, j] = tables[phase, ROW_ZETA, j] + cell[CELL_ZETA]
        mode_drives(damped[phase, ROW_DRIVE], damped[phase, ROW_BASE],
                    damped[phase, ROW_FREQUENCY], damped[phase, ROW_ZETA], cell, forces[phase])
    if spring_law:
        drives = spring_contact_inputs(cell, damped, geometry, switching, forces, scalars)
    else:
        drives = np.empty((len(SPRING_DRIVE_ROWS), 0), dtype=np.complex128)
    q0, v0 = rest_states(cell, geometry, damped[FREE], forces[FREE])
    return (damped, forces, scalars, settings(cell, geometry, t_max, search_span), q0, v0,
            (switching[SWITCH_OVERLAP], switching[SWITCH_SHIFTS], switching[SWITCH_SPRING], drives))
