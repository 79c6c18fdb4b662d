"""The contact seam: one dispatch per piece of a contact law, on ``settings.contact_law``.

Every kernel that depends on the contact law calls these functions; each law's pieces live in
its own module (`impactbeams.kernels.contact_tied`, `impactbeams.kernels.contact_spring`), and
this module is the only place that compares a law index (``TIED``, ``SPRING``, layout). A new
law adds its module and a branch in each dispatch here. Numba compiles both branches; the
integer test costs nothing beside a phase.

The pieces: the switch maps between the phases' coordinates, the coordinates in which a
state is observed (tips, energies: the tied law's own phase, the spring law's free
coordinates), the quasi-static tip loads, the tips' correction for the flexibility the modes
miss, the law's extra power (dashpot, the work at an onset's force jump), whether a contact
waits for a rising force or may be released early, and the tangent dynamics' switches
(saltation). The switching arrays come as one switching record per run (`records.SWITCHING`),
and this module is the one that reads its fields, handing each law its own. Arrays and fields
are named in `impactbeams.kernels.layout`; SI units.
"""

from impactbeams.kernels import contact_spring, contact_tied
from impactbeams.kernels.events import phase_event
from impactbeams.kernels.jit import borrowing_kernel, kernel
from impactbeams.kernels.layout import CONTACT, FREE, SPRING
from impactbeams.kernels.records import (
    SWITCH_DRIVES,
    SWITCH_OVERLAP,
    SWITCH_SHIFTS,
    SWITCH_SPRING,
)


@kernel
def keeps_free_coordinates(law):
    """Whether law ``law`` (a ``CONTACT_LAWS`` index) keeps the free coordinates in contact.

    The spring law: its contact phase is a set of oscillators of (q, q'), built per run from
    the free phase's drive (`impactbeams.kernels.forcing.spring_contact_inputs`).
    """
    return law == SPRING


@kernel
def observed_phase(phase, settings):
    """The phase whose table describes a state of ``phase`` after ``observed_state``."""
    return FREE if keeps_free_coordinates(settings.contact_law) else phase


@borrowing_kernel
def switch_state(q, v, t, to_phase, switching, settings, q_new, v_new):
    """The state (q, v) of the other phase at time t in ``to_phase``'s coordinates.

    Tied law: projection onto the new phase's modes. Spring law: the same physical state.
    ``switching``: the run's switching record, whose fields only this seam reads.
    """
    if keeps_free_coordinates(settings.contact_law):
        contact_spring.switch_state(q, v, t, to_phase, switching[SWITCH_SPRING],
                                    switching[SWITCH_DRIVES], settings, q_new, v_new)
    else:
        contact_tied.switch_state(q, v, t, to_phase, switching[SWITCH_OVERLAP],
                                  switching[SWITCH_SHIFTS], settings, q_new, v_new)


@borrowing_kernel
def observed_state(phase, y, y_rate, t, switching, settings, q, v):
    """Write into (q, v) the state (y, y') of ``phase`` at time t as it is observed.

    Spring law: a contact state back in the free coordinates; otherwise unchanged.
    """
    if phase == CONTACT and keeps_free_coordinates(settings.contact_law):
        contact_spring.free_state(y, y_rate, t, switching[SWITCH_SPRING],
                                  switching[SWITCH_DRIVES], settings, q, v)
    else:
        copy_state(y, y_rate, q, v)


@borrowing_kernel
def phase_state(phase, q, v, t, switching, settings, y, y_rate):
    """Write into (y, y') the observed state (q, v) of ``phase`` at time t in its own coordinates.

    The inverse of ``observed_state``: the spring law's contact coordinates from the free
    ones (with the run's own drives, ``switching[SWITCH_DRIVES]``: a state observed in one run
    starts another with other drives); otherwise unchanged.
    """
    if phase == CONTACT and keeps_free_coordinates(settings.contact_law):
        contact_spring.switch_state(q, v, t, CONTACT, switching[SWITCH_SPRING],
                                    switching[SWITCH_DRIVES], settings, y, y_rate)
    else:
        copy_state(q, v, y, y_rate)


@borrowing_kernel
def copy_state(q, v, out_q, out_v):
    """Copy the state (q, v) into (out_q, out_v).

    Element by element: a slice assignment (``out_q[:] = q``) compiles Numba's string
    formatting for its shape-mismatch message, about a second of a cold compile.
    """
    for j in range(q.size):
        out_q[j] = q[j]
        out_v[j] = v[j]


@kernel
def tip_loads(phase, t, settings, load1, rate1):
    """Quasi-static tip loads (Q1, Q1', Q2, Q2') (N, N/s) of an observed state of ``phase``.

    ``load1``, ``rate1``: beam 1's tip force F and F'. Tied contact: the tips share the
    quasi-static contact force; otherwise (Q1, Q2) = (F, 0).
    """
    if keeps_free_coordinates(settings.contact_law):
        return load1, rate1, 0.0, 0.0
    return contact_tied.tip_loads(phase, t, settings, load1, rate1)


@kernel
def residual_flexibility2(free_table, settings):
    """Beam 2's tip shift per unit contact force through what its modes miss (m/N).

    Packed per geometry (``settings.residual2``: 0 for the tied law, whose tips move with
    their contact shapes; `impactbeams.contact.spring.tip_shifts` for the spring law).
    """
    return settings.residual2


@kernel
def correct_tips(phase, tables, forces, phase_scalars, settings, residual2, t, q, v, out):
    """Add the tips' static response to the contact force (``TIP_COLUMNS`` of ``out``).

    Spring contact: the flexibility the modes miss moves the tips by ``+r_1 R``, ``-r_2 R``
    (``settings.residual1``, ``residual2``: the tips' shifts, side and contact point included).
    """
    if phase == CONTACT and keeps_free_coordinates(settings.contact_law):
        contact_spring.correct_tips(tables, forces, phase_scalars, settings, residual2, t, q, v,
                                    out)


@kernel
def residual_force(phase, table, scalars, q, v, t, settings):
    """R (N) and R' (N/s) acting on the tips' residual flexibility in a state of ``phase``.

    Spring contact: the contact phase's event function is R, on its own coordinates; (0, 0)
    where the law has no residual flexibility or the tips are apart.
    """
    if phase == CONTACT and keeps_free_coordinates(settings.contact_law):
        return phase_event(table, scalars, q, v, t, settings.forcing_frequency)
    return 0.0, 0.0


@kernel
def extra_dissipation(phase, free_table, free_scalars, q, v, t, settings, dissipation):
    """``dissipation`` (W) plus the law's own, from the observed (free) state at time t."""
    if keeps_free_coordinates(settings.contact_law):
        return contact_spring.dashpot_dissipation(phase == CONTACT, free_table, free_scalars,
                                                  q, v, t, settings, dissipation)
    return dissipation


@kernel
def onset_work(work, phase, tables, phase_scalars, settings, q, v, t):
    """``work`` (J) plus the work of F as a segment of ``phase`` starts in state (q, v) at t.

    Spring contact: beam 1's tip moves at once by r_1 R if R jumps (a dashpot).
    """
    if phase == CONTACT and keeps_free_coordinates(settings.contact_law):
        work += contact_spring.onset_work(tables[CONTACT], phase_scalars[CONTACT], settings, q,
                                          v, t)
    return work


@kernel
def waits_for_force(settings):
    """Whether every contact waits for its force to rise (spring: it starts at R = 0)."""
    return keeps_free_coordinates(settings.contact_law)


@kernel
def may_release_early(settings):
    """Whether a contact can end with the tips still overlapping (a spring's dashpot)."""
    return keeps_free_coordinates(settings.contact_law) and settings.contact_damping > 0.0


@kernel
def has_tangent_flow(law):
    """Whether law ``law``'s runs form a flow with tangent dynamics (Lyapunov exponents).

    The tied law's switches project onto another basis and its instantaneous impacts and
    accumulations do not form a flow whose linearisation converges in n_modes.
    """
    return keeps_free_coordinates(law)


@kernel
def tangent_switch(tangent_q, tangent_v, to_phase, switching, no_drive, out_q, out_v):
    """Linear part of a switch into ``to_phase``'s coordinates (laws with a tangent flow).

    ``no_drive``: zero drives in the layout of ``switching[SWITCH_DRIVES]`` (the switch's
    affine part).
    """
    contact_spring.tangent_switch(tangent_q, tangent_v, to_phase, switching[SWITCH_SPRING],
                                  no_drive, out_q, out_v)


@kernel
def onset_saltation(tangent_q, tangent_v, tables, phase_scalars, settings, q, v, t):
    """The tangents' saltation at an onset from free state (q, q') at time t."""
    contact_spring.onset_saltation(tangent_q, tangent_v, tables, phase_scalars, settings, q, v,
                                   t)
