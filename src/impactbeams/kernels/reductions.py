"""Reductions over a recorded run, apart from the state machine that records it.

Work of the drives, damping dissipation, and the per-cell summary of a dynamics map (impacts,
largest force, restitution, contact time); the peak contact force is
`impactbeams.kernels.peaks`'.

They use the state machine's propagation (`impactbeams.kernels.dynamics`); arrays are
named in `impactbeams.kernels.layout`.
"""

import math

import numpy as np

from impactbeams.kernels import contact
from impactbeams.kernels.drive import clamp_motion, tip_load
from impactbeams.kernels.dynamics import propagate
from impactbeams.kernels.events import phase_event
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import (
    CONTACT,
    FREE,
    OUT_CONTACT_FRACTION,
    OUT_FIRST_IMPACT,
    OUT_IMPACTS,
    OUT_MAX_FORCE,
    OUT_RESTITUTION,
    OUT_STATUS,
    ROW_BASE,
    ROW_DRIVE,
    ROW_FREQUENCY,
    ROW_TIP1,
    ROW_ZETA,
    SCALAR_LOAD_RATE,
)
from impactbeams.kernels.peaks import peak_force

_GAUSS_NODES = np.array([
    -0.9815606342467192, -0.9041172563704749, -0.7699026741943047, -0.5873179542866175,
    -0.3678314989981802, -0.1252334085114689, 0.1252334085114689, 0.3678314989981802,
    0.5873179542866175, 0.7699026741943047, 0.9041172563704749, 0.9815606342467192])
_GAUSS_WEIGHTS = np.array([
    0.0471753363865118, 0.1069393259953184, 0.1600783285433462, 0.2031674267230659,
    0.2334925365383548, 0.2491470458134028, 0.2491470458134028, 0.2334925365383548,
    0.2031674267230659, 0.1600783285433462, 0.1069393259953184, 0.0471753363865118])


@kernel
def _power(tables, forces, phase_scalars, switching, settings, recorded, k, t, work_arrays):
    """Power of the drives (W) and damping dissipation rate (W) at time t within segment k.

    The damping acts on each mode's whole coordinate, whose rate is ``q' - F' b``; the
    shaker's inertial load ``-rhoA u_b''`` does work on it through ``Gamma_n`` (the energy is
    that of the motion relative to the clamps), and the clamps' motion changes the gap, on which
    a spring contact's force works: ``-R (u_b1' - u_b2')``. The state is taken to the
    coordinates it is observed in (`contact.observed_state`); beam 1's tip also moves by
    ``r_1 R'`` (its residual flexibility under the contact force, where the law has one), and
    the law adds its own dissipation (`contact.extra_dissipation`). ``recorded``: the run's
    `records.Segments`; ``work_arrays``: scratch rows (q, v, free q, free v).
    """
    q, v, free_q, free_v = work_arrays[0], work_arrays[1], work_arrays[2], work_arrays[3]
    phase = recorded.phase[k]
    table, scalars = tables[phase], phase_scalars[phase]
    propagate(table, forces[phase], recorded.q[k], recorded.v[k], recorded.time[k], t, settings,
              q, v)
    # R' moves beam 1's tip through the flexibility its modes miss
    contact_force, contact_force_rate = contact.residual_force(phase, table, scalars, q, v, t,
                                                               settings)
    contact.observed_state(phase, q, v, t, switching, settings, free_q, free_v)
    observed = contact.observed_phase(phase, settings)
    table, scalars = tables[observed], phase_scalars[observed]
    force, force_rate = tip_load(settings, t)
    tip_rate = (-settings.c1 * scalars[SCALAR_LOAD_RATE] * force_rate
                + settings.residual1 * contact_force_rate)
    dissipation, base_rate = 0.0, 0.0
    frequencies, zeta = table[ROW_FREQUENCY], table[ROW_ZETA]
    drive, tip1 = table[ROW_DRIVE], table[ROW_TIP1]
    base = table[ROW_BASE]
    for j in range(free_q.size):
        tip_rate += tip1[j] * free_v[j]
        modal_rate = free_v[j] - force_rate * drive[j]
        dissipation += 2.0 * zeta[j] * frequencies[j] * modal_rate * modal_rate
        base_rate += base[j] * modal_rate
    dissipation = contact.extra_dissipation(phase, tables[FREE], phase_scalars[FREE], free_q,
                                            free_v, t, settings, dissipation)
    power = -force * tip_rate
    if settings.base_amplitude != 0.0:
        _, clamp_rate, clamp_acceleration = clamp_motion(settings, t)
        # the inertial load on the modes, and the clamps pushing the spring through the gap
        power -= (clamp_acceleration * base_rate
                  + settings.side * (settings.shaker1 - settings.shaker2) * clamp_rate
                  * contact_force)
    return power, dissipation


@kernel
def _integrate_power(tables, forces, phase_scalars, switching, settings, recorded, k, a, b,
                     work_arrays):
    """Integrals (J) of the power of F and of the dissipation over [a, b] in segment k.

    Composite 12-point Gauss-Legendre with panels no longer than half the shortest period
    (of the modes and of the forcing): relative error below 1e-18 per panel.
    """
    if b <= a:
        return 0.0, 0.0
    fastest = max(np.max(tables[recorded.phase[k], ROW_FREQUENCY]), settings.forcing_frequency)
    n_panels = max(1, int(math.ceil((b - a) * fastest / math.pi)))
    width = (b - a) / n_panels
    work, dissipated = 0.0, 0.0
    for p in range(n_panels):
        middle = a + (p + 0.5) * width
        for j in range(_GAUSS_NODES.size):
            t = middle + 0.5 * width * _GAUSS_NODES[j]
            power, loss = _power(tables, forces, phase_scalars, switching, settings,
                                 recorded, k, t, work_arrays)
            work += 0.5 * width * _GAUSS_WEIGHTS[j] * power
            dissipated += 0.5 * width * _GAUSS_WEIGHTS[j] * loss
    return work, dissipated


@kernel
def work_of_force(tables, forces, phase_scalars, switching, settings, recorded, t_end,
                  times, out, carried):
    """Work done by F and energy dissipated by damping from t = 0 to each of ``times`` (J).

    ``recorded``: consecutive `records.Segments` of the run, all of them recorded ones;
    ``times`` ascending in [time[0], t_end], ``t_end`` where the last segment stops; ``out``:
    rows ``(work, dissipation)``, a column per time. ``carried``: (work, dissipation, time
    integrated to) at the first segment's start, updated to the last one's end: a run taken
    in consecutive pieces (each with the times before its end) sums in the order of one call.
    """
    work_arrays = np.empty((4, recorded.q.shape[1]))
    work, dissipated, t_done, i = carried[0], carried[1], carried[2], 0
    count = recorded.time.size
    for k in range(count):
        seg_end = recorded.time[k + 1] if k + 1 < count else t_end
        work = contact.onset_work(work, recorded.phase[k], tables, phase_scalars, settings,
                                  recorded.q[k], recorded.v[k], recorded.time[k])
        while i < times.size and (times[i] < seg_end or k + 1 == count):
            dw, dd = _integrate_power(tables, forces, phase_scalars, switching, settings,
                                      recorded, k, t_done, times[i], work_arrays)
            work, dissipated, t_done = work + dw, dissipated + dd, max(t_done, times[i])
            out[0, i], out[1, i] = work, dissipated
            i += 1
        dw, dd = _integrate_power(tables, forces, phase_scalars, switching, settings,
                                  recorded, k, t_done, seg_end, work_arrays)
        work, dissipated, t_done = work + dw, dissipated + dd, max(t_done, seg_end)
    carried[0], carried[1], carried[2] = work, dissipated, t_done


@kernel
def _gap_rate(table, scalars, q, v, t, forcing_frequency):
    """dg/dt (m/s) of the free phase at time t from its modal state."""
    _, slope = phase_event(table, scalars, q, v, t, forcing_frequency)
    return slope


@kernel
def summarize_run(tables, forces, phase_scalars, settings, recorded, status, t_end, out):
    """Write a run's ``OUT_COLUMNS`` (layout) into ``out`` from its recorded `Segments`.

    ``recorded`` holds the run's recorded segments alone (`records.recorded_prefix`).

    First impact time (s, NaN if none), contact onsets, largest contact force (N, 0 if none),
    mean coefficient of restitution (NaN if no impact separated), fraction of [0, t_max] in
    contact, run status.
    """
    seg_time, seg_phase, _, seg_q, seg_v, end_q, end_v = recorded
    count = seg_time.size
    impacts, in_contact, largest = 0, 0.0, 0.0
    separation_sum, approach_sum = 0.0, 0.0
    forcing_frequency = settings.forcing_frequency
    for k in range(count):
        if seg_phase[k] != CONTACT:
            continue
        impacts += 1
        t_start = seg_time[k]
        t_stop = seg_time[k + 1] if k + 1 < count else t_end
        in_contact += t_stop - t_start
        force, _ = peak_force(tables[CONTACT], forces[CONTACT], phase_scalars[CONTACT],
                              settings, seg_q[k], seg_v[k], t_start, t_stop)
        largest = max(largest, force)
        if k + 1 < count and k >= 1:
            onset = _gap_rate(tables[FREE], phase_scalars[FREE], end_q[k - 1], end_v[k - 1],
                              t_start, forcing_frequency)
            release = _gap_rate(tables[FREE], phase_scalars[FREE], seg_q[k + 1], seg_v[k + 1],
                                t_stop, forcing_frequency)
            if onset < 0.0:
                separation_sum += release
                approach_sum -= onset
    out[OUT_FIRST_IMPACT] = seg_time[1] if count > 1 else np.nan
    out[OUT_IMPACTS] = impacts
    out[OUT_MAX_FORCE] = largest
    # approach-speed-weighted mean, sum(-dg/dt at separation) / sum(dg/dt at onset): impacts
    # with a near-zero approach speed (whose own ratio e is a truncation artefact, any size)
    # barely count
    out[OUT_RESTITUTION] = separation_sum / approach_sum if approach_sum > 0.0 else np.nan
    out[OUT_CONTACT_FRACTION] = in_contact / settings.t_max
    out[OUT_STATUS] = status
