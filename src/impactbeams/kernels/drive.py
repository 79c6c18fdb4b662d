"""The drive: every load of a run, evaluated in one place (docs/model.md, "Base excitation").

Two drives act at the forcing frequency Omega, alone or together (superposition):

* the tip force ``F(t) = F0 sin(Omega t)`` on beam 1, counted downward; the modes carry the
  remainder of its quasi-static split, driven by ``b (F'' + 2 zeta omega F')``;
* base (shaker) excitation: the clamps that the shaker carries move as
  ``u_b(t) = U0 sin(Omega t)``; in the relative coordinates ``w = y - u_b`` each mode of a
  moving clamp's beam is driven by ``-Gamma_n u_b'' = Gamma_n U0 Omega^2 sin(Omega t)``.

Both enter every mode as ``Im(A e^(i Omega t))`` (``mode_drive``) and the gap as an explicit
harmonic term ``S sin(Omega t)``,
``S = s U0 ([beam 1 moves] - [beam 2 moves]) - s G1(x1, l1) F0`` (``gap_harmonic``; s the
contact's side, x1 its point on beam 1: ``U0 (...) - c1 F0`` at the tips, from below). Arrays
and fields are named in `impactbeams.kernels.layout`; SI units.
"""

import math

import numpy as np

from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import (
    CELL_F0,
    CELL_FORCING_FREQUENCY,
    CELL_U0,
    GEO_GAP_COMPLIANCE,
    GEO_SHAKER1,
    GEO_SHAKER2,
    GEO_SIDE,
)


@kernel
def base_amplitude(cell):
    """U0 (m) of a cell row; 0 for a row without that column (``layout.CELL_COLUMNS``)."""
    return cell[CELL_U0] if cell.size > CELL_U0 else 0.0


@kernel
def harmonic(amplitude, forcing_frequency, t):
    """``a sin(Omega t)`` and its rate ``a Omega cos(Omega t)`` at time t (s).

    NumPy's sine and cosine (the same bits as ``math``'s in a kernel), so that ``py_func``
    evaluates arrays of times too (`impactbeams.trajectory.observables`).
    """
    return (amplitude * np.sin(forcing_frequency * t),
            amplitude * forcing_frequency * np.cos(forcing_frequency * t))


@kernel
def tip_load(settings, t):
    """The tip force F(t) (N, downward on beam 1) and its rate F'(t) (N/s)."""
    return harmonic(settings.force_amplitude, settings.forcing_frequency, t)


@kernel
def clamp_motion(settings, t):
    """The shaker's displacement u_b(t) (m, upward), velocity (m/s) and acceleration (m/s^2)."""
    displacement, velocity = harmonic(settings.base_amplitude, settings.forcing_frequency, t)
    return displacement, velocity, -settings.forcing_frequency**2 * displacement


@kernel
def mode_drive(drive, base, frequencies, zeta, force_amplitude, base_amplitude, forcing_frequency):
    """Complex amplitude A of a mode's drive, as ``Im(A e^(i Omega t))``: all drives summed.

    Tip force: ``b (F'' + 2 zeta omega F')`` with ``drive`` = b (m kg^1/2 / N):
    ``A = F0 Omega b (-Omega + 2 i zeta omega)``. Base: ``-Gamma u_b''`` with ``base`` = Gamma
    (kg^1/2, 0 if the mode's clamp stays): ``A = Gamma U0 Omega^2``. ``omega``, ``zeta``: the
    mode's natural frequency (rad/s) and damping ratio.
    """
    rate = force_amplitude * forcing_frequency * drive
    amplitude = complex(-forcing_frequency * forcing_frequency * force_amplitude * drive,
                        2.0 * zeta * frequencies * rate)
    if base_amplitude != 0.0:  # no base drive: the tip force's bits as they were
        amplitude += base * base_amplitude * forcing_frequency * forcing_frequency
    return amplitude


@kernel
def mode_drives(table_drive, table_base, frequencies, zeta, cell, out):
    """``mode_drive`` of every mode (rows of a phase table) for the cell's drives, into ``out``.

    Written in place: assigning a returned array to a row (``forces[phase] = ...``) compiles
    Numba's string formatting for its shape-mismatch message, about 2 s of a cold compile.
    """
    for j in range(table_drive.size):
        out[j] = mode_drive(table_drive[j], table_base[j], frequencies[j], zeta[j], cell[CELL_F0],
                            base_amplitude(cell), cell[CELL_FORCING_FREQUENCY])


@kernel
def gap_harmonic(cell, geometry):
    """S (m) of the gap's explicit term ``S sin(Omega t)``: ``s (u_b1 - u_b2) - s G1 F`` over sin.

    ``s G1`` = ``GEO_GAP_COMPLIANCE`` (m/N; c1 for a contact at the tips, from below).
    """
    tip = -geometry[GEO_GAP_COMPLIANCE] * cell[CELL_F0]
    amplitude = base_amplitude(cell)
    if amplitude == 0.0:
        return tip
    return amplitude * (geometry[GEO_SIDE] * (geometry[GEO_SHAKER1] - geometry[GEO_SHAKER2])) + tip


@kernel
def rest_velocity(cell, drive, base):
    """A mode's q' at t = 0 with both beams at rest in the absolute frame.

    The tip force's quasi-static velocity ``F0 Omega b`` and the relative velocity
    ``w' = -u_b'(0) = -U0 Omega`` of a moving clamp's beam, projected: ``-Gamma U0 Omega``.
    """
    velocity = cell[CELL_F0] * cell[CELL_FORCING_FREQUENCY] * drive
    amplitude = base_amplitude(cell)
    if amplitude != 0.0:
        velocity -= base * amplitude * cell[CELL_FORCING_FREQUENCY]
    return velocity


@kernel
def steady_state(force, frequencies, zeta, forcing_frequency):
    """A mode's (q, q') at t = 0 on its steady response ``Im(P e^(i Omega t))``, P = A / D.

    ``D = omega^2 - Omega^2 + 2 i zeta omega Omega``. An undamped driven mode exactly at
    resonance has no steady state: ``impactbeams.drive.check_steady`` refuses that start.
    """
    if force == 0:
        return 0.0, 0.0
    phasor = force / complex(frequencies * frequencies - forcing_frequency * forcing_frequency,
                             2.0 * zeta * frequencies * forcing_frequency)
    return phasor.imag, forcing_frequency * phasor.real


def modal_acceleration(force, frequencies, zeta, q, v, sine, cosine):
    """Every mode's acceleration without contact, at a time where ``sin(Omega t)`` = ``sine``.

    ``q'' = Im(A e^(i Omega t)) - 2 zeta omega q' - omega^2 q`` (arrays of the modes, or NumPy
    arrays that broadcast, e.g. states of many times against the modes; ``force`` the complex
    drive amplitudes A). Plain Python, also compiled into the kernels (``modal_acceleration_at``,
    and one mode at a time ``compiled_modal_acceleration``).
    """
    return (force.real * sine + force.imag * cosine - 2.0 * zeta * frequencies * v
            - frequencies * frequencies * q)


compiled_modal_acceleration = kernel(modal_acceleration)


@kernel
def modal_acceleration_at(force, frequencies, zeta, q, v, forcing_frequency, t):
    """``modal_acceleration`` of every mode at time t (s)."""
    return compiled_modal_acceleration(force, frequencies, zeta, q, v,
                                       math.sin(forcing_frequency * t),
                                       math.cos(forcing_frequency * t))
