"""Observables of modal states: tip deflections and velocities, gap, contact force, energies.

Everything linear or quadratic in the modal state is evaluated from the exact segment states,
with the tip-load formulas of docs/model.md: in both phases the fields are
``y_i = -c_i Q_i(t) u_i + sum_n Y_in q_n`` with tip loads ``Q1 = F, Q2 = 0`` (free) or
``Q1 = F - R_qs, Q2 = R_qs`` (tied contact). The spring law keeps the free phase's coordinates
and quasi-static part in contact, where the spring adds ``R = -k_e g - c_e g'`` and the energy
``k_e g^2 / 2``.

Energy of the fields (``a(u, v) = sum_i EI_i int u_i'' v_i''``; quasi-static shapes carry
``a(y_s, Y_n) = -sum_i Q_i Y_n(l_i)``, ``a(y_s, y_s) = sum_i c_i Q_i^2``):

* strain ``V = 1/2 sum_i c_i Q_i^2 - sum_i Q_i sum_n Y_n(l_i) q_n + 1/2 sum_n omega_n^2 q_n^2``;
* kinetic ``T = 1/2 sum_i (c_i Q_i')^2 <u_i, u_i> - sum_n q_n' sum_i c_i Q_i' <u_i, Y_n>
  + 1/2 sum_n q_n'^2``, with ``<u_i, u_i> = rhoA_i l_i 33/140`` on a uniform beam
  (with attachments theirs included: `impactbeams.modes.AttachedBeam.static_mass_per_length`).

The modal equations see only the projection of the quasi-static velocity ``y_s_t`` on the
phase's modes. Its remainder carries the *unresolved kinetic energy*
``U = 1/2 |(1 - P) y_s_t|^2``; within a phase ``d(T + V - U)/dt`` equals the power of F minus
the damping dissipation exactly, so ``energy - unresolved_kinetic_energy`` is what the energy
balance checks (U vanishes when F0 = 0; it is ~1e-8 of the energy for the paper's case).

The gap and its rate are those at the contact points (``Params.contact_point``, from
``Params.side`` s): ``g = clearance + s (y1(x1) - y2(x2))``, with each contact point's deflection
``y_i(x_i)`` (``contact_deflection_i``: the tips' at the tips; elsewhere, spring law only,
``-G_1(x1, l1) F + sum_n Y_1n(x1) q_n + s r_1 R`` on beam 1 and
``sum_n Y_2n(x2) q_n - s r_2 R`` on beam 2, r_i the flexibility each beam's modes miss at its
point, in the absolute frame like the tips).
"""

from __future__ import annotations

import numpy as np

from impactbeams.kernels.contact_spring import contact_states
from impactbeams.kernels.layout import CONTACT, TIP_COLUMNS, TIP_V1, TIP_V2, TIP_Y1, TIP_Y2
from impactbeams.kernels.stroboscope import tip_loads_at, tip_motions
from impactbeams.modes import beam
from impactbeams.packing import Packed


def loads(packed: Packed, phase: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, ...]:
    """Tip loads Q1, Q2 (N) and their rates (N/s) in the quasi-static parts at times t.

    Tied law: the contact phase's quasi-static part carries the quasi-static contact force;
    spring law: both phases keep the free one (Q1 = F, Q2 = 0). The kernels' formula
    (`kernels.stroboscope.tip_loads_at`), sample by sample.
    """
    out = np.empty((t.size, 4))
    tip_loads_at(packed.settings, phase, t, out)
    return out[:, 0], out[:, 2], out[:, 1], out[:, 3]


def per_phase(packed: Packed, phase: np.ndarray, name: str) -> np.ndarray:
    """Rows of basis attribute ``name`` matching each phase entry, shape (len(phase), N)."""
    rows = np.array([getattr(b, name) for b in packed.bases])
    return rows[phase]


def observables(packed: Packed, phase: np.ndarray, t: np.ndarray, q: np.ndarray,
                v: np.ndarray) -> dict[str, np.ndarray]:
    """Tip deflections and velocities (m, m/s), gap (m), contact force (N) and energies (J).

    ``phase``, ``t`` (s): shape (k,); ``q``, ``v``: modal states, shape (k, N). Tip 2 is
    y2(l2) itself here (not minus the clearance). With a shaker the tips are in the absolute
    frame (the clamps' motion added), the energies those of the motion relative to the clamps.
    The tips and the spring law's contact force come from the kernels that sample long runs
    (`kernels.stroboscope.tip_motion`, `kernels.contact_spring.gap_and_force`): one formula for
    both.
    """
    p = packed.params
    c1, c2 = p.tip_compliance
    phase, t = np.asarray(phase, dtype=np.int64), np.asarray(t, dtype=np.float64)
    q, v = np.ascontiguousarray(q, dtype=np.float64), np.ascontiguousarray(v, dtype=np.float64)
    q1, q2, q1_rate, q2_rate = loads(packed, phase, t)
    tip1, tip2 = per_phase(packed, phase, "tip1"), per_phase(packed, phase, "tip2")
    unit1, unit2 = per_phase(packed, phase, "unit1"), per_phase(packed, phase, "unit2")
    frequencies = per_phase(packed, phase, "frequencies")
    tips = np.empty((t.size, len(TIP_COLUMNS)))
    tip_motions(packed.tables, packed.forces, packed.phase_scalars, packed.settings, phase, t, q,
                v, tips)
    static_projection = c1 * q1_rate[:, None] * unit1 + c2 * q2_rate[:, None] * unit2
    beam1, beam2 = beam(p, 1), beam(p, 2)
    static_kinetic = 0.5 * ((c1 * q1_rate) ** 2 * beam1.static_mass_per_length * beam1.length
                            + (c2 * q2_rate) ** 2 * beam2.static_mass_per_length * beam2.length
                            ) * 33.0 / 140.0
    kinetic = (static_kinetic - np.einsum("kn,kn->k", v, static_projection)
               + 0.5 * np.einsum("kn,kn->k", v, v))
    strain = (0.5 * (c1 * q1**2 + c2 * q2**2) - q1 * np.einsum("kn,kn->k", tip1, q)
              - q2 * np.einsum("kn,kn->k", tip2, q)
              + 0.5 * np.einsum("kn,kn->k", frequencies**2, q**2))
    contact = phase == CONTACT
    if packed.spring_law:
        force, force_rate, spring_energy = _spring_contact(packed, phase, t, q, v)
        strain = strain + spring_energy
    else:
        event = per_phase(packed, phase, "event")
        force = np.where(contact, q2 + np.einsum("kn,kn->k", event, q), 0.0)
    if p.at_tips:  # the tips' own arrays: the gap's bits as they were
        points = tips[:, TIP_Y1], tips[:, TIP_Y2], tips[:, TIP_V1], tips[:, TIP_V2]
    else:  # the spring law only (`Params` refuses the tied law elsewhere)
        points = _contact_points(packed, t, q, v, force, force_rate)
    side = packed.dynamics.free.side
    return {
        "tip_deflection_1": tips[:, TIP_Y1],
        "tip_deflection_2": tips[:, TIP_Y2],
        "tip_velocity_1": tips[:, TIP_V1],
        "tip_velocity_2": tips[:, TIP_V2],
        "contact_deflection_1": points[0],
        "contact_deflection_2": points[1],
        "contact_velocity_1": points[2],
        "contact_velocity_2": points[3],
        "gap": p.clearance + side * points[0] - side * points[1],
        "contact_force": force,
        "kinetic_energy": kinetic,
        "energy": kinetic + strain,
        "unresolved_kinetic_energy": static_kinetic
        - 0.5 * np.einsum("kn,kn->k", static_projection, static_projection),
    }


def gap_rate(obs: dict[str, np.ndarray], side: float) -> np.ndarray:
    """The gap's rate g' (m/s) of `observables` ``obs``: s (y1'(x1) - y2'(x2)), s = ``side``."""
    return side * obs["contact_velocity_1"] - side * obs["contact_velocity_2"]


def _contact_points(packed: Packed, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                    force: np.ndarray, force_rate: np.ndarray) -> tuple[np.ndarray, ...]:
    """Deflections (m) and velocities (m/s) of the contact points, spring law (module doc).

    ``force``, ``force_rate``: R (N) and R' (N/s), 0 out of contact. Returns
    (y1(x1), y2(x2), y1'(x1), y2'(x2)) in the absolute frame.
    """
    p, free, spring = packed.params, packed.dynamics.free, packed.dynamics.spring
    tip_force, tip_force_rate = p.force_amplitude * np.sin(p.omega * t), (
        p.force_amplitude * p.omega * np.cos(p.omega * t))
    transfer = free.tip_transfer[0]  # G1(x1, l1) = G1(l1, x1): Maxwell's reciprocity
    shift1, shift2 = free.side * spring.residual1, -free.side * spring.residual2
    y1 = -transfer * tip_force + q @ free.point1 + shift1 * force
    v1 = -transfer * tip_force_rate + v @ free.point1 + shift1 * force_rate
    y2, v2 = q @ free.point2 + shift2 * force, v @ free.point2 + shift2 * force_rate
    clamp = p.base_amplitude * np.sin(p.omega * t)
    clamp_rate = p.base_amplitude * p.omega * np.cos(p.omega * t)
    moves1, moves2 = p.mount.clamps
    return (y1 + moves1 * clamp, y2 + moves2 * clamp, v1 + moves1 * clamp_rate,
            v2 + moves2 * clamp_rate)


def _spring_contact(packed: Packed, phase: np.ndarray, t: np.ndarray, q: np.ndarray,
                    v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The spring law's contact force R (N, 0 out of contact), its rate (N/s) and energy (J).

    The energy, ``k_e g^2 / 2 - s_1 F R``, is the spring's (its static correction included;
    held while the tips overlap, also after an early release by the dashpot) plus the work of
    F through beam 1's residual flexibility under R (s_1 = ``tip_shift1``: its tip moves by
    s_1 R), so that energy, work of F and dissipation balance exactly; g is the modal gap, on
    which R = -k_e g - c_e g' acts.
    """
    p, spring = packed.params, packed.dynamics.spring
    states = np.empty((t.size, 3))
    contact_states(packed.tables, packed.forces, packed.phase_scalars, packed.settings, phase, t,
                   q, v, states)
    gap, force, force_rate = states[:, 0], states[:, 1], states[:, 2]
    tip_force = p.force_amplitude * np.sin(p.omega * t)
    # the spring holds its energy while the tips overlap, also after an early release
    energy = (np.where((phase == CONTACT) | (gap < 0.0),
                       0.5 * spring.effective_stiffness * gap**2, 0.0)
              - spring.tip_shift1 * tip_force * force)
    return force, force_rate, energy
