"""Exact (closed-form) propagation of harmonically driven modal oscillators.

Each modal coordinate obeys ``q'' + 2 zeta omega q' + omega^2 q = Im(A e^(i Omega t))``: a drive
with a sine part ``Re A`` and a cosine part ``Im A`` (the cosine part comes from damping the
quasi-static velocity, see docs/model.md). Over a step ``h`` from ``t0`` the solution is the
free response plus the Duhamel integral, written with ``lambda = -zeta omega + i omega_d`` and
the exponential-integrator function ``phi1(z) = (e^z - 1) / z``:

    E_pm(h) = int_0^h e^(lambda (h - s)) e^(+-i Omega s) ds = h e^(lambda h) phi1(mu_pm h),
    mu_pm = +-i Omega - lambda,
    K     = conj(A) e^(-i Omega t0) E_m - A e^(i Omega t0) E_p,
    x(h)  = Re[K] / (2 omega_d),   x'(h) = Re[lambda K] / (2 omega_d).

``phi1`` is evaluated with ``expm1`` near 0, so the response is exact at resonance
``Omega = omega_d`` and loses no digits within 1e-12 of it (no 0/0). Units: seconds, rad/s,
modal coordinates in m kg^1/2.
"""

import math

from impactbeams.kernels.jit import borrowing_kernel, inlined_kernel, kernel


@kernel
def phi1(z):
    """(e^z - 1) / z for complex z, accurate for small |z| (1 at z = 0)."""
    if z == 0:
        return 1.0 + 0.0j
    x, y = z.real, z.imag
    half_sin = math.sin(0.5 * y)
    real = math.expm1(x) * math.cos(y) - 2.0 * half_sin * half_sin
    return complex(real, math.exp(x) * math.sin(y)) / z


@kernel
def duhamel(lam, mu, growth, forcing_step, h):
    """E = int_0^h e^(lam (h - s)) e^(i nu s) ds with mu = i nu - lam.

    ``growth`` is e^(lam h) and ``forcing_step`` is e^(i nu h); the direct difference
    quotient is used when |mu h| >= 1 (no cancellation), phi1 otherwise.
    """
    if at_least_one(mu * h):
        return (forcing_step - growth) / mu
    return h * growth * phi1(mu * h)


@kernel
def at_least_one(z):
    """``abs(z) >= 1``, decided on |z|^2 away from 1 (``abs`` is ``hypot``, some 20 ns).

    |z|^2 rounds to within 3 eps of itself and ``hypot`` to within an ulp: outside 1 -+ 1e-12
    both decide as the exact |z| does, and within it ``abs`` decides, as before.
    """
    square = z.real * z.real + z.imag * z.imag
    if square > 1.0 + 1e-12:
        return True
    if square < 1.0 - 1e-12:
        return False
    return abs(z) >= 1.0


@borrowing_kernel
def advance(q0, v0, t0, h, frequencies, zeta, force, forcing_frequency, q, v):
    """Advance every mode by ``h`` (s) from time ``t0`` (s), writing into ``q`` and ``v``.

    q0, v0: modal displacements and velocities at t0; frequencies: natural frequencies omega
    (rad/s); zeta: damping ratio of each mode (0 <= zeta < 1); force: complex amplitude A of
    each mode's drive Im(A e^(i Omega t)); forcing_frequency: Omega (rad/s). ``q``/``v`` may
    alias ``q0``/``v0``.
    """
    phase_plus = complex(math.cos(forcing_frequency * t0), math.sin(forcing_frequency * t0))
    step_plus = complex(math.cos(forcing_frequency * h), math.sin(forcing_frequency * h))
    for j in range(frequencies.size):
        q[j], v[j] = advance_mode(q0[j], v0[j], h, frequencies[j], zeta[j], force[j],
                                  forcing_frequency, phase_plus, step_plus)


@inlined_kernel
def advance_to(oscillators, q_s, v_s, t_s, t, q, v):
    """``advance`` the `records.Oscillators` from (q_s, v_s) at t_s (s) to time t (s)."""
    forcing_frequency, h = oscillators.forcing_frequency, t - t_s
    phase_plus = complex(math.cos(forcing_frequency * t_s), math.sin(forcing_frequency * t_s))
    step_plus = complex(math.cos(forcing_frequency * h), math.sin(forcing_frequency * h))
    for j in range(oscillators.frequencies.size):
        q[j], v[j] = advance_mode(q_s[j], v_s[j], h, oscillators.frequencies[j],
                                  oscillators.zeta[j], oscillators.force[j], forcing_frequency,
                                  phase_plus, step_plus)


@inlined_kernel
def advance_mode(q0, v0, h, w, z, f, forcing_frequency, phase_plus, step_plus):
    """One mode of ``advance``: (q, q') after ``h`` (s) from (q0, v0) at t0.

    ``phase_plus`` = e^(i Omega t0), ``step_plus`` = e^(i Omega h); w, z, f: the mode's
    omega (rad/s), zeta and complex drive amplitude.
    """
    sigma, wd, decay, c, s, e_plus, e_minus = step_factors(h, w, z, forcing_frequency,
                                                           step_plus, f != 0.0)
    return stepped_mode(q0, v0, w, f, sigma, wd, decay, c, s, e_plus, e_minus, phase_plus)


@inlined_kernel
def step_factors(h, w, z, forcing_frequency, step_plus, driven):
    """What a step of ``h`` (s) of one mode multiplies its state and drive by.

    sigma = zeta omega, omega_d, e^(-sigma h), cos and sin of omega_d h, and (if ``driven``,
    else 0) the Duhamel integrals E_+ and E_- of the module's docstring; ``step_plus`` =
    e^(i Omega h). They depend on the step, not on the state or the time: a walk of equal
    steps computes them once (`stepped_mode`).
    """
    sigma, wd = z * w, w if z == 0.0 else w * math.sqrt(1.0 - z * z)
    decay = math.exp(-sigma * h)
    c, s = math.cos(wd * h), math.sin(wd * h)
    if not driven:
        return sigma, wd, decay, c, s, 0j, 0j
    lam = complex(-sigma, wd)
    growth = decay * complex(c, s)
    e_plus = duhamel(lam, complex(sigma, forcing_frequency - wd), growth, step_plus, h)
    e_minus = duhamel(lam, complex(sigma, -forcing_frequency - wd), growth,
                      step_plus.conjugate(), h)
    return sigma, wd, decay, c, s, e_plus, e_minus


@inlined_kernel
def stepped_mode(q0, v0, w, f, sigma, wd, decay, c, s, e_plus, e_minus, phase_plus):
    """(q, q') one step after (q0, v0) at t0, from the step's `step_factors`.

    w, f: the mode's omega (rad/s) and complex drive amplitude; ``phase_plus`` = e^(i Omega
    t0).
    """
    q_free = decay * (q0 * c + (v0 + sigma * q0) / wd * s)
    v_free = decay * (v0 * c - (w * w * q0 + sigma * v0) / wd * s)
    if f == 0.0:
        return q_free, v_free
    lam = complex(-sigma, wd)
    if f.imag == 0.0:  # a sine drive: the real form, fewer roundings
        combined = phase_plus.conjugate() * e_minus - phase_plus * e_plus
        scale = f.real / (2.0 * wd)
        return q_free + scale * combined.real, v_free + scale * (lam * combined).real
    combined = f.conjugate() * phase_plus.conjugate() * e_minus - f * phase_plus * e_plus
    return q_free + combined.real / (2.0 * wd), v_free + (lam * combined).real / (2.0 * wd)


# A mode's steady state is split off when |D| >= omega^2 / 16 (its steady amplitude is at most
# 16 times the quasi-static one, 4 bits of rounding): nearer resonance the steady state and
# the transient would cancel, and the mode stays driven. |D| >= 2 zeta omega^2 sqrt(1 - zeta^2),
# so with zeta >= 0.032 no mode stays driven; a driven mode costs the walk an exact
# propagation at every step (docs/model.md, "The event search between events").
SPLIT_DETUNING = 0.0625


@kernel
def steady_phasor(w, z, f, forcing_frequency):
    """The steady state Im(P e^(i Omega t)) of a mode away from resonance: P = A / D; else 0.

    D = omega^2 - Omega^2 + 2 i zeta omega Omega; 0 for an undriven mode or |D| below
    ``SPLIT_DETUNING`` omega^2 (compared in squares: no square root per mode).
    """
    detuning = complex(w * w - forcing_frequency**2, 2.0 * z * w * forcing_frequency)
    if f == 0 or detuning.real**2 + detuning.imag**2 < (SPLIT_DETUNING * w * w)**2:
        return 0j
    return f / detuning
