"""A basin map's cells, a chunk at a time: each run in blocks until its samples settle.

One call runs every cell of a chunk with no Python between them (`settle_cells`), so that
chunks on threads run in parallel (the kernels release the GIL). The steps are those of
`impactbeams.orbits.basin_cells`, whose module doc describes them: a block of forcing periods
from t = 0 (`run_events`), its stroboscopic tip samples (`sample_states`, `tip_motion`), a test
for a period over the last ``window`` samples, the next block from the state the last one
ended in. A sample is x = (y1, y2, v1 / Omega, v2 / Omega) (m).

The period tests compare maxima of absolute differences with a fraction of a maximum: exact
operations, so the results are bit for bit those of the same tests in NumPy. Every maximum
here is NaN if any of its values is (as NumPy's), so a NaN sample never passes a test.
"""

import numpy as np

from impactbeams.kernels import contact
from impactbeams.kernels.dynamics import COMPLETE, run_events, sample_states
from impactbeams.kernels.events import event_value, phase_event_function
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.layout import CONTACT, FREE, TIP_V1, TIP_V2, TIP_Y1, TIP_Y2
from impactbeams.kernels.records import recorded_prefix, segments
from impactbeams.kernels.stroboscope import NO_STATE, tip_motion

NOT_SETTLED = -1  # a cell's status: no period within its periods
STOPPED = -2  # a run stopped before its horizon, or a start the tied law refuses


@kernel
def _larger(a, b):
    """max(a, b), NaN if either is (as NumPy's maximum)."""
    if a != a or b > a:
        return b
    return a


@kernel
def _largest_step(x, first, last, lag):
    """Max |x[k + lag] - x[k]| over rows k of [first, last - lag) and every column."""
    largest = 0.0
    for k in range(first, last - lag):
        for c in range(x.shape[1]):
            largest = _larger(largest, abs(x[k + lag, c] - x[k, c]))
    return largest


@kernel
def _largest(x, first, last):
    """Max |x[k]| over rows k of [first, last) and every column."""
    largest = 0.0
    for k in range(first, last):
        for c in range(x.shape[1]):
            largest = _larger(largest, abs(x[k, c]))
    return largest


@kernel
def period_of(x, first, last, known, tolerance, max_period):
    """The period of rows [first, last) of the samples x, 0 if none.

    The smallest p <= ``max_period`` with max |x[k + p] - x[k]| <= tolerance max |x|
    (`impactbeams.longtime.response_period`); with ``known`` > 0 that period alone.
    """
    bound = tolerance * _largest(x, first, last)
    if known > 0:
        return known if _largest_step(x, first, last, known) <= bound else 0
    for p in range(1, max_period + 1):
        if _largest_step(x, first, last, p) <= bound:
            return p
    return 0


@kernel
def settled_from(x, count, period, tolerance):
    """The first sample k from which rows [0, count) of x repeat with ``period``; 1 if all.

    Each step x[k + p] - x[k] within tolerance of the scale from sample k to the end; k + 1
    forcing periods have passed at sample k (the first sample is taken after one period).
    """
    scale = _largest(x, count - period, count)  # the largest |x| from row k on, k going down
    for k in range(count - period - 1, -1, -1):
        scale = _larger(scale, _largest(x, k, k + 1))
        if _largest_step(x, k, k + period + 1, period) > tolerance * scale:
            return k + 2
    return 1


@kernel
def start_phase(z, tables, phase_scalars, switching, settings, q, v):
    """The section state z = (q, q') at t = 0 into (q, v) in its phase's coordinates; the phase.

    The tied law starts free, from an open gap only (``NO_STATE`` otherwise); the spring law in
    contact iff g < 0 and its force -k_e g - c_e g' > 0 (`trajectory.start.phase_state`).
    """
    n = q.size
    gap, gap_rate = event_value(z[:n], z[n:], 0.0, phase_event_function(
        tables[FREE], phase_scalars[FREE], settings.forcing_frequency))
    contact.copy_state(z[:n], z[n:], q, v)
    if not contact.keeps_free_coordinates(settings.contact_law):
        return FREE if gap > 0.0 else NO_STATE
    force = -settings.contact_stiffness * gap - settings.contact_damping * gap_rate
    if not (gap < 0.0 and force > 0.0):
        return FREE
    contact.switch_state(z[:n], z[n:], 0.0, CONTACT, switching, settings, q, v)
    return CONTACT


@kernel
def _onsets_since(recorded, count, since):
    """Contact onsets (segments after the first that start a contact) at times >= since (s)."""
    onsets = 0
    for k in range(1, count):
        if recorded.phase[k] == CONTACT and recorded.time[k] >= since:
            onsets += 1
    return onsets


@kernel
def settle_cells(tables, forces, phase_scalars, switching, settings, states, known, times, omega,
                 forcing_period, window, tolerance, max_period, max_periods, max_events, period,
                 contacts, settle_periods, status, samples, end_q, end_v, end_phase):
    """Every section state of ``states`` (cells, 2 N) run in blocks until it settles.

    A block runs from t = 0 to its horizon ``settings.t_max`` (at most ``max_events``
    phases) and is sampled at ``times`` (s, its forcing periods' ends); ``known[i]`` > 0: cell
    i's period, tested alone. Writes row i of the outputs (`basin_cells.Cells`: period,
    contacts over the last period, settle periods, status, the last p samples, the state the
    last block ended in and its phase); ``samples``, ``end_q``, ``end_v`` come in NaN and
    ``end_phase`` -1.
    """
    n, block = states.shape[1] // 2, times.size
    recorded = segments(max_events, n)
    history = np.empty((max_periods + block, 4))
    q, v = np.empty(n), np.empty(n)
    sample_q, sample_v = np.empty((block, n)), np.empty((block, n))
    sample_phase = np.empty(block, dtype=np.int64)
    tips = np.empty((block, 4))
    residual2 = contact.residual_flexibility2(tables[FREE], settings)
    z = np.empty(2 * n)
    for i in range(states.shape[0]):
        phase = start_phase(states[i], tables, phase_scalars, switching, settings, q, v)
        run = 0  # forcing periods run
        while phase != NO_STATE and run < max_periods:  # NO_STATE: refused, or stopped
            count, run_status, _ = run_events(tables, forces, phase_scalars, switching, settings,
                                              q, v, recorded, 0.0, phase)
            if run_status != COMPLETE:
                phase = NO_STATE
                break
            sample_states(tables, forces, switching, settings, recorded_prefix(recorded, count),
                          times, sample_q, sample_v, sample_phase)
            for k in range(block):
                tip_motion(tables, forces, phase_scalars, settings, residual2, sample_phase[k],
                           times[k], sample_q[k], sample_v[k], tips[k])
                history[run + k, 0], history[run + k, 1] = tips[k, TIP_Y1], tips[k, TIP_Y2]
                history[run + k, 2] = tips[k, TIP_V1] / omega
                history[run + k, 3] = tips[k, TIP_V2] / omega
            run += block
            if contact.keeps_free_coordinates(settings.contact_law):  # sampled free: the phase
                contact.copy_state(sample_q[block - 1], sample_v[block - 1], z[:n], z[n:])
                phase = start_phase(z, tables, phase_scalars, switching, settings, q, v)
            else:
                contact.copy_state(sample_q[block - 1], sample_v[block - 1], q, v)
                phase = sample_phase[block - 1]
            p = period_of(history, run - window, run, known[i], tolerance,
                          max_period) if run >= window else 0
            if p:
                period[i] = p
                contacts[i] = _onsets_since(recorded, count, times[-1] - p * forcing_period)
                settle_periods[i] = settled_from(history, run, p, tolerance)
                for k in range(p):  # element by element: no slice assignment's message
                    for c in range(4):
                        samples[i, k, c] = history[run - p + k, c]
                break
        if phase == NO_STATE:
            status[i], settle_periods[i] = STOPPED, run
            continue
        contact.copy_state(q, v, end_q[i], end_v[i])
        end_phase[i] = phase
        if not period[i]:
            status[i], settle_periods[i] = NOT_SETTLED, run
