"""The first contact among several (``Params.contacts``): which contact closes first, and when.

Until the first contact the beams move freely, and the free motion does not depend on the
contacts (their points, sides, clearances and laws act only in contact): each contact's gap is
a linear function of the same free coordinates. The first root among all gaps is therefore
the earliest of each contact's own first onset, each located and certified by today's event
search on that contact's own run (`Params.each_contact`: the run with that contact alone, at
one common n_modes). The contact phase that follows is that contact's own as long as no other
gap closes during it. That is certain for the two contacts of a two-sided stop (one point, one
below and one above, against a stop or one point of beam 2): their gaps add up to the two
clearances, so while one is closed (g <= 0, R = -k g > 0 without a dashpot) the other stays
open by more than its own clearance. For any other set the episode is not reported (NaN):
finding whether another gap closes during it is the several-contact dynamics, not built yet
(docs/limits.md, "Several contacts").
"""

from __future__ import annotations

import dataclasses
import math
import warnings

from impactbeams.blas import one_blas_thread
from impactbeams.contact import recommended_modes
from impactbeams.params import MAX_MODES, Params, require_finite, require_integer, require_type

# simulate's phases up to the end of the first contact: a free flight, a contact, a free flight
_FIRST_EPISODE_PHASES = 3


@dataclasses.dataclass(frozen=True)
class FirstContact:
    """The first contact of a run among its contacts (SI units; NaN where there is none).

    Attributes:
        contact: the index in ``Params.contacts`` of the contact that closes first (0 for a
            run of one contact; -1 if none closes by ``t_max``; the lowest of equal onsets).
        onset: its onset time (s); impact_velocity: the gap's rate then (m/s, < 0).
        release, duration, impulse, peak_force: its contact phase (s, s, N s, N), reported
            when ``episode_certain``.
        episode_certain: whether no other gap can close during that contact (one contact, or
            the two of a two-sided stop).
        n_modes: the free modes per beam of every contact's run.
    """

    contact: int
    onset: float
    impact_velocity: float
    release: float
    duration: float
    impulse: float
    peak_force: float
    episode_certain: bool
    n_modes: int


def exclusive(params: Params) -> bool:
    """Whether at most one of ``params``' contacts can be closed at a time.

    One contact, or two at one point of each beam from opposite sides (a two-sided stop)
    without a dashpot (with one, a releasing contact's force outlasts its closed gap).
    """
    runs = params.each_contact()
    if len(runs) == 1:
        return True
    if len(runs) > 2:
        return False
    (a, b) = runs
    return (a.contact_point == b.contact_point and a.side.sign == -b.side.sign
            and a.contact_damping == 0.0 and b.contact_damping == 0.0)


@one_blas_thread
def first_contact(params: Params, t_max: float, n_modes: int | None = None) -> FirstContact:
    """The first contact among ``params``' contacts by ``t_max`` (s), exactly located.

    ``n_modes``: free modes per beam (default: the most any one contact's run recommends,
    `impactbeams.contact.recommended_modes`). The spring law only (several contacts need it).
    """
    from impactbeams.trajectory.simulation import simulate

    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    t_max = require_finite("t_max", t_max, "s")
    runs = params.each_contact()
    n = (max(recommended_modes(run) for run in runs) if n_modes is None
         else require_integer("n_modes", n_modes, 1, MAX_MODES))
    certain = exclusive(params)
    first, best = -1, None
    for index, run in enumerate(runs):
        with warnings.catch_warnings():  # stopping after the first contact is the point here
            warnings.simplefilter("ignore", RuntimeWarning)
            dataset = simulate(run, t_max, n, dt_output=t_max,
                               max_events=_FIRST_EPISODE_PHASES)
        if dataset.sizes["impact"] and (best is None or dataset["impact_onset_time"][0]
                                        < best["impact_onset_time"][0]):
            first, best = index, dataset
    if best is None:
        return FirstContact(-1, *(math.nan,) * 6, episode_certain=certain, n_modes=n)
    row = {name: float(best[name][0]) for name in (
        "impact_onset_time", "impact_velocity", "impact_duration", "impact_impulse",
        "impact_peak_force")}
    episode = ((row["impact_onset_time"] + row["impact_duration"], row["impact_duration"],
                row["impact_impulse"], row["impact_peak_force"]) if certain
               else (math.nan,) * 4)
    return FirstContact(first, row["impact_onset_time"], row["impact_velocity"], *episode,
                        episode_certain=certain, n_modes=n)
