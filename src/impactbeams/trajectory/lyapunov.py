"""Lyapunov exponents of one simulated run: the tangent kernel on its recorded segments.

The exponents are those of the very trajectory the Dataset holds (docs/model.md, "Lyapunov
exponents"): tangent vectors carried through every recorded phase
(`impactbeams.kernels.tangent`), renormalised every forcing period, their log growth
averaged over the complete periods after a transient.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from impactbeams.active_phases import ContactRun, PackedContacts
from impactbeams.kernels.contacts_tangent import contacts_lyapunov_sums
from impactbeams.kernels.tangent import interval_count, recorded_run_sums, renormalization_interval
from impactbeams.modes import beam
from impactbeams.packing import Packed
from impactbeams.params import ParameterError, Params, require, require_integer
from impactbeams.trajectory.phases import Trajectory
from impactbeams.variables import attributes

BATCHES = 16  # consecutive groups of periods whose means give the standard error


@dataclasses.dataclass(frozen=True)
class Exponents:
    """Leading Lyapunov exponents (1/s, descending) and their standard errors (1/s).

    The error is that of the mean of ``BATCHES`` batch means (consecutive groups of forcing
    periods), NaN with fewer than two; ``interval`` (s) the renormalisation interval,
    ``periods`` the number of intervals averaged.
    """

    values: np.ndarray
    errors: np.ndarray
    interval: float
    periods: int


def check_request(params: Params, n_modes: int, t_max: float, count: int,
                  transient_periods: int) -> None:
    """Raise ParameterError unless ``count`` exponents after ``transient_periods`` are defined.

    Checked before any model is built: the renormalisation interval needs only the forcing
    frequency, or without forcing the slowest free mode (both beams' fundamentals).
    """
    if not params.law.tangent_flow:
        raise ParameterError("Lyapunov exponents need the spring contact law: the tied law's "
                             "projections, instantaneous impacts and accumulations are not a "
                             "flow whose linearisation converges in n_modes (docs/model.md)")
    beams = params.partner.beams
    dimension = 2 * beams * n_modes
    require("lyapunov", count, isinstance(count, (int, np.integer)) and 0 < count <= dimension,
            f"must be True or a number of exponents from 1 to {dimension} "
            f"({2 * beams} n_modes)")
    fundamentals = np.array([beam(params, which).free_modes(1).frequencies[0]
                             for which in (1, 2)][:beams])
    # the kernels' own functions, run as Python: nothing compiles for a check
    interval = renormalization_interval.py_func(params.omega, fundamentals)
    periods = interval_count.py_func(t_max, interval)
    transient = require_integer("transient_periods", transient_periods, 0)
    what = ("forcing periods 2 pi / omega" if params.omega > 0 else
            "periods of the slowest free mode (omega = 0)")
    fewer = f", or transient_periods <= {periods - 1}" if periods else ""
    require("t_max", t_max, transient < periods,
            f"the exponents average over the complete {what} of {interval:.6g} s after "
            f"transient_periods = {transient}, and t_max holds {periods} of them: need t_max >= "
            f"(transient_periods + 1) x {interval:.6g} s = {(transient + 1) * interval:.6g} s"
            f"{fewer}")


def lyapunov_exponents(packed: Packed, trajectory: Trajectory, count: int,
                       transient_periods: int) -> Exponents:
    """The ``count`` leading exponents of the recorded spring-law run (1/s)."""
    return _exponents(*recorded_run_sums(
        packed.tables, packed.phase_scalars, packed.switching, packed.settings,
        trajectory.segments, trajectory.t_end, count, transient_periods, BATCHES))


def contacts_exponents(packed: PackedContacts, run: ContactRun, count: int,
                       transient_periods: int) -> Exponents:
    """The ``count`` leading exponents (1/s) of a recorded run of several contacts.

    Its tangents through every active set's phase and the saltation at every switch
    (`impactbeams.kernels.contacts_tangent`), renormalised as one contact's.
    """
    return _exponents(*contacts_lyapunov_sums(*packed.tangent_arguments(), run.arrays(),
                                              run.t_end, count, transient_periods, BATCHES))


def _exponents(sums: np.ndarray, counts: np.ndarray, interval: float) -> Exponents:
    """The exponents (1/s) and their batch-means errors of Benettin's sums."""
    count = sums.shape[1]
    periods = int(counts.sum())
    if periods == 0:
        return Exponents(np.full(count, np.nan), np.full(count, np.nan), interval, 0)
    filled = counts > 0
    means = sums[filled] / (counts[filled, None] * interval)
    errors = (means.std(axis=0, ddof=1) / math.sqrt(means.shape[0]) if means.shape[0] > 1
              else np.full(count, np.nan))
    return Exponents(sums.sum(axis=0) / (periods * interval), errors, interval, periods)


def with_exponents(dataset: xr.Dataset, exponents: Exponents, transient: int) -> xr.Dataset:
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
