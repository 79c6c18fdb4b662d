"""Full impact dynamics of the two beams: one trajectory as an xarray Dataset.

The Python layer packs the modal model (:mod:`impactbeams.model`) into plain arrays, runs the
event-driven kernel (:mod:`impactbeams.kernels.dynamics`) and turns the recorded phase segments
into observables. Everything linear or quadratic in the modal state is evaluated here from the
exact segment states, with the tip-load formulas of MODEL.md: in both phases the fields are
``y_i = -c_i Q_i(t) u_i + sum_n Y_in q_n`` with tip loads ``Q1 = F, Q2 = 0`` (free) or
``Q1 = F - R_qs, Q2 = R_qs`` (contact).

Energy of the fields (``a(u, v) = sum_i EI_i int u_i'' v_i''``; quasi-static shapes carry
``a(y_s, Y_n) = -sum_i Q_i Y_n(l_i)``, ``a(y_s, y_s) = sum_i c_i Q_i^2``):

* strain ``V = 1/2 sum_i c_i Q_i^2 - sum_i Q_i sum_n Y_n(l_i) q_n + 1/2 sum_n omega_n^2 q_n^2``;
* kinetic ``T = 1/2 sum_i (c_i Q_i')^2 <u_i, u_i> - sum_n q_n' sum_i c_i Q_i' <u_i, Y_n>
  + 1/2 sum_n q_n'^2``, with ``<u_i, u_i> = rhoA_i l_i 33/140``.

The modal equations see only the projection of the quasi-static velocity ``y_s_t`` on the
phase's modes. Its remainder carries the *unresolved kinetic energy*
``U = 1/2 |(1 - P) y_s_t|^2``; within a phase ``d(T + V - U)/dt`` equals the power of F minus
the damping dissipation exactly, so ``energy - unresolved_kinetic_energy`` is what the energy
balance checks (U vanishes when F0 = 0; it is ~1e-8 of the energy for the paper's case).
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import warnings

import numpy as np
import xarray as xr

from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.propagation import drive_amplitudes
from impactbeams.model import ModalModel, build_model, unit_tip_shape
from impactbeams.params import DAMPING_LAW, Params
from impactbeams.variables import attributes

_CHUNK = 1 << 15  # output times per sampling call: bounds memory at ~N * 0.5 MB
_INITIAL_CAPACITY = 4096  # segments; doubled (rerun from t = 0) until max_events


@dataclasses.dataclass(frozen=True)
class _Basis:
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
    bases: tuple[_Basis, _Basis]
    tables: np.ndarray
    forces: np.ndarray
    phase_scalars: np.ndarray
    shifts: np.ndarray
    settings: np.ndarray


def _bases(model: ModalModel) -> tuple[_Basis, _Basis]:
    free = model.free
    return (
        _Basis(free.omega, free.drive, free.tip1, free.tip2, free.unit1, free.unit2,
               free.tip1 - free.tip2),
        _Basis(model.contact.omega, model.contact_drive, model.contact_tip, model.contact_tip,
               model.contact_unit1, model.contact_unit2, model.contact_shear2),
    )


def phase_tables(model: ModalModel) -> tuple[np.ndarray, np.ndarray, float]:
    """The dynamics kernel's per-geometry arrays: (tables, shifts, accumulation time in s).

    ``tables[phase]`` has the rows of :mod:`impactbeams.kernels.dynamics`, with zero damping
    ratios (``ROW_ZETA``): set them for a given damping.
    """
    tables = np.array([[b.omega, 0.0 * b.omega, b.drive, b.event, b.tip1]
                       for b in _bases(model)])
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
    return Packed(model, _bases(model), tables, forces, phase_scalars, shifts, settings)


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """Recorded phase segments of one run (SI units).

    Segment k starts at ``time[k]`` in ``phase[k]`` (0 free, 1 contact; ``sustained[k]`` for a
    contact entered by the accumulation rule) with modal state
    ``q[k], v[k]`` (after the switching projection) and ends at ``time[k + 1]`` (or ``t_end``)
    in state ``end_q[k], end_v[k]`` (before the next projection). ``status`` is one of
    ``dynamics.STATUS_NAMES``.
    """

    time: np.ndarray
    phase: np.ndarray
    sustained: np.ndarray
    q: np.ndarray
    v: np.ndarray
    end_q: np.ndarray
    end_v: np.ndarray
    status: str
    t_end: float

    @property
    def segment_end(self) -> np.ndarray:
        """End time of every segment (s)."""
        return np.append(self.time[1:], self.t_end)


def _initial_state(packed: Packed) -> tuple[np.ndarray, np.ndarray]:
    """At rest in the uplift shapes: q = delta_1 <u_1, Y> + delta_2 <u_2, Y>, q' = F0 Omega b."""
    p, free = packed.model.params, packed.model.free
    return (p.uplift1 * free.unit1 + p.uplift2 * free.unit2,
            p.force_amplitude * p.omega * free.drive)


def run(packed: Packed, max_events: int) -> Trajectory:
    """Run the event kernel; grow its arrays (rerunning from t = 0) up to ``max_events``."""
    q0, v0 = _initial_state(packed)
    capacity = min(_INITIAL_CAPACITY, max_events)
    while True:
        time = np.empty(capacity)
        phase = np.empty(capacity, dtype=np.int64)
        sustained = np.empty(capacity, dtype=np.bool_)
        q, v, end_q, end_v = (np.empty((capacity, q0.size)) for _ in range(4))
        count, status, t_end = dyn.run_events(packed.tables, packed.forces, packed.phase_scalars,
                                              packed.model.overlap, packed.shifts,
                                              packed.settings, q0, v0, time, phase,
                                              sustained, q, v, end_q, end_v)
        if status != dyn.EVENT_LIMIT or capacity >= max_events:
            break
        capacity = min(2 * capacity, max_events)
    return Trajectory(time[:count], phase[:count], sustained[:count], q[:count], v[:count],
                      end_q[:count], end_v[:count], dyn.STATUS_NAMES[status], float(t_end))


def _loads(packed: Packed, phase: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, ...]:
    """Tip loads Q1, Q2 (N) and their rates (N/s) at times t in the given phases."""
    p = packed.model.params
    c1, c2 = p.tip_compliance
    force = p.force_amplitude * np.sin(p.omega * t)
    force_rate = p.force_amplitude * p.omega * np.cos(p.omega * t)
    contact = phase == dyn.CONTACT
    r_qs = np.where(contact, (c1 * force - p.clearance) / (c1 + c2), 0.0)
    r_qs_rate = np.where(contact, c1 * force_rate / (c1 + c2), 0.0)
    return force - r_qs, r_qs, force_rate - r_qs_rate, r_qs_rate


def _per_phase(packed: Packed, phase: np.ndarray, name: str) -> np.ndarray:
    """Rows of basis attribute ``name`` matching each phase entry, shape (len(phase), N)."""
    rows = np.array([getattr(b, name) for b in packed.bases])
    return rows[phase]


def observables(packed: Packed, phase: np.ndarray, t: np.ndarray, q: np.ndarray,
                v: np.ndarray) -> dict[str, np.ndarray]:
    """Tip deflections and velocities (m, m/s), gap (m), contact force (N) and energies (J).

    ``phase``, ``t`` (s): shape (k,); ``q``, ``v``: modal states, shape (k, N). Tip 2 is
    y2(l2) itself here (not minus the clearance).
    """
    p = packed.model.params
    c1, c2 = p.tip_compliance
    q1, q2, q1_rate, q2_rate = _loads(packed, phase, t)
    tip1, tip2 = _per_phase(packed, phase, "tip1"), _per_phase(packed, phase, "tip2")
    unit1, unit2 = _per_phase(packed, phase, "unit1"), _per_phase(packed, phase, "unit2")
    omega = _per_phase(packed, phase, "omega")
    y1 = -c1 * q1 + np.einsum("kn,kn->k", tip1, q)
    y2 = -c2 * q2 + np.einsum("kn,kn->k", tip2, q)
    static_projection = c1 * q1_rate[:, None] * unit1 + c2 * q2_rate[:, None] * unit2
    static_kinetic = 0.5 * ((c1 * q1_rate) ** 2 * p.rhoA1 * p.l1
                            + (c2 * q2_rate) ** 2 * p.rhoA2 * p.l2) * 33.0 / 140.0
    kinetic = (static_kinetic - np.einsum("kn,kn->k", v, static_projection)
               + 0.5 * np.einsum("kn,kn->k", v, v))
    strain = (0.5 * (c1 * q1**2 + c2 * q2**2) - q1 * np.einsum("kn,kn->k", tip1, q)
              - q2 * np.einsum("kn,kn->k", tip2, q) + 0.5 * np.einsum("kn,kn->k", omega**2, q**2))
    event = _per_phase(packed, phase, "event")
    force = np.where(phase == dyn.CONTACT, q2 + np.einsum("kn,kn->k", event, q), 0.0)
    return {
        "tip_deflection_1": y1,
        "tip_deflection_2": y2,
        "tip_velocity_1": -c1 * q1_rate + np.einsum("kn,kn->k", tip1, v),
        "tip_velocity_2": -c2 * q2_rate + np.einsum("kn,kn->k", tip2, v),
        "gap": p.clearance + y1 - y2,
        "contact_force": force,
        "kinetic_energy": kinetic,
        "energy": kinetic + strain,
        "unresolved_kinetic_energy": static_kinetic
        - 0.5 * np.einsum("kn,kn->k", static_projection, static_projection),
    }


def sample(packed: Packed, trajectory: Trajectory, times: np.ndarray,
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Phase and modal state (q, q') at ascending ``times`` within [0, t_end] (s)."""
    n_coords = trajectory.q.shape[1]
    q, v = np.empty((times.size, n_coords)), np.empty((times.size, n_coords))
    phase = np.empty(times.size, dtype=np.int64)
    dyn.sample_states(packed.tables, packed.forces, packed.settings, trajectory.time,
                      trajectory.phase, trajectory.q, trajectory.v, trajectory.time.size, times,
                      q, v, phase)
    return phase, q, v


def _time_series(packed: Packed, trajectory: Trajectory, times: np.ndarray,
                 ) -> dict[str, np.ndarray]:
    """Observables, contact flag, work of F and damping loss at ``times``; NaN past t_end."""
    inside = times <= trajectory.t_end
    names = ("tip_deflection_1", "tip_deflection_2", "tip_velocity_1", "tip_velocity_2", "gap",
             "contact_force", "kinetic_energy", "energy", "unresolved_kinetic_energy",
             "in_contact", "work_of_force", "damping_dissipation")
    out = {name: np.full(times.size, np.nan) for name in names}
    reached = np.flatnonzero(inside)
    for start in range(0, reached.size, _CHUNK):
        index = reached[start:start + _CHUNK]
        phase, q, v = sample(packed, trajectory, times[index])
        for name, values in observables(packed, phase, times[index], q, v).items():
            out[name][index] = values
        out["in_contact"][index] = phase
    work, dissipation = np.empty(reached.size), np.empty(reached.size)
    dyn.work_of_force(packed.tables, packed.forces, packed.phase_scalars, packed.settings,
                      trajectory.time, trajectory.phase, trajectory.q, trajectory.v,
                      trajectory.time.size, trajectory.t_end, times[reached], work, dissipation)
    out["work_of_force"][reached], out["damping_dissipation"][reached] = work, dissipation
    return out


def _segment_observables(packed: Packed, trajectory: Trajectory, k: np.ndarray, end: bool,
                         ) -> dict[str, np.ndarray]:
    """Observables at the start (after projection) or end (before) of segments ``k``."""
    t = trajectory.segment_end[k] if end else trajectory.time[k]
    q = trajectory.end_q[k] if end else trajectory.q[k]
    v = trajectory.end_v[k] if end else trajectory.v[k]
    return observables(packed, trajectory.phase[k], t, q, v)


def _gap_rate(obs: dict[str, np.ndarray]) -> np.ndarray:
    return obs["tip_velocity_1"] - obs["tip_velocity_2"]


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
    omega^2 int r = Re A int sin + Im A int cos - [r' + 2 zeta omega r], R = R_qs + shear . r.
    """
    p = packed.model.params
    c1, c2 = p.tip_compliance
    t0, t1 = trajectory.time[k], trajectory.segment_end[k]
    sine, cosine = _harmonic_integrals(p.omega, t0, t1)
    table, force = packed.tables[dyn.CONTACT], packed.forces[dyn.CONTACT]
    omega, zeta, shear = table[dyn.ROW_OMEGA], table[dyn.ROW_ZETA], table[dyn.ROW_EVENT]
    jump = (trajectory.end_v[k] - trajectory.v[k]
            + 2.0 * zeta * omega * (trajectory.end_q[k] - trajectory.q[k]))
    modal = (force.real * sine[:, None] + force.imag * cosine[:, None] - jump) / omega**2
    quasi_static = (c1 * p.force_amplitude * sine - p.clearance * (t1 - t0)) / (c1 + c2)
    return quasi_static + modal @ shear


def _impact_table(packed: Packed, trajectory: Trajectory) -> dict[str, np.ndarray]:
    """Per-impact quantities: one entry per contact phase (zero-duration ones included)."""
    k = np.flatnonzero(trajectory.phase == dyn.CONTACT)
    released = k + 1 < trajectory.time.size
    before = _segment_observables(packed, trajectory, k - 1, end=True)
    after = _segment_observables(packed, trajectory, k, end=False)
    at_release = _segment_observables(packed, trajectory, k, end=True)
    separated = _segment_observables(packed, trajectory,
                                     np.minimum(k + 1, trajectory.time.size - 1), end=False)
    nan = np.full(k.size, np.nan)
    onset_rate, separation_rate = _gap_rate(before), _gap_rate(separated)
    peaks = np.array([
        dyn.peak_force(packed.tables[dyn.CONTACT], packed.forces[dyn.CONTACT],
                       packed.phase_scalars[dyn.CONTACT],
                       packed.settings, trajectory.q[j], trajectory.v[j], trajectory.time[j],
                       trajectory.segment_end[j])[0] for j in k])
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


def _fields(packed: Packed, trajectory: Trajectory, times: np.ndarray, n_points: int,
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Deflection fields y_1(x_1, t), y_2(x_2, t) (m) on uniform grids of ``n_points``."""
    model = packed.model
    p, n = model.params, model.n_modes
    c1, c2 = p.tip_compliance
    x1, x2 = np.linspace(0.0, p.l1, n_points), np.linspace(0.0, p.l2, n_points)
    shapes1 = (np.vstack([model.free.beam1.shapes(x1), np.zeros((n, n_points))]),
               model.contact.beam1(x1))
    shapes2 = (np.vstack([np.zeros((n, n_points)), model.free.beam2.shapes(x2)]),
               model.contact.beam2(x2))
    y1 = np.full((times.size, n_points), np.nan)
    y2 = np.full((times.size, n_points), np.nan)
    reached = np.flatnonzero(times <= trajectory.t_end)
    for start in range(0, reached.size, _CHUNK):
        index = reached[start:start + _CHUNK]
        phase, q, _ = sample(packed, trajectory, times[index])
        q1, q2, _, _ = _loads(packed, phase, times[index])
        for ph in (dyn.FREE, dyn.CONTACT):
            rows = index[phase == ph]
            qs = q[phase == ph]
            y1[rows] = -c1 * q1[phase == ph, None] * unit_tip_shape(p.l1, x1) + qs @ shapes1[ph]
            y2[rows] = -c2 * q2[phase == ph, None] * unit_tip_shape(p.l2, x2) + qs @ shapes2[ph]
    return x1, x2, y1, y2


def _output_times(t_max: float, dt_output: float, times: np.ndarray | None) -> np.ndarray:
    if times is not None:
        times = np.asarray(times, dtype=float)
        if times.ndim != 1 or np.any(np.diff(times) < 0) or np.any((times < 0) | (times > t_max)):
            raise ValueError("times must be a 1-D ascending array within [0, t_max]")
        return times
    if not (math.isfinite(dt_output) and dt_output > 0):
        raise ValueError(f"dt_output = {dt_output!r} is not allowed: must be > 0 (s)")
    count = int(math.floor(t_max / dt_output * (1 + 1e-12))) + 1
    return np.minimum(np.arange(count) * dt_output, t_max)


def simulate(params: Params, t_max: float, n_modes: int = 5, dt_output: float = 1e-4,
             fields: bool = False, *, times: np.ndarray | None = None, n_points: int = 41,
             max_events: int = 200_000, search_span: float | None = None) -> xr.Dataset:
    """Simulate the impacting beams from t = 0 to ``t_max`` (s); return an xarray Dataset.

    Args:
        params: model parameters (SI units).
        t_max: end time (s), > 0.
        n_modes: free modes per beam (the contact phase has 2 n_modes).
        dt_output: spacing (s) of the output grid 0, dt, 2 dt, ... <= t_max.
        fields: also return the deflection fields ``deflection_1(time, x1)``,
            ``deflection_2(time, x2)`` on ``n_points`` uniform points per beam.
        times: explicit ascending output times (s) in [0, t_max], instead of ``dt_output``.
        n_points: points per beam of the deflection fields (uniform, clamp to tip).
        max_events: cap on the number of phases (events + 1); a run that reaches it stops
            there with ``attrs["status"] = "event_limit"`` (and a RuntimeWarning).
        search_span: the event search restarts from the exactly propagated state every this
            many seconds (default t_max). Results do not depend on it beyond round-off; it is
            here to test that.

    The output grid never influences the dynamics: events are located by the kernel on its
    own, and the outputs are evaluated from the exact segment states.
    """
    if not (isinstance(t_max, (int, float)) and math.isfinite(t_max) and t_max > 0):
        raise ValueError(f"t_max = {t_max!r} is not allowed: must be a finite number > 0 (s)")
    if max_events < 1:
        raise ValueError(f"max_events = {max_events!r} is not allowed: must be >= 1")
    span = float(t_max if search_span is None else search_span)
    if not span > 0:
        raise ValueError(f"search_span = {search_span!r} is not allowed: must be > 0 (s)")
    out_times = _output_times(float(t_max), dt_output, times)
    packed = pack_model(build_model(params, n_modes), float(t_max), span)
    trajectory = run(packed, max_events)
    if trajectory.status != "complete":
        warnings.warn(f"simulation stopped at t = {trajectory.t_end!r} s before t_max = "
                      f"{t_max!r} s: status {trajectory.status!r}", RuntimeWarning, stacklevel=2)
    dataset = _dataset(packed, trajectory, out_times)
    if fields:
        x1, x2, y1, y2 = _fields(packed, trajectory, out_times, n_points)
        dataset = dataset.assign_coords(x1=("x1", x1, attributes("x1")),
                                        x2=("x2", x2, attributes("x2")))
        dataset["deflection_1"] = (("time", "x1"), y1, attributes("deflection_1"))
        dataset["deflection_2"] = (("time", "x2"), y2, attributes("deflection_2"))
    dataset.attrs.update(_global_attributes(params, n_modes, float(t_max), trajectory))
    return dataset


def _dataset(packed: Packed, trajectory: Trajectory, times: np.ndarray) -> xr.Dataset:
    series = _time_series(packed, trajectory, times)
    series["tip_deflection_2"] = series["tip_deflection_2"] - packed.model.params.clearance
    impacts = _impact_table(packed, trajectory)
    data = {name: ("time", values, attributes(name)) for name, values in series.items()}
    data.update({name: ("impact", values, attributes(name)) for name, values in impacts.items()})
    coords = {"time": ("time", times, attributes("time")),
              "impact": ("impact", np.arange(impacts["impact_onset_time"].size),
                         attributes("impact"))}
    return xr.Dataset(data, coords=coords)


def _global_attributes(params: Params, n_modes: int, t_max: float, trajectory: Trajectory,
                       ) -> dict[str, object]:
    from impactbeams import __version__

    stamp = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    return {
        **params.as_dict(),
        "n_modes": n_modes,
        "t_max": t_max,
        "status": trajectory.status,
        "t_end": trajectory.t_end,
        "n_phases": trajectory.time.size,
        "damping_law": DAMPING_LAW,
        "Conventions": "CF-1.8",
        "title": "impact dynamics of two cantilevers with clearance (impactbeams.trajectory)",
        "history": f"{stamp} impactbeams {__version__} simulate",
    }
