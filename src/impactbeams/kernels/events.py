"""Certified location of the first root of a phase's event function.

Both switching conditions are roots of a linear functional of the modal state,

    e(t) = const + Im(sine_amp e^(i Omega t)) + sum_j weights_j q_j(t),

the gap ``g`` in the free phase (const = Delta, sine_amp = -c_1 F0, weights = tip values) and
the contact force ``R`` in the contact phase. ``sine_amp`` is a real number (a sine) or a
complex one (a sine and a cosine part, as a spring law's dashpot gives). ``first_root`` walks
forward with steps that are certified root-free by a bound ``M2 >= |e''|`` on the step (from
each mode's amplitude and drive): ``e(t + s) >= e + e' s - M2 s^2 / 2 > 0``. Near a grazing
minimum these steps shrink like ``sqrt(e / M2)``, not like ``e / |e'|``, so a minimum that stays
open is passed in a logarithmic number of steps and one that closes, however briefly, is found.
When the linear estimate says a crossing is near, a probe beyond it brackets the root; a bracket
on which ``e`` is certified monotone holds exactly one root, which safeguarded Newton then
resolves to a few ulps of time. The walk's own points are evaluated by a rotor
(`impactbeams.kernels.rotor`: undriven modes as rotating amplitudes, the steady states
split off by ``split_steady_states``); the probe and Newton propagate exactly.

Certified in exact arithmetic; in floating point e is known only to within its evaluation
error. ``search_root`` therefore takes a round-off rule: e counts as 0 where it is within
``tolerance`` eps of its evaluation scale (the magnitudes of its terms summed), and the walk
certifies e above that level. Maps use it (a grazing gap is classified one way, whatever
the path to it); the dynamics' switches use ``tolerance`` = 0. Every loop is capped: the walk
by ``step_limit`` (it then returns ``GAVE_UP``), Newton by ``NEWTON_LIMIT``.
"""

import math

import numpy as np

from impactbeams.kernels.drive import compiled_modal_acceleration
from impactbeams.kernels.jit import borrowing_kernel, inlined_kernel, kernel
from impactbeams.kernels.layout import (
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
)
from impactbeams.kernels.propagation import advance_to, steady_phasor
from impactbeams.kernels.records import EventFunction, Oscillators
from impactbeams.kernels.rotor import (
    free_event,
    modulus_bound,
    rotor_bounds,
    rotor_event,
    rotor_load,
    turn,
)

_EPS = np.finfo(np.float64).eps
NO_EVENT = np.nan
GAVE_UP = -np.inf  # the walk reached its step cap (``step_limit``): undecided
NEWTON_LIMIT = 200
REFRESH_STEPS = 8  # a walk's bounds are recomputed from its rotor every this many steps


@borrowing_kernel
def evaluate(q, v, t, event):
    """Return e(t), e'(t) and e's evaluation scale for modal state (q, v) at time t.

    ``event``: the `records.EventFunction`.
    The scale, the sum of the magnitudes of the terms summed into e, bounds them, so e's
    rounding error is a few eps times it: a value within ``tolerance`` eps of the scale is zero
    to within its own evaluation error (the round-off rule of ``search_root``).
    """
    const, sine_amp = event.const, event.sine_amp
    forcing_frequency = event.forcing_frequency
    sine, cosine = math.sin(forcing_frequency * t), math.cos(forcing_frequency * t)
    sine_term, cosine_term = sine_amp.real * sine, sine_amp.imag * cosine
    value = const + sine_term + cosine_term
    slope = (sine_amp.real * forcing_frequency * cosine
             - sine_amp.imag * forcing_frequency * sine)
    scale = abs(const) + abs(sine_term) + abs(cosine_term)
    for j in range(q.size):
        term = event.weights[j] * q[j]
        value += term
        scale += abs(term)
        slope += event.weights[j] * v[j]
    return value, slope, scale


@borrowing_kernel
def event_value(q, v, t, event):
    """Return e(t) and e'(t) of `records.EventFunction` ``event`` for modal state (q, v) at t."""
    value, slope, _ = evaluate(q, v, t, event)
    return value, slope


@kernel
def event_sine(scalars):
    """A phase's event function harmonic part as a complex amplitude (sine + i cosine)."""
    return complex(scalars[SCALAR_SINE], scalars[SCALAR_COSINE])


@inlined_kernel
def phase_event_function(table, scalars, forcing_frequency):
    """The `records.EventFunction` of the phase with ``table`` and ``scalars``."""
    return EventFunction(table[ROW_EVENT], scalars[SCALAR_CONST], event_sine(scalars),
                         forcing_frequency)


@inlined_kernel
def phase_oscillators(table, force, forcing_frequency):
    """The `records.Oscillators` of the phase with ``table`` and drive amplitudes ``force``."""
    return Oscillators(table[ROW_FREQUENCY], table[ROW_ZETA], force, forcing_frequency)


@borrowing_kernel
def phase_event(table, scalars, q, v, t, forcing_frequency):
    """e(t), e'(t) of the event function of the phase with ``table`` and ``scalars``."""
    return event_value(q, v, t, phase_event_function(table, scalars, forcing_frequency))


@borrowing_kernel
def event_acceleration(q, v, t, oscillators, event):
    """e''(t) from the modal equations: q'' = Im(A e^(i Omega t)) - 2 zeta omega q' - omega^2 q."""
    sine_amp = event.sine_amp
    forcing_frequency = event.forcing_frequency
    sine = math.sin(forcing_frequency * t)
    cosine = math.cos(forcing_frequency * t)
    value = (-sine_amp.real * forcing_frequency**2 * sine
             - sine_amp.imag * forcing_frequency**2 * cosine)
    for j in range(q.size):
        value += event.weights[j] * compiled_modal_acceleration(
            oscillators.force[j], oscillators.frequencies[j], oscillators.zeta[j], q[j], v[j], sine,
            cosine)
    return value


@kernel
def _mode_split(q, v, w, zeta, f, forcing_frequency, rotation, span):
    """Split one mode into a steady state at Omega and a free transient, for bounds.

    Returns ``(steady, amplitude, curvature)``: the steady state's phasor ``A / D`` (0 if not
    used), a bound on the rest's |q| and one on the rest's |q''| over [t, t + span], with
    ``D = omega^2 - Omega^2 + 2 i sigma Omega`` and the drive Im(A e^(i Omega t)), |drive| <=
    |A|. The transient has constant or decaying amplitude R, so |q| <= R and |q''| <=
    omega^2 R for any span. A mode at (or too near) resonance is bounded instead by its free
    amplitude plus the growth of its driven part from rest: |x| <= |A| span / omega_d,
    |x''| <= |A| (1 + 2 sigma span omega / omega_d + omega^2 min(span^2 / 2, span / omega_d)).
    """
    root = math.sqrt(1.0 - zeta * zeta)
    sigma, wd = zeta * w, w * root
    free = modulus_bound(q, (v + sigma * q) / wd)
    if f == 0:  # undriven (its steady state split off): the growth terms below are 0
        return 0j, free, w * w * free
    grow = free + abs(f) * span / wd
    grow_curvature = w * w * free + abs(f) * (
        1.0 + 2.0 * sigma * span / root + w * w * min(0.5 * span * span, span / wd))
    D = complex(w * w - forcing_frequency**2, 2.0 * sigma * forcing_frequency)
    if D == 0:
        return 0j, grow, grow_curvature
    steady = f / D
    P = steady * rotation
    dq, dv = q - P.imag, v - forcing_frequency * P.real
    transient = modulus_bound(dq, (dv + sigma * dq) / wd)
    if abs(steady) + transient >= grow:
        return 0j, grow, grow_curvature
    return steady, transient, w * w * transient


@borrowing_kernel
def phase_bounds(q, v, t, span, oscillators, event):
    """Split e over [t, t + span] into an exact sinusoid at Omega and a bounded rest.

    Returns ``(coherent, band, curvature, jerk, any_span)``: over the window,
    ``e(t + s) >= const + Im(coherent e^(i Omega (t + s))) - band``, ``|e''| <= curvature``
    and, when ``any_span``, ``|e'''| <= jerk`` (each time derivative of a transient of
    amplitude R is at most omega R, since |lambda| = omega). The steady states of all modes
    oscillate at Omega, so they are summed coherently with the forcing term into one phasor:
    above a resonance they largely cancel the quasi-static term, which a mode-by-mode bound
    would miss. ``any_span`` is True when no mode
    needed the span-limited growth bound, so that the split holds for every s >= 0.
    """
    sine_amp = event.sine_amp
    forcing_frequency = event.forcing_frequency
    rotation = complex(math.cos(forcing_frequency * t), math.sin(forcing_frequency * t))
    coherent = complex(sine_amp.real, sine_amp.imag)
    band = curvature = jerk = 0.0
    any_span = True
    for j in range(q.size):
        steady, amplitude, mode_curvature = _mode_split(
            q[j], v[j], oscillators.frequencies[j], oscillators.zeta[j], oscillators.force[j],
            forcing_frequency, rotation, span)
        if steady == 0 and oscillators.force[j] != 0:
            any_span = False
        coherent += event.weights[j] * steady
        band += abs(event.weights[j]) * amplitude
        curvature += abs(event.weights[j]) * mode_curvature
        jerk += abs(event.weights[j]) * oscillators.frequencies[j] * mode_curvature
    forced = abs(coherent)
    return (coherent, band, curvature + forcing_frequency**2 * forced,
            jerk + forcing_frequency**3 * forced, any_span)


@kernel
def band_step(margin, coherent, amplitude, t, forcing_frequency):
    """Largest s with margin + Im(coherent e^(i Omega (t + s'))) > 0 for all s' in [0, s).

    The sinusoid |K| sin(theta), theta = Omega t + arg K, drops to the level -margin at the
    next theta = pi - asin(c) (mod 2 pi), c = -margin / |K|. Shortened by a relative 1e-9 so
    that rounding cannot carry it past that point. ``amplitude`` is |K| (``abs(coherent)``,
    which the walk computes once per bounds, not at each of its steps).
    """
    if margin - amplitude > 0.0:
        return math.inf
    if forcing_frequency == 0.0 or margin + amplitude <= 0.0:
        return math.inf if margin + coherent.imag > 0.0 else 0.0
    level = -margin / amplitude
    theta = forcing_frequency * t + math.atan2(coherent.imag, coherent.real)
    if math.sin(theta) <= level:
        return 0.0
    crossing = math.pi - math.asin(level)
    turns = math.ceil((theta - crossing) / (2.0 * math.pi))
    target = crossing + 2.0 * math.pi * turns
    if target <= theta:
        target += 2.0 * math.pi
    return (target - theta) / forcing_frequency * (1.0 - 1e-9)


@inlined_kernel
def split_steady_states(q_s, v_s, t_s, oscillators, event):
    """Move the steady states of the modes away from resonance into the event's sinusoid.

    Mode j driven by Im(A e^(i Omega t)) is its steady state Im(P e^(i Omega t))
    (``propagation.steady_phasor``) plus a free transient from its state at t_s (s) less the
    steady one. The event function keeps its value, with the steady states summed into its
    ``sine_amp`` (the `records.EventFunction` returned) and those modes undriven: their
    propagation is then a free oscillation, about 2-3 times cheaper than the driven one.
    ``q_s``, ``v_s`` and ``oscillators.force`` are changed in place (``split_sine``). Inlined,
    so that the record it returns is counted by its caller's rules (`jit.borrowing_kernel`).
    """
    return EventFunction(event.weights, event.const,
                         split_sine(q_s, v_s, t_s, oscillators, event), event.forcing_frequency)


@borrowing_kernel
def split_sine(q_s, v_s, t_s, oscillators, event):
    """``split_steady_states``' work: the split event's ``sine_amp``, the state changed in place."""
    sine_amp = event.sine_amp
    forcing_frequency = event.forcing_frequency
    rotation = complex(math.cos(forcing_frequency * t_s), math.sin(forcing_frequency * t_s))
    for j in range(oscillators.frequencies.size):
        steady = steady_phasor(oscillators.frequencies[j], oscillators.zeta[j],
                               oscillators.force[j], forcing_frequency)
        if steady == 0:
            continue
        phasor = steady * rotation
        q_s[j] -= phasor.imag
        v_s[j] -= forcing_frequency * phasor.real
        sine_amp += event.weights[j] * steady
        oscillators.force[j] = 0.0
    return sine_amp


@kernel
def _first_positive_root(a, b, c):
    """First s > 0 where a + b s + c s^2 reaches 0 (a > 0), inf if never; cancellation-free."""
    if c == 0.0:
        return a / -b if b < 0.0 else math.inf
    discriminant = b * b - 4.0 * a * c
    if discriminant < 0.0:
        return math.inf  # c > 0: the parabola stays above 0
    if b < 0.0:
        return 2.0 * a / (math.sqrt(discriminant) - b)
    return math.inf if c > 0.0 else (b + math.sqrt(discriminant)) / (-2.0 * c)


@kernel
def certified_step(value, slope, curvature):
    """Largest s with value + slope s - curvature s^2 / 2 > 0 (value > 0)."""
    return _first_positive_root(value, slope, -0.5 * curvature)


@kernel
def cubic_step(value, slope, acceleration, jerk, start):
    """A step s >= start with value + slope u + acceleration u^2 / 2 - jerk u^3 / 6 > 0.

    Certified on windows [0, w], w = 2 start, 4 start, ..., where the cubic term is at most
    jerk w u^2 / 6, which leaves a parabola.
    """
    step = start
    window = 2.0 * start
    for _ in range(6):
        root = _first_positive_root(value, slope, 0.5 * acceleration - jerk * window / 6.0)
        if root < window:
            return max(step, root)
        step = window
        window *= 2.0
    return step


@kernel
def _quadratic_root(value, slope, acceleration, curvature, jerk, t):
    """The root of e near t (s) from e's exact local quadratic, past it by its error; NaN if unsure.

    With e(t) = value, e'(t) = slope < 0 and e''(t) = acceleration, and |e''| <= curvature,
    |e'''| <= jerk around t: at the root t + d of value + slope d + acceleration d^2 / 2,
    |e| <= jerk |d|^3 / 6 and |e'| >= m ~ |slope| - 2 curvature |d|, so the root of e lies
    within err = jerk |d|^3 / (6 m) of it. Returned (plus err and 2 eps t: past the root) only
    where err is below an ulp of t, as a converged Newton iteration would end.
    """
    if not slope < 0.0:
        return np.nan
    if value > 0.0:
        d = _first_positive_root(value, slope, 0.5 * acceleration)
    else:  # past the root: the same parabola backwards
        d = -_first_positive_root(-value, slope, -0.5 * acceleration)
    m = -slope - curvature * (2.0 * abs(d) + 4.0 * _EPS * abs(t))  # over [t + d -+ err]
    if not m > -0.5 * slope:
        return np.nan
    error = jerk * abs(d) ** 3 / (6.0 * m)
    if not error <= _EPS * abs(t):
        return np.nan
    return t + d + error + 2.0 * _EPS * abs(t)


@borrowing_kernel
def _newton_in_bracket(q_s, v_s, t_s, lo, hi, e_lo, e_hi, guess, oscillators, event, tolerance,
                       q, v, curvature=np.inf, jerk=np.inf):
    """The single root of a monotone e on [lo, hi] (e(lo) > 0, e(hi) <= round-off).

    Safeguarded Newton, started from ``guess`` if it is inside the bracket, else from the
    secant point; it stops at a few ulps of time or, with ``tolerance`` > 0, as soon as |e| is
    within the round-off rule (Newton steps inside e's noise band wander: they would cost
    evaluations and change nothing). With ``tolerance`` = 0 and bounds ``curvature`` >= |e''|
    and ``jerk`` >= |e'''| on the bracket, an iterate whose exact local quadratic pins the root
    to an ulp ends it (``_quadratic_root``): one evaluation, where Newton takes two or three.
    Returns the root and the time of the state left in q, v.
    """
    t = guess if lo < guess < hi else lo + (hi - lo) * e_lo / (e_lo - e_hi)
    if not lo < t < hi:
        t = 0.5 * (lo + hi)
    for _ in range(NEWTON_LIMIT):
        advance_to(oscillators, q_s, v_s, t_s, t, q, v)
        value, slope, scale = evaluate(q, v, t, event)
        if value > 0.0:
            lo = t
        else:
            hi = t
        if value == 0.0 or hi - lo <= 4.0 * _EPS * hi:
            return hi, t
        if abs(value) <= tolerance * _EPS * scale:
            return t, t
        if tolerance == 0.0 and jerk < np.inf:
            root = _quadratic_root(value, slope, event_acceleration(q, v, t, oscillators, event),
                                   curvature, jerk, t)
            if lo < root:
                return min(root, hi), t
        step = t - value / slope if slope != 0.0 else lo - 1.0
        # converged to within an ulp (tested before the safeguard, which would otherwise
        # replace a step that stays at t = lo or hi by a bisection far from the root): the
        # root is t, or the Newton point with a margin of 2 eps t past it
        if abs(step - t) <= 2.0 * _EPS * abs(t):
            return (hi if value <= 0.0 else min(hi, max(step, t) + 2.0 * _EPS * abs(t))), t
        if not lo < step < hi:
            step = 0.5 * (lo + hi)
        t = step
    return hi, t  # the bracket has shrunk by at least 2^-NEWTON_LIMIT: hi is past the root


@borrowing_kernel
def step_limit(t_s, t_end, frequencies):
    """A cap on the walk's steps over (t_s, t_end]: far above any certified walk's count.

    A walk takes a few steps per period of the fastest mode (fewer near grazing minima, which
    it passes in a logarithmic number of steps), so 64 per period plus 2^20 is never reached
    unless the bounds degenerate; the search then ends with ``GAVE_UP`` instead of spinning.
    """
    highest = frequencies[0]
    for j in range(1, frequencies.size):  # not np.max, which compiles take_impl
        highest = max(highest, frequencies[j])
    return 2.0**20 + 64.0 * (t_end - t_s) * highest / (2.0 * math.pi)


@borrowing_kernel
def first_root(q_s, v_s, t_s, t_end, oscillators, event, q, v, rotor):
    """First time in (t_s, t_end] where e(t) reaches 0 from above, NaN if none.

    ``search_root`` from t_s with no round-off tolerance (a root is a value <= 0, resolved to
    a few ulps of time), as the switching events of the dynamics use it, on the same e with
    the steady states split off (``split_steady_states``: cheaper steps).
    """
    max_steps = step_limit(t_s, t_end, oscillators.frequencies)
    q_free, v_free, free = _unsplit_copy(q_s, v_s, oscillators, rotor)
    split = split_steady_states(q_free, v_free, t_s, free, event)
    split_start, _, _ = evaluate(q_free, v_free, t_s, split)
    start, _, _ = evaluate(q_s, v_s, t_s, event)
    if split_start <= 0.0 < start:
        # e is at round-off level at t_s and the two forms round it differently: the caller
        # saw e > 0 there (it may have stepped off a root to that point), so search its form
        return search_root(q_s, v_s, t_s, t_s, t_end, oscillators, event, 0.0, max_steps, q, v,
                           rotor)
    return search_root(q_free, v_free, t_s, t_s, t_end, free, split, 0.0, max_steps, q, v,
                       rotor)


@inlined_kernel
def _unsplit_copy(q_s, v_s, oscillators, rotor):
    """Copies of the state and of the oscillators, for ``split_steady_states``.

    In the rotor's work arrays (``rotor.split``, ``rotor.split_force``), so that a search
    allocates nothing. Returns the copied state's rows and the copied `records.Oscillators`.
    """
    n = q_s.size
    for j in range(n):  # element by element: a slice assignment compiles string formatting
        rotor.split[0, j], rotor.split[1, j] = q_s[j], v_s[j]
        rotor.split_force[j] = oscillators.force[j]
    return rotor.split[0, :n], rotor.split[1, :n], Oscillators(
        oscillators.frequencies, oscillators.zeta, rotor.split_force[:n],
        oscillators.forcing_frequency)


@borrowing_kernel
def root_after_rise(q_s, v_s, t_s, t_end, oscillators, event, q, v, rotor):
    """``first_root`` of an e that rises through 0 at t_s: ``(root, certified)``.

    With e(t_s) <= 0 < e'(t_s) and |e''| <= C over the search (``phase_bounds``), e rises for
    s < e'(t_s) / C and gains at least e'^2 / (2 C) by then: if that lifts it above 0, it has
    crossed 0 exactly once, and the search for its next root starts at the window's end
    (steady states split off as in ``first_root``). ``certified`` is False when the bound
    cannot show the rise (or rounding keeps e at 0 there): the caller then follows e to its
    peak, which costs a search of e'.
    """
    q_free, v_free, free = _unsplit_copy(q_s, v_s, oscillators, rotor)
    split = split_steady_states(q_free, v_free, t_s, free, event)
    value, slope, _ = evaluate(q_free, v_free, t_s, split)
    if slope <= 0.0:
        return np.nan, False
    bounds = phase_bounds(q_free, v_free, t_s, t_end - t_s, free, split)
    curvature = bounds[2]
    reach = min(slope / curvature, t_end - t_s) if curvature > 0.0 else t_end - t_s
    if not value + reach * (slope - 0.5 * curvature * reach) > 0.0:
        return np.nan, False
    t_start = t_s + reach
    root, _ = walk(q_free, v_free, t_s, t_start, t_end, free, split, 0.0,
                   step_limit(t_s, t_end, free.frequencies), bounds, np.nan, q, v, rotor)
    if root == t_start:  # e not above 0 at the window's end: only through rounding
        return np.nan, False
    return root, True


@borrowing_kernel
def search_root(q_s, v_s, t_s, t_start, t_end, oscillators, event, tolerance, max_steps, q, v,
                rotor):
    """First time in [t_start, t_end] where e(t) reaches 0 from above; NaN if none.

    q_s, v_s: modal state at t_s (s) of the phase's `records.Oscillators`; ``event``: the
    `records.EventFunction`. The caller guarantees that e has no root in (t_s, t_start) (a warm
    start). ``q``, ``v`` are work arrays.

    Round-off rule: e counts as 0 where ``e <= tolerance * eps * scale`` (``evaluate``'s
    scale), i.e. where it is zero to within its own evaluation error, so that grazing at the
    level of rounding is classified one way consistently (``tolerance`` = 0: e <= 0 only).
    Returns ``GAVE_UP`` (-inf) after ``max_steps`` steps of the walk (see ``step_limit``).
    """
    bounds = phase_bounds(q_s, v_s, t_s, t_end - t_s, oscillators, event)
    root, _ = walk(q_s, v_s, t_s, t_start, t_end, oscillators, event, tolerance, max_steps,
                   bounds, np.nan, q, v, rotor)
    return root


@borrowing_kernel
def walk(q_s, v_s, t_s, t_start, t_end, oscillators, event, tolerance, max_steps, bounds, t_state,
         q, v, rotor):
    """``search_root`` given ``bounds``, ``phase_bounds`` over [t_s, t_end].

    The bounds do not depend on ``const``: event functions that differ in it alone (a column
    of a map along the clearance) share them. ``q``, ``v`` hold the state at ``t_state`` on
    entry (NaN: at no time) and on return, which is ``(root, t_state)``, so that a search
    starting where the previous one ended need not propagate to its start.
    """
    const, forcing_frequency = event.const, event.forcing_frequency
    # bounds hold over a step of at most this span (a loop, not np.min: compile time)
    lowest = oscillators.frequencies[0]
    for j in range(1, oscillators.frequencies.size):
        lowest = min(lowest, oscillators.frequencies[j])
    span_cap = 2.0 * math.pi / lowest
    coherent, band, curvature, jerk, any_span = bounds
    amplitude = abs(coherent)  # of the bounds' sinusoid, which only per-step bounds change
    floor = const - band - amplitude
    if floor > tolerance * _EPS * (abs(const) + band + amplitude):
        return NO_EVENT, t_state  # the event function cannot reach 0 in this phase
    # With every mode split into steady state + free transient, the bounds hold for the whole
    # phase (transient amplitudes do not grow): computed once. Otherwise (a mode at or near
    # resonance) they are recomputed over each step's window.
    per_step = not any_span
    t = t_start
    if t == t_s:
        for j in range(q.size):  # not q[:] = q_s, whose shape check compiles string formatting
            q[j], v[j] = q_s[j], v_s[j]
    elif t != t_state:
        advance_to(oscillators, q_s, v_s, t_s, t, q, v)
    t_state = t
    value, slope, scale = evaluate(q, v, t, event)
    acceleration = event_acceleration(q, v, t, oscillators, event)
    # Between exact states the walk's own steps rotate the undriven modes (rotor), unless the
    # bounds need the exact state at every step.
    driven = 0 if per_step else rotor_load(rotor, q, v, t, oscillators, event)
    t_origin, offset = t, 0.0  # t = t_origin + offset, offset a sum of the rotor's steps
    steps = 0
    while steps < max_steps:
        steps += 1
        noise = tolerance * _EPS * scale
        if value <= noise:
            return t, t_state
        if per_step:
            coherent, band, curvature, jerk, any_span = phase_bounds(q, v, t, span_cap,
                                                                     oscillators, event)
            amplitude = abs(coherent)
        elif driven == 0 and steps % REFRESH_STEPS == 0:  # the fast transients have decayed
            coherent, band, curvature, jerk, any_span = rotor_bounds(
                rotor, oscillators, event, coherent)
        margin = value - noise  # certify e > noise over the step
        step = min(certified_step(margin, slope, curvature), span_cap)
        if not per_step:  # third order with the exact local e'': wide steps through minima
            step = min(cubic_step(margin, slope, acceleration, jerk, step), span_cap)
        # the exact sinusoid at Omega minus the bounded rest may certify a longer step
        skip = band_step(const - band - noise, coherent, amplitude, t, forcing_frequency)
        step = max(step, skip if any_span else min(skip, span_cap))
        if step <= 4.0 * _EPS * max(abs(t), span_cap):
            return t, t_state  # the event function is at round-off level: touching
        if slope < 0.0:  # approaching: try to bracket a crossing beyond the linear estimate
            # min of two floats, as everywhere in the search: each signature compiles its own
            reach = min(min(2.0 * value / -slope, span_cap), t_end - t)
            if reach > step and slope + curvature * reach < 0.0:  # e monotone on the bracket
                # start Newton at the root of e's local quadratic: error ~ jerk s^3
                guess = t + _first_positive_root(value, slope, 0.5 * acceleration)
                # e <= value + slope s + curvature s^2 / 2, which may reach 0 on the bracket:
                # then the root is certified there, with no probe
                below = _first_positive_root(value, slope, 0.5 * curvature)
                if tolerance == 0.0 and below <= reach:
                    return _newton_in_bracket(q_s, v_s, t_s, t, t + below, value, 0.0, guess,
                                              oscillators, event, tolerance, q, v, curvature,
                                              jerk if any_span else np.inf)
                t_probe = t + reach
                advance_to(oscillators, q_s, v_s, t_s, t_probe, q, v)
                t_state = t_probe
                probe, _, probe_scale = evaluate(q, v, t_probe, event)
                if probe <= tolerance * _EPS * probe_scale:
                    return _newton_in_bracket(q_s, v_s, t_s, t, t_probe, value, probe, guess,
                                              oscillators, event, tolerance, q, v, curvature,
                                              jerk if any_span else np.inf)
        if t + step >= t_end:
            return NO_EVENT, t_state
        # the rotor's arrays passed loose, not the record: fewer reference counts per step
        taken = 0.0 if per_step else turn(rotor.amplitudes, rotor.eigenvalues, rotor.levels,
                                          rotor.factors, step)
        if taken == 0.0:  # (a step below the rotor's table: exact)
            t += step
        else:
            offset += taken
            t = t_origin + offset
            if driven == 0:
                value, slope, scale, acceleration = free_event(
                    rotor.amplitudes, rotor.rates, oscillators.frequencies.size, event)
            else:
                value, slope, scale, acceleration = rotor_event(rotor, q_s, v_s, t_s, t,
                                                                oscillators, event)
            if value > tolerance * _EPS * scale:
                continue
            # at round-off level of a root: decide on the exact state, and go on from it
        advance_to(oscillators, q_s, v_s, t_s, t, q, v)
        t_state = t
        value, slope, scale = evaluate(q, v, t, event)
        acceleration = event_acceleration(q, v, t, oscillators, event)
        if not per_step:
            rotor_load(rotor, q, v, t, oscillators, event)
            t_origin, offset = t, 0.0
    return GAVE_UP, t_state
