"""Every kernel input, built from the physics objects (:mod:`impactbeams.model`).

The kernels (:mod:`impactbeams.kernels`) take plain arrays in SI units, named in
:mod:`impactbeams.kernels.layout`; this module is the one place that fills them: a geometry's
phase tables and geometry row, the cell rows of a grid or of one run, and a run's complete
inputs (:func:`pack_model`). What depends on a cell's forcing, damping and uplifts is computed
by :func:`impactbeams.kernels.forcing.run_inputs`, the same function the map kernels call per
cell, so a simulated run and a sweep cell with the same parameters get the same bits.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.kernels import layout
from impactbeams.kernels.forcing import run_inputs

if TYPE_CHECKING:
    from impactbeams.model import FreePhase, ModalModel
    from impactbeams.params import Params


@dataclasses.dataclass(frozen=True)
class Basis:
    """One phase's modal coordinates as plain arrays (SI units).

    tip1, tip2: tip displacement of each shape on beam 1 / beam 2; unit1, unit2: <u_i, mode>;
    drive: b with q'' + 2 zeta omega q' + omega^2 q = b (F'' + 2 zeta omega F'); event:
    event-function weights (free: the gap, contact: the contact force).
    """

    omega: np.ndarray
    drive: np.ndarray
    tip1: np.ndarray
    tip2: np.ndarray
    unit1: np.ndarray
    unit2: np.ndarray
    event: np.ndarray


def free_basis(free: FreePhase) -> Basis:
    """The free phase's modal coordinates."""
    return Basis(free.omega, free.drive, free.tip1, free.tip2, free.unit1, free.unit2,
                 free.tip1 - free.tip2)


def bases(model: ModalModel) -> tuple[Basis, Basis]:
    """The free and the contact phase's modal coordinates of ``model``."""
    return (free_basis(model.free),
            Basis(model.contact.omega, model.contact_drive, model.contact_tip,
                  model.contact_tip, model.contact_unit1, model.contact_unit2,
                  model.contact_shear2))


def phase_table(basis: Basis) -> np.ndarray:
    """A phase's table, rows ``layout.TABLE_ROWS``, with zero damping ratios."""
    rows = {"omega": basis.omega, "zeta": 0.0 * basis.omega, "drive": basis.drive,
            "event": basis.event, "tip1": basis.tip1, "unit1": basis.unit1,
            "unit2": basis.unit2}
    return np.array([rows[name] for name in layout.TABLE_ROWS])


def free_tables(free: FreePhase) -> np.ndarray:
    """The first-impact kernel's tables of one geometry: the free phase alone, (1, rows, N)."""
    return phase_table(free_basis(free))[None]


def phase_tables(model: ModalModel) -> tuple[np.ndarray, np.ndarray]:
    """The dynamics kernel's per-geometry arrays: (tables of both phases, static shifts)."""
    tables = np.array([phase_table(basis) for basis in bases(model)])
    return tables, np.array([model.free.static_shift, model.contact_static_shift])


def geometry_row(params: Params, free: FreePhase) -> np.ndarray:
    """A geometry's ``layout.GEOMETRY`` fields: tip compliances (m/N), accumulation time (s).

    An instantaneous impact re-closing within half a period of the fastest free mode is the
    truncated bases disagreeing, not a new impact (see dynamics.run_events).
    """
    fields = {"c1": params.tip_compliance[0], "c2": params.tip_compliance[1],
              "accumulation": math.pi / np.max(free.omega)}
    return np.array([fields[name] for name in layout.GEOMETRY])


def cell_rows(columns: Mapping[str, np.ndarray | float], size: int) -> np.ndarray:
    """``size`` cell rows (``layout.CELL_COLUMNS``) from per-column values (arrays or scalars)."""
    cells = np.empty((size, len(layout.CELL_COLUMNS)))
    for index, name in enumerate(layout.CELL_COLUMNS):
        cells[:, index] = columns[name]
    return cells


@dataclasses.dataclass(frozen=True)
class Packed:
    """The modal model and forcing of one run, packed for the kernels (see kernels.layout)."""

    model: ModalModel
    bases: tuple[Basis, Basis]
    tables: np.ndarray
    forces: np.ndarray
    phase_scalars: np.ndarray
    shifts: np.ndarray
    settings: np.void  # a record of kernels.layout.SETTINGS_DTYPE
    q0: np.ndarray
    v0: np.ndarray


def pack_model(model: ModalModel, t_max: float, search_span: float) -> Packed:
    """Pack ``model`` and its forcing for the kernels; ``t_max``, ``search_span`` in s."""
    p = model.params
    tables, shifts = phase_tables(model)
    cell = cell_rows({**p.as_dict(), "geometry": 0.0}, 1)[0]
    damped, forces, scalars, settings, q0, v0 = run_inputs(
        cell, tables, geometry_row(p, model.free), t_max, search_span)
    return Packed(model, bases(model), damped, forces, scalars, shifts, settings[0], q0, v0)
