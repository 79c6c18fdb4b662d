"""Modal states of a run: its start from a given state, and its final state.

A state is the free coordinates z = (q, q') of both beams (2 N values, N = 2 n_modes, or
n_modes with ``counterpart = "stop"``) at t = 0, the stroboscopic section (the forcing
F0 sin(Omega t) and the clamps' motion U0 sin(Omega t) are at phase 0 there). q is the
dynamic part of the deflection, the quasi-static part F(t) s(x) taken out (docs/model.md).
The contact phase at the start follows from the state (spring law): in contact iff the tips
overlap (g < 0) and the contact force -k_e g - c_e g' pushes them apart (> 0).
"""

from __future__ import annotations

import dataclasses
import math
import reprlib
from collections.abc import Callable

import numpy as np
import xarray as xr

from impactbeams import modes
from impactbeams.kernels import contact
from impactbeams.kernels.layout import CONTACT, FREE
from impactbeams.modes import AttachedBeam, FreeModes, UniformBeam
from impactbeams.packing import Packed, section_gap
from impactbeams.params import MAX_DEFLECTION, ParameterError, require_type
from impactbeams.trajectory.phases import Trajectory, free_states
from impactbeams.variables import attributes

# a Dataset's final state restarts a run if its t_end is a whole number of forcing periods to
# this relative tolerance (round-off of t_end = k 2 pi / Omega is ~1e-15 k)
SECTION_TOLERANCE = 1e-9


def checked_state(packed: Packed, state: object, name: str = "initial_state") -> np.ndarray:
    """``state`` as a float array z = (q, q') of the run's 2 N free coordinates.

    ArgumentTypeError unless it is numbers, ParameterError (one line) unless they are 2 N
    finite values.
    """
    size = 2 * packed.q0.size
    allowed = (f"{size} finite numbers, the modal state (q, q') of this model's "
               f"2 x {packed.q0.size} free coordinates (n_modes, counterpart)")
    try:
        given = np.asarray(state)
        z = None if given.dtype.kind not in "biuf" else given.astype(float)
    except (TypeError, ValueError):
        z = None
    if z is None and np.iscomplexobj(given):  # its imaginary part would be dropped
        raise ParameterError(f"{name} = {reprlib.repr(state)} is not allowed: complex; must "
                             f"be {allowed}")
    require_type(name, state, z is not None, allowed)
    if z.shape != (size,) or not np.all(np.isfinite(z)):
        raise ParameterError(f"{name} = {reprlib.repr(state)} (shape {z.shape}) is not "
                             f"allowed: must be {allowed}")
    _check_reach(packed, z, name)
    return z


def _check_reach(packed: Packed, z: np.ndarray, name: str) -> None:
    """Refuse a state whose free vibration may move a tip beyond the small-deflection limit.

    Each mode's amplitude sqrt(q_n^2 + (q_n' / omega_n)^2) times its tip deflection, summed:
    the most the state's free vibration can deflect each tip (m), against MAX_DEFLECTION of
    the beam's length, as every drive is (`impactbeams.params.check_joint`).
    """
    free, p = packed.dynamics.free, packed.params
    n = packed.q0.size
    amplitudes = np.hypot(z[:n], z[n:] / free.frequencies)
    for beam, tips in (("1", free.tip1), ("2", free.tip2)):
        reach, limit = float(np.abs(tips) @ amplitudes), MAX_DEFLECTION * getattr(p, "l" + beam)
        if reach > limit:
            raise ParameterError(
                f"{name} is not allowed: its free vibration deflects beam {beam}'s tip by up to "
                f"{reach:.3g} m, more than {MAX_DEFLECTION:g} l{beam} = {limit:.3g} m (small "
                "deflections: the beam model is linear); is it in the run's modal units (q in "
                "kg^1/2 m^1/2, as final_displacement)?")


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
    gap, gap_rate = section_gap(packed, z, t)
    force = -s["contact_stiffness"] * gap - s["contact_damping"] * gap_rate
    if not (gap < 0.0 and force > 0.0):
        return q, v, FREE
    y, y_rate = np.empty(n), np.empty(n)
    contact.switch_state(q, v, t, CONTACT, packed.switching, s, y, y_rate)
    return y, y_rate, CONTACT


def free_state(packed: Packed, phase: int, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The state (q, q') of ``phase`` at time t (s) as free coordinates z = (q, q').

    Through ``free_states``, the kernel `simulate` has loaded already: calling
    ``contact.observed_state`` from Python compiled it once more (0.2 s of a cold simulate).
    """
    q_out, v_out = free_states(packed, np.array([phase], dtype=np.int64), np.array([float(t)]),
                               np.ascontiguousarray(q, dtype=np.float64)[None],
                               np.ascontiguousarray(v, dtype=np.float64)[None])
    return np.concatenate([q_out[0], v_out[0]])


def final_state(packed: Packed, trajectory: Trajectory) -> np.ndarray:
    """The run's state z = (q, q') at ``t_end`` in the free coordinates.

    NaN if it ends in a tied contact, whose coordinates are the contact modes'.
    """
    last = trajectory.time.size - 1
    phase = int(trajectory.phase[last])
    if phase == FREE:  # already the free coordinates: no kernel call (12 us of a period map's)
        return np.concatenate([trajectory.end_q[last], trajectory.end_v[last]])
    if not packed.spring_law:
        return np.full(2 * packed.q0.size, np.nan)
    return free_state(packed, phase, trajectory.t_end, trajectory.end_q[last],
                      trajectory.end_v[last])


@dataclasses.dataclass(frozen=True)
class InitialFields:
    """Deflection and velocity fields of both beams at t = 0, as functions of x (m).

    Each of ``deflection1(x)``, ``velocity1(x)`` (beam 1, m and m/s at positions x in
    [0, l1], absolute frame) and ``deflection2``, ``velocity2`` (beam 2) takes an array of
    positions and returns the field there; None is zero. ``simulate`` projects them on the
    run's free modes with the mass matrix, ``q_n = <y, Y_n>`` and ``q_n' = <v, Y_n>`` (y, v
    the fields) plus the quasi-static and base parts of the rest velocity (docs/model.md; at
    t = 0 the tip force and the clamps are at their zero, so the displacements need no such
    part), where
    ``<w, Y> = sum over segments rhoA int w Y dx + sum over point masses (mass w(x_k) Y(x_k)
    + rotary_inertia w'(x_k) Y'(x_k))`` (uniform beams: ``rhoA int w Y dx``). The slope w' at
    a rotary inertia is a second-order difference of the given function with step 6e-6 of
    the beam's length (error ~5e-11 of the slope for a field smooth on the beam's scale;
    `impactbeams.structure.StructureModes.projection`). A user structure (``structure1``)
    has no positions x: refused. The truncation keeps the mass-weighted least-squares fit
    of each field by the n_modes shapes: what the shapes miss (a kink, a concentrated load's
    local shape, anything shorter than the last mode's half wave) is lost, and the fitted
    tips differ from the given ones by that much.
    """

    deflection1: Callable[[np.ndarray], np.ndarray] | None = None
    velocity1: Callable[[np.ndarray], np.ndarray] | None = None
    deflection2: Callable[[np.ndarray], np.ndarray] | None = None
    velocity2: Callable[[np.ndarray], np.ndarray] | None = None

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            require_type(field.name, value, value is None or callable(value),
                         "None or a function of the positions x (m)")


def _projection(field: Callable[[np.ndarray], np.ndarray] | None, name: str,
                beam_modes: FreeModes, cantilever: UniformBeam | AttachedBeam) -> np.ndarray:
    """<field, Y_n> of every mode of one beam, the mass inner product (kg^1/2 per unit)."""
    if field is None or beam_modes.frequencies.size == 0:
        return np.zeros(beam_modes.frequencies.size)

    def values(x: np.ndarray) -> np.ndarray:
        given = np.asarray(field(x), dtype=float)
        if given.shape != x.shape or not np.all(np.isfinite(given)):
            raise ParameterError(f"initial_state.{name}: must return {x.size} finite values "
                                 f"for {x.size} positions x in [0, {cantilever.length!r}] m")
        return given

    return cantilever.projection(beam_modes.shapes, values)


def projected_fields(packed: Packed, fields: InitialFields) -> np.ndarray:
    """The section state z = (q, q') of ``fields`` (see `InitialFields`).

    On uniform beams, stepped beams and beams with attachments (each beam's own mass inner
    product, `projection`); a user structure (``structure1``) has no positions x: refused.
    """
    p, free = packed.params, packed.dynamics.free
    beam1, beam2 = modes.beam(p, 1), modes.beam(p, 2)
    if not (beam1.continuous and beam2.continuous):
        raise ParameterError("initial_state: initial fields are projected on beams along x "
                             "(uniform, stepped or with attachments), not on a user structure "
                             "(structure1 has no positions x: start from rest, a steady state, "
                             "a modal state or an earlier run's Dataset)")
    if not p.partner.has_beam2:
        for name in ("deflection2", "velocity2"):
            if getattr(fields, name) is not None:
                raise ParameterError(f"initial_state.{name} is not allowed: counterpart = "
                                     "'stop' has no beam 2; leave it None")
    q = np.concatenate([_projection(fields.deflection1, "deflection1", free.beam1, beam1),
                        _projection(fields.deflection2, "deflection2", free.beam2, beam2)])
    v = np.concatenate([_projection(fields.velocity1, "velocity1", free.beam1, beam1),
                        _projection(fields.velocity2, "velocity2", free.beam2, beam2)])
    return np.concatenate([q, v + packed.v0])  # packed.v0: the rest velocity (no uplift)


def dataset_final_state(packed: Packed, dataset: xr.Dataset) -> np.ndarray:
    """The final state of an earlier run's Dataset, at a whole number of forcing periods.

    A simulate() result, or one cell of a stepped sweep (each cell ends after whole forcing
    periods of its own omega: its end state is on the section, `impactbeams.sweep`).
    """
    if "final_displacement" not in dataset:
        raise ParameterError("initial_state: the Dataset has no final_displacement (not a "
                             "simulate() result or a stepped sweep's of this version)")
    cells = [dim for dim in dataset["final_displacement"].dims if dim != "coordinate"]
    if cells:
        raise ParameterError(
            "initial_state: the Dataset holds an end state per cell (dimensions "
            f"{', '.join(map(str, cells))}): give one cell, e.g. dataset.isel("
            f"{', '.join(f'{dim}=0' for dim in cells)})")
    if "t_end" not in dataset.attrs:
        if "stepping" not in dataset.attrs:
            raise ParameterError("initial_state: the Dataset has no t_end (not a simulate() "
                                 "result or a stepped sweep's of this version)")
        return np.concatenate([dataset["final_displacement"].values,
                               dataset["final_velocity"].values])
    t_end, omega = float(dataset.attrs["t_end"]), packed.params.omega
    turns = omega * t_end / (2.0 * math.pi)
    if abs(turns - round(turns)) > SECTION_TOLERANCE * max(turns, 1.0):
        raise ParameterError(f"initial_state: the Dataset ends at t_end = {t_end!r} s, "
                             f"{turns:.9g} forcing periods; a run starts on the section "
                             "t = 0 mod 2 pi / omega: need a whole number of periods")
    return np.concatenate([dataset["final_displacement"].values,
                           dataset["final_velocity"].values])


def initial_phase_state(packed: Packed, initial_state: object,
                        ) -> tuple[np.ndarray, np.ndarray, int]:
    """`phases.run`'s start from ``simulate``'s ``initial_state`` (checked, ParameterError).

    An array z = (q, q'), an earlier run's Dataset (its final state) or `InitialFields`.
    It replaces ``params.start`` and the uplifts, which must be left at their defaults. The
    tied law starts free only (its contact phase has the contact modes' coordinates): a state
    whose tips overlap is refused.
    """
    z = initial_free_state(packed, initial_state)
    start = phase_state(packed, z)
    if not packed.spring_law:
        gap, _ = section_gap(packed, z)
        if not gap > 0.0:
            raise ParameterError(f"initial_state: the tips overlap (gap {gap!r} m at t = 0); "
                                 "the tied law starts from an open gap only")
    return start


def initial_free_state(packed: Packed, initial_state: object) -> np.ndarray:
    """``simulate``'s ``initial_state`` as the free state z = (q, q') at t = 0 (checked).

    An array z, an earlier run's Dataset (its final state) or `InitialFields`, in the free
    coordinates of ``packed`` (which several contacts' runs share); ``params.start`` and the
    uplifts must be left at their defaults (ParameterError).
    """
    p = packed.params
    if p.start != "rest" or p.uplift1 != 0.0 or p.uplift2 != 0.0:
        raise ParameterError("initial_state replaces params.start and the uplifts: leave "
                             f"start = 'rest' and uplift1 = uplift2 = 0 (got start = "
                             f"{p.start!r}, uplift1 = {p.uplift1!r}, uplift2 = {p.uplift2!r})")
    if isinstance(initial_state, InitialFields):
        z = projected_fields(packed, initial_state)
    elif isinstance(initial_state, xr.Dataset):
        z = dataset_final_state(packed, initial_state)
    else:
        z = initial_state
    return checked_state(packed, z)


def with_final_state(dataset: xr.Dataset, z: np.ndarray) -> xr.Dataset:
    """``dataset`` with the run's free state z = (q, q') at t_end.

    ``final_displacement`` and ``final_velocity``: the ``initial_state`` of a run that
    continues it.
    """
    n = z.size // 2
    dataset = dataset.assign_coords(coordinate=("coordinate", np.arange(n),
                                                 attributes("coordinate")))
    dataset["final_displacement"] = ("coordinate", z[:n], attributes("final_displacement"))
    dataset["final_velocity"] = ("coordinate", z[n:], attributes("final_velocity"))
    return dataset
