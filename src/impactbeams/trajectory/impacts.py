"""The per-impact table of a trajectory: one entry per contact phase.

Onset time, duration, impulse, peak force, restitution, and the energy changes at the switches.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from impactbeams.kernels.layout import (
    CONTACT,
    ROW_EVENT,
    ROW_FREQUENCY,
    ROW_ZETA,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
)
from impactbeams.kernels.reductions import peak_force
from impactbeams.packing import Packed
from impactbeams.trajectory.observables import gap_rate, observables
from impactbeams.trajectory.phases import Trajectory, free_states

_REPORT_EVERY = 256  # contacts between progress reports


def _segment_observables(packed: Packed, trajectory: Trajectory, k: np.ndarray, end: bool,
                         ) -> dict[str, np.ndarray]:
    """Observables at the start (after projection) or end (before) of segments ``k``."""
    t = trajectory.segment_end[k] if end else trajectory.time[k]
    q = trajectory.end_q[k] if end else trajectory.q[k]
    v = trajectory.end_v[k] if end else trajectory.v[k]
    q, v = free_states(packed, trajectory.phase[k], t, q, v)
    return observables(packed, trajectory.phase[k], t, q, v)


def _harmonic_integrals(omega: float, t0: np.ndarray, t1: np.ndarray,
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Integrals of sin(Omega t) and cos(Omega t) over [t0, t1] (s), without cancellation.

    The sine integral is 0 when Omega = 0 (so is the sine), the cosine integral t1 - t0.
    """
    if omega == 0.0:
        return np.zeros_like(t0), t1 - t0
    middle, half_width = 0.5 * omega * (t0 + t1), np.sin(0.5 * omega * (t1 - t0))
    return (2.0 * np.sin(middle) * half_width / omega,
            2.0 * np.cos(middle) * half_width / omega)


def _impulses(packed: Packed, trajectory: Trajectory, k: np.ndarray) -> np.ndarray:
    """Integral of R over contact segments ``k`` (N s), in closed form.

    From r'' + 2 zeta omega r' + omega^2 r = Im(A e^(i Omega t)):
    omega^2 int r = Re A int sin + Im A int cos - [r' + 2 zeta omega r], R = R_qs + shear . r
    (tied law; the spring law's oscillators likewise, with R = const + Im(S e^(i Omega t))
    + weights . y).
    """
    p = packed.params
    c1, c2 = p.tip_compliance
    t0, t1 = trajectory.time[k], trajectory.segment_end[k]
    sine, cosine = _harmonic_integrals(p.omega, t0, t1)
    table, force = packed.tables[CONTACT], packed.forces[CONTACT]
    omega, zeta, shear = table[ROW_FREQUENCY], table[ROW_ZETA], table[ROW_EVENT]
    jump = (trajectory.end_v[k] - trajectory.v[k]
            + 2.0 * zeta * omega * (trajectory.end_q[k] - trajectory.q[k]))
    modal = (force.real * sine[:, None] + force.imag * cosine[:, None] - jump) / omega**2
    if packed.spring_law:
        scalars = packed.phase_scalars[CONTACT]
        quasi_static = (scalars[SCALAR_CONST] * (t1 - t0) + scalars[SCALAR_SINE] * sine
                        + scalars[SCALAR_COSINE] * cosine)
    else:
        quasi_static = (c1 * p.force_amplitude * sine - p.clearance * (t1 - t0)) / (c1 + c2)
    return quasi_static + modal @ shear


def peak_forces(packed: Packed, trajectory: Trajectory,
                report: Callable[[int], None] | None = None) -> np.ndarray:
    """The peak contact force (N) of each contact phase of ``trajectory``, in order.

    ``report`` as in `impact_table`.
    """
    k = np.flatnonzero(trajectory.phase == CONTACT)
    peaks = np.empty(k.size)
    segment_end = trajectory.segment_end
    for i, j in enumerate(k):
        peaks[i] = peak_force(packed.tables[CONTACT], packed.forces[CONTACT],
                              packed.phase_scalars[CONTACT], packed.settings, trajectory.q[j],
                              trajectory.v[j], trajectory.time[j], segment_end[j])[0]
        if report is not None and ((i + 1) % _REPORT_EVERY == 0 or i + 1 == k.size):
            report(i % _REPORT_EVERY + 1)
    return peaks


def contact_measures(packed: Packed, trajectory: Trajectory,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each contact phase's peak force (N), impulse (N s) and impact velocity (m/s), in order.

    `impact_table`'s ``impact_peak_force``, ``impact_impulse`` and ``impact_velocity`` alone
    (a periodic orbit's measures, read at every point a continuation keeps).
    """
    k = np.flatnonzero(trajectory.phase == CONTACT)
    before = _segment_observables(packed, trajectory, k - 1, end=True)
    return (peak_forces(packed, trajectory), _impulses(packed, trajectory, k),
            gap_rate(before, packed.dynamics.free.side))


def impact_table(packed: Packed, trajectory: Trajectory,
                 report: Callable[[int], None] | None = None) -> dict[str, np.ndarray]:
    """Per-impact quantities: one entry per contact phase (zero-duration ones included).

    ``report(count)`` is called as the peak forces of ``count`` more contacts are found (the
    costly part: a search of each contact at the fastest mode's time scale).
    """
    k = np.flatnonzero(trajectory.phase == CONTACT)
    released = k + 1 < trajectory.time.size
    before = _segment_observables(packed, trajectory, k - 1, end=True)
    after = _segment_observables(packed, trajectory, k, end=False)
    at_release = _segment_observables(packed, trajectory, k, end=True)
    separated = _segment_observables(packed, trajectory,
                                     np.minimum(k + 1, trajectory.time.size - 1), end=False)
    nan = np.full(k.size, np.nan)
    side = packed.dynamics.free.side
    onset_rate, separation_rate = gap_rate(before, side), gap_rate(separated, side)
    peaks = peak_forces(packed, trajectory, report)
    return {
        "impact_onset_time": trajectory.time[k],
        "impact_duration": np.where(released, trajectory.segment_end[k] - trajectory.time[k],
                                    nan),
        "impact_impulse": _impulses(packed, trajectory, k),
        "impact_peak_force": peaks.reshape(k.size),
        "restitution_coefficient": np.where(released, -separation_rate / onset_rate, nan),
        "impact_sustained": trajectory.sustained[k].astype(np.int8),
        "impact_velocity": onset_rate,
        "separation_velocity": np.where(released, separation_rate, nan),
        "impact_energy_loss": before["energy"] - after["energy"],
        "impact_kinetic_energy_loss": before["kinetic_energy"] - after["kinetic_energy"],
        "release_energy_change": np.where(released, separated["energy"] - at_release["energy"],
                                          nan),
        "release_gap": np.where(released, separated["gap"], nan),
        "release_contact_force": np.where(released, at_release["contact_force"], nan),
    }
