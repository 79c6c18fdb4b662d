"""Modal states of a run: its start from a given state, and its final state.

A state is the free coordinates z = (q, q') of both beams (2 N values, N = 2 n_modes, or
n_modes with ``counterpart = "stop"``) at t = 0, the stroboscopic section (the forcing
F0 sin(Omega t) and the clamps' motion U0 sin(Omega t) are at phase 0 there). q is the
dynamic part of the deflection, the quasi-static part F(t) s(x) taken out (docs/model.md).
The contact phase at the start follows from the state (spring law): in contact iff the tips
overlap (g < 0) and the contact force -k_e g - c_e g' pushes them apart (> 0).
"""

from __future__ import annotations

import numpy as np

from impactbeams.kernels import contact
from impactbeams.kernels.events import event_sine, event_value
from impactbeams.kernels.layout import CONTACT, FREE, ROW_EVENT, SCALAR_CONST
from impactbeams.packing import Packed
from impactbeams.params import ParameterError


def checked_state(packed: Packed, state: object, name: str = "initial_state") -> np.ndarray:
    """``state`` as a float array z = (q, q') of the run's 2 N free coordinates.

    ParameterError in one line unless it is a finite vector of that size.
    """
    size = 2 * packed.q0.size
    try:
        z = np.asarray(state, dtype=float)
    except (TypeError, ValueError):
        z = None
    if z is None or z.shape != (size,) or not np.all(np.isfinite(z)):
        shown = np.shape(z) if z is not None else type(state).__name__
        raise ParameterError(f"{name} = {shown}: must be a finite modal state (q, q') of "
                             f"{size} values (2 x {packed.q0.size} free coordinates of this "
                             "model's n_modes and counterpart)")
    return z


def phase_state(packed: Packed, z: np.ndarray, t: float = 0.0,
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """The free state z = (q, q') at time t (s) as (state, rate, phase) in that phase's coordinates.

    Spring law: contact iff g < 0 and -k_e g - c_e g' > 0 (see the module doc); the contact
    state is the same physical state in the contact oscillators' coordinates.
    """
    n = packed.q0.size
    q, v = z[:n].copy(), z[n:].copy()
    if not packed.spring_law:
        return q, v, FREE
    s = packed.settings
    scalars = packed.phase_scalars[FREE]
    gap, gap_rate = event_value(q, v, t, packed.tables[FREE, ROW_EVENT], scalars[SCALAR_CONST],
                                event_sine(scalars), s["forcing_frequency"])
    force = -s["contact_stiffness"] * gap - s["contact_damping"] * gap_rate
    if not (gap < 0.0 and force > 0.0):
        return q, v, FREE
    y, y_rate = np.empty(n), np.empty(n)
    contact.switch_state(q, v, t, CONTACT, *packed.switching(), s, y, y_rate)
    return y, y_rate, CONTACT


def free_state(packed: Packed, phase: int, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The state (q, q') of ``phase`` at time t (s) as free coordinates z = (q, q')."""
    q_out, v_out = np.empty_like(q), np.empty_like(v)
    contact.observed_state(phase, q, v, t, packed.dynamics.spring_arrays, packed.drives,
                           packed.settings, q_out, v_out)
    return np.concatenate([q_out, v_out])
