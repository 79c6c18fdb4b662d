"""Several contacts (``Params.contacts``): the first contact among them, and two-sided stops.

Until a contact closes the beams move freely, and the free motion does not depend on the
contacts (their points, sides, clearances and laws act only in contact): each contact's gap is
a linear function of the same free coordinates. The first root among all gaps is therefore the
earliest of each contact's own first onset, each located and certified by the event kernel on
that contact's own packed run (`Params.each_contact`: the run with that contact alone, at one
common n_modes), all started from the same free state.

The contact phase that follows is that contact's own (its own eigen-decomposition and static
correction, `impactbeams.contact.spring_contact`) as long as no other gap closes during it.
That is certain for the two contacts of a two-sided stop (one point, one below and one above,
against a stop or one point of beam 2) without a dashpot: their gaps add up to the two
clearances, so while one is closed (g <= 0, R = -k g > 0) the other is open by more than its
own clearance. Its whole dynamics is then a chain of such runs, each restarted at a release
from the free state the kernel recorded there (where the kernel itself resumes its windows bit
for bit, `impactbeams.trajectory.phases.run`): `contact_sequence`. Contacts that can be closed
together (e.g. a stop at mid-span and one at the tip) need the contact phase of both at once
(docs/model.md, "Several contacts"), not built: their first onset is found, their contact
phase is not (docs/limits.md, "Several contacts").
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from impactbeams.blas import one_blas_thread
from impactbeams.contact import recommended_modes
from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.layout import CONTACT, FREE
from impactbeams.kernels.records import segments
from impactbeams.packing import Packed, pack_run
from impactbeams.params import (
    MAX_EVENTS,
    MAX_MODES,
    ParameterError,
    Params,
    require,
    require_finite,
    require_integer,
    require_type,
)
from impactbeams.trajectory.impacts import impact_table
from impactbeams.trajectory.phases import Trajectory

# a free flight, a contact and the free flight after it: one contact episode of one run
_EPISODE = 3
# the per-impact quantities a sequence reports, from `impact_table`
_IMPACT_COLUMNS = ("impact_onset_time", "impact_duration", "impact_impulse",
                   "impact_peak_force", "impact_velocity", "separation_velocity")


@dataclasses.dataclass(frozen=True)
class FirstContact:
    """The first contact of a run among its contacts (SI units; NaN where there is none).

    Attributes:
        contact: the index in ``Params.contacts`` of the contact that closes first (0 for a
            run of one contact; -1 if none closes by ``t_max``; the lowest of equal onsets).
        onset: its onset time (s); impact_velocity: the gap's rate then (m/s, < 0).
        release, duration, impulse, peak_force: its contact phase (s, s, N s, N), reported
            when ``episode_certain`` (and released by t_max).
        episode_certain: whether no other gap can close during it (`exclusive`).
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
    a, b = runs
    return (a.contact_point == b.contact_point and a.side.sign == -b.side.sign
            and a.contact_damping == 0.0 and b.contact_damping == 0.0)


def _packs(params: Params, t_max: float, n_modes: int | None) -> tuple[list[Packed], int]:
    """Each contact's packed run at one n_modes (default: the most any of them recommends)."""
    _check_run(params, t_max)
    runs = params.each_contact()
    n = (max(recommended_modes(run) for run in runs) if n_modes is None
         else require_integer("n_modes", n_modes, 1, MAX_MODES))
    return [pack_run(run, n, t_max, t_max) for run in runs], n


def _check_run(params: Params, t_max: float) -> None:
    """Raise ParameterError (an ArgumentTypeError for a type) unless both are allowed."""
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    t_max = require_finite("t_max", t_max, "s")
    require("t_max", t_max, t_max > 0, "must be > 0", "s")


def _episode(packed: Packed, q: np.ndarray, v: np.ndarray, t: float) -> Trajectory:
    """One run's segments from the free state (q, v) at t (s) to the end of its next contact."""
    recorded = segments(_EPISODE, q.size)
    count, status, t_end = dyn.run_events(packed.tables, packed.forces, packed.phase_scalars,
                                          *packed.switching(), packed.settings, q, v, recorded,
                                          t, FREE)
    if status in (dyn.STUCK, dyn.SEARCH_LIMIT):
        raise RuntimeError(f"the event search stopped at t = {t_end!r} s: status "
                           f"{dyn.STATUS_NAMES[status]!r}")
    return Trajectory(*(array[:count] for array in recorded), dyn.STATUS_NAMES[status],
                      float(t_end))


def _earliest(packs: list[Packed], q: np.ndarray, v: np.ndarray, t: float,
              ) -> tuple[int, Trajectory | None]:
    """The contact that closes first from the free state (q, v) at t, and its run's episode.

    (-1, None) if none closes by t_max.
    """
    first, best = -1, None
    for index, packed in enumerate(packs):
        episode = _episode(packed, q, v, t)
        closes = episode.time.size > 1 and episode.phase[1] == CONTACT
        if closes and (best is None or episode.time[1] < best.time[1]):
            first, best = index, episode
    return first, best


@one_blas_thread
def first_contact(params: Params, t_max: float, n_modes: int | None = None) -> FirstContact:
    """The first contact among ``params``' contacts by ``t_max`` (s), exactly located.

    ``n_modes``: free modes per beam (default: the most any one contact's run recommends,
    `impactbeams.contact.recommended_modes`). The spring law only (several contacts need it).
    """
    packs, n = _packs(params, t_max, n_modes)
    certain = exclusive(params)
    first, episode = _earliest(packs, packs[0].q0, packs[0].v0, 0.0)
    if episode is None:
        return FirstContact(-1, *(math.nan,) * 6, episode_certain=certain, n_modes=n)
    row = {name: float(value[0]) for name, value in impact_table(packs[first], episode).items()}
    phase = ((row["impact_onset_time"] + row["impact_duration"], row["impact_duration"],
              row["impact_impulse"], row["impact_peak_force"]) if certain
             else (math.nan,) * 4)
    return FirstContact(first, row["impact_onset_time"], row["impact_velocity"], *phase,
                        episode_certain=certain, n_modes=n)


@one_blas_thread
def contact_sequence(params: Params, t_max: float, n_modes: int | None = None,
                     max_contacts: int = MAX_EVENTS // 2) -> xr.Dataset:
    """Every contact of a two-sided stop (or of one contact) up to ``t_max`` (s), exactly.

    Returns a Dataset along ``impact``: ``impact_contact`` (which of ``params.contacts``),
    the onset time, duration, impulse, peak force, impact and separation velocities (as
    `impactbeams.simulate`'s impact table), and ``attrs["status"]`` ("complete", or
    "event_limit" after ``max_contacts``). Contacts that can be closed together are refused.
    """
    _check_run(params, t_max)
    if not exclusive(params):
        raise ParameterError(
            f"contacts: {len(params.contacts)} contacts that can be closed together are not "
            "allowed in contact_sequence, which takes one contact or a two-sided stop (two "
            "contacts at one point, below and above, no dashpot); their first contact is "
            "impactbeams.first_contact (docs/limits.md, 'Several contacts')")
    max_contacts = require_integer("max_contacts", max_contacts, 1)
    packs, n = _packs(params, t_max, n_modes)
    q, v, t = packs[0].q0, packs[0].v0, 0.0
    rows: dict[str, list[float]] = {name: [] for name in ("impact_contact", *_IMPACT_COLUMNS)}
    status = "complete"
    while True:
        first, episode = _earliest(packs, q, v, t)
        if episode is None:
            break
        if len(rows["impact_contact"]) == max_contacts:
            status = "event_limit"
            break
        table = impact_table(packs[first], episode)
        rows["impact_contact"].append(first)
        for name in _IMPACT_COLUMNS:
            rows[name].append(float(table[name][0]))
        if episode.time.size < _EPISODE:  # still in contact at t_max
            break
        q, v, t = episode.q[2], episode.v[2], float(episode.time[2])
    data = {name: ("impact", np.array(values, dtype=np.int64 if name == "impact_contact"
                                      else float)) for name, values in rows.items()}
    return xr.Dataset(data, attrs={"status": status, "n_modes": n, "t_max": t_max})
