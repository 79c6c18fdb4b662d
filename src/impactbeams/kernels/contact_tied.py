"""The tied contact law (the paper's): tips tied in contact, switches project between bases.

Switching (docs/model.md) uses ``overlap[m, n] = <Z_m, Y_n>`` and the static shifts
``shifts[FREE] = <s, Y_n>``, ``shifts[CONTACT] = <s, Z_m>``:

* onset at t: ``r = overlap q - R_qs(t) shifts[CONTACT]``,
  ``r' = overlap q' - R_qs'(t) shifts[CONTACT]``;
* release at t: ``q = overlap^T r + R_qs(t) shifts[FREE]``, likewise for the velocities;

with ``R_qs = (c1 F - clearance) / (c1 + c2)`` the quasi-static contact force. In contact the
quasi-static tip loads are ``Q1 = F - R_qs``, ``Q2 = R_qs``. The law adds no power of its own
(its impacts are instantaneous projections) and has no tangent flow. Arrays and fields are
named in `impactbeams.kernels.layout`; SI units.
"""


from impactbeams.kernels.drive import harmonic
from impactbeams.kernels.jit import borrowing_kernel, kernel
from impactbeams.kernels.layout import CONTACT, FREE


@borrowing_kernel
def quasi_static_force(t, settings):
    """R_qs(t) = (c1 F(t) - clearance) / (c1 + c2) (N) and its rate R_qs'(t) (N/s)."""
    c1, c2 = settings.c1, settings.c2
    total = c1 + c2
    load, rate = harmonic(c1 * settings.force_amplitude, settings.forcing_frequency, t)
    return (load - settings.clearance) / total, rate / total


@borrowing_kernel
def switch_state(q, v, t, to_phase, overlap, shifts, settings, q_new, v_new):
    """Projection of the state (q, v) at time t onto ``to_phase``'s modes (not in place)."""
    r_qs, r_qs_rate = quasi_static_force(t, settings)
    if to_phase == CONTACT:
        _projected(overlap, False, q, v, -r_qs, -r_qs_rate, shifts[CONTACT], q_new, v_new)
    else:
        _projected(overlap, True, q, v, r_qs, r_qs_rate, shifts[FREE], q_new, v_new)


@borrowing_kernel
def _projected(overlap, transposed, q, v, load, rate, shift, q_new, v_new):
    """(q_new, v_new) = (P q + load shift, P v + rate shift), P ``overlap`` or its transpose.

    Loops, not ``overlap @ q``: BLAS's products cost a cold compile about 0.7 s, and round
    as these sums within a few ulps of their terms. Not a slice assignment either
    (``q_new[:] = ...`` compiles Numba's string formatting for its shape-mismatch message);
    ``a + (-x) s`` rounds as ``a - x s``, so the signs are exact.
    """
    for i in range(q_new.size):
        projected_q = projected_v = 0.0
        for j in range(q.size):
            weight = overlap[j, i] if transposed else overlap[i, j]
            projected_q += weight * q[j]
            projected_v += weight * v[j]
        q_new[i] = projected_q + load * shift[i]
        v_new[i] = projected_v + rate * shift[i]


@kernel
def tip_loads(phase, t, settings, load1, rate1):
    """Quasi-static tip loads (Q1, Q1', Q2, Q2') (N, N/s) given beam 1's tip force F, F'.

    Contact: the tied tips share the quasi-static contact force, Q1 = F - R_qs, Q2 = R_qs.
    """
    if phase != CONTACT:
        return load1, rate1, 0.0, 0.0
    load2, rate2 = quasi_static_force(t, settings)
    return load1 - load2, rate1 - rate2, load2, rate2
