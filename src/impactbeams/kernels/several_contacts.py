"""Several spring contacts closed at once: exact phases, the first event among all contacts.

The kernels take the run's phases as one record, ``sets``, the active sets record
(`impactbeams.kernels.records.ACTIVE_SETS`, a plain tuple read by the indices ``SET_*``),
packed by `impactbeams.active_phases.pack_contacts` from `impactbeams.contact.active_sets`.
A phase is one active set a (the contacts closed, a bit mask ``mask`` read through
``sets[SET_OF_MASK]``); its state is kept in the free coordinates (q, q') (every switch is the
identity on them). Each contact f has one event function in each phase: its contact force R_f
if it is closed, its physical gap (the modal gap plus what the active forces deflect it
through the flexibility the modes miss) if it is open. Both are

    e_f(t) = const + Im(H e^(i Omega t)) + sum_j 2 Re(c_j z_j(t))

in the phase's complex modes z, which is `impactbeams.kernels.contact_spring`'s contact force
with its own phases rho_j = c_j / |c_j|: oscillators y_j = 2 Re(rho_j z_j) - y_eq_j of one
phase's table per function (the record's tables, forces, scalars, modes and drives at
``[a, f]``, in the layout of the single contact's contact phase; its lefts and rights at
``[a]``, the set's change of coordinates in the kernels' layout). So each
function's next switch is the single contact's own certified search
(`impactbeams.kernels.dynamics.find_switch`: a function that starts at 0 and rising, the
contact that has just closed or opened, waits for its rise) and the phase ends at the earliest
of them. With dashpots a contact released early (its gap still closed) is followed instead by
the single contact's rule (`impactbeams.kernels.dynamics.reonset_or_opening`) on its force in
the set with it added (function n + f) and its gap, until that gap opens. Its closed
contacts' impulses follow in closed form from the oscillators' ends, their peak forces from
the certified branch and bound of `impactbeams.kernels.peaks`.
"""

import math

import numpy as np

from impactbeams.kernels.contact_spring import to_contact, to_free
from impactbeams.kernels.dynamics import (
    COMPLETE,
    EVENT_LIMIT,
    SEARCH_LIMIT,
    STUCK,
    ZENO_LIMIT,
    find_switch,
    instantaneous,
    propagate,
    reonset_or_opening,
)
from impactbeams.kernels.events import GAVE_UP, phase_event
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import (
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
)
from impactbeams.kernels.peaks import peak_force
from impactbeams.kernels.records import (
    SET_DRIVES,
    SET_FORCES,
    SET_LEFTS,
    SET_MODES,
    SET_OF_MASK,
    SET_RIGHTS,
    SET_SCALARS,
    SET_TABLES,
)
from impactbeams.kernels.rotor import rotor_arrays

# a run that reached an active set that cannot occur (both sides of a two-sided stop)
IMPOSSIBLE_SET = 4


@kernel
def _sine_cosine_integrals(forcing_frequency, t0, t1):
    """Integrals of sin(Omega t) and cos(Omega t) over [t0, t1] (s), without cancellation."""
    if forcing_frequency == 0.0:
        return 0.0, t1 - t0
    middle = 0.5 * forcing_frequency * (t0 + t1)
    half_width = math.sin(0.5 * forcing_frequency * (t1 - t0))
    return (2.0 * math.sin(middle) * half_width / forcing_frequency,
            2.0 * math.cos(middle) * half_width / forcing_frequency)


@kernel
def impulse(table, force, scalars, forcing_frequency, y0, y_rate0, t0, y1, y_rate1, t1):
    """Integral of the event function over [t0, t1] (N s for a force), in closed form.

    From y'' + 2 zeta omega y' + omega^2 y = Im(A e^(i Omega t)): omega^2 int y =
    Re A int sin + Im A int cos - [y' + 2 zeta omega y].
    """
    sine, cosine = _sine_cosine_integrals(forcing_frequency, t0, t1)
    total = (scalars[SCALAR_CONST] * (t1 - t0) + scalars[SCALAR_SINE] * sine
             + scalars[SCALAR_COSINE] * cosine)
    for j in range(y0.size):
        omega, zeta = table[ROW_FREQUENCY, j], table[ROW_ZETA, j]
        jump = y_rate1[j] - y_rate0[j] + 2.0 * zeta * omega * (y1[j] - y0[j])
        modal = (force[j].real * sine + force[j].imag * cosine - jump) / (omega * omega)
        total += table[ROW_EVENT, j] * modal
    return total


@kernel
def run_contacts(sets, settings, early_release, q0, v0, t_start, mask_start, recorded):
    """Integrate from the free state (q0, v0) with contacts ``mask_start`` closed at t_start.

    No contact released early at the start: `resume_contacts` with ``early_start`` = 0.
    """
    return resume_contacts(sets, settings, early_release, q0, v0, t_start, mask_start, 0,
                           recorded)


@kernel
def resume_contacts(sets, settings, early_release, q0, v0, t_start, mask_start, early_start,
                    recorded):
    """Integrate from the free state (q0, v0) with contacts ``mask_start`` closed at t_start.

    ``sets``: the run's active sets record (`records.ACTIVE_SETS`). ``early_start``: the bit
    mask of the open contacts released early whose gaps have not opened since (a run resumed
    at one of its recorded phases goes on as it went, bit for bit).

    ``recorded`` = (time, mask, switched, q, v, impulses, peaks): phase k starts at
    ``time[k]`` (s) with the contacts of bit mask ``mask[k]`` closed, in state (q[k], v[k]),
    after contact ``switched[k]`` closed or opened (-1 at the start; n + f where contact f's
    gap opened after an early release, the set unchanged); ``impulses[k, f]`` (N s) and
    ``peaks[k, f]`` (N) are closed contact f's integral and largest force over the phase
    (0 for an open one). It ends where phase k + 1 starts, or at the returned end time.

    ``early_release`` (a dashpot among the contacts): a contact released with its gap still
    closed (R fell to 0 with the gap < 0) closes again where the force it would have rises
    through 0, unless its gap opens first (`dynamics.reonset_or_opening`, function n + f of
    a phase: -R_f of the set with f added), as the single contact's run does.

    Returns (number of phases, status, end time in s): ``COMPLETE`` (t_max reached),
    ``EVENT_LIMIT`` (arrays full), ``STUCK`` (more than ``ZENO_LIMIT`` zero-length phases in
    a row), ``SEARCH_LIMIT`` (an event search reached its step cap) or ``IMPOSSIBLE_SET``
    (a switch into a set that cannot occur).
    """
    seg_time, seg_mask, seg_switched, seg_q, seg_v, seg_impulse, seg_peak = recorded
    n_contacts, m = seg_impulse.shape[1], q0.size
    forcing_frequency = settings.forcing_frequency
    q, v = q0.copy(), v0.copy()
    y, y_rate = np.empty((n_contacts, m)), np.empty((n_contacts, m))
    y_force, y_force_rate = np.empty(m), np.empty(m)
    y_end, y_rate_end = np.empty(m), np.empty(m)
    q_work, v_work = np.empty(m), np.empty(m)
    rotor = rotor_arrays(m)
    t, mask, switched, zero_run = t_start, mask_start, -1, 0
    early = early_start  # the contacts released early whose gaps have not opened since
    for k in range(seg_time.size):
        a = sets[SET_OF_MASK][mask]
        seg_time[k], seg_mask[k], seg_switched[k] = t, mask, switched
        for n in range(m):
            seg_q[k, n], seg_v[k, n] = q[n], v[n]
        first, t_event, opening = -1, math.inf, False
        for f in range(n_contacts):
            to_contact(q, v, t, sets[SET_LEFTS][a], sets[SET_MODES][a, f],
                       sets[SET_DRIVES][a, f], forcing_frequency, y[f], y_rate[f])
            if (early >> f) & 1 and phase_event(sets[SET_TABLES][a, f], sets[SET_SCALARS][a, f],
                                                y[f], y_rate[f], t, forcing_frequency)[0] >= 0.0:
                early ^= 1 << f  # its gap is open: a plain open contact from here
            opens = False
            if (early >> f) & 1:
                g = n_contacts + f
                to_contact(q, v, t, sets[SET_LEFTS][a], sets[SET_MODES][a, g],
                           sets[SET_DRIVES][a, g], forcing_frequency, y_force, y_force_rate)
                t_f, opens = reonset_or_opening(
                    sets[SET_TABLES][a, g], sets[SET_FORCES][a, g], sets[SET_SCALARS][a, g],
                    y_force, y_force_rate, sets[SET_TABLES][a, f], sets[SET_FORCES][a, f],
                    sets[SET_SCALARS][a, f], y[f], y_rate[f], t, settings, q_work, v_work,
                    rotor)
            else:
                t_f = find_switch(sets[SET_TABLES][a, f], sets[SET_FORCES][a, f],
                                  sets[SET_SCALARS][a, f], y[f], y_rate[f], t, True, False,
                                  settings, q_work, v_work, rotor)
            if t_f == GAVE_UP:
                return k + 1, SEARCH_LIMIT, t
            if not math.isnan(t_f) and t_f < t_event:
                first, t_event, opening = f, t_f, opens
        t_stop = settings.t_max if first < 0 else t_event
        for f in range(n_contacts):
            seg_impulse[k, f] = seg_peak[k, f] = 0.0
            if not (mask >> f) & 1:
                continue
            propagate(sets[SET_TABLES][a, f], sets[SET_FORCES][a, f], y[f], y_rate[f], t,
                      t_stop, settings, y_end, y_rate_end)
            seg_impulse[k, f] = impulse(sets[SET_TABLES][a, f], sets[SET_FORCES][a, f],
                                        sets[SET_SCALARS][a, f], forcing_frequency, y[f],
                                        y_rate[f], t, y_end, y_rate_end, t_stop)
            seg_peak[k, f] = peak_force(sets[SET_TABLES][a, f], sets[SET_FORCES][a, f],
                                        sets[SET_SCALARS][a, f], settings, y[f], y_rate[f], t,
                                        t_stop)[0]
        # the new state from the oscillators of the function whose root ends the phase
        f = max(first, 0)
        propagate(sets[SET_TABLES][a, f], sets[SET_FORCES][a, f], y[f], y_rate[f], t, t_stop,
                  settings, y_end, y_rate_end)
        to_free(y_end, y_rate_end, t_stop, sets[SET_RIGHTS][a], sets[SET_MODES][a, f],
                sets[SET_DRIVES][a, f], forcing_frequency, q, v)
        if first < 0:
            return k + 1, COMPLETE, t_stop
        zero_run = zero_run + 1 if instantaneous(t, t_event) else 0
        if zero_run > ZENO_LIMIT:
            return k + 1, STUCK, t_stop
        t = t_event
        if (early >> first) & 1:  # its gap opened, or it closes again
            early ^= 1 << first
        if opening:
            switched = n_contacts + first
            continue
        mask ^= 1 << first
        switched = first
        if early_release and not (mask >> first) & 1:
            early |= 1 << first
        if sets[SET_OF_MASK][mask] < 0:
            return k + 1, IMPOSSIBLE_SET, t
    return seg_time.size, EVENT_LIMIT, t


@kernel
def sample_contacts(sets, settings, seg_time, seg_mask, seg_q, seg_v, times, q_out, v_out):
    """Free states (q, q') at the ascending ``times`` (s) of a recorded run, in closed form.

    ``sets``: the run's active sets record. At an event time the state of the phase that
    starts there.
    """
    m = seg_q.shape[1]
    y, y_rate = np.empty(m), np.empty(m)
    y_end, y_rate_end = np.empty(m), np.empty(m)
    k = 0
    for i in range(times.size):
        while k + 1 < seg_time.size and seg_time[k + 1] <= times[i]:
            k += 1
        a = sets[SET_OF_MASK][seg_mask[k]]
        to_contact(seg_q[k], seg_v[k], seg_time[k], sets[SET_LEFTS][a], sets[SET_MODES][a, 0],
                   sets[SET_DRIVES][a, 0], settings.forcing_frequency, y, y_rate)
        propagate(sets[SET_TABLES][a, 0], sets[SET_FORCES][a, 0], y, y_rate, seg_time[k],
                  times[i], settings, y_end, y_rate_end)
        to_free(y_end, y_rate_end, times[i], sets[SET_RIGHTS][a], sets[SET_MODES][a, 0],
                sets[SET_DRIVES][a, 0], settings.forcing_frequency, q_out[i], v_out[i])
