"""simulate()'s long-time variables: stroboscopic samples, response period, steady rates.

Taken from the run's own recorded segments and its contact and episode tables (NumPy), apart
from the sweep's stroboscope kernel, which computes the same in bounded memory.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from impactbeams.longtime import LongTime, response_period, steady_rate
from impactbeams.packing import Packed
from impactbeams.trajectory.fields import time_series
from impactbeams.trajectory.phases import Trajectory
from impactbeams.variables import VARIABLES, attributes


def long_time_variables(packed: Packed, trajectory: Trajectory, dataset: xr.Dataset,
                        long_time: LongTime, transient_periods: int) -> xr.Dataset:
    """``dataset`` (simulate's, with its impact and episode tables) plus the long-time ones.

    Sampled after ``transient_periods`` forcing periods.
    """
    omega, clearance = packed.params.omega, packed.params.clearance
    times = long_time.sample_times(omega, transient_periods)
    series = time_series(packed, trajectory, times, energy=False)  # tip 2 is y2 itself here
    tips = [series[name] for name in ("tip_deflection_1", "tip_deflection_2", "tip_velocity_1",
                                      "tip_velocity_2")]
    start, end = times[0], long_time.horizon(omega, transient_periods)

    def rate(onsets: xr.DataArray) -> float:
        count = np.count_nonzero((onsets.values >= start) & (onsets.values < end))
        return float(steady_rate(count, start, end, trajectory.t_end))

    values = {"poincare_deflection1": tips[0], "poincare_deflection2": tips[1] - clearance,
              "poincare_velocity1": tips[2], "poincare_velocity2": tips[3],
              "response_period": response_period(*tips, omega, long_time.period_tolerance,
                                                 long_time.max_period),
              "steady_impact_rate": rate(dataset.impact_onset_time),
              "steady_episode_rate": rate(dataset.episode_onset_time)}
    return with_long_time(dataset, values, long_time, transient_periods)


def with_long_time(dataset: xr.Dataset, values: dict[str, object], long_time: LongTime,
                   transient_periods: int) -> xr.Dataset:
    """``dataset`` with the long-time ``values``, the ``period`` coordinate and attributes.

    The samples along ``period``, the rest scalars, each as registered (its dtype).
    """
    data = {name: (("period",) if np.ndim(value) else (), np.asarray(
        value, dtype=VARIABLES[name].dtype), attributes(name)) for name, value in values.items()}
    period = {"period": ("period", long_time.period_numbers(transient_periods),
                         attributes("period"))}
    result = dataset.assign_coords(period).assign(data)
    result.attrs.update({key: getattr(long_time, key) for key in
                         ("sampled_periods", "period_tolerance", "max_period")},
                        transient_periods=transient_periods)
    return result
