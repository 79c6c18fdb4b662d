"""Several contacts (``Params.contacts``): the first contact among them, and their dynamics.

Until a contact closes the beams move freely, and the free motion does not depend on the
contacts (their points, sides, clearances and laws act only in contact): each contact's gap is
a linear function of the same free coordinates. The first root among all gaps is therefore the
earliest of each contact's own first onset, each located and certified by the event kernel on
that contact's own packed run (`Params.each_contact`: the run with that contact alone, at one
common n_modes), all started from the same free state.

The contacts that follow are the phases of the active sets (`impactbeams.contact.active_sets`,
packed by `impactbeams.active_phases`, run by `impactbeams.kernels.several_contacts`):
`contact_sequence` and `impactbeams.simulate` of several contacts (`several_run`),
contacts closed together included. One contact's sequence is `simulate`'s own run, restarted
at each release from the free state the kernel recorded there (where the kernel itself resumes
its windows bit for bit, `impactbeams.trajectory.phases.run`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from impactbeams.active_phases import (
    IMPACT_COLUMNS as _IMPACT_COLUMNS,
)
from impactbeams.active_phases import (
    PackedContacts,
    episodes,
    pack_contacts,
    run_contacts,
)
from impactbeams.blas import one_blas_thread
from impactbeams.contact import recommended_modes
from impactbeams.kernels import dynamics as dyn
from impactbeams.kernels.layout import CONTACT, FREE
from impactbeams.kernels.records import segments
from impactbeams.packing import Packed, pack_run
from impactbeams.params import (
    MAX_EVENTS,
    MAX_MODES,
    Params,
    require,
    require_finite,
    require_integer,
    require_type,
)
from impactbeams.preflight import check_run
from impactbeams.trajectory.impacts import impact_table
from impactbeams.trajectory.phases import Trajectory

# a free flight (two segments after a dashpot's early release: until the gap opens, then on), a
# contact and the free flight after it: one contact episode of one run
_EPISODE = 4
# the per-impact quantities a sequence reports, from `impact_table`


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

    One contact, or two at one point of each beam from opposite sides (a two-sided stop),
    dashpots and damping or not: a contact's force acts only while its gap g is closed (< 0),
    and the other's gap is then the sum of the two clearances less g, > 0.
    """
    runs = params.each_contact()
    if len(runs) == 1:
        return True
    if len(runs) > 2:
        return False
    a, b = runs
    return a.contact_point == b.contact_point and a.side.sign == -b.side.sign


def _packs(params: Params, t_max: float, n_modes: int) -> list[Packed]:
    """Each contact's packed run at ``n_modes`` (checked: `check_contact_runs`)."""
    return [pack_run(run, n_modes, t_max, t_max) for run in params.each_contact()]


def check_contact_runs(params: Params, t_max: float, n_modes: int | None) -> int:
    """The modes per beam of ``params``' contacts' runs, once their horizon and modes are allowed.

    Refuses before any compute (ParameterError; an ArgumentTypeError for a type) a ``t_max``
    (s) or ``n_modes`` beyond any contact's run's range, as `impactbeams.simulate` does
    (`preflight.check_run`), at the modes they share (default: the most any of them
    recommends).
    """
    require_type("params", params, isinstance(params, Params), "an impactbeams.Params")
    t_max = require_finite("t_max", t_max, "s")
    require("t_max", t_max, t_max > 0, "must be > 0", "s")
    runs = params.each_contact()
    n = (max(recommended_modes(run) for run in runs) if n_modes is None
         else require_integer("n_modes", n_modes, 1, MAX_MODES))
    for run in runs:
        check_run(run.numeric(), t_max, n, springs=run.grounded_springs,
                  structure1=run.structure1, steps=run.step_factors)
    return n


def _episode(packed: Packed, q: np.ndarray, v: np.ndarray, t: float) -> Trajectory:
    """One run's segments from the free state (q, v) at t (s) to the end of its next contact."""
    recorded = segments(_EPISODE, q.size)
    count, status, t_end = dyn.run_events(packed.tables, packed.forces, packed.phase_scalars,
                                          packed.switching, packed.settings, q, v, recorded,
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
    first, best, onset = -1, None, math.inf
    for index, packed in enumerate(packs):
        episode = _episode(packed, q, v, t)
        k = _contact_segment(episode)
        if k > 0 and episode.time[k] < onset:
            first, best, onset = index, episode, episode.time[k]
    return first, best


def _contact_segment(episode: Trajectory) -> int:
    """The index of an episode's contact segment, -1 if it has none."""
    closed = np.flatnonzero(episode.phase == CONTACT)
    return int(closed[0]) if closed.size else -1


@one_blas_thread
def first_contact(params: Params, t_max: float, n_modes: int | None = None) -> FirstContact:
    """The first contact among ``params``' contacts by ``t_max`` (s), exactly located.

    ``n_modes``: free modes per beam (default: the most any one contact's run recommends,
    `impactbeams.contact.recommended_modes`). The spring law only (several contacts need it).
    """
    n = check_contact_runs(params, t_max, n_modes)
    packs = _packs(params, t_max, n)
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
    """Every contact of ``params``' contacts up to ``t_max`` (s), exactly.

    Returns a Dataset along ``impact``: ``impact_contact`` (which of ``params.contacts``),
    the onset time, duration, impulse, peak force, impact and separation velocities (as
    `impactbeams.simulate`'s impact table), and ``attrs["status"]`` ("complete", or
    "event_limit" after ``max_contacts``). One contact: `impactbeams.simulate`'s own run, to
    its bits; several: the phases of every set of contacts closed at once
    (`impactbeams.active_phases`), contacts closing together and dashpots
    included.
    """
    n = check_contact_runs(params, t_max, n_modes)
    max_contacts = require_integer("max_contacts", max_contacts, 1)
    if params.several_contacts:
        return _several_sequence(params, t_max, n, max_contacts)
    packs = _packs(params, t_max, n)
    q, v, t = packs[0].q0, packs[0].v0, 0.0
    rows: dict[str, list[float]] = {name: [] for name in ("impact_contact", *_IMPACT_COLUMNS)}
    status = "complete"
    while True:
        _, episode = _earliest(packs, q, v, t)
        if episode is None:
            break
        if len(rows["impact_contact"]) == max_contacts:
            status = "event_limit"
            break
        table = impact_table(packs[0], episode)
        rows["impact_contact"].append(0)
        for name in _IMPACT_COLUMNS:
            rows[name].append(float(table[name][0]))
        after = _contact_segment(episode) + 1
        if after == episode.time.size:  # still in contact at t_max
            break
        q, v, t = episode.q[after], episode.v[after], float(episode.time[after])
    return _sequence_dataset(rows, status, n, t_max)


def _sequence_dataset(rows: dict[str, list[float]], status: str, n_modes: int, t_max: float,
                      ) -> xr.Dataset:
    """``contact_sequence``'s Dataset of its rows."""
    data = {name: ("impact", np.array(values, dtype=np.int64 if name == "impact_contact"
                                      else float)) for name, values in rows.items()}
    return xr.Dataset(data, attrs={"status": status, "n_modes": n_modes, "t_max": t_max})


def _several_sequence(params: Params, t_max: float, n: int, max_contacts: int) -> xr.Dataset:
    """``contact_sequence`` of several contacts (n modes per beam): the active sets' phases."""
    packed = _packed_contacts(params, n, t_max, t_max)
    # a contact's onset, release and (a dashpot's early release) its gap's opening are three
    # phases: the run stops once max_contacts onsets are recorded and one more is found
    run = run_contacts(packed, 3 * max_contacts + 3)
    rows = episodes(packed, run)
    if len(rows["impact_contact"]) > max_contacts:  # (always so when the arrays are full)
        rows = {name: values[:max_contacts] for name, values in rows.items()}
        return _sequence_dataset(rows, "event_limit", n, t_max)
    if run.status != "complete":
        raise RuntimeError(f"the event search stopped at t = {run.t_end!r} s: status "
                           f"{run.status!r}")
    return _sequence_dataset(rows, "complete", n, t_max)


def _packed_contacts(params: Params, n_modes: int, t_max: float, search_span: float,
                     ) -> PackedContacts:
    """The packed phases of several contacts (the spring law), n_modes per beam."""
    return pack_contacts(params, n_modes, t_max, search_span)
