"""Tangent dynamics of a run of several spring contacts: the period map's exact Jacobian.

The run is `impactbeams.kernels.several_contacts.run_contacts`'s: phase k in the active set of
bit mask ``mask[k]`` from its start state (q[k], q'[k]) (free coordinates) at ``time[k]`` (s).
The kernels take the run's phases as that kernel does, one active sets record ``sets``
(`impactbeams.kernels.records.ACTIVE_SETS`), and read its fields in place.
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
from impactbeams.kernels.jit import borrowing_kernel, kernel
from impactbeams.kernels.layout import CONTACT, FREE, ROW_EVENT, SPRING_DRIVE_ROWS
from impactbeams.kernels.records import (
    CLOCK_RENORMALIZATIONS,
    CLOCK_TIME,
    SET_DRIVES,
    SET_LEFTS,
    SET_MODES,
    SET_OF_MASK,
    SET_RIGHTS,
    SET_SCALARS,
    SET_TABLES,
)
from impactbeams.kernels.tangent import (
    advance_tangents,
    lyapunov_schedule,
    new_tangent,
    orthonormalize,
    record_growth,
    renormalization_time,
)


@borrowing_kernel
def event_at(sets, settings, a, f, q, v, t, y, y_rate):
    """Event function f of set a, and its rate, at the free state (q, q') at time t (s)."""
    to_contact(q, v, t, sets[SET_LEFTS][a], sets[SET_MODES][a, f], sets[SET_DRIVES][a, f],
               settings.forcing_frequency, y, y_rate)
    return phase_event(sets[SET_TABLES][a, f], sets[SET_SCALARS][a, f], y, y_rate, t,
                       settings.forcing_frequency)


@borrowing_kernel
def force_jump(sets, settings, gap_weights, old_mask, new_mask, q, v, t, y, y_rate, jump):
    """Write into ``jump`` B_new R_new - B_old R_old: the modal forces' jump at a switch."""
    for j in range(jump.size):
        jump[j] = 0.0
    for mask, sign in ((new_mask, 1.0), (old_mask, -1.0)):
        a = sets[SET_OF_MASK][mask]
        for f in range(gap_weights.shape[0]):
            if (mask >> f) & 1:
                force, _ = event_at(sets, settings, a, f, q, v, t, y, y_rate)
                for j in range(jump.size):
                    jump[j] += sign * force * gap_weights[f, j]


@kernel
def apply_contacts_saltation(tangent_q, tangent_v, sets, settings, gap_weights, old_mask,
                             new_mask, trigger, q, v, t):
    """Apply S (module doc) at the switch from ``old_mask`` to ``new_mask`` at (q, q', t).

    ``trigger``: the event function of the old set whose root is the switch.
    """
    m = q.size
    y, y_rate, jump = np.empty(m), np.empty(m), np.empty(m)
    force_jump(sets, settings, gap_weights, old_mask, new_mask, q, v, t, y, y_rate, jump)
    a = sets[SET_OF_MASK][old_mask]
    _, rate = event_at(sets, settings, a, trigger, q, v, t, y, y_rate)
    no_drive = np.zeros((len(SPRING_DRIVE_ROWS), m), dtype=np.complex128)
    weights = sets[SET_TABLES][a, trigger, ROW_EVENT]
    for row in range(tangent_q.shape[0]):
        # n . (dq, dq'): the event function's linear part, its oscillators without drive
        to_contact(tangent_q[row], tangent_v[row], 0.0, sets[SET_LEFTS][a],
                   sets[SET_MODES][a, trigger], no_drive, 0.0, y, y_rate)
        projection = 0.0
        for j in range(m):
            projection += weights[j] * y[j]
        for j in range(m):
            tangent_v[row, j] += jump[j] * projection / rate


@kernel
def open_gaps_clear(sets, settings, a, n, early, q, v, t):
    """``early`` without the contacts whose gaps are open (>= 0) at (q, q', t) in set a."""
    m = q.size
    y, y_rate = np.empty(m), np.empty(m)
    for f in range(n):
        if (early >> f) & 1:
            gap, _ = event_at(sets, settings, a, f, q, v, t, y, y_rate)
            if gap >= 0.0:
                early ^= 1 << f
    return early


@kernel
def carry_contact_tangents(sets, settings, early_release, gap_weights, free_frequencies,
                           recorded, t_end, early, schedule, tangent):
    """Carry the tangent rows (dq, dq') from ``recorded``'s start to ``t_end`` (s), in place.

    ``sets``: the run's active sets record; ``recorded`` = (time, mask, switched, q, v) of
    `run_contacts` (its arrays cut to the run's phases); ``early``: the bit mask of contacts
    released early at the start (0 without a dashpot). ``tangent``, a `records.Tangent`
    ``(q, v, clock, sums, counts)``: the rows in the free coordinates at ``clock[CLOCK_TIME] =
    recorded.time[0]``, there on return at ``t_end``. ``schedule = (interval, t_max,
    transient, total)`` as for one contact (`tangent.carry_tangents`): the rows are
    orthonormalised in the energy product of the ``free_frequencies`` (rad/s) at ``i
    interval`` for i = 1 .. total and the logs of the growth summed into ``sums``,
    ``counts``; ``total`` = 0 (the monodromy) renormalises none, each phase then carried whole.
    """
    seg_time, seg_mask, seg_switched, seg_q, seg_v = recorded
    tangent_q, tangent_v, clock, sums, counts = tangent
    interval, t_max, _, total = schedule
    n = gap_weights.shape[0]
    rows, m = tangent_q.shape
    no_drive = np.zeros((len(SPRING_DRIVE_ROWS), m), dtype=np.complex128)
    y_q, y_v = np.empty((rows, m)), np.empty((rows, m))
    log_growth = np.empty(rows)
    count = seg_time.size
    for k in range(count):
        a = sets[SET_OF_MASK][seg_mask[k]]
        t_stop = seg_time[k + 1] if k + 1 < count else t_end
        oscillators = (sets[SET_LEFTS][a], sets[SET_RIGHTS][a], sets[SET_MODES][a, 0])
        while clock[CLOCK_RENORMALIZATIONS] < total:
            t_next = renormalization_time(clock[CLOCK_RENORMALIZATIONS] + 1.0, interval, t_max)
            if t_next > t_stop:
                break
            _advance_in_set(sets[SET_TABLES][a, 0], oscillators, no_drive, clock, t_next,
                            tangent_q, tangent_v, y_q, y_v)
            orthonormalize(tangent_q, tangent_v, free_frequencies, log_growth)
            clock[CLOCK_RENORMALIZATIONS] += 1.0
            record_growth(sums, counts, log_growth, int(clock[CLOCK_RENORMALIZATIONS]), schedule)
        _advance_in_set(sets[SET_TABLES][a, 0], oscillators, no_drive, clock, t_stop, tangent_q,
                        tangent_v, y_q, y_v)
        if k + 1 == count or not early_release:
            continue  # without a dashpot every S = I (module doc)
        early = open_gaps_clear(sets, settings, a, n, early, seg_q[k], seg_v[k], seg_time[k])
        switched = seg_switched[k + 1]
        if switched >= n:  # an early-released gap opened: the set is unchanged
            early &= ~(1 << (switched - n))
            continue
        closing = (seg_mask[k + 1] >> switched) & 1
        trigger = n + switched if closing and (early >> switched) & 1 else switched
        apply_contacts_saltation(tangent_q, tangent_v, sets, settings, gap_weights, seg_mask[k],
                                 seg_mask[k + 1], trigger, seg_q[k + 1], seg_v[k + 1],
                                 seg_time[k + 1])
        early &= ~(1 << switched)
        if not closing:
            early |= 1 << switched


@kernel
def _advance_in_set(table, oscillators, no_drive, clock, t, tangent_q, tangent_v, y_q, y_v):
    """Advance the free-coordinate rows from ``clock[CLOCK_TIME]`` to t (s) in one set's phase.

    Through the set's oscillators (``oscillators`` = (left, right, modes); ``y_q``, ``y_v``
    their scratch rows) and back; the clock then reads t.
    """
    no_force = no_drive[0]
    tangent_switch(tangent_q, tangent_v, CONTACT, oscillators, no_drive, y_q, y_v)
    advance_tangents(table, y_q, y_v, clock[CLOCK_TIME], t - clock[CLOCK_TIME], no_force)
    tangent_switch(y_q, y_v, FREE, oscillators, no_drive, tangent_q, tangent_v)
    clock[CLOCK_TIME] = t


@kernel
def contacts_lyapunov_sums(sets, settings, early_release, gap_weights, free_frequencies,
                           recorded, t_end, columns, transient, batches):
    """Lyapunov sums of a recorded run of several contacts from t = 0 (all its phases).

    ``sets``: the run's active sets record. As `tangent.recorded_run_sums` for one contact:
    ``columns`` tangent rows from `tangent.new_tangent`, renormalised every forcing period
    (Omega = 0: the slowest free mode's) to ``settings.t_max``; returns ``(sums, counts,
    interval)``. The run starts with no contact released early (`run_contacts` from rest or a
    given state).
    """
    schedule = lyapunov_schedule(settings.forcing_frequency, free_frequencies, settings.t_max,
                                 transient)
    tangent = new_tangent(columns, free_frequencies, batches)
    carry_contact_tangents(sets, settings, early_release, gap_weights, free_frequencies,
                           recorded, t_end, 0, schedule, tangent)
    return tangent.sums, tangent.counts, schedule[0]
