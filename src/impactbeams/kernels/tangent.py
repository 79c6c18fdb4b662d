"""Tangent dynamics of the spring law and Benettin's method: Lyapunov exponents of a run.

The state is the free coordinates x = (q, q') of both beams (4 n values; docs/model.md,
"Long-time dynamics"); time enters only through the forcing. Arrays are named in
`impactbeams.kernels.layout`; SI units.

**Within a phase** a tangent vector obeys the phase's modal equations without their drive
(the drive does not depend on the state), so it is advanced by the same closed-form
propagation (`advance`'s arithmetic, zero drive) in the phase's
own coordinates: the free modes, or the contact oscillators y of
`impactbeams.kernels.contact_spring`. The maps between (q, q') and (y, y') are affine, with
linear parts that do not depend on time: ``to_contact`` and ``to_free`` with zero drives
are those linear parts.

**At a switch** the Jacobian of the flow is multiplied by the saltation matrix
``S = I + (f+ - f-) n^T / (n . f- + dh/dt)``: h the event function, n its gradient in x,
f- and f+ the vector fields before and after. The reset is the identity on x (no
projection), and in the free coordinates the two vector fields differ by the contact force
alone, ``f+ - f- = (0, (R+ - R-) w)`` with w the gap weights. R is continuous (S = I) at a
release (R = 0 on both sides) and at a re-onset after a dashpot's early release (R rises
through 0). At an onset where the gap closes, ``h = g``, ``n = (w, 0)``,
``n . f- + dh/dt = g' < 0``, and R jumps from 0 to ``-c_e g'`` (the spring's part ``-k_e g``
is 0 there): ``S = I - c_e (0; w) (w^T, 0)``, i.e. ``dq' -= c_e w (w . dq)``. Without a
dashpot S = I at every switch. The tied law is not covered: its switches project onto
another basis and its instantaneous impacts and accumulations do not form a flow whose
linearisation converges in n_modes.

**Benettin's method.** k tangent vectors are orthonormalised (modified Gram-Schmidt) every
``interval`` s, at t = i interval, in the energy inner product of the free modes,
``<a, b> = sum omega_n^2 a_q b_q + a_q' b_q'``, a norm every undamped mode keeps exactly (so
undamped motion without contact has exponent 0 to round-off). The logs of the growth factors
(the diagonal of R in the QR factorisation) of the intervals after ``transient`` are summed
in ``batches`` consecutive groups, for the exponents (1/s) and their batch-means error.
"""

import math

import numpy as np

from impactbeams.kernels import contact
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import (
    CONTACT,
    FREE,
    ROW_FREQUENCY,
    ROW_ZETA,
    SPRING_DRIVE_ROWS,
)
from impactbeams.kernels.propagation import step_factors, stepped_mode
from impactbeams.kernels.records import CLOCK, CLOCK_RENORMALIZATIONS, CLOCK_TIME, Tangent


@kernel
def renormalization_interval(forcing_frequency, free_frequencies):
    """Benettin interval (s): the forcing period 2 pi / Omega (Omega = 0: slowest free mode's)."""
    if forcing_frequency > 0.0:
        return 2.0 * math.pi / forcing_frequency
    return 2.0 * math.pi / np.min(free_frequencies)


@kernel
def interval_count(t_max, interval):
    """Number of renormalisation intervals in [0, t_max]; a last one short by round-off counts."""
    return int(math.floor(t_max / interval * (1.0 + 1e-12)))


@kernel
def renormalization_time(i, interval, t_max):
    """End (s) of renormalisation interval i (from 1); t_max if past it by round-off."""
    return min(i * interval, t_max)


@kernel
def _hash_uniform(n):
    """A fixed number in [-1, 1) for the integer n (splitmix64): reproducible everywhere."""
    z = np.uint64(n) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return (z >> np.uint64(11)) * (2.0 / 9007199254740992.0) - 1.0


@kernel
def orthonormalize(tangent_q, tangent_v, frequencies, log_growth):
    """Modified Gram-Schmidt of the rows of (tangent_q, tangent_v) in the energy product.

    ``<a, b> = sum_n omega_n^2 a_q b_q + a_v b_v`` (omega: free frequencies, rad/s). Writes
    the log of each row's norm after removing the earlier rows (the diagonal of R).
    """
    columns, m = tangent_q.shape
    for c in range(columns):
        for d in range(c):
            dot = 0.0
            for j in range(m):
                dot += (frequencies[j] * frequencies[j] * tangent_q[c, j] * tangent_q[d, j]
                        + tangent_v[c, j] * tangent_v[d, j])
            for j in range(m):
                tangent_q[c, j] -= dot * tangent_q[d, j]
                tangent_v[c, j] -= dot * tangent_v[d, j]
        norm = 0.0
        for j in range(m):
            norm += (frequencies[j] * tangent_q[c, j]) ** 2 + tangent_v[c, j] ** 2
        norm = math.sqrt(norm)
        log_growth[c] = math.log(norm)
        for j in range(m):
            tangent_q[c, j] /= norm
            tangent_v[c, j] /= norm


@kernel
def initial_tangents(columns, frequencies):
    """``columns`` orthonormal tangent vectors (energy product) in the free coordinates.

    Fixed pseudo-random directions (not random: the same exponent on every machine), so that
    the leading ones have a component along every direction the flow stretches.
    """
    m = frequencies.size
    tangent_q, tangent_v = np.empty((columns, m)), np.empty((columns, m))
    for c in range(columns):
        for j in range(m):
            tangent_q[c, j] = _hash_uniform(2 * m * c + j) / frequencies[j]
            tangent_v[c, j] = _hash_uniform(2 * m * c + m + j)
    orthonormalize(tangent_q, tangent_v, frequencies, np.empty(columns))
    return tangent_q, tangent_v


@kernel
def _renormalize(tangent_q, tangent_v, phase, switching, no_drive, frequencies, scratch_q,
                 scratch_v, log_growth):
    """Orthonormalise the tangents (in the free coordinates) in the coordinates of ``phase``."""
    if phase == FREE:
        orthonormalize(tangent_q, tangent_v, frequencies, log_growth)
        return
    contact.tangent_switch(tangent_q, tangent_v, FREE, switching, no_drive, scratch_q, scratch_v)
    orthonormalize(scratch_q, scratch_v, frequencies, log_growth)
    contact.tangent_switch(scratch_q, scratch_v, CONTACT, switching, no_drive, tangent_q,
                           tangent_v)


@kernel
def advance_tangents(table, tangent_q, tangent_v, t, h, no_force):
    """Advance every tangent row by h (s) with the phase's unforced closed-form propagation.

    `propagation.advance`'s arithmetic, with each mode's exponential, cosine and sine
    (`propagation.step_factors`) computed once for all the rows instead of once per row.
    """
    frequencies, zeta = table[ROW_FREQUENCY], table[ROW_ZETA]
    for j in range(frequencies.size):
        sigma, wd, decay, c, s, e_plus, e_minus = step_factors(h, frequencies[j], zeta[j], 0.0,
                                                               1.0 + 0.0j, False)
        for row in range(tangent_q.shape[0]):
            tangent_q[row, j], tangent_v[row, j] = stepped_mode(
                tangent_q[row, j], tangent_v[row, j], frequencies[j], no_force[j], sigma, wd,
                decay, c, s, e_plus, e_minus, 1.0 + 0.0j)


@kernel
def record_growth(sums, counts, log_growth, i, schedule):
    """Add interval i's log growths to its batch, if i (from 1) lies after the transient."""
    _, _, transient, total = schedule
    j = i - 1 - transient
    if j < 0:
        return
    batch = j * counts.size // (total - transient)
    counts[batch] += 1
    for c in range(log_growth.size):
        sums[batch, c] += log_growth[c]


@kernel
def carry_tangents(tables, phase_scalars, switching, settings, recorded, t_end, schedule,
                   tangent):
    """Carry the tangent vectors through the recorded segments of a spring-law run.

    ``switching``: the run's switching record (`records.SWITCHING`).
    ``recorded``: the run's `records.Segments`, all of them recorded ones (each segment's end
    state ``end_q``, ``end_v`` gives the onsets' saltation).
    ``tangent``, a `records.Tangent` ``(q, v, clock, sums, counts)``: k tangent rows in the
    coordinates of ``recorded.phase[0]`` at ``clock[CLOCK_TIME] = recorded.time[0]`` (s),
    ``clock[CLOCK_RENORMALIZATIONS]``
    renormalisations done; on return at ``t_end`` in the last segment's coordinates.
    ``schedule = (interval, t_max, transient, total)``: renormalise at ``i interval`` (s) for
    i = 1 .. total (the run's complete intervals to ``t_max``), and add the logs of the growth
    of intervals ``transient + 1 .. total`` into ``sums[batch, row]``, ``counts[batch]``
    (spread evenly over the batches).
    """
    tangent_q, tangent_v, clock, sums, counts = tangent
    interval, t_max, _, total = schedule
    columns, m = tangent_q.shape
    free_frequencies = tables[FREE, ROW_FREQUENCY]
    no_force = np.zeros(m, dtype=np.complex128)
    no_drive = np.zeros((len(SPRING_DRIVE_ROWS), m), dtype=np.complex128)
    scratch_q, scratch_v = np.empty((columns, m)), np.empty((columns, m))
    log_growth = np.empty(columns)
    seg_time, seg_phase, count = recorded.time, recorded.phase, recorded.time.size
    for k in range(count):
        phase = seg_phase[k]
        seg_end = seg_time[k + 1] if k + 1 < count else t_end
        while clock[CLOCK_RENORMALIZATIONS] < total:
            t_next = renormalization_time(clock[CLOCK_RENORMALIZATIONS] + 1.0, interval, t_max)
            if t_next > seg_end:
                break
            advance_tangents(tables[phase], tangent_q, tangent_v, clock[CLOCK_TIME],
                              t_next - clock[CLOCK_TIME], no_force)
            _renormalize(tangent_q, tangent_v, phase, switching, no_drive, free_frequencies,
                         scratch_q, scratch_v, log_growth)
            clock[CLOCK_TIME] = t_next
            clock[CLOCK_RENORMALIZATIONS] += 1.0
            record_growth(sums, counts, log_growth, int(clock[CLOCK_RENORMALIZATIONS]), schedule)
        advance_tangents(tables[phase], tangent_q, tangent_v, clock[CLOCK_TIME],
                          seg_end - clock[CLOCK_TIME], no_force)
        clock[CLOCK_TIME] = seg_end
        if k + 1 == count or seg_phase[k + 1] == phase:
            continue
        if phase == FREE:
            contact.onset_saltation(tangent_q, tangent_v, tables, phase_scalars, settings,
                                    recorded.end_q[k], recorded.end_v[k], seg_end)
        contact.tangent_switch(tangent_q, tangent_v, seg_phase[k + 1], switching, no_drive,
                            scratch_q, scratch_v)
        for row in range(tangent_q.shape[0]):
            contact.copy_state(scratch_q[row], scratch_v[row], tangent_q[row], tangent_v[row])


@kernel
def lyapunov_schedule(forcing_frequency, free_frequencies, t_max, transient):
    """``(interval, t_max, transient, total)`` of a run to ``t_max`` (s).

    ``total`` complete intervals, of which those after the first ``transient`` count.
    """
    interval = renormalization_interval(forcing_frequency, free_frequencies)
    return interval, t_max, transient, interval_count(t_max, interval)


@kernel
def new_tangent(columns, free_frequencies, batches):
    """A run's tangent state at t = 0 (see `carry_tangents`)."""
    tangent_q, tangent_v = initial_tangents(columns, free_frequencies)
    return Tangent(tangent_q, tangent_v, np.zeros(len(CLOCK)), np.zeros((batches, columns)),
                   np.zeros(batches, dtype=np.int64))


@kernel
def recorded_run_sums(tables, phase_scalars, switching, settings, recorded, t_end, columns,
                      transient, batches):
    """Lyapunov sums of a recorded spring-law run from t = 0 (all its `records.Segments`).

    Returns ``(sums, counts, interval)``: ``sums[batch, row]`` the summed log growths of the
    ``columns`` leading directions over ``counts[batch]`` intervals of ``interval`` s.
    """
    schedule = lyapunov_schedule(settings.forcing_frequency, tables[FREE, ROW_FREQUENCY],
                                 settings.t_max, transient)
    tangent = new_tangent(columns, tables[FREE, ROW_FREQUENCY], batches)
    carry_tangents(tables, phase_scalars, switching, settings, recorded, t_end, schedule, tangent)
    return tangent.sums, tangent.counts, schedule[0]
