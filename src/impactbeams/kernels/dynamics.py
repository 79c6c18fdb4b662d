"""Event-driven impact dynamics: the phase state machine.

Exact propagation within phases, certified switching events, and the states at any time.

Plain-array interface, packed by `impactbeams.packing`; every array is named in
`impactbeams.kernels.layout`: ``tables[phase]`` (rows ``TABLE_ROWS``), ``forces[phase]``
(complex drive amplitudes), ``phase_scalars[phase]`` (``PHASE_SCALARS``) and ``settings``
(``SETTINGS``). Both phases have ``N = 2 n`` modal coordinates. Reductions over a run (work,
dissipation, peak force) are in `impactbeams.kernels.reductions`.

The contact law is ``settings.contact_law``; what depends on it is dispatched by
`impactbeams.kernels.contact` (switch maps: the tied law's projections, the spring law's change
of coordinates), which alone reads the run's switching arrays: every kernel here takes them as
one switching record (`records.SWITCHING`), ``switching``, and passes it on whole.
"""

import math

import numpy as np

from impactbeams.kernels import contact
from impactbeams.kernels.drive import modal_acceleration_at
from impactbeams.kernels.events import (
    GAVE_UP,
    event_sine,
    first_root,
    phase_event,
    phase_event_function,
    phase_oscillators,
    root_after_rise,
)
from impactbeams.kernels.jit import borrowing_kernel, inlined_kernel, kernel
from impactbeams.kernels.layout import (
    CONTACT,
    FREE,
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
)
from impactbeams.kernels.propagation import advance, step_factors, stepped_mode
from impactbeams.kernels.records import EventFunction, Oscillators
from impactbeams.kernels.rotor import rotor_arrays

COMPLETE, EVENT_LIMIT, STUCK, SEARCH_LIMIT = 0, 1, 2, 3
NOT_RISEN = -1.0  # find_event: a rise it could not certify (times are never negative)
STATUS_NAMES = ("complete", "event_limit", "stuck", "search_limit")
# Consecutive zero-length phases allowed before the run is declared stuck. A chattering
# sequence that converges (alternating projections) ends well before; a persistent conflict
# between the two truncated phases would repeat forever at one instant.
ZENO_LIMIT = 64

_EPS = np.finfo(np.float64).eps


@kernel
def instantaneous(t_start, t_event):
    """Whether a phase that starts at t_start (s) and ends at t_event (s) has zero length."""
    return t_event <= t_start + 4.0 * _EPS * max(t_start, 1.0)


@borrowing_kernel
def propagate(table, force, q_s, v_s, t_s, t, settings, q, v):
    """State at time t (s) of the phase with ``table``, ``force`` from (q_s, v_s) at t_s."""
    advance(q_s, v_s, t_s, t - t_s, table[ROW_FREQUENCY], table[ROW_ZETA], force,
            settings.forcing_frequency, q, v)


@borrowing_kernel
def find_event(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor, rising=False):
    """First root in (t_s, t_max] of the phase's event function, NaN if none.

    The certified search restarts from the exactly propagated state every ``search span``
    seconds (settings, ``_later_event`` past the first); the root does not depend on that span
    beyond round-off. ``GAVE_UP`` if a search reached its step cap. ``rising``: e(t_s) <= 0 <
    e'(t_s), and the root sought is the first after e has risen through 0
    (``events.root_after_rise``); ``NOT_RISEN`` if that rise cannot be certified.
    """
    if not t_s < settings.t_max:
        return np.nan
    t_b = _span_end(t_s, settings)
    oscillators = phase_oscillators(table, force, settings.forcing_frequency)
    event = phase_event_function(table, scalars, settings.forcing_frequency)
    if rising:
        root, risen = root_after_rise(q_s, v_s, t_s, t_b, oscillators, event, q, v, rotor)
        if not risen:
            return NOT_RISEN
    else:
        root = first_root(q_s, v_s, t_s, t_b, oscillators, event, q, v, rotor)
    if not math.isnan(root) or not t_b < settings.t_max:
        return root
    return _later_event(table, force, scalars, q_s, v_s, t_s, t_b, settings, q, v, rotor)


@borrowing_kernel
def _span_end(t_a, settings):
    """The end (s) of the search span from t_a, at most t_max.

    A span below the resolution of t searches the rest at once (it could not advance t).
    """
    t_b = min(t_a + settings.search_span, settings.t_max)
    return settings.t_max if t_b <= t_a else t_b


@kernel
def _later_event(table, force, scalars, q_s, v_s, t_s, t_a, settings, q, v, rotor):
    """``find_event``'s search spans from t_a on, each from the exactly propagated state."""
    oscillators = phase_oscillators(table, force, settings.forcing_frequency)
    event = phase_event_function(table, scalars, settings.forcing_frequency)
    q_a, v_a = np.empty_like(q_s), np.empty_like(v_s)
    while t_a < settings.t_max:
        propagate(table, force, q_s, v_s, t_s, t_a, settings, q_a, v_a)
        t_b = _span_end(t_a, settings)
        root = first_root(q_a, v_a, t_a, t_b, oscillators, event, q, v, rotor)
        if not math.isnan(root):
            return root
        t_a = t_b
    return np.nan


@kernel
def rate_root(table, force, scalars, sign, q_s, v_s, t_s, t_end, settings, q, v, rotor):
    """First time in (t_s, t_end] where ``sign * e'`` reaches 0 from above; NaN if none.

    ``e' = sine_amp Omega cos(Omega t) + weights . q'(t)``. The velocities p = q' obey the
    differentiated modal equations, driven by ``Im(i Omega A e^(i Omega t))``: the same
    oscillators driven by ``Im(Omega A e^(i Omega tau))`` in the shifted time
    ``tau = t + pi / (2 Omega)``, so ``first_root`` applies unchanged.
    """
    forcing_frequency = settings.forcing_frequency
    frequencies, zeta = table[ROW_FREQUENCY], table[ROW_ZETA]
    shift = 0.5 * math.pi / forcing_frequency if forcing_frequency > 0.0 else 0.0
    acceleration = modal_acceleration_at(force, frequencies, zeta, q_s, v_s, forcing_frequency, t_s)
    rates = Oscillators(frequencies, zeta, force * forcing_frequency, forcing_frequency)
    event_rate = EventFunction(sign * table[ROW_EVENT], 0.0,
                               sign * event_sine(scalars) * forcing_frequency, forcing_frequency)
    root = first_root(v_s, acceleration, t_s + shift, t_end + shift, rates, event_rate, q, v,
                      rotor)
    return root - shift


@borrowing_kernel
def _step_until(table, force, scalars, q_s, v_s, t_s, t, positive_rate, settings, q, v):
    """First time from t on, in growing steps of a few ulps, where e > 0 (or e' > 0).

    Moves a search off a root it has just located, where e (or e') is 0 to round-off.
    ``GAVE_UP`` if it is still not positive after 64 doublings of the step (a span of
    2^66 eps t: the root was not a crossing).
    """
    step = 4.0 * _EPS * max(abs(t), 1e-300)
    for _ in range(64):
        propagate(table, force, q_s, v_s, t_s, t, settings, q, v)
        value, slope = phase_event(table, scalars, q, v, t, settings.forcing_frequency)
        if (slope if positive_rate else value) > 0.0:
            return t
        t += step
        step *= 2.0
    return GAVE_UP


@inlined_kernel
def _opposite(table, scalars, forcing_frequency):
    """-e of the phase's event function: its roots from above are where e rises through 0."""
    return EventFunction(-table[ROW_EVENT], -scalars[SCALAR_CONST], -event_sine(scalars),
                         forcing_frequency)


@borrowing_kernel
def find_switch(table, force, scalars, q_s, v_s, t_s, wait_rising, wait_falling, settings, q,
                v, rotor):
    """First time (s) from t_s at which e <= 0 while not rising (e' <= 0); NaN if none.

    e > 0 at the start: its first root (``find_event``). e <= 0 at the start: t_s, except

    * rising (e' > 0) and ``wait_rising``: follow e until it has risen through 0 and falls back
      to it, or until it peaks below 0 (e' = 0), whichever comes first (``_switch_after_rise``);
    * falling and ``wait_falling``: follow e to its minimum, then as when rising
      (``_switch_after_minimum``).

    ``rotor``: the phase's (``rotor.rotor_arrays``), kept across its searches.
    """
    value, slope = phase_event(table, scalars, q_s, v_s, t_s, settings.forcing_frequency)
    if value > 0.0:
        return find_event(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor)
    if slope <= 0.0:
        if not wait_falling:
            return t_s
        return _switch_after_minimum(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor)
    if not wait_rising:
        return t_s
    return _switch_after_rise(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor)


@kernel
def _switch_after_minimum(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor):
    """``find_switch`` from a falling e <= 0: its minimum, then as from a rise there."""
    t_min = rate_root(table, force, scalars, -1.0, q_s, v_s, t_s, settings.t_max, settings, q, v,
                      rotor)
    if math.isnan(t_min) or t_min == GAVE_UP:
        return t_min
    q_a, v_a = np.empty_like(q_s), np.empty_like(v_s)
    t_a = _step_until(table, force, scalars, q_s, v_s, t_s, t_min, True, settings, q_a, v_a)
    if t_a == GAVE_UP:
        return GAVE_UP
    value, _ = phase_event(table, scalars, q_a, v_a, t_a, settings.forcing_frequency)
    if value > 0.0:
        return find_event(table, force, scalars, q_a, v_a, t_a, settings, q, v, rotor)
    return _switch_after_rise(table, force, scalars, q_a, v_a, t_a, settings, q, v, rotor)


@borrowing_kernel
def _switch_after_rise(table, force, scalars, q_a, v_a, t_a, settings, q, v, rotor):
    """``find_switch`` from e <= 0 < e' at t_a: the root after the rise, or the peak below 0.

    A rise certified by ``events.root_after_rise`` needs no search for the peak
    (``_switch_by_peak``).
    """
    root = find_event(table, force, scalars, q_a, v_a, t_a, settings, q, v, rotor, True)
    if root != NOT_RISEN:  # certainly risen through 0: no need to find its peak
        return root
    return _switch_by_peak(table, force, scalars, q_a, v_a, t_a, settings, q, v, rotor)


@kernel
def _switch_by_peak(table, force, scalars, q_a, v_a, t_a, settings, q, v, rotor):
    """``_switch_after_rise`` where the rise is not certified: e's peak, then its root."""
    t_max = settings.t_max
    t_peak = rate_root(table, force, scalars, 1.0, q_a, v_a, t_a, t_max, settings, q, v, rotor)
    if t_peak == GAVE_UP:
        return GAVE_UP
    t_limit = t_max if math.isnan(t_peak) else t_peak
    t_up = first_root(q_a, v_a, t_a, t_limit,
                      phase_oscillators(table, force, settings.forcing_frequency),
                      _opposite(table, scalars, settings.forcing_frequency), q, v, rotor)
    if t_up == GAVE_UP:
        return GAVE_UP
    if math.isnan(t_up) or t_up >= t_limit:
        return t_peak
    t_up = _step_until(table, force, scalars, q_a, v_a, t_a, t_up, False, settings, q, v)
    if t_up == GAVE_UP:
        return GAVE_UP
    q_up, v_up = q.copy(), v.copy()
    return find_event(table, force, scalars, q_up, v_up, t_up, settings, q, v, rotor)


@kernel
def _reonset_after_early_release(table, force, scalars, q_s, v_s, t_s, settings, q, v, rotor):
    """Spring law with a dashpot, free phase entered with the tips still overlapping.

    The dashpot released them early (R = -k_e g - c_e g' fell to 0 with g < 0). Returns
    ``(t, opened)``: the time that force rises through 0 again while g < 0 (the next onset,
    ``opened`` False), or the time the gap opens first (``opened`` True: the free phase goes on
    from there as a new segment, so that the spring's relaxation, which ends there, is
    integrated on its own). The force is tracked through y = k_e q + c_e q', oscillators
    with the same frequencies and the drive (k_e + i c_e Omega) A, so that ``-R = k_e g +
    c_e g' = k_e clearance + Im((k_e + i c_e Omega) S e^(i Omega t)) + weights . y``.
    """
    stiffness, damping = settings.contact_stiffness, settings.contact_damping
    forcing_frequency = settings.forcing_frequency
    frequencies, zeta = table[ROW_FREQUENCY], table[ROW_ZETA]
    impedance = complex(stiffness, damping * forcing_frequency)
    acceleration = modal_acceleration_at(force, frequencies, zeta, q_s, v_s, forcing_frequency, t_s)
    y, y_rate = stiffness * q_s + damping * v_s, stiffness * v_s + damping * acceleration
    force_scalars = scalars.copy()
    force_scalars[SCALAR_CONST] = stiffness * scalars[SCALAR_CONST]
    harmonic = impedance * event_sine(scalars)
    force_scalars[SCALAR_SINE], force_scalars[SCALAR_COSINE] = harmonic.real, harmonic.imag
    return reonset_or_opening(table, impedance * force, force_scalars, y, y_rate, table, force,
                              scalars, q_s, v_s, t_s, settings, q, v, rotor)


@kernel
def reonset_or_opening(force_table, force_drive, force_scalars, y_s, y_rate_s, gap_table,
                       gap_drive, gap_scalars, q_s, v_s, t_s, settings, q, v, rotor):
    """After an early release at t_s (s): ``(t, opened)``, the re-onset or the gap's opening.

    Two event functions of one phase, each in its own oscillators: -R, the force the released
    contact would have if closed (``force_*``, from (y_s, y_rate_s); 0 and rising at the
    release), and its gap g (``gap_*``, from (q_s, v_s); < 0). The re-onset is where R rises
    through 0 again (``find_switch`` waiting for -R's rise, ``opened`` False), unless the gap
    opens first (g rises through 0: ``opened`` True).
    """
    t_onset = find_switch(force_table, force_drive, force_scalars, y_s, y_rate_s, t_s, True,
                          False, settings, q, v, rotor)
    t_open = first_root(q_s, v_s, t_s, settings.t_max,
                        Oscillators(gap_table[ROW_FREQUENCY], gap_table[ROW_ZETA], gap_drive,
                                    settings.forcing_frequency),
                        _opposite(gap_table, gap_scalars, settings.forcing_frequency), q, v,
                        rotor)
    if t_open == GAVE_UP:
        return GAVE_UP, False
    if math.isnan(t_open) or t_onset <= t_open:
        return t_onset, False
    return t_open, True


@kernel
def run_events(tables, forces, phase_scalars, switching, settings, q0, v0, recorded, t_start=0.0,
               phase_start=FREE):
    """Integrate from the free-phase state (q0, v0) at t = 0 to t_max, event by event.

    ``t_start``, ``phase_start``: start instead from the state (q0, v0) of that phase (in its
    coordinates) at that time (s), to run a long horizon in windows of bounded memory. A
    window starts afresh: in the tied law the accumulation and conflict history of the
    previous window is not carried over. At the start of a recorded free segment that follows
    a contact of positive length that history is empty, so a window started there (from its
    ``seg_time, seg_q, seg_v``) records the same segments, bit for bit, as the uninterrupted
    run.

    ``recorded``: `records.Segments` to fill. Segment k starts at ``time[k]`` in phase
    ``phase[k]`` with state ``q[k], v[k]`` and ends (next event, or t_max for the last one) in
    state ``end_q[k], end_v[k]`` before any projection. At most ``time.size`` segments.

    Onset: the gap is <= 0 while closing; release: the contact force is <= 0 while falling
    (``find_switch``). A spring contact starts at zero force (rising: it waits for the force).
    In the tied law the two truncated bases do not agree exactly at a switch, so:

    * a free phase that starts with a gap <= 0 but opening (the released state's truncation
      error) waits for the gap;
    * a contact that starts with a force <= 0 is an instantaneous impact (released at once),
      except after an accumulation: an onset within ``accumulation time`` (settings) of the
      release of an instantaneous impact starts a sustained contact (``sustained[k]``)
      that waits for a rising force;
    * if even a sustained contact is released at once (force <= 0 and falling: a conflict,
      both bases call for the other phase), the free phase that follows waits for the gap's
      minimum: separation wins, as the force is tensile; the gap is then < 0 briefly, by
      about the release's truncation error.

    Returns (number of segments, status, end time of the last segment in s). Status:
    ``COMPLETE`` (t_max reached), ``EVENT_LIMIT`` (arrays full: the run stops at the last
    recorded event), ``STUCK`` (more than ``ZENO_LIMIT`` zero-length phases in a row) or
    ``SEARCH_LIMIT`` (an event search reached its step cap, ``events.step_limit``; the run
    stops at the start of that segment).
    """
    seg_time, seg_phase, seg_sustained, seg_q, seg_v, end_q, end_v = recorded
    n_coords = q0.size
    q, v = q0.copy(), v0.copy()
    q_end, v_end = np.empty(n_coords), np.empty(n_coords)
    rotors = (rotor_arrays(n_coords), rotor_arrays(n_coords))  # a phase's searches share one
    phase, t, zero_run, instant_release = phase_start, t_start, 0, -math.inf
    sustained = conflict = False
    waits_for_force = contact.waits_for_force(settings)  # a spring contact starts at R = 0
    opened = False  # the previous segment ended where an early-released gap opened
    for k in range(seg_time.size):
        seg_time[k], seg_phase[k], seg_sustained[k] = t, phase, sustained
        contact.copy_state(q, v, seg_q[k], seg_v[k])
        table, force, scalars = tables[phase], forces[phase], phase_scalars[phase]
        free = phase == FREE
        value, _ = phase_event(table, scalars, q, v, t, settings.forcing_frequency)
        reopening = opened
        opened = False
        if free and contact.may_release_early(settings) and value < 0.0 and not reopening:
            t_event, opened = _reonset_after_early_release(table, force, scalars, q, v, t,
                                                           settings, q_end, v_end, rotors[phase])
        else:
            t_event = find_switch(table, force, scalars, q, v, t,
                                  free or sustained or waits_for_force, free and conflict,
                                  settings, q_end, v_end, rotors[phase])
        if t_event == GAVE_UP:  # an event search reached its step cap: stop, undecided
            contact.copy_state(q, v, end_q[k], end_v[k])
            return k + 1, SEARCH_LIMIT, t
        t_stop = settings.t_max if math.isnan(t_event) else t_event
        propagate(table, force, q, v, t, t_stop, settings, q_end, v_end)
        contact.copy_state(q_end, v_end, end_q[k], end_v[k])
        if math.isnan(t_event):
            return k + 1, COMPLETE, t_stop
        if opened:  # the same free phase goes on from the opening of the gap
            contact.copy_state(q_end, v_end, q, v)
            t = t_event
            continue
        instant = instantaneous(t, t_event)
        zero_run = zero_run + 1 if instant else 0
        if zero_run > ZENO_LIMIT:
            return k + 1, STUCK, t_stop
        if free:
            phase = CONTACT
            sustained = t_event - instant_release <= settings.accumulation
        else:
            phase = FREE
            instant_release = t_event if instant else -math.inf
            conflict = instant and sustained
            sustained = False
        contact.switch_state(q_end, v_end, t_event, phase, switching, settings, q, v)
        t = t_event
    return seg_time.size, EVENT_LIMIT, t


@kernel
def segment_index(seg_time, count, t, start):
    """Index of the last segment (from ``start``) that begins at or before time t."""
    k = start
    while k + 1 < count and seg_time[k + 1] <= t:
        k += 1
    return k


@kernel
def sample_states(tables, forces, switching, settings, recorded, times, q_out, v_out, phase_out):
    """Modal state and phase at each of the ascending ``times`` (s), in closed form.

    ``recorded``: the run's `records.Segments`, all of them recorded ones. At an event time the
    state after the switch is returned, in the coordinates it is observed in
    (``contact.observed_state``: the spring law's free ones, the tied law's phase's own).
    """
    k = 0
    n_coords = recorded.q.shape[1]
    y, y_rate = np.empty(n_coords), np.empty(n_coords)
    for i in range(times.size):
        k = segment_index(recorded.time, recorded.time.size, times[i], k)
        phase = recorded.phase[k]
        phase_out[i] = phase
        propagate(tables[phase], forces[phase], recorded.q[k], recorded.v[k], recorded.time[k],
                  times[i], settings, y, y_rate)
        contact.observed_state(phase, y, y_rate, times[i], switching, settings, q_out[i], v_out[i])


@kernel
def sample_grid(tables, forces, switching, settings, recorded, times, q_out, v_out, phase_out):
    """``sample_states`` at equally spaced ``times`` (s), a step at a time within a segment.

    A segment's first time is reached from the segment's start, each next one by one step
    from the one before, whose exponentials, sines and cosines (`propagation.step_factors`)
    are computed once per phase instead of at every time and mode: some ten times cheaper.
    A state k steps into a segment carries about k roundings more than ``sample_states``'
    (k ulps of the motion's size: enough to find where to refine, not a result).
    """
    n_coords = recorded.q.shape[1]
    y, y_rate = np.empty(n_coords), np.empty(n_coords)
    factors, integrals = _step_factors(tables, forces, settings, times[1] - times[0])
    omega_forcing = settings.forcing_frequency
    k, last = 0, -1
    for i in range(times.size):
        k = segment_index(recorded.time, recorded.time.size, times[i], k)
        phase = recorded.phase[k]
        phase_out[i] = phase
        if k != last:
            propagate(tables[phase], forces[phase], recorded.q[k], recorded.v[k],
                      recorded.time[k], times[i], settings, y, y_rate)
            last = k
        else:
            phase_plus = complex(math.cos(omega_forcing * times[i - 1]),
                                 math.sin(omega_forcing * times[i - 1]))
            frequencies, force = tables[phase, ROW_FREQUENCY], forces[phase]
            for j in range(frequencies.size):
                f, g = factors[phase, :, j], integrals[phase, :, j]
                y[j], y_rate[j] = stepped_mode(y[j], y_rate[j], frequencies[j], force[j], f[0],
                                               f[1], f[2], f[3], f[4], g[0], g[1], phase_plus)
        contact.observed_state(phase, y, y_rate, times[i], switching, settings, q_out[i], v_out[i])


@kernel
def sample_segments(tables, forces, switching, settings, recorded, ends, count, q_out, v_out):
    """``count`` equally spaced states over each recorded segment, a step at a time.

    Segment k's samples, rows ``k * count`` to ``(k + 1) * count - 1`` of the outputs, are at
    ``time[k] + i h_k``, h_k = (``ends[k]`` - time[k]) / (count - 1): the first is the
    segment's start, each next one step (`propagation.step_factors`, computed once per
    segment) from the one before; observed as `sample_states`' are. As `sample_grid`'s, a
    state i steps in carries about i roundings more than `sample_states`' would: where to
    look closer, not a result.
    """
    n_coords = recorded.q.shape[1]
    y, y_rate = np.empty(n_coords), np.empty(n_coords)
    factors = np.empty((tables.shape[0], 5, tables.shape[2]))
    integrals = np.zeros((tables.shape[0], 2, tables.shape[2]), dtype=np.complex128)
    omega_forcing = settings.forcing_frequency
    for k in range(recorded.time.size):
        phase, start = recorded.phase[k], recorded.time[k]
        h = (ends[k] - start) / (count - 1)
        _phase_step_factors(tables, forces, settings, h, phase, factors, integrals)
        y[:], y_rate[:] = recorded.q[k], recorded.v[k]
        frequencies, force = tables[phase, ROW_FREQUENCY], forces[phase]
        for i in range(count):
            t = start + i * h
            if i > 0:
                t_before = start + (i - 1) * h
                phase_plus = complex(math.cos(omega_forcing * t_before),
                                     math.sin(omega_forcing * t_before))
                for j in range(frequencies.size):
                    f, g = factors[phase, :, j], integrals[phase, :, j]
                    y[j], y_rate[j] = stepped_mode(y[j], y_rate[j], frequencies[j], force[j],
                                                   f[0], f[1], f[2], f[3], f[4], g[0], g[1],
                                                   phase_plus)
            contact.observed_state(phase, y, y_rate, t, switching, settings,
                                   q_out[k * count + i], v_out[k * count + i])


@kernel
def _step_factors(tables, forces, settings, h):
    """Each phase's modes' `step_factors` for a step of ``h`` (s): real and complex parts."""
    n_phases, n_modes = tables.shape[0], tables.shape[2]
    factors = np.empty((n_phases, 5, n_modes))
    integrals = np.zeros((n_phases, 2, n_modes), dtype=np.complex128)
    for phase in range(n_phases):
        _phase_step_factors(tables, forces, settings, h, phase, factors, integrals)
    return factors, integrals


@kernel
def _phase_step_factors(tables, forces, settings, h, phase, factors, integrals):
    """``phase``'s modes' `step_factors` for a step of ``h`` (s) into its rows of the outputs."""
    omega_forcing = settings.forcing_frequency
    step_plus = complex(math.cos(omega_forcing * h), math.sin(omega_forcing * h))
    frequencies, zeta = tables[phase, ROW_FREQUENCY], tables[phase, ROW_ZETA]
    for j in range(frequencies.size):
        sigma, wd, decay, c, s, e_plus, e_minus = step_factors(
            h, frequencies[j], zeta[j], omega_forcing, step_plus, forces[phase, j] != 0.0)
        factors[phase, 0, j], factors[phase, 1, j], factors[phase, 2, j] = sigma, wd, decay
        factors[phase, 3, j], factors[phase, 4, j] = c, s
        integrals[phase, 0, j], integrals[phase, 1, j] = e_plus, e_minus


@kernel
def observed_states(phase, times, q, v, switching, settings, q_out, v_out):
    """States ``(q[i], v[i])`` of ``phase[i]`` at ``times[i]`` (s) as observed, into the outputs.

    ``contact.observed_state``: the spring law's contact states back in the free coordinates.
    """
    for i in range(times.size):
        contact.observed_state(phase[i], q[i], v[i], times[i], switching, settings, q_out[i],
                               v_out[i])
