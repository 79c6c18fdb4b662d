"""Modal drive data of the drives, from the parameters (SciPy/NumPy; docs/model.md).

The tip force's modal drive (b = Y_1n(l1) / omega_n^2) comes with the free phase
(`impactbeams.contact.build_free_phase`); this module adds base (shaker) excitation: which clamps
move (``shaker``) and each mode's participation factor ``Gamma_n = rhoA int_0^l Y_n dx``. The
kernels (`impactbeams.kernels.drive`) sum every drive per mode as ``Im(A e^(i Omega t))``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from impactbeams.modes import beam, participation
from impactbeams.params import require

if TYPE_CHECKING:
    from impactbeams.contact import FreePhase, ModalModel
    from impactbeams.params import Params

def drive_summary(params: Params) -> str:
    """One line naming every drive of ``params``, e.g. for a command's header.

    ``"drives: tip force F0 = 0.001 N; base motion U0 = 1e-05 m on beam 1's clamp and the stop
    (the stop moves with the shaker: shaker = 'beam1' keeps it fixed); Omega = 50 rad/s"``.
    """
    drives = [f"tip force F0 = {params.force_amplitude:g} N"] if params.force_amplitude else []
    if params.base_amplitude:
        words = params.mount.place(params.partner)
        moving_stop = params.mount.moves_stop(params.partner)
        drives.append(f"base motion U0 = {params.base_amplitude:g} m {words}" + (
            " (the stop moves with the shaker: shaker = 'beam1' keeps it fixed)" if moving_stop
            else ""))
    return (f"drives: {'; '.join(drives) or 'none'}; Omega = {params.omega:g} rad/s")


def check_steady(params: Params, free: FreePhase) -> None:
    """Refuse ``start = "steady"`` when an undamped free mode is driven exactly at resonance.

    Its steady amplitude A / D has D = 0: there is no steady state to start on.
    """
    if params.start != "steady":
        return
    resonant = (free.frequencies == params.omega) & (free.damping_ratios(params.damping_ratio)
                                                     == 0.0)
    require("start", params.start, not np.any(resonant),
            f"omega = {params.omega!r} rad/s is a natural frequency and damping_ratio = 0: an "
            "undamped mode driven at resonance has no steady state (use start = 'rest' or "
            "damping_ratio > 0)")


def base_participation(params: Params, free: FreePhase) -> np.ndarray:
    """Each free mode's ``Gamma_n`` if the shaker moves its beam's clamp, else 0 (kg^1/2)."""
    moves1, moves2 = params.mount.clamps
    return np.concatenate([moves1 * beam(params, 1).participation(free.beam1.shapes),
                           moves2 * beam(params, 2).participation(free.beam2.shapes)])


def contact_participation(model: ModalModel) -> np.ndarray:
    """Each tied contact mode's ``sum_i rhoA_i int Z_im`` over the beams whose clamp moves.

    The tied law takes both clamps on one shaker only (`impactbeams.params`): one moving clamp
    would move the tied tips' clearance too.
    """
    p, contact = model.params, model.contact
    moves1, moves2 = p.mount.clamps
    gamma = moves1 * participation(contact.beam1, p.rhoA1)
    if not p.partner.has_beam2:  # the contact modes live on beam 1: a stop's mount moves no mass
        return gamma
    return gamma + moves2 * participation(contact.beam2, p.rhoA2)
