"""Long-time response: stroboscopic sampling, the period of the steady response, steady rates.

Definitions (docs/model.md, "Long-time dynamics"): after ``transient_periods`` forcing periods
T = 2 pi / Omega (the run's transient, shared with the Lyapunov exponent's: the sweep key and
simulate's keyword), the tips are sampled once per period at forcing phase 0,
``t_k = (transient_periods + k) T``, k = 0 .. ``sampled_periods`` - 1; the sampled window is
``[t_0, t_0 + sampled_periods T)``. The period of the steady response is the smallest p <=
``max_period`` for which the samples repeat with period p within ``period_tolerance`` of
their scale; 0 if there is none.

The tolerance is relative to the samples' scale, the largest of |y1|, |y2|, |v1| / Omega,
|v2| / Omega over the window (m: velocities over Omega are displacement amplitudes; for a
harmonic response sqrt(y^2 + (v / Omega)^2) is its amplitude at any phase). The default,
1e-4, lies eight orders above the samples' round-off (exact propagation, event times to a few
ulps: 1e-11 of the scale and below on stable periodic orbits, tests/test_longtime.py), so a
periodic response is recognised once its transient has decayed by 1e4, ln(1e4) = 9.2 time
constants of the slowest one. With modal damping zeta the slowest free mode decays at
zeta omega_min (omega_min = 170.9 rad/s for the default beams): at zeta = 0.02 that takes
2.7 s, 500 forcing periods up to Omega = 1170 rad/s. A run whose transient has not decayed
that far reports 0 (or a spurious long period, when the leftover transient is nearly periodic
in the samples): lengthen the transient or loosen the tolerance. Chaotic responses change from
period to period by a sizeable fraction of their scale (10 % to 100 % on the shipped sweeps).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from impactbeams.kernels import layout
from impactbeams.params import (
    CONTACTS,
    contact_field,
    is_integer,
    is_real,
    part_field,
    require,
)

if TYPE_CHECKING:
    import xarray as xr

DEFAULT_PERIOD_TOLERANCE = 1e-4
LARGEST_MAX_PERIOD = 16  # the default max_period, when the samples allow it


@dataclasses.dataclass(frozen=True)
class LongTime:
    """How a long run is sampled after its transient, and its period detected (module doc).

    Attributes:
        sampled_periods: number of samples, one per forcing period (>= 2).
        period_tolerance: relative tolerance of the period detection (0 < tol < 1).
        max_period: largest period looked for, at most sampled_periods / 2 so that a period
            is seen to repeat at least once over each of its samples; default the smaller of
            16 and sampled_periods // 2.
    """

    sampled_periods: int = 200
    period_tolerance: float = DEFAULT_PERIOD_TOLERANCE
    max_period: int | None = None

    def __post_init__(self) -> None:
        require("sampled_periods", self.sampled_periods,
                is_integer(self.sampled_periods) and self.sampled_periods >= 2,
                "must be an integer >= 2")
        tolerance = self.period_tolerance
        require("period_tolerance", tolerance, is_real(tolerance) and 0.0 < tolerance < 1.0,
                "must be a number between 0 and 1 (relative to the samples' scale)")
        if self.max_period is None:
            object.__setattr__(self, "max_period",
                               min(LARGEST_MAX_PERIOD, self.sampled_periods // 2))
        require("max_period", self.max_period, is_integer(self.max_period)
                and 1 <= self.max_period <= self.sampled_periods // 2,
                f"must be an integer from 1 to sampled_periods // 2 = "
                f"{self.sampled_periods // 2}")
        # Python numbers: a sweep's definition holding them is hashed as JSON
        for name, kind in (("sampled_periods", int), ("period_tolerance", float),
                           ("max_period", int)):
            object.__setattr__(self, name, kind(getattr(self, name)))

    def forcing_period(self, omega: float | np.ndarray) -> float | np.ndarray:
        """T = 2 pi / Omega (s); Omega in rad/s, > 0."""
        return 2.0 * math.pi / np.asarray(omega, dtype=float)

    def sample_times(self, omega: float | np.ndarray, transient_periods: int) -> np.ndarray:
        """Sample times t_k (s), shape ``omega.shape + (sampled_periods,)``."""
        period = np.asarray(self.forcing_period(omega))[..., None]
        return self.period_numbers(transient_periods) * period

    def horizon(self, omega: float | np.ndarray, transient_periods: int) -> float | np.ndarray:
        """End of the sampled window (s): (transient_periods + sampled_periods) T."""
        return (transient_periods + self.sampled_periods) * self.forcing_period(omega)

    def window(self, omega: float | np.ndarray) -> float | np.ndarray:
        """Length of the sampled window (s), sampled_periods T."""
        return self.sampled_periods * self.forcing_period(omega)

    def period_numbers(self, transient_periods: int) -> np.ndarray:
        """Forcing periods from t = 0 to each sample: the ``period`` coordinate."""
        return transient_periods + np.arange(self.sampled_periods)


STEPPINGS = {"up": ("up",), "down": ("down",), "both": ("up", "down")}  # the rows of each
# axes along which a stepped sweep may carry its state: the drive's (a cell's forcing and gap;
# the modes, and so the carried coordinates, stay those of the row's geometry)
STEPPED_AXES = ("omega", "force_amplitude", "base_amplitude", "clearance")
# with several contacts a contact's clearance too: the axis contacts.INDEX.clearance
STEPPED_CONTACT_FIELD = "clearance"


@dataclasses.dataclass(frozen=True)
class Stepping:
    """A stepped-sine sweep, as on a shaker (docs/model.md, "Stepped-sine sweeps").

    Along ``axis`` each cell starts from the state its neighbour ended in at its horizon, on
    the stroboscopic section (t = 0 mod 2 pi / Omega, which is phase 0 of the next cell's
    forcing too), instead of from the sweep's ``start``; the first cell of a row starts from
    ``start``. ``direction``: ``"up"`` (increasing values), ``"down"`` or ``"both"`` (two rows,
    a ``sweep_direction`` dimension of the map). The other axes stay parallel rows.

    Attributes:
        direction: "up", "down" or "both".
        axis: the swept parameter stepped along, one of ``STEPPED_AXES`` (default omega), or
            with several contacts one contact's clearance, ``contacts.INDEX.clearance``.
    """

    direction: str
    axis: str = "omega"

    def __post_init__(self) -> None:
        require("stepping", self.direction,
                isinstance(self.direction, str) and self.direction in STEPPINGS,
                f"must be one of {', '.join(map(repr, STEPPINGS))}")
        require("stepped_axis", self.axis,
                not isinstance(self.axis, str) or part_field(self.axis) is None,
                "a part's field changes the modes, whose coordinates a cell carries from its "
                "predecessor: carried as the beams' deflection and velocity instead, the next "
                "modes would keep only their span of it, and how a part joins a moving beam "
                "(its velocity kept, or its momentum) has no one answer. Step along a drive "
                "or a clearance, the part's axis as parallel rows")
        require("stepped_axis", self.axis,
                isinstance(self.axis, str) and (self.axis in STEPPED_AXES or (
                    contact_field(self.axis) or (0, ""))[1] == STEPPED_CONTACT_FIELD),
                f"must be one of {', '.join(STEPPED_AXES)} or, with several contacts, "
                f"{CONTACTS}.INDEX.{STEPPED_CONTACT_FIELD} (a drive parameter or a clearance: "
                "the carried modal state needs the same modes from step to step)")

    @property
    def directions(self) -> tuple[str, ...]:
        """The rows' directions, in the order of the ``sweep_direction`` dimension."""
        return STEPPINGS[self.direction]


def response_period(deflection1: np.ndarray, deflection2: np.ndarray, velocity1: np.ndarray,
                    velocity2: np.ndarray, omega: float | np.ndarray, tolerance: float,
                    max_period: int) -> np.ndarray:
    """Period of the sampled response in forcing periods (0 if none up to ``max_period``).

    Tip deflections (m) and velocities (m/s) of shape ``(..., samples)``; ``omega`` (rad/s)
    broadcasts against ``(...)``. Samples with NaN (a run that stopped early) give 0.
    """
    scaled = 1.0 / np.asarray(omega, dtype=float)[..., None]
    state = np.stack([deflection1, deflection2, velocity1 * scaled, velocity2 * scaled],
                     axis=-1)  # (..., samples, 4), all in m
    scale = np.max(np.abs(state), axis=(-2, -1))
    period = np.zeros(scale.shape, dtype=np.int32)
    for p in range(max_period, 0, -1):  # smallest last: it wins
        distance = np.max(np.abs(state[..., p:, :] - state[..., :-p, :]), axis=(-2, -1))
        period = np.where(distance <= tolerance * scale, p, period)
    return period


def steady_rate(count: float | np.ndarray, start: float | np.ndarray, end: float | np.ndarray,
                reached: float | np.ndarray) -> float | np.ndarray:
    """Events per second (1/s) counted over the window [start, end) up to the time reached (s).

    NaN where the run stopped before the window began.
    """
    covered = np.minimum(end, reached) - start
    return np.where(covered > 0, count / np.where(covered > 0, covered, 1.0), np.nan)


def long_time_values(long_time: LongTime, transient_periods: int, omega: np.ndarray,
                     clearance: np.ndarray, samples: np.ndarray,
                     summary: np.ndarray) -> dict[str, np.ndarray]:
    """The long-time observables of runs from the stroboscope kernel's output.

    ``omega`` (rad/s), ``clearance`` (m): per run; ``samples``: (runs, sampled_periods,
    ``TIP_COLUMNS``), y2 itself (the stored ``poincare_deflection2`` is y2 - Delta, as
    ``tip_deflection_2``); ``summary``: (runs, ``STROBOSCOPE_COLUMNS``). Also the runs'
    ``dynamics_status``.
    """
    y1, y2, v1, v2 = (samples[..., column] for column in (layout.TIP_Y1, layout.TIP_Y2,
                                                          layout.TIP_V1, layout.TIP_V2))
    start = long_time.sample_times(omega, transient_periods)[..., 0]
    end = long_time.horizon(omega, transient_periods)
    reached = summary[:, layout.STROBE_T_END]
    return {
        "poincare_deflection1": y1,
        "poincare_deflection2": y2 - np.asarray(clearance)[:, None],
        "poincare_velocity1": v1,
        "poincare_velocity2": v2,
        "response_period": response_period(y1, y2, v1, v2, omega, long_time.period_tolerance,
                                           long_time.max_period),
        "steady_impact_rate": steady_rate(summary[:, layout.STROBE_ONSETS], start, end, reached),
        "steady_episode_rate": steady_rate(summary[:, layout.STROBE_EPISODES], start, end,
                                           reached),
        "dynamics_status": summary[:, layout.STROBE_STATUS],
    }


def hysteresis(dataset: xr.Dataset) -> xr.DataArray:
    """Where the up and down rows of a stepped sweep (``stepping = "both"``) differ.

    True at the cells whose stroboscopic samples, x = (y1, v1 / Omega[, y2, v2 / Omega]) as in
    `response_period`, are not the same set in both directions: the Hausdorff distance of the
    two sets of samples exceeds the sweep's ``period_tolerance`` times their scale (a cyclic
    shift of a period-p orbit's samples is the same response). Two coexisting attractors (the
    band between the folds of a resonance, where a shaker sweep jumps) differ by a sizeable
    fraction of the scale; one attractor reached from both sides agrees to its transient's
    leftover. The up sweep jumps after the band's last cell in its direction, the down sweep
    after its first. Cells where either run stopped early (NaN samples) are False.
    """
    state = _section_samples(dataset)
    up, down = (state.sel(sweep_direction=direction) for direction in ("up", "down"))
    scale = np.maximum(abs(up).max(("period", "component")), abs(down).max(("period", "component")))
    # every sample of one set to its nearest in the other, both ways
    apart = abs(up - down.rename(period="other")).max("component")
    distance = np.maximum(apart.min("other").max("period"), apart.min("period").max("other"))
    return (distance > dataset.attrs["period_tolerance"] * scale).rename("hysteresis")


def _section_samples(dataset: xr.Dataset) -> xr.DataArray:
    """The samples x of `response_period` along a ``component`` dimension (m)."""
    import xarray as xr

    omega = dataset["omega"] if "omega" in dataset.coords else dataset.attrs["omega"]
    parts = [dataset[f"poincare_{kind}{beam}"] / (omega if kind == "velocity" else 1.0)
             for beam in "12" for kind in ("deflection", "velocity")
             if f"poincare_{kind}{beam}" in dataset]
    return xr.concat(parts, "component")
