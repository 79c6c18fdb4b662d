"""Time to first impact: the free phase only, stopped at the first gap closure.

Plain-array interface, packed by `impactbeams.packing` (names in
`impactbeams.kernels.layout`): ``cells[i]`` with columns ``CELL_COLUMNS``;
``tables[g, FREE]`` the free-phase table of geometry g (rows ``TABLE_ROWS``; its ``event`` row
is the gap weight ``Y_1n(l1) - Y_2n(l2)``); ``geometry[g]`` with fields ``GEOMETRY``.

A cell's gap is ``g(t) = clearance + S sin(Omega t) + sum_n event_n q_n(t)``, from the initial
state of docs/model.md (`forcing.rest_state`), with each mode driven by all drives
(`impactbeams.kernels.drive`: the tip force's ``b_n (F'' + 2 zeta omega_n F')``, the shaker's
``-Gamma_n u_b''``) and S = ``drive.gap_harmonic``.
"""

import math

import numpy as np
from numba import prange

from impactbeams.kernels.drive import (
    base_amplitude,
    compiled_modal_acceleration,
    gap_harmonic,
    mode_drive,
)
from impactbeams.kernels.events import (
    _EPS,
    GAVE_UP,
    NEWTON_LIMIT,
    _first_positive_root,
    phase_bounds,
    search_root,
    split_steady_states,
    step_limit,
    walk,
)
from impactbeams.kernels.forcing import rest_state
from impactbeams.kernels.jit import kernel, parallel_kernel
from impactbeams.kernels.layout import (
    CELL_CLEARANCE,
    CELL_F0,
    CELL_FORCING_FREQUENCY,
    CELL_GEOMETRY,
    CELL_UPLIFT1,
    CELL_UPLIFT2,
    CELL_ZETA,
    FREE,
    GEO_START,
    REST,
    ROW_BASE,
    ROW_DRIVE,
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_UNIT1,
    ROW_UNIT2,
    ROW_ZETA,
)
from impactbeams.kernels.propagation import advance_mode
from impactbeams.kernels.records import EventFunction, Oscillators
from impactbeams.kernels.rotor import rotor_arrays

# rows of the per-mode scratch of the moving modes (private to this kernel)
_WORK_ROWS = ("q_s", "v_s", "frequency", "zeta", "weights", "q", "v")
_Q_S, _V_S, _FREQUENCY, _ZETA, _WEIGHTS, _Q, _V = range(len(_WORK_ROWS))


# The round-off rule of the map's event search (``events.search_root``): a gap within
# 8 eps of its evaluation scale is touching. Its evaluation sums a handful of terms of that
# scale, each correctly rounded, plus the propagated modes' own few-ulp errors.
TOUCH_TOLERANCE = 8.0


@kernel
def _load_moving_modes(cell, table, work, force, start=REST):
    """Copy the modes that move into the scratch rows; return how many.

    Beam 2 rests unless uplifted or shaken, so its modes drop out; one mode is kept if none
    moves. ``start``: the initial state (``layout.STARTS``, the geometry's ``start``).
    """
    active = 0
    last = table.shape[1] - 1
    for j in range(table.shape[1]):
        # its own ratio (a user structure's, else 0) and the cell's, written out at each use:
        # a helper kernel was one more to compile in every cold first map
        zeta = table[ROW_ZETA, j] + cell[CELL_ZETA]
        f = mode_drive(table[ROW_DRIVE, j], table[ROW_BASE, j], table[ROW_FREQUENCY, j],
                       zeta, cell[CELL_F0], base_amplitude(cell), cell[CELL_FORCING_FREQUENCY])
        q0, v0 = rest_state(cell, start, table[ROW_UNIT1, j], table[ROW_UNIT2, j],
                            table[ROW_DRIVE, j], table[ROW_BASE, j], f, table[ROW_FREQUENCY, j],
                            zeta)
        if q0 != 0.0 or v0 != 0.0 or f != 0 or (j == last and active == 0):
            work[_Q_S, active], work[_V_S, active], force[active] = q0, v0, f
            work[_FREQUENCY, active], work[_WEIGHTS, active] = table[ROW_FREQUENCY,
                                                                     j], table[ROW_EVENT, j]
            work[_ZETA, active] = zeta
            active += 1
    return active


@kernel
def first_impact_time(cell, table, geo, t_max, t_start, work, force, rotor):
    """Time (s) of the first gap closure in (0, t_max] for one cell, NaN if none.

    ``table``: the free-phase table of the cell's geometry; ``geo``: its geometry row;
    ``t_start``: a time before which the gap is known to stay open (0 if none, see
    ``_column``); ``work`` (rows ``_WORK_ROWS``) and the complex ``force``: scratch per mode,
    reused across cells (no heap allocation per cell: allocations serialise threads).
    Returns ``events.GAVE_UP`` (-inf) if the search reached its step cap.
    """
    active = _load_moving_modes(cell, table, work, force, geo[GEO_START])
    q_s, v_s = work[_Q_S, :active], work[_V_S, :active]
    sine = gap_harmonic(cell, geo)
    if sine == 0.0 and q_s[0] == 0.0 and v_s[0] == 0.0 and force[0] == 0 and active == 1:
        return np.nan  # nothing moves: the gap stays open
    frequencies = work[_FREQUENCY, :active]
    oscillators = Oscillators(frequencies, work[_ZETA, :active], force[:active],
                              cell[CELL_FORCING_FREQUENCY])
    gap = EventFunction(work[_WEIGHTS, :active], cell[CELL_CLEARANCE],
                        complex(sine, 0.0),
                        cell[CELL_FORCING_FREQUENCY])
    return search_root(q_s, v_s, 0.0, t_start, t_max, oscillators, gap, TOUCH_TOLERANCE,
                       step_limit(0.0, t_max, frequencies), work[_Q, :active], work[_V, :active],
                       rotor)


@kernel
def _uplift_stays_below_clearance(cell, table):
    """Whether clearance + u(t) > 0 for all t, u the unforced response to the uplifts.

    Each mode's free motion from rest at q0 has amplitude at most |q0| / sqrt(1 - zeta^2).
    """
    reach = 0.0
    for j in range(table.shape[1]):
        q0 = cell[CELL_UPLIFT1] * table[ROW_UNIT1, j] + cell[CELL_UPLIFT2] * table[ROW_UNIT2, j]
        zeta = table[ROW_ZETA, j] + cell[CELL_ZETA]  # its own (a user structure's) and the cell's
        reach += abs(table[ROW_EVENT, j] * q0) / np.sqrt(1.0 - zeta**2)
    return cell[CELL_CLEARANCE] - reach > 0.0


@kernel
def _walk_order(cells, lo, hi, key, table):
    """Cells lo..hi-1 of a column in order of non-decreasing first impact time, or none.

    Returns ``(first, stride)``, the walk being first, first + stride, ...; stride 0 when the
    column cannot be ordered (each cell is then searched from t = 0). Along the clearance the
    gap is ``clearance + (a response shared by the column)``: it closes later (or never) for a
    larger clearance. Along F0 with U0 = 0 (along U0 with F0 = 0 likewise) it is
    ``clearance + u(t) - F0 h(t)``: if clearance + u > 0 throughout, it closes where
    ``F0 >= (clearance + u) / h``, later for a smaller F0. With both drives the other one's
    response is not bounded here: no order.
    """
    if hi - lo < 2:
        return lo, 0
    rising = cells[lo + 1, key] > cells[lo, key]
    for i in range(lo + 1, hi):
        step = cells[i, key] - cells[i - 1, key]
        if step == 0.0 or (step > 0.0) != rising:
            return lo, 0
    if key == CELL_CLEARANCE:
        return (lo, 1) if rising else (hi - 1, -1)
    other_drive = base_amplitude(cells[lo]) if key == CELL_F0 else cells[lo, CELL_F0]
    if (other_drive != 0.0 or min(cells[lo, key], cells[hi - 1, key]) < 0.0
            or not _uplift_stays_below_clearance(cells[lo], table)):
        return lo, 0
    return (hi - 1, -1) if rising else (lo, 1)


# The column's two responses (``_load_column``): rows of ``work`` after ``_WORK_ROWS``, each
# at t = 0 (``*_0``) and at the column's current time (``*_t``); ``drives[_A]``,
# ``drives[_B]`` their drive amplitudes, ``drives[_CELL]`` one cell's.
_COLUMN_ROWS = ("q_a0", "v_a0", "q_b0", "v_b0", "q_at", "v_at", "q_bt", "v_bt")
(_Q_A0, _V_A0, _Q_B0, _V_B0, _Q_AT, _V_AT, _Q_BT,
 _V_BT) = range(len(_WORK_ROWS), len(_WORK_ROWS) + len(_COLUMN_ROWS))
_CELL, _A, _B = range(3)


@kernel
def _load_column(source, key, table, geo, work, drives):
    """Split a column's cells into two responses: cell x's state is ``a + x b``; their count.

    Along F0 (along U0 likewise) x is the cell's F0, ``a`` the response with F0 = 0 (the
    uplifts) and ``b`` the response to F0 = 1 N from a flat start; along the clearance x = 0
    and ``a`` is the whole response. Drive, initial state and the gap's harmonic are linear
    in F0 and U0 (`impactbeams.kernels.drive`), so the split is exact; a mode is kept if it
    moves in either. Returns the number of modes kept and the harmonics ``(S_a, S_b)``.
    """
    a_cell, b_cell = source.copy(), source.copy()
    if key != CELL_CLEARANCE:
        a_cell[key] = 0.0
        b_cell[key], b_cell[CELL_UPLIFT1], b_cell[CELL_UPLIFT2] = 1.0, 0.0, 0.0
    active, last = 0, table.shape[1] - 1
    for j in range(table.shape[1]):
        kept = False
        for row, cell, state in ((_A, a_cell, _Q_A0), (_B, b_cell, _Q_B0)):
            zeta = table[ROW_ZETA, j] + cell[CELL_ZETA]
            f = mode_drive(table[ROW_DRIVE, j], table[ROW_BASE, j], table[ROW_FREQUENCY, j],
                           zeta, cell[CELL_F0], base_amplitude(cell),
                           cell[CELL_FORCING_FREQUENCY])
            q0, v0 = rest_state(cell, geo[GEO_START], table[ROW_UNIT1, j], table[ROW_UNIT2, j],
                                table[ROW_DRIVE, j], table[ROW_BASE, j], f,
                                table[ROW_FREQUENCY, j], zeta)
            if key == CELL_CLEARANCE and row == _B:
                f, q0, v0 = 0j, 0.0, 0.0
            drives[row, active], work[state, active], work[state + 1, active] = f, q0, v0
            kept = kept or q0 != 0.0 or v0 != 0.0 or f != 0
        if kept or (j == last and active == 0):
            work[_FREQUENCY, active], work[_WEIGHTS, active] = table[ROW_FREQUENCY,
                                                                     j], table[ROW_EVENT, j]
            work[_ZETA, active] = table[ROW_ZETA, j] + source[CELL_ZETA]
            active += 1
    harmonics = (complex(gap_harmonic(a_cell, geo), 0.0),
                 0j if key == CELL_CLEARANCE else complex(gap_harmonic(b_cell, geo), 0.0))
    return active, harmonics


@kernel
def _column_states(t, work, drives, n, forcing_frequency):
    """Both responses' states at t (s), into rows ``_Q_AT``.. of ``work``; ``e^(i Omega t)``.

    A mode undriven in both (its steady states split off) shares its free rotation, the
    arithmetic of ``propagation.advance_mode`` (no exponential without damping); a driven one
    (near resonance) is propagated exactly per response.
    """
    turn = complex(math.cos(forcing_frequency * t), math.sin(forcing_frequency * t))
    for j in range(n):
        w, z = work[_FREQUENCY, j], work[_ZETA, j]
        if drives[_A, j] != 0 or drives[_B, j] != 0:
            for row, state, now in ((_A, _Q_A0, _Q_AT), (_B, _Q_B0, _Q_BT)):
                work[now, j], work[now + 1, j] = advance_mode(
                    work[state, j], work[state + 1, j], t, w, z, drives[row, j],
                    forcing_frequency, 1.0 + 0.0j, turn)
            continue
        sigma, wd = z * w, w if z == 0.0 else w * math.sqrt(1.0 - z * z)
        decay = 1.0 if sigma == 0.0 else math.exp(-sigma * t)
        c, s = math.cos(wd * t), math.sin(wd * t)
        for state, now in ((_Q_A0, _Q_AT), (_Q_B0, _Q_BT)):
            q0, v0 = work[state, j], work[state + 1, j]
            work[now, j] = decay * (q0 * c + (v0 + sigma * q0) / wd * s)
            work[now + 1, j] = decay * (v0 * c - (w * w * q0 + sigma * v0) / wd * s)
    return turn


# Newton's corrections turn the state by e^(lambda h) where |lambda h| is at most this (rad):
# sines and cosines of small arguments, cheaper than of the phase from t = 0
_SHORT_TURN = 1.0 / 16.0


@kernel
def _turn_states(h, turn, work, drives, n, forcing_frequency):
    """Both responses' states h (s) on from the column's current ones (at t); e^(i Omega (t + h)).

    ``omega |h|`` and ``Omega |h|`` at most ``_SHORT_TURN``; ``turn`` is e^(i Omega t). An
    undriven mode turns by e^(lambda h) as ``propagation.advance_mode``
    propagates it; a driven one is propagated by ``advance_mode`` from its current state.
    """
    step = complex(math.cos(forcing_frequency * h), math.sin(forcing_frequency * h))
    for j in range(n):
        w, z = work[_FREQUENCY, j], work[_ZETA, j]
        if drives[_A, j] != 0 or drives[_B, j] != 0:
            for row, now in ((_A, _Q_AT), (_B, _Q_BT)):
                work[now, j], work[now + 1, j] = advance_mode(
                    work[now, j], work[now + 1, j], h, w, z, drives[row, j], forcing_frequency,
                    turn, step)
            continue
        sigma, wd = z * w, w if z == 0.0 else w * math.sqrt(1.0 - z * z)
        decay = 1.0 if sigma == 0.0 else math.exp(-sigma * h)
        rotation = complex(decay * math.cos(wd * h), decay * math.sin(wd * h))
        for now in (_Q_AT, _Q_BT):
            q0, v0 = work[now, j], work[now + 1, j]
            work[now, j] = rotation.real * q0 + (v0 + sigma * q0) / wd * rotation.imag
            work[now + 1, j] = rotation.real * v0 - (w * w * q0 + sigma * v0) / wd * rotation.imag
    return turn * step


@kernel
def _cell_gap(x, const, harmonics, turn, work, drives, n, forcing_frequency):
    """A cell's gap e, e', its evaluation scale and e'' from the column's states (x: its F0).

    As ``events.evaluate`` and ``events.event_acceleration`` on the cell's state ``a + x b``.
    """
    sine_amp = harmonics[0] + x * harmonics[1]
    sine, cosine = turn.imag, turn.real
    sine_term, cosine_term = sine_amp.real * sine, sine_amp.imag * cosine
    value = const + sine_term + cosine_term
    scale = abs(const) + abs(sine_term) + abs(cosine_term)
    slope = forcing_frequency * (sine_amp.real * cosine - sine_amp.imag * sine)
    acceleration = -forcing_frequency**2 * (sine_term + cosine_term)
    for j in range(n):
        q = work[_Q_AT, j] + x * work[_Q_BT, j]
        v = work[_V_AT, j] + x * work[_V_BT, j]
        term = work[_WEIGHTS, j] * q
        value += term
        scale += abs(term)
        slope += work[_WEIGHTS, j] * v
        acceleration += work[_WEIGHTS, j] * compiled_modal_acceleration(
            drives[_A, j] + x * drives[_B, j], work[_FREQUENCY, j], work[_ZETA, j], q, v, sine,
            cosine)
    return value, slope, scale, acceleration


@kernel
def _follow_flank(t, turn, x, const, curvature, t_max, harmonics, work, drives, n,
                  forcing_frequency, fastest):
    """A cell's first root on the falling flank it is on at t: ``(root, t_state, turn)``.

    The column's states are at t on entry (``turn`` = e^(i Omega t)) and at ``t_state`` on
    return (``turn`` then e^(i Omega t_state)). With |e''| <= curvature,
    e falls on [t, t - e'(t) / curvature]: there it has one root, which safeguarded Newton
    (the stops of ``events._newton_in_bracket``) finds from the root of e's local quadratic,
    mostly in one or two evaluations: the first at its exact state (``_column_states``), the
    corrections by turning that state (``_turn_states``; ``fastest`` is the largest of the
    modes' frequencies and Omega, rad/s). Returns root NaN (unresolved) with ``t_state`` the last
    time where e was above its round-off, if the root is not on that certified flank.
    """
    value, slope, scale, acceleration = _cell_gap(x, const, harmonics, turn, work, drives, n,
                                                  forcing_frequency)
    if value <= TOUCH_TOLERANCE * _EPS * scale:
        return t, t, turn
    if slope >= 0.0 or not curvature > 0.0:
        return np.nan, t, turn
    lo, hi, bracketed = t, min(t - slope / curvature, t_max), False
    step = t + _first_positive_root(value, slope, 0.5 * acceleration)
    t_state = t
    for _ in range(NEWTON_LIMIT):
        if not lo < step < hi:
            if not bracketed:
                return np.nan, t_state, turn
            step = 0.5 * (lo + hi)
        # the first point exactly; Newton's short corrections turn the state from there
        turn = (_column_states(step, work, drives, n, forcing_frequency)
                if t_state == t or fastest * abs(step - t_state) > _SHORT_TURN else
                _turn_states(step - t_state, turn, work, drives, n, forcing_frequency))
        t_state = step
        value, slope, scale, _ = _cell_gap(x, const, harmonics, turn, work, drives, n,
                                           forcing_frequency)
        if value > 0.0:
            lo = step
        else:
            hi, bracketed = step, True
        if value == 0.0 or (bracketed and hi - lo <= 4.0 * _EPS * hi):
            return hi, t_state, turn
        if abs(value) <= TOUCH_TOLERANCE * _EPS * scale:
            return step, t_state, turn
        newton = step - value / slope if slope != 0.0 else lo - 1.0
        if bracketed and abs(newton - step) <= 2.0 * _EPS * abs(step):
            past = hi if value <= 0.0 else min(hi, max(newton, step) + 2.0 * _EPS * step)
            return past, t_state, turn
        step = newton
    return (hi if bracketed else np.nan), t_state, turn


@kernel
def _response_bounds(row, state, harmonic, active, t, span, omega, work, drives):
    """One of a column's two responses: its gap harmonic without its steady states, bounds.

    From its state at t (s) in rows ``state``, ``state + 1`` of ``work``, over [t, t + span]
    (``events.phase_bounds``). At t = 0 the steady states are split off, in place; later
    (rows ``_Q_AT``.., already split) the split finds none left and the bounds are a window's.
    A kernel called once per response rather than a loop collecting lists (Numba's list
    code costs a cold compile about 0.3 s).
    """
    frequencies, zeta, weights = work[_FREQUENCY, :active], work[_ZETA, :active], work[
        _WEIGHTS, :active]
    q_s, v_s = work[state, :active], work[state + 1, :active]
    oscillators = Oscillators(frequencies, zeta, drives[row, :active], omega)
    event = split_steady_states(q_s, v_s, t, oscillators,
                                EventFunction(weights, 0.0, harmonic, omega))
    return event.sine_amp, phase_bounds(q_s, v_s, t, span, oscillators, event)


@kernel
def _shared_column(cells, first, stride, count, key, table, geo, t_max, work, drives, rotor,
                   out):
    """One ordered column, whose cells share two modal responses; walked once in time.

    Cell x's gap is ``clearance + a(t) + x b(t)`` (``_load_column``), so one evaluation of
    the modes at a time serves every cell. Each cell starts where the previous one closed:
    most close a little later on the same falling flank (``_follow_flank``); the others are
    searched by the certified walk from there, with the sum of both responses' bounds.
    """
    active, harmonics = _load_column(cells[first], key, table, geo, work, drives)
    frequencies, zeta, weights = work[_FREQUENCY, :active], work[_ZETA, :active], work[
        _WEIGHTS, :active]
    omega = cells[first, CELL_FORCING_FREQUENCY]
    harmonic_a, (coherent_a, band_a, curvature_a, jerk_a, any_a) = _response_bounds(
        _A, _Q_A0, harmonics[0], active, 0.0, t_max, omega, work, drives)
    harmonic_b, (coherent_b, band_b, curvature_b, jerk_b, any_b) = _response_bounds(
        _B, _Q_B0, harmonics[1], active, 0.0, t_max, omega, work, drives)
    harmonics = (harmonic_a, harmonic_b)
    max_steps = step_limit(0.0, t_max, frequencies)
    fastest = omega
    for j in range(active):  # not np.max, which compiles take_impl (0.3 s of a cold compile)
        fastest = max(fastest, frequencies[j])
    t, t_states, turn = 0.0, np.nan, 1.0 + 0.0j
    # a mode near resonance (its steady state not split off) grows over [0, t_max]: its
    # bounds there hold the whole growth, or its large steady state and transient apart,
    # and certify few flanks; a window's bounds from its start's state certify more
    # (``_response_bounds`` over [window start, window_end])
    growing = False
    for j in range(active):
        growing = growing or drives[_A, j] != 0 or drives[_B, j] != 0
    window_end, window_a, window_b = -1.0, 0.0, 0.0
    i = first
    for _ in range(count):
        if np.isnan(t):
            out[i] = np.nan
            i += stride
            continue
        x = 0.0 if key == CELL_CLEARANCE else cells[i, key]
        const = cells[i, CELL_CLEARANCE]
        cell_bounds = (coherent_a + x * coherent_b, band_a + abs(x) * band_b,
                       curvature_a + abs(x) * curvature_b, jerk_a + abs(x) * jerk_b,
                       any_a and any_b)
        curvature, flank_end = cell_bounds[2], t_max
        for attempt in range(2):  # one call site each: a call compiles (is inlined) anew
            if t != t_states:
                turn = _column_states(t, work, drives, active, omega)
                t_states = t
            if attempt == 1:  # the flank with the bounds of the forcing period from t on
                if not t < window_end:
                    window_end = min(t + 2.0 * math.pi / omega, t_max)
                    for k in range(2):
                        window = _response_bounds(_A + k, _Q_AT + 2 * k, harmonics[k], active,
                                                  t, window_end - t, omega, work, drives)[1][2]
                        if k == 0:
                            window_a = window
                        else:
                            window_b = window
                curvature, flank_end = window_a + abs(x) * window_b, window_end
            root, t_states, turn = _follow_flank(t, turn, x, const, curvature, flank_end,
                                                 harmonics, work, drives, active, omega, fastest)
            if not (growing and np.isnan(root)):
                break
        if np.isnan(root):
            for j in range(active):
                work[_Q_S, j] = work[_Q_A0, j] + x * work[_Q_B0, j]
                work[_V_S, j] = work[_V_A0, j] + x * work[_V_B0, j]
                drives[_CELL, j] = drives[_A, j] + x * drives[_B, j]
            root, _ = walk(work[_Q_S, :active], work[_V_S, :active], 0.0, t_states, t_max,
                           Oscillators(frequencies, zeta, drives[_CELL, :active], omega),
                           EventFunction(weights, const, harmonics[0] + x * harmonics[1], omega),
                           TOUCH_TOLERANCE, max_steps, cell_bounds, np.nan, work[_Q, :active],
                           work[_V, :active], rotor)
            t_states = np.nan
        out[i] = root
        t = 0.0 if root == GAVE_UP else root  # NaN ends the column
        i += stride


@kernel
def _column(cells, lo, hi, key, tables, geometry, t_max, work, drives, rotor, out):
    """Fill out[lo:hi], one column, each search starting where the previous closed.

    In walk order the first impact time does not decrease, so each cell's gap stays open until
    the previous cell's impact, and once a cell has none neither has any after it. A column
    that cannot be ordered is searched cell by cell from t = 0.
    """
    g = int(cells[lo, CELL_GEOMETRY])
    table, geo = tables[g, FREE], geometry[g]
    i, stride = _walk_order(cells, lo, hi, key, table)
    if stride != 0:
        _shared_column(cells, i, stride, hi - lo, key, table, geo, t_max, work, drives, rotor,
                       out)
        return
    t_start = 0.0
    for _ in range(hi - lo):
        if np.isnan(t_start):
            out[i] = np.nan
        else:
            out[i] = first_impact_time(cells[i], table, geo, t_max, 0.0, work, drives[_CELL],
                                       rotor)
        i += 1


@kernel
def _scratch(n_modes):
    """A search's scratch for up to ``n_modes`` modes: ``work``, ``drives`` and a rotor."""
    return (np.empty((len(_WORK_ROWS) + len(_COLUMN_ROWS), n_modes)),
            np.empty((3, n_modes), dtype=np.complex128), rotor_arrays(n_modes))


@kernel
def _residue(block, n_blocks):
    """The bit reversal of ``block`` among ``n_blocks`` (a power of two)."""
    residue, half = 0, n_blocks // 2
    while half > 0:
        residue, block, half = 2 * residue + block % 2, block // 2, half // 2
    return residue


_BLOCK = 256  # cells per unit of parallel work at least: scratch allocated once per block
_MAX_BLOCKS = 64  # blocks of interleaved columns, a power of two


def _first_impact_map(cells, columns, key, tables, geometry, t_max, out):
    """Fill out[i] with the first impact time of cells[i], column by column.

    Column c is ``cells[columns[c]:columns[c + 1]]``, cells that differ in column ``key`` of
    ``CELL_COLUMNS`` alone (``CELL_F0``, ``CELL_U0`` or ``CELL_CLEARANCE``, axes in which the
    gap is affine);
    columns of one cell are searched on their own. The columns are dealt to n_blocks blocks
    (a power of two, at most ``_MAX_BLOCKS``) so that the costly regions of a grid (near
    resonances and the no-impact boundary) are shared evenly between the threads of prange's
    static schedule, which gives each of T threads a contiguous range of blocks: block b takes
    columns r, r + n_blocks, ... with r the bit reversal of b (``_residue``), so that for T a
    power of two thread k takes the columns c = k mod T (with one block per column, as before,
    Fig. 5a's resonance fell to one thread: 1.38 times the mean work). Each iteration owns its
    columns, so the result does not depend on the number of threads.
    """
    n_columns = columns.size - 1
    n_blocks = 1
    while 2 * n_blocks <= min(n_columns, (cells.shape[0] + _BLOCK - 1) // _BLOCK, _MAX_BLOCKS):
        n_blocks *= 2
    for block in prange(n_blocks):
        work, drives, rotor = _scratch(tables.shape[3])
        for c in range(_residue(block, n_blocks), n_columns, n_blocks):
            _column(cells, columns[c], columns[c + 1], key, tables, geometry, t_max, work,
                    drives, rotor, out)


first_impact_map_parallel, first_impact_map_serial = parallel_kernel(_first_impact_map)


@kernel
def first_impact_cells(cells, tables, geometry, t_max, out):
    """``out[i]``: each cell searched on its own from t = 0 (the reference for the columns)."""
    work, drives, rotor = _scratch(tables.shape[3])
    for i in range(cells.shape[0]):
        g = int(cells[i, CELL_GEOMETRY])
        out[i] = first_impact_time(cells[i], tables[g, FREE], geometry[g], t_max, 0.0,
                                   work, drives[_CELL], rotor)
