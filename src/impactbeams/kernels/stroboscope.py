"""Stroboscopic (Poincare) samples of a long run, in windows of bounded memory.

A long run (hundreds of forcing periods, thousands of phases) is integrated by
`run_events` into segment arrays of a fixed capacity.
When they are full, the states at the sample times that the recorded segments cover are taken
in closed form (`sample_states`), and the run resumes from
the start of the last free segment that follows a contact of positive length, which reproduces
the uninterrupted run bit for bit. A cell's memory is the capacity, whatever the horizon.

Per sample: the tip deflections and velocities (``TIP_COLUMNS``, layout); per run, over the
sampled window ``[t_first, t_max)``: contact onsets and impact episodes (a contact starts a new
episode unless the free interval since the previous release is shorter than ``separation``,
the rule of `impactbeams.trajectory.episodes`), in ``STROBOSCOPE_COLUMNS``. Arrays are
named in `impactbeams.kernels.layout`; SI units.

A run starts from its cell's own initial state or from a given state and phase, and hands
on its state at its horizon: a stepped-sine row (`stepped_map_parallel`) runs its cells one
after the other, each from the state its predecessor ended in (docs/model.md, "Stepped-sine
sweeps").
"""

import math

import numpy as np
from numba import prange

from impactbeams.kernels import contact
from impactbeams.kernels.cells import cell_run, settings_of
from impactbeams.kernels.drive import clamp_motion, tip_load
from impactbeams.kernels.dynamics import (
    COMPLETE,
    EVENT_LIMIT,
    instantaneous,
    run_events,
    sample_states,
)
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import (
    CELL_FORCING_FREQUENCY,
    CELL_GEOMETRY,
    CONTACT,
    FREE,
    ROW_FREQUENCY,
    ROW_TIP1,
    ROW_TIP2,
    STROBE_EPISODES,
    STROBE_ONSETS,
    STROBE_STATUS,
    STROBE_T_END,
    TIP_V1,
    TIP_V2,
    TIP_Y1,
    TIP_Y2,
)
from impactbeams.kernels.records import geometry_switching, recorded_prefix, segments

NO_STATE = -1  # a phase index for no state: a run's own start, or a run that stopped early


@kernel
def tip_motion(tables, forces, phase_scalars, settings, residual2, phase, t, q, v, out):
    """Tip deflections y1(l1), y2(l2) (m) and velocities (m/s) of a sampled state into ``out``.

    ``y_i = -c_i Q_i(t) + sum_n Y_in(l_i) q_n`` with the quasi-static tip loads Q_i of
    `contact.tip_loads` (the free phase's Q1 = F, Q2 = 0; in tied contact, whose two tips
    share the contact shapes' values, Q1 = F - R_qs, Q2 = R_qs), in the coordinates the state
    is observed in (`contact.observed_state`), plus the law's correction
    (`contact.correct_tips`: in a spring contact the flexibility the modes miss moves the tips
    by ``+r_1 R``, ``-r_2 R``; ``residual2`` is r_2, m/N). With a shaker the tips are reported
    in the absolute frame: ``y_i = u_b + w_i`` on a beam whose clamp moves.
    """
    load1, rate1 = tip_load(settings, t)
    load1, rate1, load2, rate2 = contact.tip_loads(phase, t, settings, load1, rate1)
    observed = contact.observed_phase(phase, settings)
    shared_tips = observed == CONTACT  # tied contact: both tips move with the contact shapes
    table = tables[observed]
    y1, y2 = -settings.c1 * load1, -settings.c2 * load2
    v1, v2 = -settings.c1 * rate1, -settings.c2 * rate2
    tip1, tip2_row = table[ROW_TIP1], table[ROW_TIP2]
    for j in range(q.size):
        tip2 = tip1[j] if shared_tips else tip2_row[j]
        y1 += tip1[j] * q[j]
        y2 += tip2 * q[j]
        v1 += tip1[j] * v[j]
        v2 += tip2 * v[j]
    out[TIP_Y1], out[TIP_Y2], out[TIP_V1], out[TIP_V2] = y1, y2, v1, v2
    contact.correct_tips(phase, tables, forces, phase_scalars, settings, residual2, t, q, v, out)
    if settings.base_amplitude != 0.0:  # the absolute frame: the clamps' motion added
        clamp, clamp_rate, _ = clamp_motion(settings, t)
        out[TIP_Y1] += settings.shaker1 * clamp
        out[TIP_Y2] += settings.shaker2 * clamp
        out[TIP_V1] += settings.shaker1 * clamp_rate
        out[TIP_V2] += settings.shaker2 * clamp_rate


@kernel
def tip_loads_at(settings, phase, t, out):
    """`contact.tip_loads` of ``phase[k]`` at ``t[k]`` (s): row k of ``out`` is (Q1, Q1', Q2, Q2').

    The loads of the tip force F(t) in the quasi-static parts (N, N/s), one formula with
    ``tip_motion``'s (`impactbeams.trajectory.observables` evaluates energies with them).
    """
    for k in range(t.size):
        load1, rate1 = tip_load(settings, t[k])
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = contact.tip_loads(phase[k], t[k], settings,
                                                                       load1, rate1)


@kernel
def tip_motions(tables, forces, phase_scalars, settings, phase, t, q, v, out):
    """``tip_motion`` of every observed state (q[k], v[k]) of ``phase[k]`` at ``t[k]`` (s)."""
    residual2 = contact.residual_flexibility2(tables[FREE], settings)
    for k in range(t.size):
        tip_motion(tables, forces, phase_scalars, settings, residual2, phase[k], t[k], q[k],
                   v[k], out[k])


@kernel
def resume_point(seg_time, seg_phase, count):
    """The last recorded segment k >= 1 from which a run can resume exactly, or 0 if none.

    A free segment that follows a contact of positive length (see ``run_events``).
    """
    for k in range(count - 1, 0, -1):
        if (seg_phase[k] == FREE and seg_phase[k - 1] == CONTACT
                and not instantaneous(seg_time[k - 1], seg_time[k])):
            return k
    return 0


@kernel
def _count_onsets(seg_time, seg_phase, count, keep, window_start, window_end, separation,
                  last_release, summary):
    """Add the contact onsets and episode starts of segments 0..keep-1 in the window.

    Returns the release time of the last released contact (``last_release`` if none).
    """
    for j in range(keep):
        if seg_phase[j] != CONTACT:
            continue
        onset = seg_time[j]
        if window_start <= onset < window_end:
            summary[STROBE_ONSETS] += 1
            if not onset - last_release < separation:
                summary[STROBE_EPISODES] += 1
        if j + 1 < count:
            last_release = seg_time[j + 1]
    return last_release


@kernel
def sampled_run(run, start_phase, q_start, v_start, times, separation, capacity, max_phases,
                samples, summary, end_state):
    """Run `RunInputs` ``run`` from t = 0 to its settings' ``t_max``; tip samples at ``times``.

    The run starts in ``start_phase`` from the state ``(q_start, v_start)`` as observed
    (`contact.observed_state`; ``run.q0``, ``run.v0`` in ``FREE`` for its own start).
    ``times`` (s): ascending sample times, the sampled window being ``[times[0], t_max)``;
    ``separation`` (s): the episode rule's free interval; ``capacity``: segments held at once;
    ``max_phases``: cap on the run's phases (status ``EVENT_LIMIT`` beyond). Writes
    ``samples[k]`` (``TIP_COLUMNS``, NaN past the point the run reached), ``summary``
    (``STROBOSCOPE_COLUMNS``) and ``end_state``, rows (q, q') of the state at t_max as
    observed. Returns the phase at t_max, ``NO_STATE`` if the run stopped before it
    (``end_state`` is then NaN).
    """
    tables, forces, phase_scalars = run.tables, run.forces, run.phase_scalars
    settings = settings_of(run)
    n_coords = run.q0.size
    recorded = segments(capacity, n_coords)
    seg_time, seg_phase, _, seg_q, seg_v, _, _ = recorded
    sample_q, sample_v = np.empty((times.size, n_coords)), np.empty((times.size, n_coords))
    sample_phase = np.empty(times.size, dtype=np.int64)
    residual2 = contact.residual_flexibility2(tables[FREE], settings)
    samples[:] = np.nan
    summary[STROBE_ONSETS] = summary[STROBE_EPISODES] = 0.0
    t0, q, v, phase = 0.0, np.empty(n_coords), np.empty(n_coords), start_phase
    contact.phase_state(phase, q_start, v_start, t0, run.switching, settings, q, v)
    done, phases, last_release = 0, 0, -math.inf
    while True:
        count, status, t_end = run_events(tables, forces, phase_scalars, run.switching, settings,
                                          q, v, recorded, t0, phase)
        keep, final = count, True
        if status == EVENT_LIMIT:
            resume = resume_point(seg_time, seg_phase, count)
            if resume > 0 and phases + resume < max_phases:
                keep, final, t_end = resume, False, seg_time[resume]
        phases += keep
        first = done
        while done < times.size and (times[done] < t_end or (final and times[done] <= t_end)):
            done += 1
        sample_states(tables, forces, run.switching, settings, recorded_prefix(recorded, count),
                      times[first:done], sample_q[first:done], sample_v[first:done],
                      sample_phase[first:done])
        for k in range(first, done):
            tip_motion(tables, forces, phase_scalars, settings, residual2, sample_phase[k],
                       times[k], sample_q[k], sample_v[k], samples[k])
        last_release = _count_onsets(seg_time, seg_phase, count, keep, times[0],
                                     settings.t_max, separation, last_release, summary)
        if final:
            summary[STROBE_STATUS] = status
            summary[STROBE_T_END] = t_end
            return _end_state(status, recorded, count, t_end, run.switching, settings,
                              end_state)
        t0, phase = seg_time[keep], FREE  # a resume point starts a free segment
        contact.copy_state(seg_q[keep], seg_v[keep], q, v)


@kernel
def _end_state(status, recorded, count, t_end, switching, settings, end_state):
    """The observed state at ``t_end`` (s) of a complete run into ``end_state``; its phase.

    ``NO_STATE`` (and NaN) if the run stopped before its horizon (``status`` not complete).
    """
    if status != COMPLETE:
        end_state[:] = np.nan
        return NO_STATE
    phase = recorded.phase[count - 1]
    contact.observed_state(phase, recorded.end_q[count - 1], recorded.end_v[count - 1], t_end,
                           switching, settings, end_state[0], end_state[1])
    return phase


@kernel
def cell_stroboscope(cell, tables, switching, geometry, times, horizon, capacity,
                     max_phases_per_period, start_phase, start_state, samples, summary,
                     end_state):
    """One map cell's long run to ``horizon`` (s), sampled at ``times`` (s): ``sampled_run``.

    From the cell's own start (``start``, uplifts) if ``start_phase`` is ``NO_STATE``, else
    from ``start_state`` (rows q, q', as observed) in that phase at t = 0. The episode rule's
    separation is a quarter period of the slowest free mode; the cap on phases is
    ``max_phases_per_period`` per forcing period of the horizon. Returns the phase at the
    horizon (``sampled_run``).
    """
    separation = 0.5 * math.pi / np.min(tables[FREE, ROW_FREQUENCY])
    periods = horizon * cell[CELL_FORCING_FREQUENCY] / (2.0 * math.pi)
    max_phases = int(max_phases_per_period * math.ceil(periods))
    run = cell_run(cell, tables, geometry, switching, horizon, horizon)
    if start_phase == NO_STATE:
        return sampled_run(run, FREE, run.q0, run.v0, times, separation, capacity,
                           max_phases, samples, summary, end_state)
    return sampled_run(run, start_phase, start_state[0], start_state[1], times, separation,
                       capacity, max_phases, samples, summary, end_state)


def _stroboscope_map(cells, tables, switching, geometry, times, horizons, capacity,
                     max_phases_per_period, samples, summary):
    """Fill samples[i] and summary[i] for cells[i], each from its own start; i owns row i."""
    for i in prange(cells.shape[0]):
        g = int(cells[i, CELL_GEOMETRY])
        end_state = np.empty((2, tables[g].shape[-1]))
        cell_stroboscope(cells[i], tables[g], geometry_switching(switching, g), geometry[g],
                         times[i], horizons[i], capacity, max_phases_per_period, NO_STATE,
                         end_state, samples[i], summary[i], end_state)


stroboscope_map_parallel, stroboscope_map_serial = parallel_kernel(_stroboscope_map)


def _stepped_map(cells, steps, tables, switching, geometry, times, horizons, capacity,
                 max_phases_per_period, samples, summary, start_phases, start_states, end_phases,
                 end_states):
    """Stepped-sine rows: cells ``steps[r, 0], steps[r, 1], ...`` of row r one after the other.

    The first from its own start, each next one from the state its predecessor ended in
    (``end_states[i]``, rows q, q' as observed, in ``end_phases[i]``), copied into its
    ``start_states`` at t = 0: the stroboscopic section, phase 0 of every forcing frequency.
    After a run that stopped before its horizon (``NO_STATE``) the next cell starts afresh.
    Rows run in parallel; iteration r owns the cells of row r.
    """
    for r in prange(steps.shape[0]):
        phase = NO_STATE
        for k in range(steps.shape[1]):
            i = steps[r, k]
            g = int(cells[i, CELL_GEOMETRY])
            start_phases[i] = phase
            if phase == NO_STATE:
                start_states[i] = np.nan
            else:
                start_states[i] = end_states[steps[r, k - 1]]
            phase = cell_stroboscope(cells[i], tables[g], geometry_switching(switching, g),
                                     geometry[g], times[i], horizons[i], capacity,
                                     max_phases_per_period, phase, start_states[i], samples[i],
                                     summary[i], end_states[i])
            end_phases[i] = phase


stepped_map_parallel, stepped_map_serial = parallel_kernel(_stepped_map)
