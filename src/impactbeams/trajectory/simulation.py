"""simulate(): the public entry for one trajectory, its output times and its Dataset."""

from __future__ import annotations

import dataclasses
import sys
import warnings
from collections.abc import Callable

import numpy as np
import xarray as xr

from impactbeams import costs
from impactbeams.blas import one_blas_thread
from impactbeams.compilation import compile_in_two_processes
from impactbeams.contact.spring import needed_modes, recommended_modes
from impactbeams.kernels.layout import CONTACT
from impactbeams.longtime import LongTime
from impactbeams.modes import beam
from impactbeams.packing import Packed, pack_run
from impactbeams.params import (
    MAX_EVENTS,
    MAX_MODES,
    Params,
    is_integer,
    modes_per_beam,
    require,
    require_finite,
    require_integer,
    require_one_contact,
    require_type,
)
from impactbeams.preflight import (
    Cost,
    check_run,
    format_time,
    highest_frequency,
    require_memory,
)
from impactbeams.progress import Progress
from impactbeams.trajectory.episodes import default_separation, episode_table
from impactbeams.trajectory.fields import SAMPLE_CHUNK, time_series, with_deflections
from impactbeams.trajectory.impacts import impact_table
from impactbeams.trajectory.lyapunov import check_request, lyapunov_exponents, with_exponents
from impactbeams.trajectory.phases import Trajectory, run, sample
from impactbeams.trajectory.poincare import long_time_variables
from impactbeams.trajectory.start import (
    InitialFields,
    final_state,
    initial_phase_state,
    with_final_state,
)
from impactbeams.variables import attributes, global_attributes, validate

# The event search restarts at least every search_span seconds; a span below this fraction of
# t_max would restart it more than a million times per search (and below eps t_max it cannot
# advance the time at all).
MIN_SEARCH_SPAN = 1e-6
SERIES = 10  # time series always stored (time, tips, gap, force, energies, in_contact)
ENERGY_SERIES = 2  # work_of_force, damping_dissipation
# float64 arrays of (output times in a sampling chunk) x (coordinates) alive while a chunk is
# sampled and its observables evaluated: measured peaks 12 to 15 (tests/test_bad_inputs.py)
SAMPLING_ARRAYS = 20


def _output_times(t_max: float, dt_output: float, times: np.ndarray | None) -> np.ndarray:
    if times is not None:
        return times
    return np.minimum(np.arange(int(_output_count(t_max, dt_output))) * dt_output, t_max)


def _output_count(t_max: float, dt_output: float) -> float:
    """Points of the output grid 0, dt, 2 dt, ... <= t_max (a float: it may be huge, or inf)."""
    return float(np.floor(t_max / dt_output * (1 + 1e-12))) + 1


def _checked_times(times: np.ndarray | None, t_max: float) -> np.ndarray | None:
    if times is None:
        return None
    try:
        array = np.asarray(times, dtype=float)
    except (TypeError, ValueError):  # not numbers
        array = None
    require_type("times", times, array is not None, "an array of output times (s)")
    times = array
    require("times", times, times.ndim == 1 and bool(np.all(np.isfinite(times)))
            and not np.any(np.diff(times) < 0) and not np.any((times < 0) | (times > t_max)),
            "must be a 1-D ascending array within [0, t_max]", "s")
    return times


def simulation_cost(params: Params, t_max: float, n_modes: int, n_times: float, fields: bool,
                    n_points: int, energy_balance: bool, max_events: int) -> Cost:
    """Peak memory and rough time of a simulated run (arguments as in [`simulate`][]).

    Memory: the output series (and fields) twice (arrays and Dataset), the workspace of the
    sampling (SAMPLING_ARRAYS float64 arrays of a chunk's times by the coordinates) and the
    recorded segments at the ``max_events`` cap (time, phase and four states of 2 n_modes).
    Time: `impactbeams.costs` (the run and its impact table per cycle, the sampling, and the
    energy balance's quadratures).
    """
    coordinates = 2 * n_modes
    series = 1 + SERIES + ENERGY_SERIES * energy_balance + 2 * n_points * fields
    sampling = SAMPLING_ARRAYS * 8 * min(n_times, SAMPLE_CHUNK) * coordinates
    segments = max_events * (4 * coordinates + 3) * 8
    seconds = float(costs.dynamics_seconds(costs.run_values(params, n_modes), params.law,
                                           n_modes, t_max, "simulate", params.partner)
                    ) + costs.SAMPLING * n_times * n_modes
    if energy_balance:
        fastest = float(highest_frequency(params.numeric(), n_modes, params.grounded_springs,
                                          params.structure1, params.step_factors))
        seconds += costs.energy_seconds(fastest, n_modes, t_max, n_times)
    return Cost(2 * 8 * series * n_times + sampling + segments, seconds)


@one_blas_thread
def simulate(params: Params, t_max: float, n_modes: int | None = None, dt_output: float = 1e-4,
             fields: bool = False, *, times: np.ndarray | None = None, n_points: int = 41,
             max_events: int = MAX_EVENTS, search_span: float | None = None,
             episode_separation: float | None = None,
             energy_balance: bool = False, lyapunov: bool | int = False,
             transient_periods: int = 0, long_time: LongTime | None = None,
             progress: bool = False,
             initial_state: np.ndarray | xr.Dataset | InitialFields | None = None,
             ) -> xr.Dataset:
    """Simulate the impacting beams from t = 0 to ``t_max`` (s); return an xarray Dataset.

    Args:
        params: model parameters (SI units).
        t_max: end time (s), > 0; the fastest mode (or the forcing) may turn through at
            most ``preflight.MAX_PHASE`` = 1e10 rad by then.
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
            many seconds (default t_max; at least 1e-6 t_max, ``MIN_SEARCH_SPAN``). Results do
            not depend on it beyond round-off; it is here to test that.
        episode_separation: contacts closer than this (s, free interval from release to the
            next onset) form one impact episode; default a quarter period of the slowest free
            mode (see `impactbeams.trajectory.episodes`).
        energy_balance: also compute the work of F and the dissipation (``work_of_force``,
            ``damping_dissipation``) and the episodes' dissipated energy and energetic
            restitution: quadratures at the fastest mode's time scale, which with many modes
            cost far more than the dynamics (the energy itself is always there).
        lyapunov: also the largest Lyapunov exponent of this run (True), or that many leading
            exponents (an integer up to 4 n_modes, the state's dimension): variables
            ``lyapunov_exponent`` and ``lyapunov_exponent_error`` (1/s), and with more than one
            ``lyapunov_spectrum`` and its error along ``exponent``. Tangent propagation with
            Benettin renormalisation every forcing period; spring law only (docs/model.md);
            with several contacts through every active set's phase (docs/lyapunov.md).
        transient_periods: forcing periods at the start left out of the exponents' average,
            and before the first stroboscopic sample of ``long_time``.
        long_time: also the long-time response ([`impactbeams.longtime.LongTime`][]):
            stroboscopic tip samples ``poincare_deflection1`` ... ``poincare_velocity2``
            along the dimension ``period``, ``response_period``, ``steady_impact_rate`` and
            ``steady_episode_rate`` (with this run's ``episode_separation``). Needs
            Omega > 0 and t_max at least (transient_periods + sampled_periods) 2 pi / Omega.
        progress: print the expected time, then progress bars with an ETA over the simulated
            time and over the impacts' peak forces, on stderr (the results are the same).
        initial_state: start from this state at t = 0 instead of ``params.start`` (which must
            then be "rest", without uplifts): t = 0 is the stroboscopic section, where the
            forcing and the clamps' motion are at phase 0. Either the modal state
            z = (q, q') in the run's free coordinates (2 N values: beam 1's n_modes, then beam
            2's; q without the quasi-static part, as ``final_displacement``), or an earlier
            run's Dataset (its ``final_displacement``, ``final_velocity``; it must end at a
            whole number of forcing periods), or deflection and velocity fields
            ([`impactbeams.trajectory.start.InitialFields`][], projected on the modes with
            the mass matrix). Spring law: the run starts in contact if the tips overlap and
            the contact force -k_e g - c_e g' is positive; the tied law starts from an open gap
            only. Restarting from a run's final state continues it to round-off.

    The output grid never influences the dynamics: events are located by the kernel on its
    own, and the outputs are evaluated from the exact segment states.

    Every argument is checked before any work: a bad one, or a run that would not fit in
    memory (`simulation_cost`), raises [`ParameterError`][] naming
    it, its value and what is allowed (docs/limits.md, "Allowed values").
    """
    _check_options(fields, energy_balance, lyapunov, transient_periods, long_time, progress)
    if isinstance(params, Params) and params.several_contacts:
        if long_time is not None:
            _check_long_time(params, t_max, transient_periods, long_time)
        return _simulate_several(params, t_max, n_modes, dt_output, times, max_events,
                                 search_span, episode_separation, energy_balance, progress,
                                 initial_state, lyapunov, long_time, transient_periods,
                                 fields, n_points)
    run_inputs = _checked_inputs(params, t_max, n_modes, dt_output, times, n_points, max_events,
                                 search_span, episode_separation, fields, energy_balance)
    t_max, n_modes, resolution = run_inputs.t_max, run_inputs.n_modes, run_inputs.resolution
    if long_time is not None:
        _check_long_time(params, t_max, transient_periods, long_time)
    if n_modes < resolution and params.law.compliant:
        warnings.warn(f"n_modes = {n_modes} does not resolve the spring contact of stiffness "
                      f"{params.contact_stiffness:g} N/m: use n_modes >= {resolution} "
                      "(docs/model.md, Resolution)", RuntimeWarning, stacklevel=2)
    if params.moving_stop():
        warnings.warn(params.moving_stop(), UserWarning, stacklevel=2)
    if lyapunov:
        check_request(params, n_modes, t_max, lyapunov, transient_periods)
    out_times = run_inputs.times
    packed = pack_run(params, n_modes, t_max, run_inputs.search_span)  # refuses overdamping
    start = None if initial_state is None else initial_phase_state(packed, initial_state)
    compile_in_two_processes("simulate")  # a cold compile: part of it in a helper process
    if progress:
        _announce(params, run_inputs)
    bar = Progress(t_max, enabled=progress, unit="s simulated")
    trajectory = run(packed, run_inputs.max_events,
                     _EventPace(bar, t_max, run_inputs.max_events).report, start)
    if trajectory.status == "complete":
        bar.reach(t_max)
    else:
        bar.stop(trajectory.t_end, f"{trajectory.status} at t = {trajectory.t_end:.6g} s")
    if trajectory.status != "complete":
        warnings.warn(f"simulation stopped at t = {trajectory.t_end!r} s before t_max = "
                      f"{t_max!r} s: status {trajectory.status!r}", RuntimeWarning, stacklevel=2)
        if progress and energy_balance:  # the estimate announced was for the whole t_max
            _announce_energy(params, n_modes, trajectory.t_end,
                             int(np.count_nonzero(out_times <= trajectory.t_end)))
    separation = run_inputs.episode_separation
    dataset = _dataset(packed, trajectory, out_times,
                       default_separation(packed) if separation is None else separation,
                       energy_balance, progress)
    if fields:
        dataset = with_deflections(dataset, packed,
                                   lambda t: sample(packed, trajectory, t)[:2],
                                   trajectory.t_end, out_times, run_inputs.n_points)
    if lyapunov:
        exponents = lyapunov_exponents(packed, trajectory, int(lyapunov), transient_periods)
        dataset = with_exponents(dataset, exponents, transient_periods)
    if long_time is not None:
        dataset = long_time_variables(packed, trajectory, dataset, long_time, transient_periods)
    dataset = with_final_state(dataset, final_state(packed, trajectory))
    dataset.attrs.update(_global_attributes(params, n_modes, t_max, trajectory))
    if params.law.compliant:
        dataset.attrs.update(_contact_attributes(packed, n_modes >= resolution, resolution))
    validate(dataset)  # as registered, or a bug of the package
    return dataset


def _simulate_several(params: Params, t_max: float, n_modes: int | None, dt_output: float,
                      times: np.ndarray | None, max_events: int, search_span: float | None,
                      episode_separation: float | None, energy_balance: bool, progress: bool,
                      initial_state: object, lyapunov: bool | int,
                      long_time: LongTime | None, transient_periods: int, fields: bool,
                      n_points: int) -> xr.Dataset:
    """[`simulate`][] of several contacts (`impactbeams.trajectory.several_run`).

    The options are checked as for one contact, on each contact's run, at the most modes any
    of them recommends.
    """
    from impactbeams.trajectory.several import check_contact_runs
    from impactbeams.trajectory.several_run import simulate_contacts

    n_modes = check_contact_runs(params, t_max, n_modes)
    runs = params.each_contact()
    checked = [_checked_inputs(run, t_max, n_modes, dt_output, times, n_points, max_events,
                               search_span, episode_separation, fields, energy_balance)
               for run in runs]
    inputs = checked[0]
    if lyapunov:
        check_request(runs[0], inputs.n_modes, inputs.t_max, lyapunov, transient_periods)
    return simulate_contacts(params, inputs.t_max, inputs.n_modes, inputs.times,
                             inputs.search_span, inputs.max_events,
                             energy_balance=energy_balance, initial_state=initial_state,
                             progress=progress, episode_separation=inputs.episode_separation,
                             expected=sum(each.seconds for each in checked),
                             long_time=long_time, transient_periods=transient_periods,
                             fields=inputs.n_points if fields else 0, lyapunov=int(lyapunov))


class _EventPace:
    """Progress of a run, and a warning once its pace says it will reach ``max_events``.

    The pace is the phases per simulated second so far (reported after each window of
    `phases.run`), the run's own measure: no estimate before the run knows how often a rattle
    makes contact.
    """

    def __init__(self, bar: Progress, t_max: float, max_events: int) -> None:
        self.bar, self.t_max, self.max_events, self.warned = bar, t_max, max_events, False

    def report(self, t: float, phases: int) -> None:
        self.bar.reach(t)
        if self.warned or t <= 0.0 or phases * self.t_max / t <= self.max_events:
            return
        self.warned = True
        warnings.warn(f"at its pace so far ({phases} phases in {t:.4g} s) the run reaches "
                      f"max_events = {self.max_events} phases at about t = "
                      f"{self.max_events * t / phases:.3g} s of t_max = {self.t_max:g} s, and "
                      "stops there: raise max_events (--max-events) to go on",
                      RuntimeWarning, stacklevel=4)


@dataclasses.dataclass(frozen=True)
class _RunInputs:
    """simulate()'s arguments once checked: floats and ints, defaults filled in."""

    t_max: float
    n_modes: int
    resolution: int  # n_modes that resolves a spring contact (5 for the tied law)
    times: np.ndarray
    search_span: float
    episode_separation: float | None
    max_events: int
    n_points: int
    seconds: float  # expected compute time (simulation_cost)


def _checked_inputs(params: Params, t_max: float, n_modes: int | None, dt_output: float,
                    times: np.ndarray | None, n_points: int, max_events: int,
                    search_span: float | None, episode_separation: float | None, fields: bool,
                    energy_balance: bool) -> _RunInputs:
    """Check every argument of [`simulate`][] (same names) before any work; ParameterError.

    The run's modes and horizon (`check_run`) and its memory
    (`simulation_cost`) are checked too, before the output grid is allocated.
    """
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    require_one_contact(params, "simulate")
    t_max = require_finite("t_max", t_max, "s")
    require("t_max", t_max, t_max > 0, "must be > 0", "s")
    times = _checked_times(times, t_max)
    if times is None:
        dt_output = require_finite("dt_output", dt_output, "s")
        require("dt_output", dt_output, 0 < dt_output <= t_max,
                f"must be > 0 and <= t_max = {t_max!r} (a longer step stores only t = 0)", "s")
    max_events = require_integer("max_events", max_events, 1)
    n_points = require_integer("n_points", n_points, 2)
    span = t_max if search_span is None else require_finite("search_span", search_span, "s")
    require("search_span", search_span, span >= MIN_SEARCH_SPAN * t_max,
            f"must be >= {MIN_SEARCH_SPAN:g} t_max = {MIN_SEARCH_SPAN * t_max:.3g} (a shorter "
            "span only restarts the event search more often, more than a million times per "
            "search)", "s")
    if episode_separation is not None:
        episode_separation = require_finite("episode_separation", episode_separation, "s")
        require("episode_separation", episode_separation, episode_separation >= 0,
                "must be >= 0", "s")
    beam1 = beam(params, 1)
    require("fields", fields, not fields or beam1.continuous,
            "beam 1 is a user structure (structure1): it has no fields along a beam")
    resolution = needed_modes(params)
    if n_modes is None:
        n_modes = recommended_modes(params)
    n_modes = require_integer("n_modes", n_modes, 1, MAX_MODES)
    check_run(params.numeric(), t_max, n_modes, springs=params.grounded_springs,
              structure1=params.structure1, steps=params.step_factors)
    n_times = times.size if times is not None else _output_count(t_max, dt_output)
    cost = simulation_cost(params, t_max, n_modes, n_times, fields, n_points, energy_balance,
                           max_events)
    grid = "times" if times is not None else f"dt_output = {dt_output!r} s"
    require_memory(f"{grid} ({n_times:.3g} output times over t_max = {t_max!r} s; n_modes = "
                   f"{n_modes}, max_events = {max_events})", cost.memory,
                   "use a larger dt_output or a shorter t_max (or fewer fields, modes or "
                   "max_events)")
    return _RunInputs(t_max, n_modes, resolution, _output_times(t_max, dt_output, times), span,
                      episode_separation, max_events, n_points, cost.seconds)


def _announce(params: Params, run_inputs: _RunInputs) -> None:
    """The run's expected time on stderr, with the kernels' compile if they are not cached."""
    from impactbeams.compilation import kernels_cached

    compile_note = ("" if kernels_cached("simulate") else
                    ", after compiling its kernels (once per install), expected "
                    f"{costs.compile_estimate('simulate').describe()}")
    print(f"simulate: {params.contact_law} contact, "
          f"{modes_per_beam(run_inputs.n_modes, params.partner)}, "
          f"t_max = {run_inputs.t_max:g} s; expected: roughly "
          f"{format_time(run_inputs.seconds)}{compile_note}", file=sys.stderr)


def _announce_energy(params: Params, n_modes: int, t_end: float, n_times: int) -> None:
    """The expected time of the energy balance over a run that stopped at ``t_end`` (s)."""
    fastest = highest_frequency(params.numeric(), n_modes, params.grounded_springs,
                                params.structure1, params.step_factors)
    seconds = costs.energy_seconds(float(fastest), n_modes, t_end, n_times)
    print(f"simulate: the energy balance over the {t_end:.4g} s simulated: roughly "
          f"{format_time(seconds)}", file=sys.stderr)


def _check_options(fields: bool, energy_balance: bool, lyapunov: bool | int,
                   transient_periods: int, long_time: LongTime | None,
                   progress: bool) -> None:
    """Check the types of [`simulate`][]'s options (same names).

    A transient must be left out of something: the exponents or the long-time samples.
    """
    for name, value in (("fields", fields), ("energy_balance", energy_balance),
                        ("progress", progress)):
        require_type(name, value, isinstance(value, (bool, np.bool_)), "True or False")
    require_type("lyapunov", lyapunov, isinstance(lyapunov, (bool, np.bool_))
                 or is_integer(lyapunov), "True, False or a number of exponents")
    require_type("long_time", long_time, long_time is None or isinstance(long_time, LongTime),
                 "None or an impactbeams.LongTime")
    transient = require_integer("transient_periods", transient_periods, 0)
    require("transient_periods", transient_periods, not transient or lyapunov
            or long_time is not None, "only the Lyapunov exponents (lyapunov) and the "
            "long-time samples (long_time) leave a transient out; this run has neither")


def _check_long_time(params: Params, t_max: float, transient_periods: int,
                     long_time: LongTime) -> None:
    """Stroboscopic samples need a forcing period and a run that covers the sampled window."""
    require("omega", params.omega, params.omega > 0, "long_time samples once per forcing "
            "period: need omega > 0", "rad/s")
    horizon = float(long_time.horizon(params.omega, transient_periods))
    require("t_max", t_max, t_max >= horizon, "long_time needs t_max >= (transient_periods + "
            f"sampled_periods) 2 pi / omega = {horizon!r}", "s")


def _dataset(packed: Packed, trajectory: Trajectory, times: np.ndarray, separation: float,
             energy: bool, progress: bool = False) -> xr.Dataset:
    series = time_series(packed, trajectory, times, energy,
                         _integration_bar(trajectory, energy and progress, "work and dissipation"))
    series["tip_deflection_2"] = series["tip_deflection_2"] - packed.params.clearance
    contacts = int(np.count_nonzero(trajectory.phase == CONTACT))
    bar = Progress(contacts, enabled=progress and contacts > 0, unit="contacts' peak forces")
    impacts = impact_table(packed, trajectory, bar.update)
    data = {name: ("time", values, attributes(name)) for name, values in series.items()}
    data.update({name: ("impact", values, attributes(name)) for name, values in impacts.items()})
    episodes = episode_table(packed, trajectory, impacts, separation, energy,
                             _integration_bar(trajectory, energy and progress,
                                              "episodes' energies"))
    data.update({name: ("episode", values, attributes(name))
                 for name, values in episodes.items()})
    coords = {"time": ("time", times, attributes("time")),
              "impact": ("impact", np.arange(impacts["impact_onset_time"].size),
                         attributes("impact")),
              "episode": ("episode", np.arange(episodes["episode_onset_time"].size),
                          attributes("episode"))}
    dataset = xr.Dataset(data, coords=coords)
    dataset.attrs["episode_separation"] = separation
    # energies of the motion relative to the clamps (docs/model.md, "Base excitation")
    dataset.attrs["energy_frame"] = "relative"
    return dataset


def _integration_bar(trajectory: Trajectory, enabled: bool, what: str,
                     ) -> Callable[[float], None]:
    """A progress bar over the simulated time an energy quadrature has integrated."""
    return Progress(trajectory.t_end, enabled=enabled, unit=f"s integrated ({what})").reach


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
