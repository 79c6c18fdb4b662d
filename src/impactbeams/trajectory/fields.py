"""Time series on the output grid (tips, work, damping loss) and deflection surfaces."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import xarray as xr

from impactbeams.kernels.drive import harmonic
from impactbeams.kernels.layout import CONTACT, FREE
from impactbeams.kernels.records import Segments
from impactbeams.kernels.reductions import work_of_force
from impactbeams.modes import beam
from impactbeams.packing import Packed
from impactbeams.trajectory.observables import loads, observables
from impactbeams.trajectory.phases import Trajectory, sample
from impactbeams.variables import attributes

SAMPLE_CHUNK = 1 << 15  # output times per sampling call: bounds memory at ~N * 0.5 MB


def time_series(packed: Packed, trajectory: Trajectory, times: np.ndarray, energy: bool = True,
                report: Callable[[float], None] | None = None) -> dict[str, np.ndarray]:
    """Observables and contact flag at ``times``; NaN past t_end.

    With ``energy``, also the work of F and the damping dissipation (``report`` as in
    `energy_integrals`).
    """
    inside = times <= trajectory.t_end
    p = packed.params
    points = [] if p.at_tips else ["contact_deflection_1", "contact_deflection_2"][:p.partner.beams]
    names = ["tip_deflection_1", "tip_deflection_2", "tip_velocity_1", "tip_velocity_2",
             *points, "gap", "contact_force", "kinetic_energy", "energy",
             "unresolved_kinetic_energy", "in_contact"] + (
        ["work_of_force", "damping_dissipation"] if energy else [])
    out = {name: np.full(times.size, np.nan) for name in names}
    reached = np.flatnonzero(inside)
    for start in range(0, reached.size, SAMPLE_CHUNK):
        index = reached[start:start + SAMPLE_CHUNK]
        phase, q, v = sample(packed, trajectory, times[index])
        for name, values in observables(packed, phase, times[index], q, v).items():
            if name in out:  # the contact points' series only where they are not the tips'
                out[name][index] = values
        out["in_contact"][index] = phase
    if not energy:
        return out
    work, dissipation = energy_integrals(packed, trajectory, times[reached], report)
    out["work_of_force"][reached], out["damping_dissipation"][reached] = work, dissipation
    return out


ENERGY_PIECES = 100  # pieces of a run's energy quadrature: a progress report after each


def energy_integrals(packed: Packed, trajectory: Trajectory, times: np.ndarray,
                     report: Callable[[float], None] | None = None) -> np.ndarray:
    """Work of the drives and damping dissipation (J) from t = 0 to each of ``times``.

    ``times`` ascending in [0, t_end]; returns rows (work, dissipation). The quadrature
    (`kernels.reductions.work_of_force`, at the fastest mode's time scale: with many modes
    it costs far more than the run) goes in about ENERGY_PIECES pieces of equal simulated
    time, cut at segment starts, and ``report(t)`` is called after each with the time
    integrated to (s). The pieces carry the sums over, in the order of one call: bit for bit.
    """
    recorded, t_end = trajectory.segments, trajectory.t_end
    count = recorded.time.size
    cuts = np.searchsorted(recorded.time, np.linspace(0.0, t_end, ENERGY_PIECES + 1)[1:-1])
    starts = np.unique(np.concatenate([[0], cuts[cuts < count]]))
    out, carried, done = np.empty((2, times.size)), np.zeros(3), 0
    for first, stop in zip(starts, [*starts[1:], count], strict=True):
        end = recorded.time[stop] if stop < count else t_end
        # a time at a segment's start belongs to that segment, as in one call
        upto = int(np.searchsorted(times, end)) if stop < count else times.size
        piece = np.empty((2, upto - done))
        work_of_force(packed.tables, packed.forces, packed.phase_scalars,
                      packed.switching, packed.settings,
                      Segments(*(array[first:stop] for array in recorded)), end,
                      times[done:upto], piece, carried)
        out[:, done:upto], done = piece, upto
        if report is not None:
            report(float(end))
    return out


def deflections(packed: Packed, states: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                t_end: float, times: np.ndarray, n_points: int,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Deflection fields y_1(x_1, t), y_2(x_2, t) (m) on uniform grids of ``n_points``.

    ``states(t)``: the run's phase and modal state q at the times t (s) up to its end
    ``t_end`` (a recorded `Trajectory`'s, `sample`; several contacts' in the free
    coordinates). Absolute: a moving clamp's motion is added (docs/model.md, "Base
    excitation").
    """
    p, free, model = packed.params, packed.dynamics.free, packed.dynamics.model
    n1, n2 = free.modes_per_beam  # n2 = 0 against a stop: y2 = 0 there
    c1, c2 = p.tip_compliance
    x1, x2 = np.linspace(0.0, p.l1, n_points), np.linspace(0.0, p.l2, n_points)
    free1 = np.vstack([free.beam1.shapes(x1), np.zeros((n2, n_points))])
    free2 = np.vstack([np.zeros((n1, n_points)), free.beam2.shapes(x2)])
    # the spring law's states come back in the free coordinates in both phases
    shapes1 = (free1, free1 if model is None else model.contact.beam1(x1))
    # against a stop free2 is all zeros, one row per coordinate of either phase
    shapes2 = (free2, free2 if model is None or n2 == 0 else model.contact.beam2(x2))
    static1, static2 = beam(p, 1).unit_tip_shape(x1), beam(p, 2).unit_tip_shape(x2)
    y1 = np.full((times.size, n_points), np.nan)
    y2 = np.full((times.size, n_points), np.nan)
    reached = np.flatnonzero(times <= t_end)
    for start in range(0, reached.size, SAMPLE_CHUNK):
        index = reached[start:start + SAMPLE_CHUNK]
        phase, q = states(times[index])
        q1, q2, _, _ = loads(packed, phase, times[index])
        for ph in (FREE, CONTACT):
            rows = index[phase == ph]
            qs = q[phase == ph]
            y1[rows] = -c1 * q1[phase == ph, None] * static1 + qs @ shapes1[ph]
            y2[rows] = -c2 * q2[phase == ph, None] * static2 + qs @ shapes2[ph]
    if p.base_amplitude != 0.0:
        clamp, _ = harmonic.py_func(p.base_amplitude, p.omega, times[reached])
        moves1, moves2 = p.mount.clamps
        y1[reached] += moves1 * clamp[:, None]
        y2[reached] += moves2 * clamp[:, None]
    return x1, x2, y1, y2


def with_deflections(dataset: xr.Dataset, packed: Packed,
                     states: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                     t_end: float, times: np.ndarray, n_points: int) -> xr.Dataset:
    """``dataset`` with the fields ``deflection_1(time, x1)``, ``deflection_2(time, x2)``.

    `deflections` at ``times`` (the Dataset's, s), ``states`` and ``t_end`` as there.
    """
    x1, x2, y1, y2 = deflections(packed, states, t_end, times, n_points)
    dataset = dataset.assign_coords(x1=("x1", x1, attributes("x1")),
                                    x2=("x2", x2, attributes("x2")))
    dataset["deflection_1"] = (("time", "x1"), y1, attributes("deflection_1"))
    dataset["deflection_2"] = (("time", "x2"), y2, attributes("deflection_2"))
    return dataset
