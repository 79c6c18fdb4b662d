"""simulate(): the public entry for one trajectory, its output times and its Dataset."""

from __future__ import annotations

import math
import warnings

import numpy as np
import xarray as xr

from impactbeams.compliant import MAX_MODES, required_modes
from impactbeams.packing import Packed, pack_run
from impactbeams.params import Params
from impactbeams.trajectory.episodes import default_separation, episode_table
from impactbeams.trajectory.fields import deflections, time_series
from impactbeams.trajectory.impacts import impact_table
from impactbeams.trajectory.lyapunov import Exponents, check_request, lyapunov_exponents
from impactbeams.trajectory.phases import Trajectory, run
from impactbeams.variables import attributes, global_attributes


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


def simulate(params: Params, t_max: float, n_modes: int | None = None, dt_output: float = 1e-4,
             fields: bool = False, *, times: np.ndarray | None = None, n_points: int = 41,
             max_events: int = 200_000, search_span: float | None = None,
             episode_separation: float | None = None,
             energy_balance: bool = False, lyapunov: bool | int = False,
             transient_periods: int = 0) -> xr.Dataset:
    """Simulate the impacting beams from t = 0 to ``t_max`` (s); return an xarray Dataset.

    Args:
        params: model parameters (SI units).
        t_max: end time (s), > 0.
        n_modes: free modes per beam. Default: 5 for the tied law (the contact phase has
            2 n_modes modes); for the spring law the number that resolves the contact,
            4 n* (docs/model.md, "Resolution"), at least 5. A spring-law run with fewer gets
            a warning and ``attrs["contact_resolved"] = 0``.
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
        episode_separation: contacts closer than this (s, free interval from release to the
            next onset) form one impact episode; default a quarter period of the slowest free
            mode (see :mod:`impactbeams.trajectory.episodes`).
        energy_balance: also compute the work of F and the dissipation (``work_of_force``,
            ``damping_dissipation``) and the episodes' dissipated energy and energetic
            restitution: quadratures at the fastest mode's time scale, which with many modes
            cost far more than the dynamics (the energy itself is always there).
        lyapunov: also the largest Lyapunov exponent of this run (True), or that many leading
            exponents (an integer up to 4 n_modes, the state's dimension): variables
            ``lyapunov_exponent`` and ``lyapunov_exponent_error`` (1/s), and with more than one
            ``lyapunov_spectrum`` and its error along ``exponent``. Tangent propagation with
            Benettin renormalisation every forcing period; spring law only (docs/model.md).
        transient_periods: forcing periods at the start left out of the exponents' average.

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
    resolution = required_modes(params) if params.contact_law == "spring" else 5
    if n_modes is None:
        n_modes = min(resolution, MAX_MODES)
    if n_modes < resolution and params.contact_law == "spring":
        warnings.warn(f"n_modes = {n_modes} does not resolve the spring contact of stiffness "
                      f"{params.contact_stiffness:g} N/m: use n_modes >= {resolution} "
                      "(docs/model.md, Resolution)", RuntimeWarning, stacklevel=2)
    packed = pack_run(params, n_modes, float(t_max), span)
    if lyapunov:
        check_request(packed, lyapunov, transient_periods)
    trajectory = run(packed, max_events)
    if trajectory.status != "complete":
        warnings.warn(f"simulation stopped at t = {trajectory.t_end!r} s before t_max = "
                      f"{t_max!r} s: status {trajectory.status!r}", RuntimeWarning, stacklevel=2)
    if episode_separation is None:
        episode_separation = default_separation(packed)
    dataset = _dataset(packed, trajectory, out_times, float(episode_separation),
                       energy_balance)
    if fields:
        x1, x2, y1, y2 = deflections(packed, trajectory, out_times, n_points)
        dataset = dataset.assign_coords(x1=("x1", x1, attributes("x1")),
                                        x2=("x2", x2, attributes("x2")))
        dataset["deflection_1"] = (("time", "x1"), y1, attributes("deflection_1"))
        dataset["deflection_2"] = (("time", "x2"), y2, attributes("deflection_2"))
    if lyapunov:
        exponents = lyapunov_exponents(packed, trajectory, int(lyapunov), transient_periods)
        dataset = _with_exponents(dataset, exponents, transient_periods)
    dataset.attrs.update(_global_attributes(params, n_modes, float(t_max), trajectory))
    if params.contact_law == "spring":
        dataset.attrs.update(_contact_attributes(packed, n_modes >= resolution, resolution))
    return dataset


def _dataset(packed: Packed, trajectory: Trajectory, times: np.ndarray, separation: float,
             energy: bool) -> xr.Dataset:
    series = time_series(packed, trajectory, times, energy)
    series["tip_deflection_2"] = series["tip_deflection_2"] - packed.params.clearance
    impacts = impact_table(packed, trajectory)
    data = {name: ("time", values, attributes(name)) for name, values in series.items()}
    data.update({name: ("impact", values, attributes(name)) for name, values in impacts.items()})
    episodes = episode_table(packed, trajectory, impacts, separation, energy)
    data.update({name: ("episode", values, attributes(name))
                 for name, values in episodes.items()})
    coords = {"time": ("time", times, attributes("time")),
              "impact": ("impact", np.arange(impacts["impact_onset_time"].size),
                         attributes("impact")),
              "episode": ("episode", np.arange(episodes["episode_onset_time"].size),
                          attributes("episode"))}
    dataset = xr.Dataset(data, coords=coords)
    dataset.attrs["episode_separation"] = separation
    return dataset


def _with_exponents(dataset: xr.Dataset, exponents: Exponents, transient: int) -> xr.Dataset:
    """The run's Lyapunov exponents as variables, with how they were averaged."""
    averaging = {"renormalization_interval": exponents.interval,
                 "transient_periods": transient, "averaged_periods": exponents.periods}
    dataset["lyapunov_exponent"] = ((), exponents.values[0],
                                    {**attributes("lyapunov_exponent"), **averaging})
    dataset["lyapunov_exponent_error"] = ((), exponents.errors[0],
                                          attributes("lyapunov_exponent_error"))
    if exponents.values.size > 1:
        dataset = dataset.assign_coords(exponent=("exponent", np.arange(exponents.values.size),
                                                  attributes("exponent")))
        dataset["lyapunov_spectrum"] = ("exponent", exponents.values,
                                        {**attributes("lyapunov_spectrum"), **averaging})
        dataset["lyapunov_spectrum_error"] = ("exponent", exponents.errors,
                                              attributes("lyapunov_spectrum_error"))
    return dataset


def _global_attributes(params: Params, n_modes: int, t_max: float, trajectory: Trajectory,
                       ) -> dict[str, object]:
    run = {"t_max": t_max, "t_max_units": "s", "n_modes": n_modes,
           "status": trajectory.status, "t_end": trajectory.t_end,
           "n_phases": trajectory.time.size}
    return global_attributes(
        "impact dynamics of two cantilevers with clearance (impactbeams.simulate)", "simulate",
        params.as_dict(), **run)


def _contact_attributes(packed: Packed, resolved: bool, resolution: int) -> dict[str, object]:
    """The spring law's effective contact (static correction) and its resolution."""
    spring = packed.dynamics.spring
    return {"contact_stiffness_effective": spring.effective_stiffness,
            "contact_damping_effective": spring.effective_damping,
            "residual_flexibility": spring.residual,
            "contact_resolved": int(resolved), "contact_resolution_modes": resolution}
