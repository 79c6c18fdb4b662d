"""The compliant (spring) contact law: its contact oscillators, switch maps, force and powers.

Plain arrays, packed from [`impactbeams.compliant.SpringContact`][] (see that module for the
derivation). With M free coordinates x = (q, q') (2 M values) and the contact phase's complex
modes z (M, one of each conjugate pair):

* ``modes`` (complex, rows ``layout.SPRING_MODE_ROWS``): eigenvalues lambda_j (1/s) and
  phases rho_j (|rho_j| = 1) of the contact oscillators y_j = 2 Re(rho_j z_j) - y_eq_j;
* ``left`` (2 M, M): z = left^T x; ``right`` (M, 2 M): x = 2 Re(right^T z) (the transposes of
  the compliant module's, so that a change of coordinates adds up contiguous rows, which
  vectorises in a fixed order);
* ``drives`` (complex, rows ``layout.SPRING_DRIVE_ROWS``, per run): the modal drive of z,
  z_j' = lambda_j z_j + P_j e^(i Omega t) + N_j e^(-i Omega t) + C_j, and y_eq_j.

Every switch between the phases is the identity on (q, q'): these maps change coordinates only.
The law's other pieces: the contact force ``R = -k_e g - c_e g'`` and its rate in the free
coordinates, the tips' static response to R through the flexibility the modes miss
(``+r_1 R``, ``-r_2 R``), the dashpot's dissipation, the work of F at an onset's force jump,
and the saltation of the tangent dynamics at an onset (`impactbeams.kernels.tangent`).
"""

import math

import numpy as np

from impactbeams.kernels.drive import tip_load
from impactbeams.kernels.events import (
    event_acceleration,
    phase_event,
    phase_event_function,
    phase_oscillators,
)
from impactbeams.kernels.jit import borrowing_kernel, kernel
from impactbeams.kernels.layout import (
    CONTACT,
    DRIVE_CONSTANT,
    DRIVE_EQUILIBRIUM,
    DRIVE_FALLING,
    DRIVE_RISING,
    FREE,
    MODE_EIGENVALUE,
    MODE_PHASE,
    ROW_EVENT,
    SPRING_DRIVE_ROWS,
    TIP_V1,
    TIP_V2,
    TIP_Y1,
    TIP_Y2,
)


@kernel
def spring_drives(left, modes, contact_drive, constant_drive, forcing_frequency, forces):
    """The modes' drive phasors and the oscillators' drives for one cell.

    ``contact_drive`` (complex, M): amplitude A' of the contact phase's modal drive
    Im(A' e^(i Omega t)); ``constant_drive`` (M): its constant part (N-ish modal units).
    Returns ``drives`` with rows ``SPRING_DRIVE_ROWS`` (the last, y_eq_j, real), and writes
    into ``forces`` the drive amplitudes A_j of the oscillators,
    y_j'' + 2 zeta_j |lambda_j| y_j' + |lambda_j|^2 y_j = Im(A_j e^(i Omega t)).
    """
    m = left.shape[1]
    drives = np.empty((len(SPRING_DRIVE_ROWS), m), dtype=np.complex128)
    # the products of the contact phase's velocity rows, sum_n left[m + n, j] x_n, in loops
    # over n in order: BLAS's sums split with its thread count (issue 32)
    rising = np.zeros(m, dtype=np.complex128)  # of A' / 2i
    falling = np.zeros(m, dtype=np.complex128)  # of -conj(A') / 2i
    constant = np.zeros(m, dtype=np.complex128)  # of the constant part
    for n in range(m):
        up, down = contact_drive[n] / 2j, -contact_drive[n].conjugate() / 2j
        for j in range(m):
            rising[j] += left[m + n, j] * up
            falling[j] += left[m + n, j] * down
            constant[j] += left[m + n, j] * constant_drive[n]
    for j in range(m):
        lam, rho = modes[MODE_EIGENVALUE, j], modes[MODE_PHASE, j]
        up = rho * (1j * forcing_frequency - lam.conjugate()) * rising[j]
        down = rho * (-1j * forcing_frequency - lam.conjugate()) * falling[j]
        forces[j] = 2j * (up + down.conjugate())
        offset = -2.0 * (rho * lam.conjugate() * constant[j]).real
        drives[DRIVE_RISING, j] = rising[j]
        drives[DRIVE_FALLING, j] = falling[j]
        drives[DRIVE_CONSTANT, j] = constant[j]
        drives[DRIVE_EQUILIBRIUM, j] = offset / (lam.real**2 + lam.imag**2)
    return drives


@borrowing_kernel
def _turn(t, forcing_frequency):
    """e^(i Omega t)."""
    return complex(math.cos(forcing_frequency * t), math.sin(forcing_frequency * t))


@borrowing_kernel
def _mode_drive(drives, j, turn):
    """The drive gamma_j(t) of complex mode j, given ``turn`` = e^(i Omega t)."""
    return (drives[DRIVE_RISING, j] * turn + drives[DRIVE_FALLING, j] * turn.conjugate()
            + drives[DRIVE_CONSTANT, j])


@borrowing_kernel
def to_contact(q, v, t, left, modes, drives, forcing_frequency, y, y_rate):
    """Contact oscillators (y, y') at time t of the free coordinates (q, q') (not in place).

    z = left^T x is summed in y (real parts) and y' (imaginary parts): no work arrays.
    """
    m = q.size
    for j in range(m):
        y[j] = y_rate[j] = 0.0
    for n in range(2 * m):
        x = q[n] if n < m else v[n - m]
        row = left[n]
        for j in range(m):
            y[j] += row[j].real * x
            y_rate[j] += row[j].imag * x
    turn = _turn(t, forcing_frequency)
    for j in range(m):
        z = complex(y[j], y_rate[j])
        lam, rho = modes[MODE_EIGENVALUE, j], modes[MODE_PHASE, j]
        y[j] = 2.0 * (rho * z).real - drives[DRIVE_EQUILIBRIUM, j].real
        y_rate[j] = 2.0 * (rho * (lam * z + _mode_drive(drives, j, turn))).real


@borrowing_kernel
def to_free(y, y_rate, t, right, modes, drives, forcing_frequency, q, v):
    """Free coordinates (q, q') at time t of the contact oscillators (y, y') (not in place).

    x = 2 Re(right^T z) is summed in q and q' themselves: no work arrays.
    """
    m = y.size
    turn = _turn(t, forcing_frequency)
    for n in range(m):
        q[n] = v[n] = 0.0
    for j in range(m):
        lam, rho = modes[MODE_EIGENVALUE, j], modes[MODE_PHASE, j]
        a = 0.5 * (y[j] + drives[DRIVE_EQUILIBRIUM, j].real)
        forced = (rho * _mode_drive(drives, j, turn)).real
        b = (lam.real * a - 0.5 * y_rate[j] + forced) / lam.imag
        z = rho.conjugate() * complex(a, b)
        row = right[j]
        for n in range(m):
            q[n] += row[n].real * z.real - row[n].imag * z.imag
        for n in range(m):
            v[n] += row[m + n].real * z.real - row[m + n].imag * z.imag
    for n in range(m):
        q[n], v[n] = 2.0 * q[n], 2.0 * v[n]


@borrowing_kernel
def switch_state(q, v, t, to_phase, spring, drives, settings, q_new, v_new):
    """The same physical state (q, v) at time t in ``to_phase``'s coordinates."""
    left, right, modes = spring
    if to_phase == CONTACT:
        to_contact(q, v, t, left, modes, drives, settings.forcing_frequency, q_new, v_new)
    else:
        to_free(q, v, t, right, modes, drives, settings.forcing_frequency, q_new, v_new)


@borrowing_kernel
def free_state(y, y_rate, t, spring, drives, settings, q, v):
    """Free coordinates (q, q') at time t of the contact oscillators (y, y')."""
    _, right, modes = spring
    to_free(y, y_rate, t, right, modes, drives, settings.forcing_frequency, q, v)


@kernel
def gap_and_force(tables, forces, phase_scalars, settings, t, q, v):
    """Modal gap g_N (m), spring contact force R = -k_e g_N - c_e g_N' (N) and R' (N/s).

    Free coordinates. In contact the modal acceleration has the contact force's share ``R w``
    on top of the free phase's (``w`` the gap weights), which enters R' through the dashpot.
    """
    table, scalars = tables[FREE], phase_scalars[FREE]
    weights = table[ROW_EVENT]
    gap, gap_rate = phase_event(table, scalars, q, v, t, settings.forcing_frequency)
    stiffness, damping = settings.contact_stiffness, settings.contact_damping
    force = -stiffness * gap - damping * gap_rate
    if damping == 0.0:
        return gap, force, -stiffness * gap_rate
    gap_acceleration = event_acceleration(
        q, v, t, phase_oscillators(table, forces[FREE], settings.forcing_frequency),
        phase_event_function(table, scalars, settings.forcing_frequency))
    norm = 0.0  # w . w: a loop, not np.dot, whose BLAS call costs a cold compile 0.2 s
    for j in range(weights.size):
        norm += weights[j] * weights[j]
    gap_acceleration += force * norm
    return gap, force, -stiffness * gap_rate - damping * gap_acceleration


@kernel
def contact_states(tables, forces, phase_scalars, settings, phase, t, q, v, out):
    """Modal gap (m), contact force (N) and its rate (N/s) of each sampled state, into ``out[k]``.

    Free states (q[k], v[k]) of ``phase[k]`` at ``t[k]`` (s); R and R' are 0 out of contact.
    """
    for k in range(t.size):
        gap, force, force_rate = gap_and_force(tables, forces, phase_scalars, settings, t[k],
                                               q[k], v[k])
        if phase[k] != CONTACT:
            force = force_rate = 0.0
        out[k, 0], out[k, 1], out[k, 2] = gap, force, force_rate


@kernel
def correct_tips(tables, forces, phase_scalars, settings, residual2, t, q, v, out):
    """Add to a contact state's tips (``TIP_COLUMNS``) what the modes miss: +r_1 R, -r_2 R."""
    _, force, force_rate = gap_and_force(tables, forces, phase_scalars, settings, t, q, v)
    out[TIP_Y1] = out[TIP_Y1] + settings.residual1 * force
    out[TIP_Y2] = out[TIP_Y2] - residual2 * force
    out[TIP_V1] = out[TIP_V1] + settings.residual1 * force_rate
    out[TIP_V2] = out[TIP_V2] - residual2 * force_rate


@kernel
def dashpot_dissipation(contact, free_table, free_scalars, q, v, t, settings, dissipation):
    """``dissipation`` (W) plus the dashpot's, from the free state (q, q') at time t.

    In contact the dashpot dissipates ``c_e g'^2``; after an early release (the dashpot pulled
    R to 0 while the tips still overlap) it absorbs the energy the relaxing spring gives up,
    ``-k_e g g'``.
    """
    if settings.contact_damping > 0.0:
        gap, gap_rate = phase_event(free_table, free_scalars, q, v, t,
                                    settings.forcing_frequency)
        if contact:
            dissipation += settings.contact_damping * gap_rate * gap_rate
        elif gap < 0.0:  # released early: the dashpot absorbs the relaxing spring's energy
            dissipation -= settings.contact_stiffness * gap * gap_rate
    return dissipation


@kernel
def onset_work(table, scalars, settings, y, y_rate, t):
    """Work (J) of F as a spring contact starts with a force jump (a dashpot's -c_e g').

    Beam 1's tip moves at once by r_1 R through its residual flexibility, against F.
    """
    force, _ = phase_event(table, scalars, y, y_rate, t, settings.forcing_frequency)
    tip_force, _ = tip_load(settings, t)
    return -tip_force * settings.residual1 * force


@borrowing_kernel
def tangent_switch(tangent_q, tangent_v, to_phase, spring, no_drive, out_q, out_v):
    """Linear part of the switch into ``to_phase``'s coordinates, row by row."""
    left, right, modes = spring
    for c in range(tangent_q.shape[0]):
        if to_phase == CONTACT:
            to_contact(tangent_q[c], tangent_v[c], 0.0, left, modes, no_drive, 0.0, out_q[c],
                       out_v[c])
        else:
            to_free(tangent_q[c], tangent_v[c], 0.0, right, modes, no_drive, 0.0, out_q[c],
                    out_v[c])


@kernel
def apply_saltation(tangent_q, tangent_v, weights, force_jump, gap_rate):
    """Apply S = I + (f+ - f-) n^T / (n . f- + dg/dt) at an onset where the gap closes.

    In the free coordinates: ``f+ - f- = (0, force_jump w)`` (the contact force jumps by
    ``force_jump``, N), ``n = (w, 0)`` and ``n . f- + dg/dt = gap_rate`` (g', m/s, < 0); w the
    gap ``weights``.
    """
    if force_jump == 0.0:
        return
    scale = force_jump / gap_rate
    for c in range(tangent_q.shape[0]):
        projection = 0.0
        for j in range(weights.size):
            projection += weights[j] * tangent_q[c, j]
        for j in range(weights.size):
            tangent_v[c, j] += scale * projection * weights[j]


@kernel
def onset_force_jump(phase_scalars, tables, settings, q, v, t):
    """The contact force's jump (N) and the gap rate (m/s) at an onset from free state (q, q').

    The gap closes (g' < 0): R jumps from 0 to -c_e g' (g = 0). The gap opens (g' > 0): a
    re-onset after an early release, where R rises through 0 continuously: no jump.
    """
    _, gap_rate = phase_event(tables[FREE], phase_scalars[FREE], q, v, t,
                              settings.forcing_frequency)
    if gap_rate >= 0.0:
        return 0.0, gap_rate
    return -settings.contact_damping * gap_rate, gap_rate


@kernel
def onset_saltation(tangent_q, tangent_v, tables, phase_scalars, settings, q, v, t):
    """The saltation of an onset from free state (q, q') at time t, applied to the tangents."""
    force_jump, gap_rate = onset_force_jump(phase_scalars, tables, settings, q, v, t)
    apply_saltation(tangent_q, tangent_v, tables[FREE, ROW_EVENT], force_jump, gap_rate)
