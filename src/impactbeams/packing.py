"""Every kernel input, built from the physics objects (:mod:`impactbeams.model`).

The kernels (:mod:`impactbeams.kernels`) take plain arrays in SI units; this module is the one
place that builds them: per-geometry phase tables, and a run's forcing, settings and initial
state.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.propagation import drive_amplitudes
from impactbeams.model import ModalModel


@dataclasses.dataclass(frozen=True)
class Basis:
    """One phase's modal coordinates as plain arrays (SI units).

    tip1, tip2: tip displacement of each shape on beam 1 / beam 2; unit1, unit2: <u_i, mode>;
    drive: b with q'' + 2 zeta omega q' + omega^2 q = b F''; event: event-function weights.
    """

    omega: np.ndarray
    drive: np.ndarray
    tip1: np.ndarray
    tip2: np.ndarray
    unit1: np.ndarray
    unit2: np.ndarray
    event: np.ndarray


@dataclasses.dataclass(frozen=True)
class Packed:
    """The modal model and forcing packed for the kernels."""

    model: ModalModel
    bases: tuple[Basis, Basis]
    tables: np.ndarray
    forces: np.ndarray
    phase_scalars: np.ndarray
    shifts: np.ndarray
    settings: np.ndarray


def bases(model: ModalModel) -> tuple[Basis, Basis]:
    """The free and the contact phase's modal coordinates of ``model``."""
    free = model.free
    return (
        Basis(free.omega, free.drive, free.tip1, free.tip2, free.unit1, free.unit2,
               free.tip1 - free.tip2),
        Basis(model.contact.omega, model.contact_drive, model.contact_tip, model.contact_tip,
               model.contact_unit1, model.contact_unit2, model.contact_shear2),
    )


def phase_tables(model: ModalModel) -> tuple[np.ndarray, np.ndarray, float]:
    """The dynamics kernel's per-geometry arrays: (tables, shifts, accumulation time in s).

    ``tables[phase]`` has the rows of :mod:`impactbeams.kernels.dynamics`, with zero damping
    ratios (``ROW_ZETA``): set them for a given damping.
    """
    tables = np.array([[b.omega, 0.0 * b.omega, b.drive, b.event, b.tip1]
                       for b in bases(model)])
    shifts = np.array([model.free.static_shift, model.contact_static_shift])
    # an instantaneous impact re-closing within half a period of the fastest free mode is
    # the truncated bases disagreeing, not a new impact: see dynamics.run_events
    return tables, shifts, math.pi / np.max(model.free.omega)


def pack_model(model: ModalModel, t_max: float, search_span: float) -> Packed:
    """Pack ``model`` and its forcing for the kernels; ``t_max``, ``search_span`` in s."""
    p = model.params
    c1, c2 = p.tip_compliance
    total = c1 + c2
    tables, shifts, accumulation = phase_tables(model)
    tables[:, dyn.ROW_ZETA] = p.damping_ratio
    forces = np.array([drive_amplitudes(table[dyn.ROW_DRIVE], table[dyn.ROW_OMEGA],
                                        table[dyn.ROW_ZETA], p.force_amplitude, p.omega)
                       for table in tables])
    phase_scalars = np.array([[p.clearance, -c1 * p.force_amplitude, 1.0],
                              [-p.clearance / total, c1 * p.force_amplitude / total, c2 / total]])
    settings = np.array([p.clearance, c1, c2, p.force_amplitude, p.omega, t_max, search_span,
                         accumulation])
    return Packed(model, bases(model), tables, forces, phase_scalars, shifts, settings)


def initial_state(packed: Packed) -> tuple[np.ndarray, np.ndarray]:
    """At rest in the uplift shapes: q = delta_1 <u_1, Y> + delta_2 <u_2, Y>, q' = F0 Omega b."""
    p, free = packed.model.params, packed.model.free
    return (p.uplift1 * free.unit1 + p.uplift2 * free.unit2,
            p.force_amplitude * p.omega * free.drive)
