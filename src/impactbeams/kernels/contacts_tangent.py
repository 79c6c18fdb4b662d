"""Tangent dynamics of a run of several spring contacts: the period map's exact Jacobian.

The run is `impactbeams.kernels.several_contacts.run_contacts`'s: phase k in the active set of
bit mask ``mask[k]`` from its start state (q[k], q'[k]) (free coordinates) at ``time[k]`` (s).
A tangent vector (dq, dq') obeys each phase's modal equations without their drive, so within a
phase it is carried by the phase's own closed-form propagation (`tangent.advance_tangents`)
in the phase's contact oscillators, entered and left by the linear part of the change of
coordinates (`contact_spring.tangent_switch`; function 0's oscillators, as the run's samples
are taken).

**At a switch** (contact f closes or opens; the state is kept) the tangents are multiplied by
the saltation matrix ``S = I + (f+ - f-) n^T / (dh/dt)``, h the event function whose root
ended the phase (f's physical gap at a closing, its force R_f at an opening, the force it
would have, -R_f, at a re-onset after a dashpot's early release), n its gradient in (q, q')
and dh/dt its rate along the phase before. In the free coordinates the two vector fields
differ by the contact forces alone, ``f+ - f- = (0, B_new R_new - B_old R_old)`` (b_j the gap
weights), both sets' forces read at the switch state. Without a dashpot the forces are
continuous at every switch (a contact closes at zero physical gap, where adding it with
R_f = 0 leaves the other forces of ``(K^-1 + R_N) R = -g`` where they were; it opens at
R_f = 0, where the same equations without row f hold), so S = I and nothing is applied, as
for one contact. With dashpots the forces jump (one contact: by -c_e g' at an onset) and S is
applied. A dashpot's gap opening after an early release changes no set: S = I. Which function
ended a closing follows the run's own bookkeeping of early releases (`run_contacts`): a
contact released while a dashpot is among the contacts is early until its gap is found open
at a phase's start or it opens or closes again.
"""

import numpy as np

from impactbeams.kernels.contact_spring import tangent_switch, to_contact
from impactbeams.kernels.events import phase_event
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import CONTACT, FREE, ROW_EVENT, SPRING_DRIVE_ROWS
from impactbeams.kernels.tangent import advance_tangents


@kernel
def event_at(tables, scalars, modes, drives, lefts, settings, a, f, q, v, t, y, y_rate):
    """Event function f of set a, and its rate, at the free state (q, q') at time t (s)."""
    to_contact(q, v, t, lefts[a], modes[a, f], drives[a, f], settings.forcing_frequency, y,
               y_rate)
    return phase_event(tables[a, f], scalars[a, f], y, y_rate, t, settings.forcing_frequency)


@kernel
def force_jump(tables, scalars, modes, drives, lefts, set_of_mask, settings, gap_weights,
               old_mask, new_mask, q, v, t, y, y_rate, jump):
    """Write into ``jump`` B_new R_new - B_old R_old: the modal forces' jump at a switch."""
    for j in range(jump.size):
        jump[j] = 0.0
    for mask, sign in ((new_mask, 1.0), (old_mask, -1.0)):
        a = set_of_mask[mask]
        for f in range(gap_weights.shape[0]):
            if (mask >> f) & 1:
                force, _ = event_at(tables, scalars, modes, drives, lefts, settings, a, f, q,
                                    v, t, y, y_rate)
                for j in range(jump.size):
                    jump[j] += sign * force * gap_weights[f, j]


@kernel
def apply_contacts_saltation(tangent_q, tangent_v, tables, scalars, modes, drives, lefts,
                             set_of_mask, settings, gap_weights, old_mask, new_mask, trigger, q,
                             v, t):
    """Apply S (module doc) at the switch from ``old_mask`` to ``new_mask`` at (q, q', t).

    ``trigger``: the event function of the old set whose root is the switch.
    """
    m = q.size
    y, y_rate, jump = np.empty(m), np.empty(m), np.empty(m)
    force_jump(tables, scalars, modes, drives, lefts, set_of_mask, settings, gap_weights,
               old_mask, new_mask, q, v, t, y, y_rate, jump)
    a = set_of_mask[old_mask]
    _, rate = event_at(tables, scalars, modes, drives, lefts, settings, a, trigger, q, v, t, y,
                       y_rate)
    no_drive = np.zeros((len(SPRING_DRIVE_ROWS), m), dtype=np.complex128)
    weights = tables[a, trigger, ROW_EVENT]
    for row in range(tangent_q.shape[0]):
        # n . (dq, dq'): the event function's linear part, its oscillators without drive
        to_contact(tangent_q[row], tangent_v[row], 0.0, lefts[a], modes[a, trigger], no_drive,
                   0.0, y, y_rate)
        projection = 0.0
        for j in range(m):
            projection += weights[j] * y[j]
        for j in range(m):
            tangent_v[row, j] += jump[j] * projection / rate


@kernel
def open_gaps_clear(tables, scalars, modes, drives, lefts, settings, a, n, early, q, v, t):
    """``early`` without the contacts whose gaps are open (>= 0) at (q, q', t) in set a."""
    m = q.size
    y, y_rate = np.empty(m), np.empty(m)
    for f in range(n):
        if (early >> f) & 1:
            gap, _ = event_at(tables, scalars, modes, drives, lefts, settings, a, f, q, v, t, y,
                              y_rate)
            if gap >= 0.0:
                early ^= 1 << f
    return early


@kernel
def carry_contact_tangents(tables, scalars, modes, drives, lefts, rights, set_of_mask, settings,
                           early_release, gap_weights, recorded, t_end, early, tangent_q,
                           tangent_v):
    """Carry the tangent rows (dq, dq') from ``recorded``'s start to ``t_end`` (s), in place.

    ``recorded`` = (time, mask, switched, q, v) of `run_contacts` (its arrays cut to the run's
    phases); ``early``: the bit mask of contacts released early at the start (0 without a
    dashpot). The rows are free coordinates at both ends.
    """
    seg_time, seg_mask, seg_switched, seg_q, seg_v = recorded
    n = gap_weights.shape[0]
    rows, m = tangent_q.shape
    no_force = np.zeros(m, dtype=np.complex128)
    no_drive = np.zeros((len(SPRING_DRIVE_ROWS), m), dtype=np.complex128)
    y_q, y_v = np.empty((rows, m)), np.empty((rows, m))
    count = seg_time.size
    for k in range(count):
        a = set_of_mask[seg_mask[k]]
        t_stop = seg_time[k + 1] if k + 1 < count else t_end
        oscillators = (lefts[a], rights[a], modes[a, 0])
        tangent_switch(tangent_q, tangent_v, CONTACT, oscillators, no_drive, y_q, y_v)
        advance_tangents(tables[a, 0], y_q, y_v, seg_time[k], t_stop - seg_time[k], no_force)
        tangent_switch(y_q, y_v, FREE, oscillators, no_drive, tangent_q, tangent_v)
        if k + 1 == count or not early_release:
            continue  # without a dashpot every S = I (module doc)
        early = open_gaps_clear(tables, scalars, modes, drives, lefts, settings, a, n,
                                early, seg_q[k], seg_v[k], seg_time[k])
        switched = seg_switched[k + 1]
        if switched >= n:  # an early-released gap opened: the set is unchanged
            early &= ~(1 << (switched - n))
            continue
        closing = (seg_mask[k + 1] >> switched) & 1
        trigger = n + switched if closing and (early >> switched) & 1 else switched
        apply_contacts_saltation(tangent_q, tangent_v, tables, scalars, modes, drives, lefts,
                                 set_of_mask, settings, gap_weights, seg_mask[k],
                                 seg_mask[k + 1], trigger, seg_q[k + 1], seg_v[k + 1],
                                 seg_time[k + 1])
        early &= ~(1 << switched)
        if not closing:
            early |= 1 << switched
