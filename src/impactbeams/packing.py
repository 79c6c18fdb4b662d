"""Every kernel input, built from the physics objects (`impactbeams.contact`).

The kernels (`impactbeams.kernels`) take plain arrays in SI units, named in
`impactbeams.kernels.layout`; this module is the one place that fills them: a geometry's
phase tables and geometry row, the cell rows of a grid or of one run, and a run's complete
inputs (`pack_run`). What depends on a cell's forcing, damping and uplifts is computed
by `impactbeams.kernels.forcing.run_inputs`, the same function the map kernels call per
cell, so a simulated run and a sweep cell with the same parameters get the same bits.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.configuration import BELOW, SPRING_LAW
from impactbeams.kernels import layout
from impactbeams.kernels.events import event_value, phase_event_function
from impactbeams.kernels.forcing import run_inputs

if TYPE_CHECKING:
    from impactbeams.contact import FreePhase, ModalModel, SpringContact
    from impactbeams.params import Params


@dataclasses.dataclass(frozen=True)
class Basis:
    """One phase's modal coordinates as plain arrays (SI units).

    frequencies: natural frequencies omega_n (rad/s);
    tip1, tip2: tip displacement of each shape on beam 1 / beam 2; unit1, unit2: <u_i, mode>;
    drive: b with q'' + 2 zeta omega q' + omega^2 q = b (F'' + 2 zeta omega F'); event:
    event-function weights (free: the gap, contact: the contact force); base: Gamma_n of the
    modes whose clamp the shaker moves (`impactbeams.drive`), 0 for the others; own_damping:
    each mode's damping ratio of its own (a user structure's), to which the kernels add the
    cell's ``damping_ratio`` (`impactbeams.kernels.forcing.run_inputs`), 0 for the others.
    """

    frequencies: np.ndarray
    drive: np.ndarray
    tip1: np.ndarray
    tip2: np.ndarray
    unit1: np.ndarray
    unit2: np.ndarray
    event: np.ndarray
    base: np.ndarray
    own_damping: np.ndarray


def free_basis(free: FreePhase, params: Params | None) -> Basis:
    """The free phase's modal coordinates.

    ``params``: which clamps the shaker moves; None: no shaker (no base drive).
    """
    from impactbeams.drive import base_participation

    base = (np.zeros(free.frequencies.size) if params is None
            else base_participation(params, free))
    return Basis(free.frequencies, free.drive, free.tip1, free.tip2, free.unit1, free.unit2,
                 free.gap_weights, base, free.own_damping)


def bases(model: ModalModel) -> tuple[Basis, Basis]:
    """The free and the contact phase's modal coordinates of ``model``."""
    from impactbeams.drive import contact_participation

    return (free_basis(model.free, model.params),
            Basis(model.contact.frequencies, model.contact_drive, model.contact_tip,
                  model.contact_tip, model.contact_unit1, model.contact_unit2,
                  model.contact_shear2, contact_participation(model),
                  np.zeros(model.contact.frequencies.size)))


def phase_table(basis: Basis) -> np.ndarray:
    """A phase's table, rows ``layout.TABLE_ROWS``, with the modes' own damping ratios."""
    rows = {"frequency": basis.frequencies, "zeta": basis.own_damping, "drive": basis.drive,
            "event": basis.event, "tip1": basis.tip1, "tip2": basis.tip2, "unit1": basis.unit1,
            "unit2": basis.unit2, "base": basis.base}
    return np.array([rows[name] for name in layout.TABLE_ROWS])


def free_tables(free: FreePhase, params: Params | None = None) -> np.ndarray:
    """The first-impact kernel's tables of one geometry: the free phase alone, (1, rows, N).

    ``params``: which clamps the shaker moves (None: no shaker).
    """
    return phase_table(free_basis(free, params))[None]


def phase_tables(model: ModalModel) -> tuple[np.ndarray, np.ndarray]:
    """The tied law's per-geometry arrays: (tables of both phases, static shifts)."""
    tables = np.array([phase_table(basis) for basis in bases(model)])
    return tables, np.array([model.free.static_shift, model.contact_static_shift])


def spring_table(spring: SpringContact) -> np.ndarray:
    """The spring law's contact table: its oscillators and the contact force weights."""
    zeros = np.zeros(spring.eigenvalues.size)
    rows = {"frequency": spring.frequencies, "zeta": spring.damping_ratios, "drive": zeros,
            "event": spring.force_weights, "tip1": zeros, "tip2": zeros, "unit1": zeros,
            "unit2": zeros,
            "base": zeros}
    return np.array([rows[name] for name in layout.TABLE_ROWS])


def geometry_row(params: Params, free: FreePhase, spring: SpringContact | None = None,
                 ) -> np.ndarray:
    """A geometry's ``layout.GEOMETRY`` fields (SI units).

    Tip compliances, the gap's compliance to the tip force and the contact's side, the
    accumulation time (an instantaneous impact re-closing within half a
    period of the fastest free mode is the truncated bases disagreeing, not a new impact: see
    dynamics.run_events), the contact law, the spring law's effective k_e, c_e and the tips'
    shifts per unit contact force (`impactbeams.contact.spring.tip_shifts`), the clamps the
    shaker moves and the initial state.
    """
    shaker1, shaker2 = params.mount.clamps
    fields = {"c1": params.tip_compliance[0], "c2": params.tip_compliance[1],
              "gap_compliance": free.gap_compliance, "side": free.side,
              "accumulation": math.pi / np.max(free.frequencies),
              "contact_law": params.law.index,
              "contact_stiffness": spring.effective_stiffness if spring else 0.0,
              "contact_damping": spring.effective_damping if spring else 0.0,
              "residual1": spring.tip_shift1 if spring else 0.0,
              "residual2": spring.tip_shift2 if spring else 0.0,
              "shaker1": shaker1, "shaker2": shaker2,
              "start": float(layout.STARTS.index(params.start))}
    return np.array([fields[name] for name in layout.GEOMETRY])


@dataclasses.dataclass(frozen=True)
class Dynamics:
    """One geometry's modes and arrays for the dynamics kernels, for its contact law.

    ``model``: the tied law's modal model (contact modes, projections), else None; ``spring``:
    the spring law's contact phase, else None. ``bases``: the coordinates in which sampled
    states come back (the spring law's are the free ones in both phases). ``switching``: the
    geometry's switching record (`impactbeams.kernels.records.SWITCHING`: the tied law's
    ``overlap``, ``shifts``, the spring law's ``spring`` = (left, right, modes), in the layout
    of `impactbeams.kernels.contact_spring`, zeros for the other law; no run's drives: empty).
    """

    params: Params
    free: FreePhase
    model: ModalModel | None
    spring: SpringContact | None
    bases: tuple[Basis, Basis]
    tables: np.ndarray
    geometry: np.ndarray
    switching: tuple  # (overlap, shifts, spring, drives)


def _no_spring(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Zero spring arrays of the full size (geometries of both laws stack in one map)."""
    return (np.zeros((2 * m, m), complex), np.zeros((m, 2 * m), complex),
            np.zeros((len(layout.SPRING_MODE_ROWS), m), complex))


def _geometry_switching(overlap: np.ndarray, shifts: np.ndarray,
                        spring: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple:
    """A geometry's switching record: its laws' arrays, and the empty drives of no run.

    Every array C-contiguous, as the run's record that `run_inputs` returns: a kernel has one
    signature whichever built the record it takes.
    """
    overlap, shifts = np.ascontiguousarray(overlap), np.ascontiguousarray(shifts)
    spring = tuple(np.ascontiguousarray(array) for array in spring)
    return (overlap, shifts, spring,
            np.empty((len(layout.SPRING_DRIVE_ROWS), 0), dtype=np.complex128))


def stacked_switching(records: Sequence[tuple]) -> tuple[np.ndarray, ...]:
    """The switching records of a map's geometries stacked field by field (index: geometry).

    The fields of `impactbeams.kernels.records.STACKED_SWITCHING`, the spring arrays flat.

    The map kernels take geometry g's out with `impactbeams.kernels.records.geometry_switching`.
    """
    return tuple(np.array(arrays) for arrays in zip(
        *((overlap, shifts, *spring, drives) for overlap, shifts, spring, drives in records),
        strict=True))


def dynamics_arrays(params: Params, n_modes: int) -> Dynamics:
    """The dynamics kernels' arrays of one geometry (``n_modes`` per beam) and contact law.

    In the spring law the contact phase depends on the damping ratio, the contact stiffness
    and the dashpot, which therefore belong to the geometry.
    """
    from impactbeams.contact import build_free_phase, build_tied_model, spring_contact

    if params.law.projects:
        model = build_tied_model(params, n_modes)
        tables, shifts = phase_tables(model)
        return Dynamics(params, model.free, model, None, bases(model), tables,
                        geometry_row(params, model.free),
                        _geometry_switching(model.overlap, shifts,
                                            _no_spring(model.free.frequencies.size)))
    free = build_free_phase(params, n_modes)
    spring = spring_contact(free, free.point_compliance, params.damping_ratio,
                            params.contact_stiffness, params.contact_damping)
    tables = np.array([phase_table(free_basis(free, params)), spring_table(spring)])
    modes = np.array([spring.eigenvalues, spring.phase])
    m = free.frequencies.size  # zero tied-law arrays of the full size, as for the spring ones
    basis = free_basis(free, params)
    return Dynamics(params, free, None, spring, (basis, basis), tables,
                    geometry_row(params, free, spring),
                    _geometry_switching(np.zeros((m, m)), np.zeros((2, m)),
                                        (np.ascontiguousarray(spring.left.T),  # the kernels' layout
                                         np.ascontiguousarray(spring.right.T), modes)))


def cell_rows(columns: Mapping[str, np.ndarray | float], shape: int | tuple[int, ...],
              ) -> np.ndarray:
    """Cell rows (``layout.CELL_COLUMNS``) of a box of ``shape`` cells (or of ``shape`` cells).

    Without base excitation (``base_amplitude`` 0 throughout) the rows stop before its column,
    which the kernels then read as 0 (`impactbeams.kernels.drive.base_amplitude`).

    The rows are in C order; each column's value is a scalar or an array that broadcasts to
    ``shape`` (a swept axis's values along its dimension).
    """
    box = (shape,) if isinstance(shape, int) else shape
    names = _cell_columns(columns["base_amplitude"])
    cells = np.empty((*box, len(names)))
    for index, name in enumerate(names):
        cells[..., index] = columns[name]
    return cells.reshape(-1, len(names))


def _cell_columns(base_amplitude: np.ndarray | float) -> tuple[str, ...]:
    """The cell columns (``layout.CELL_COLUMNS``) of rows with these base amplitudes (m)."""
    if np.ndim(base_amplitude) == 0 and base_amplitude == 0.0:
        return layout.CELL_COLUMNS[:layout.CELL_U0]  # no shaker: a row without U0 reads 0
    return layout.CELL_COLUMNS


@dataclasses.dataclass(frozen=True)
class Packed:
    """One run's inputs, packed for the kernels (see kernels.layout).

    The geometry's arrays (``dynamics``) and what depends on the run's forcing, damping and
    uplifts; ``switching``: the run's switching record (`impactbeams.kernels.records.SWITCHING`:
    the geometry's with the run's drives), which the kernels take whole.
    """

    dynamics: Dynamics
    tables: np.ndarray
    forces: np.ndarray
    phase_scalars: np.ndarray
    switching: tuple  # (overlap, shifts, spring, drives)
    settings: np.void  # a record of kernels.layout.SETTINGS_DTYPE
    q0: np.ndarray
    v0: np.ndarray

    @property
    def params(self) -> Params:
        """The run's parameters."""
        return self.dynamics.params

    @property
    def bases(self) -> tuple[Basis, Basis]:
        """The coordinates of sampled states in each phase."""
        return self.dynamics.bases

    @property
    def spring_law(self) -> bool:
        """Whether the run uses the spring contact law."""
        return self.dynamics.spring is not None


def pack_run(params: Params, n_modes: int, t_max: float, search_span: float,
             dynamics: Dynamics | None = None) -> Packed:
    """Pack one run of ``params`` with ``n_modes`` per beam; ``t_max``, ``search_span`` in s.

    ``dynamics``: the geometry's arrays if already built for these ``params`` (those of a run
    that differs in the cell's parameters only, `impactbeams.orbits` reuses them along a
    branch), else None.
    """
    from impactbeams.drive import check_steady

    dynamics = dynamics_arrays(params, n_modes) if dynamics is None else dynamics
    check_steady(params, dynamics.free)
    # one cell: its row straight from the values (`cell_rows`' for a box of one; the geometry
    # is the run's own, index 0)
    cell = np.array([0.0 if name == "geometry" else getattr(params, name)
                     for name in _cell_columns(params.base_amplitude)], dtype=float)
    damped, forces, scalars, settings, q0, v0, switching = run_inputs(
        cell, dynamics.tables, dynamics.geometry, dynamics.switching, t_max, search_span)
    return Packed(dynamics, damped, forces, scalars, switching, settings[0], q0, v0)


@dataclasses.dataclass(frozen=True)
class ReducedModel:
    """The spring law's reduced model, for peers that take linear modes plus a gap element.

    Coordinates: the free modes' whole coordinates eta_n = <y, Y_n> (beam 1's modes, then beam
    2's), unit modal masses. With the tip force F(t) = F0 sin(Omega t) (downward) and the
    contact force R >= 0 (pushing beam 1 up, beam 2 down):

        eta'' + diag(damping) eta' + diag(frequencies^2) eta = tip1 (R - F) - tip2 R,
        y1(l1) = tip1 . eta + residual1 (R - F),   y2(l2) = tip2 . eta - residual2 R,
        R = max(0, -stiffness (clearance + y1(l1) - y2(l2)))   (no dashpot).

    That is, a massless point at each tip (the tip the engine reports), on a spring
    1 / residual_i to the modes' tip tip_i . eta and loaded by F (beam 1) and R, with the
    contact spring ``stiffness`` between the two points; in series they give
    effective_stiffness (docs/model.md, the static correction).
    All SI units: rad/s, 1/s, m per unit eta, m/N, N/m, m, N.
    """

    frequencies: np.ndarray
    damping: np.ndarray
    tip1: np.ndarray
    tip2: np.ndarray
    residual1: float
    residual2: float
    stiffness: float
    effective_stiffness: float
    clearance: float
    force_amplitude: float
    omega: float


def reduced_model(params: Params, n_modes: int) -> ReducedModel:
    """The reduced model of ``params`` with ``n_modes`` per beam (spring law, tip force only).

    Raises ParameterError for what it cannot express: the tied law, a dashpot, base excitation,
    a contact elsewhere than the tips or from above, several contacts (one gap element).
    """
    from impactbeams.contact import build_free_phase, spring_contact
    from impactbeams.params import CONTACTS, ParameterError

    if params.several_contacts:  # its peers take one gap element: R is one max(0, ...)
        raise ParameterError(
            f"reduced_model: {CONTACTS} = {len(params.contacts)} contacts; it supports one "
            "contact only (a linear modal model with one spring gap element between the tips, "
            "which its peers take)")
    law = params.law  # a spring gap element: a compliant law that keeps the free coordinates
    for name, value, supported, allowed in (
            ("contact_law", params.contact_law, law.compliant and law.tangent_flow,
             SPRING_LAW.name),
            ("contact_damping", params.contact_damping, params.contact_damping == 0.0, 0.0),
            ("base_amplitude", params.base_amplitude, params.base_amplitude == 0.0, 0.0),
            ("contact_position1", params.contact_position1, params.contact_position1 is None,
             None),
            ("contact_position2", params.contact_position2, params.contact_position2 is None,
             None),
            ("contact_side", params.contact_side, params.side.sign > 0.0, BELOW.name)):
        if not supported:
            raise ParameterError(f"reduced_model: {name} = {value!r}; it supports {allowed!r}"
                                 " only (a linear modal model with a spring gap element)")
    free = build_free_phase(params, n_modes)
    spring = spring_contact(free, free.point_compliance, params.damping_ratio,
                            params.contact_stiffness)
    return ReducedModel(free.frequencies,
                        2.0 * free.damping_ratios(params.damping_ratio) * free.frequencies,
                        free.tip1, free.tip2, spring.residual1, spring.residual2,
                        params.contact_stiffness, spring.effective_stiffness,
                        params.clearance, params.force_amplitude, params.omega)


def section_gap(packed: Packed, z: np.ndarray, t: float = 0.0) -> tuple[float, float]:
    """The gap g (m) and its rate g' (m/s) of the free state z = (q, q') at time t (s)."""
    n = packed.q0.size
    scalars = packed.phase_scalars[layout.FREE]
    gap, rate = event_value(z[:n], z[n:], t, phase_event_function(
        packed.tables[layout.FREE], scalars, packed.settings["forcing_frequency"]))
    return float(gap), float(rate)
