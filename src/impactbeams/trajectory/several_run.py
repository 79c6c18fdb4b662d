"""`impactbeams.simulate` of several contacts: the run of the active sets' phases, its Dataset.

The run is `impactbeams.active_phases`' (the kernel of several contacts); this module
turns it into `simulate`'s Dataset: the time series, each contact's gap and force, the contacts
(`impactbeams.active_phases.episodes`), their impact episodes, the energy balance, the
long-time samples (`impactbeams.active_phases.long_time_values`), the start from a given state
and the final state.

Episodes (`impactbeams.trajectory.episodes` for one contact): the contacts of all contacts
together, in order of onset, cluster into one episode while each onset follows the latest
release before it by less than the separation (``episode_*``, the beams' collisions), and each
contact's own contacts alone cluster by the same rule (``contact_episode_*``).

Energy balance. In active set S the modes feel B_S R_S, R_S = -K_S g_S - C_S g_S' (modal gaps),
and the energy is the beams' plus g_S^T K_S g_S / 2 minus F times beam 1's tip shift under the
closed forces, sum_j s_1j R_j (`simulate_contacts`). Within a phase it changes by the power of
the drives, ``-F (tip rate of the modes and F's quasi-static part + sum_j s_1j R_j')`` (and under
a shaker its inertial load and the clamps pushing each contact), minus the modal damping's
``2 zeta omega (q' - F' b)^2`` and the dashpots' ``g_S'^T C_S g_S'``. The work is integrated
by parts, ``int -F s_1 . R' = -F s_1 . R + int F' s_1 . R`` (F(0) = 0), which also counts the
tip's jump with R at a dashpot's switch; where the closed set changes with dashpots, the springs'
term g_S^T K_S g_S / 2 jumps at one state (a contact released early, its spring still
compressed, gives up what it held): that jump counts as dissipated. Both by 12-point
Gauss-Legendre on panels of half the fastest period of each phase, as for one contact.
"""

from __future__ import annotations

import math
import sys
import warnings
from collections.abc import Callable

import numpy as np
import xarray as xr
from numpy.polynomial.legendre import leggauss

from impactbeams.active_phases import (
    ContactRun,
    PackedContacts,
    _modal_gap_rates,
    contact_quantities,
    contacts_start,
    episode_labels,
    episodes,
    force_rates,
    long_time_values,
    pack_contacts,
    run_contacts,
    sample,
    tip_motions,
)
from impactbeams.blas import one_blas_thread
from impactbeams.kernels.layout import FREE, SCALAR_LOAD_RATE, TABLE_ROWS
from impactbeams.longtime import LongTime
from impactbeams.params import Params, modes_per_beam, without_unused_law_keys
from impactbeams.preflight import format_time
from impactbeams.progress import Progress
from impactbeams.trajectory.episodes import default_separation
from impactbeams.trajectory.fields import with_deflections
from impactbeams.trajectory.lyapunov import contacts_exponents, with_exponents
from impactbeams.trajectory.observables import observables
from impactbeams.trajectory.poincare import with_long_time
from impactbeams.trajectory.start import initial_free_state, with_final_state
from impactbeams.variables import attributes, global_attributes, validate

_NODES, _WEIGHTS = leggauss(12)
_CHUNK_NODES = 1 << 16  # quadrature nodes evaluated at once: bounds memory at ~N * 10 MB


@one_blas_thread
def simulate_contacts(params: Params, t_max: float, n_modes: int, times: np.ndarray,
                      search_span: float, max_events: int, *, energy_balance: bool = False,
                      initial_state: object = None, progress: bool = False,
                      episode_separation: float | None = None, expected: float = math.nan,
                      long_time: LongTime | None = None, transient_periods: int = 0,
                      fields: int = 0, lyapunov: int = 0) -> xr.Dataset:
    """`impactbeams.simulate` of several contacts (its arguments checked): a Dataset.

    Along ``time``: ``energy``, ``kinetic_energy``, ``unresolved_kinetic_energy``, the tips
    (m), each contact's physical gap ``contact_gaps`` (m) and force ``contact_forces`` (N)
    along ``contact``, and with ``energy_balance`` ``work_of_force`` and
    ``damping_dissipation`` (module doc); along ``impact``: each contact (the columns of
    `contact_sequence`); along ``episode`` the episodes of all contacts together, along
    ``contact_episode`` each contact's own; ``final_displacement``, ``final_velocity``; with
    ``long_time`` its variables after ``transient_periods`` (`active_phases.long_time_values`);
    with ``fields`` (a number of points per beam) the deflection fields, as one spring
    contact's (the modes' and the tip force's quasi-static part); with ``lyapunov`` that many
    leading Lyapunov exponents after ``transient_periods``, as one contact's
    (`impactbeams.trajectory.lyapunov.contacts_exponents`).
    ``expected``: the announced compute time (s) with ``progress``.
    """
    packed = pack_contacts(params, n_modes, t_max, search_span)
    start = (None if initial_state is None
             else contacts_start(packed, initial_free_state(packed.runs[0], initial_state)))
    if progress:
        print(f"simulate: {len(params.contacts)} contacts, "
              f"{modes_per_beam(n_modes, params.partner)}, t_max = "
              f"{t_max:g} s; expected: roughly {format_time(expected)}", file=sys.stderr)
    bar = Progress(t_max, enabled=progress, unit="s simulated")
    run = run_contacts(packed, max_events, start,
                       (lambda t, _: bar.reach(t)) if progress else None)
    if run.status == "complete":
        bar.reach(t_max)
    else:
        bar.stop(run.t_end, f"{run.status} at t = {run.t_end:.6g} s")
        warnings.warn(f"simulation stopped at t = {run.t_end!r} s before t_max = {t_max!r} s: "
                      f"status {run.status!r}", RuntimeWarning, stacklevel=4)
    times = times[times <= run.t_end]
    data = _series(packed, run, times)
    impacts = {name: np.array(values, dtype=np.int64 if name == "impact_contact" else float)
               for name, values in episodes(packed, run).items()}
    switches = _switch_columns(packed, run, impacts)
    separation = (default_separation(packed.runs[0]) if episode_separation is None
                  else episode_separation)
    works = _contact_works(packed, run, impacts) if energy_balance else None
    joint = _episode_table(impacts, episode_labels(impacts, separation), works)
    own = _contact_episodes(impacts, separation, works)
    if energy_balance:
        bounds = np.concatenate([times, *(_bounds(table) for table in (joint, own))])
        order = np.argsort(bounds, kind="stable")
        work, dissipation = np.empty_like(bounds), np.empty_like(bounds)
        work[order], dissipation[order] = energy_integrals(
            packed, run, bounds[order],
            Progress(run.t_end, enabled=progress, unit="s integrated (work and dissipation)"
                     ).reach)
        data["work_of_force"] = work[:times.size]
        data["damping_dissipation"] = dissipation[:times.size]
        at = dissipation[times.size:]
        for table in (joint, own):
            size = table["episode_onset_time"].size
            table["episode_dissipated_energy"] = at[size:2 * size] - at[:size]
            at = at[2 * size:]
    dataset = _dataset(data, {**impacts, **switches}, joint, own, times)
    if fields:  # the free coordinates, as one spring contact's (its phases keep them)
        dataset = with_deflections(
            dataset, packed.runs[0],
            lambda t: (np.full(t.size, FREE, dtype=np.int64), sample(packed, run, t)[0]),
            run.t_end, times, fields)
    if lyapunov:
        dataset = with_exponents(dataset, contacts_exponents(packed, run, lyapunov,
                                                             transient_periods),
                                 transient_periods)
    if long_time is not None:
        dataset = with_long_time(dataset, long_time_values(
            packed, run, impacts, long_time, transient_periods, separation), long_time,
            transient_periods)
    z = np.concatenate(sample(packed, run, np.array([run.t_end]))[:2], axis=1)[0]
    dataset = with_final_state(dataset, z)
    described = without_unused_law_keys(params.as_dict())
    dataset.attrs.update(global_attributes(
        "impact dynamics of cantilevers with several contacts (impactbeams.simulate)",
        "simulate", described, t_max=t_max, t_max_units="s", n_modes=n_modes,
        status=run.status, t_end=run.t_end, n_phases=run.time.size,
        n_active_sets=len(packed.members), episode_separation=separation,
        energy_frame="relative"))
    validate(dataset)  # as registered, or a bug of the package
    return dataset


def _series(packed: PackedContacts, run: ContactRun, times: np.ndarray,
            ) -> dict[str, np.ndarray]:
    """The time series at ``times`` (s, <= the run's end): tips, energies, gaps and forces.

    The tips' velocities include the closed forces' rates through the flexibility the modes
    miss (`active_phases.tip_motions`).

    The energy is the beams' (`impactbeams.trajectory.observables`) plus the closed contacts'
    g_S^T K_eff g_S / 2 and the work of F through beam 1's tip shifts under them.
    """
    q, v, mask = sample(packed, run, times)
    free = _free_observables(packed, times, q, v)
    contact = contact_quantities(packed, times, q, v, mask)
    forces = contact["contact_force"]
    return {
        **tip_motions(packed, times, q, v, mask, forces),
        "kinetic_energy": free["kinetic_energy"],
        "unresolved_kinetic_energy": free["unresolved_kinetic_energy"],
        "energy": _energy(packed, times, free, contact),
        "contact_gaps": contact["gap"],
        "contact_forces": forces,
    }


def _free_observables(packed: PackedContacts, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                      ) -> dict[str, np.ndarray]:
    """Contact 0's run's observables (energies, tips) of the free states (q, v) at t (s)."""
    return observables(packed.runs[0], np.full(t.size, FREE, dtype=np.int64), t, q, v)


def _energy(packed: PackedContacts, t: np.ndarray, free: dict[str, np.ndarray],
            contact: dict[str, np.ndarray]) -> np.ndarray:
    """The energy (J) at t (s): the beams' (``free``) and the closed contacts' (``contact``).

    The beams' `observables` of the free states, the closed springs' g_S^T K_eff g_S / 2
    (`contact_quantities`) and minus the tip force times beam 1's tip shifts under them.
    """
    params = packed.runs[0].params
    springs = [run_.dynamics.spring for run_ in packed.runs]
    shift1 = np.array([spring.tip_shift1 for spring in springs])
    tip_force = params.force_amplitude * np.sin(params.omega * t)
    # the observables of contact 0's run count its own spring where its modal gap is < 0
    # (`observables._spring_contact`): the closed contacts' energy replaces it
    own_gap = contact["modal_gap"][:, 0]
    own_spring = np.where(own_gap < 0.0, 0.5 * springs[0].effective_stiffness * own_gap**2, 0.0)
    return (free["energy"] - own_spring + contact["contact_energy"]
            - tip_force * (contact["contact_force"] @ shift1))


def _switch_columns(packed: PackedContacts, run: ContactRun, impacts: dict[str, np.ndarray],
                    ) -> dict[str, np.ndarray]:
    """Each contact's per-impact energy columns, as one contact's impact table has them.

    At its onset (the state kept, the set changed): ``impact_energy_loss``, the energy
    (`_energy`) in the set before minus after (J; a dashpot's force jumps there, and with it
    the springs' energy and the tip force's term), and ``impact_kinetic_energy_loss`` (J, 0:
    the kinetic energy is the state's); at its release: ``release_energy_change``, after minus
    before (J; what a dashpot's early release gives up), ``release_gap`` (m, its physical gap
    in the set after: < 0 released early) and ``release_contact_force`` (N, its force in the
    set before: 0 to round-off); ``restitution_coefficient``, minus its gap's rate after the
    release over before the onset. NaN where the run holds no such switch (a contact closed
    at its start has no onset in it, one closed at its end no release).
    """
    n, count = len(packed.runs), impacts["impact_onset_time"].size
    columns = {name: np.full(count, math.nan) for name in (
        "impact_energy_loss", "impact_kinetic_energy_loss", "release_energy_change",
        "release_gap", "release_contact_force")}
    with np.errstate(divide="ignore", invalid="ignore"):  # a re-onset at rest: no ratio
        columns["restitution_coefficient"] = (-impacts["separation_velocity"]
                                              / impacts["impact_velocity"])
    t, q, v = run.time[1:], run.q[1:], run.v[1:]
    free = _free_observables(packed, t, q, v)
    before = contact_quantities(packed, t, q, v, run.mask[:-1])
    after = contact_quantities(packed, t, q, v, run.mask[1:])
    change = _energy(packed, t, free, after) - _energy(packed, t, free, before)
    # the contacts closed at the start have the first rows (`active_phases.episodes`)
    rows = {f: row for row, f in enumerate(f for f in range(n) if (run.mask[0] >> f) & 1)}
    onsets = len(rows)
    for k, f in enumerate(run.switched[1:].tolist()):
        if f >= n:  # a gap opened after an early release: no switch of the set
            continue
        if (run.mask[k + 1] >> f) & 1:
            rows[f], onsets = onsets, onsets + 1
            columns["impact_energy_loss"][rows[f]] = -change[k]
            columns["impact_kinetic_energy_loss"][rows[f]] = 0.0
        else:
            row = rows.pop(f)
            columns["release_energy_change"][row] = change[k]
            columns["release_gap"][row] = after["gap"][k, f]
            columns["release_contact_force"][row] = before["contact_force"][k, f]
    return columns


def _episode_table(impacts: dict[str, np.ndarray], labels: np.ndarray,
                   works: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The episodes of ``impacts`` grouped by ``labels`` (ascending): the ``episode_*`` columns.

    The restitution is the gap's: -(its rate after the last release) / (before the first
    onset), where all of the episode's contacts are one contact's (NaN otherwise). With
    ``works`` (`_contact_works`, per contact) also the energetic restitution, sqrt(work of R
    while the gaps open / while they close) over the episode's released contacts.
    """
    onset = impacts["impact_onset_time"]
    release = onset + impacts["impact_duration"]
    contact = impacts["impact_contact"]
    count = int(labels[-1]) + 1 if labels.size else 0
    first = np.searchsorted(labels, np.arange(count))
    stops = np.append(first[1:], labels.size)[:count].astype(int)  # none without impacts
    table = {name: np.empty(count) for name in (
        "episode_onset_time", "episode_duration", "episode_impulse", "episode_peak_force",
        "episode_restitution")}
    table["episode_contact_count"] = (stops - first).astype(np.int32)
    for e, (a, b) in enumerate(zip(first, stops, strict=True)):
        closed = bool(np.all(np.isfinite(release[a:b])))
        last = a + int(np.argmax(release[a:b])) if closed else a
        one = bool(np.all(contact[a:b] == contact[a]))
        table["episode_onset_time"][e] = onset[a]
        table["episode_duration"][e] = release[last] - onset[a] if closed else math.nan
        table["episode_impulse"][e] = np.sum(impacts["impact_impulse"][a:b])
        table["episode_peak_force"][e] = np.max(impacts["impact_peak_force"][a:b])
        table["episode_restitution"][e] = (
            -impacts["separation_velocity"][last] / impacts["impact_velocity"][a]
            if closed and one else math.nan)
    if works is not None:
        approach = np.add.reduceat(works[0], first) if count else np.empty(0)
        opening = np.add.reduceat(works[1], first) if count else np.empty(0)
        closed = np.isfinite(table["episode_duration"])
        table["episode_energetic_restitution"] = np.where(
            closed & (approach > 0), np.sqrt(opening / np.where(approach > 0, approach, 1.0)),
            np.nan)
    return table


def _contact_episodes(impacts: dict[str, np.ndarray], separation: float,
                      works: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Each contact's own episodes (its contacts alone, `episode_labels`), in order of onset.

    The ``episode_*`` columns and ``episode_contact`` (which contact).
    """
    tables = []
    for j in np.unique(impacts["impact_contact"]):
        mine = impacts["impact_contact"] == j
        own = {name: values[mine] for name, values in impacts.items()}
        table = _episode_table(own, episode_labels(own, separation),
                               None if works is None else works[:, mine])
        table["episode_contact"] = np.full(table["episode_onset_time"].size, j, dtype=np.int64)
        tables.append(table)
    if not tables:
        return {**_episode_table(impacts, np.zeros(0, dtype=np.int64), works),
                "episode_contact": np.zeros(0, dtype=np.int64)}
    table = {name: np.concatenate([each[name] for each in tables]) for name in tables[0]}
    order = np.argsort(table["episode_onset_time"], kind="stable")
    return {name: values[order] for name, values in table.items()}


_PANELS_PER_HALF_PERIOD = 4  # Gauss panels per half period of the fastest mode in contact


def _contact_works(packed: PackedContacts, run: ContactRun, impacts: dict[str, np.ndarray],
                   ) -> np.ndarray:
    """Each released contact's work (J) of R_j on its physical gap: rows approach, opening.

    R_j g_j' split by its sign (g_j the contact's physical gap, whose rate has the closed
    forces' rates through the flexibility the modes miss, ``R_N[j, S] R_S'``), by
    Gauss-Legendre on panels of an eighth of the fastest period of the phases it spans, as one
    contact's (`impactbeams.trajectory.episodes`; the sign change in a panel limits it to
    ~1e-6 relative). 0 for a contact still closed at the end.
    """
    out = np.zeros((2, impacts["impact_onset_time"].size))
    omega = packed.runs[0].params.omega
    for i, (j, t0, duration) in enumerate(zip(impacts["impact_contact"],
                                              impacts["impact_onset_time"],
                                              impacts["impact_duration"], strict=True)):
        if not np.isfinite(duration):
            continue
        t1 = t0 + duration
        spans = np.flatnonzero((run.time < t1) & (np.append(run.time[1:], run.t_end) > t0))
        fastest = max(omega, *(float(np.max(packed.contacts.sets[packed.members[
            packed.set_of_mask[run.mask[k]]]].frequencies)) for k in spans))
        panels = max(4, math.ceil(duration * fastest / math.pi * _PANELS_PER_HALF_PERIOD))
        edges = np.linspace(t0, t1, panels + 1)
        half = 0.5 * np.diff(edges)[:, None]
        t = (0.5 * (edges[:-1] + edges[1:])[:, None] + half * _NODES).ravel()
        weights = (half * _WEIGHTS).ravel()
        q, v, mask = sample(packed, run, t)
        forces = contact_quantities(packed, t, q, v, mask)["contact_force"]
        rate = (_modal_gap_rates(packed, t, v)[:, j]
                + force_rates(packed, t, q, v, mask) @ packed.contacts.residual[j])
        power = forces[:, j] * rate
        out[:, i] = -np.sum(weights * np.minimum(power, 0.0)), np.sum(weights
                                                                      * np.maximum(power, 0.0))
    return out


def _bounds(table: dict[str, np.ndarray]) -> np.ndarray:
    """The episodes' onsets, then their ends (s).

    An episode still open at the end has no dissipated energy: its end is its onset again.
    """
    onset = table["episode_onset_time"]
    end = onset + table["episode_duration"]
    return np.concatenate([onset, np.where(np.isfinite(end), end, onset)])


def _dataset(data: dict[str, np.ndarray], impacts: dict[str, np.ndarray],
             joint: dict[str, np.ndarray], own: dict[str, np.ndarray],
             times: np.ndarray) -> xr.Dataset:
    """The Dataset of the series, the contacts and both episode tables."""
    variables = {name: (("time", "contact") if values.ndim == 2 else "time", values,
                        attributes(name)) for name, values in data.items()}
    variables.update({name: ("impact", values, attributes(name))
                      for name, values in impacts.items()})
    if "episode_dissipated_energy" in joint:
        closed = np.isfinite(joint["episode_duration"]), np.isfinite(own["episode_duration"])
        joint["episode_dissipated_energy"] = np.where(closed[0],
                                                      joint["episode_dissipated_energy"], np.nan)
        own["episode_dissipated_energy"] = np.where(closed[1], own["episode_dissipated_energy"],
                                                    np.nan)
    variables.update({name: ("episode", values, attributes(name))
                      for name, values in joint.items()})
    variables.update({"contact_" + name: ("contact_episode", values, attributes("contact_" + name))
                      for name, values in own.items()})
    coords = {"time": ("time", times, attributes("time")),
              "impact": ("impact", np.arange(impacts["impact_onset_time"].size),
                         attributes("impact")),
              "episode": ("episode", np.arange(joint["episode_onset_time"].size),
                          attributes("episode")),
              "contact_episode": ("contact_episode", np.arange(own["episode_onset_time"].size),
                                  attributes("contact_episode")),
              "contact": ("contact", np.arange(data["contact_forces"].shape[1]),
                          attributes("contact"))}
    return xr.Dataset(variables, coords=coords)


def energy_integrals(packed: PackedContacts, run: ContactRun, times: np.ndarray,
                     report: Callable[[float], None] | None = None,
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Work of the drives and dissipation (J) from t = 0 to each of ``times`` (ascending).

    ``report(t)``: called with the time integrated to (s) after each block of nodes.
    """
    edges = np.unique(np.concatenate([run.time, times, [run.t_end]]))
    edges = edges[edges <= run.t_end]
    phase = np.searchsorted(run.time, edges[:-1], side="right") - 1
    fastest = np.array([max(float(np.max(packed.contacts.sets[members].frequencies)),
                            packed.runs[0].params.omega) for members in packed.members])
    width = np.diff(edges)
    panels = np.maximum(1, np.ceil(width * fastest[packed.set_of_mask[run.mask[phase]]]
                                   / math.pi)).astype(np.int64)
    sums = np.zeros((2, width.size))
    first = 0
    while first < width.size:  # blocks of intervals of at most _CHUNK_NODES nodes (or one)
        stop = first + max(1, int(np.searchsorted(np.cumsum(panels[first:]) * _NODES.size,
                                                  _CHUNK_NODES, side="right")))
        sums[:, first:stop] = _interval_integrals(packed, run, edges[first:stop + 1],
                                                  panels[first:stop])
        if report is not None:
            report(float(edges[stop]))
        first = stop
    cumulative = np.concatenate([[[0.0], [0.0]], np.cumsum(sums, axis=1)], axis=1)
    switches = np.searchsorted(edges, run.time[1:])  # the phases' starts among the edges
    jumps = np.zeros(edges.size)
    np.add.at(jumps, switches, _springs_given_up(packed, run))
    cumulative[1] += np.cumsum(jumps)
    at = np.searchsorted(edges, times)
    q, v, mask = sample(packed, run, times)
    forces = contact_quantities(packed, times, q, v, mask)["contact_force"]
    params = packed.runs[0].params
    shift1 = np.array([run_.dynamics.spring.tip_shift1 for run_ in packed.runs])
    tip_force = params.force_amplitude * np.sin(params.omega * times)
    return cumulative[0, at] - tip_force * (forces @ shift1), cumulative[1, at]


def _interval_integrals(packed: PackedContacts, run: ContactRun, edges: np.ndarray,
                        panels: np.ndarray) -> np.ndarray:
    """Integrals (J; rows power, dissipation) over each [edges[i], edges[i + 1]] (one phase).

    On ``panels[i]`` equal panels of 12 Gauss-Legendre nodes each.
    """
    interval = np.repeat(np.arange(panels.size), panels)
    start = np.cumsum(panels) - panels
    half = 0.5 * np.diff(edges)[interval] / panels[interval]
    middle = edges[interval] + (2 * (np.arange(interval.size) - start[interval]) + 1) * half
    t = (middle[:, None] + half[:, None] * _NODES).ravel()
    weights = (half[:, None] * _WEIGHTS).ravel()
    power, dissipation = _powers(packed, run, t)
    out = np.zeros((2, panels.size))
    np.add.at(out[0], np.repeat(interval, _NODES.size), weights * power)
    np.add.at(out[1], np.repeat(interval, _NODES.size), weights * dissipation)
    return out


def _powers(packed: PackedContacts, run: ContactRun, t: np.ndarray,
            ) -> tuple[np.ndarray, np.ndarray]:
    """The drives' power but F s_1 . R' (W, module doc) and the dissipation rate (W) at t."""
    first = packed.runs[0]
    params, table = first.params, first.tables[FREE]
    row = {name: table[TABLE_ROWS.index(name)] for name in ("frequency", "zeta", "drive",
                                                             "tip1", "base")}
    q, v, mask = sample(packed, run, t)
    forces = contact_quantities(packed, t, q, v, mask)["contact_force"]
    shift1 = np.array([run_.dynamics.spring.tip_shift1 for run_ in packed.runs])
    omega, f0 = params.omega, params.force_amplitude
    force, force_rate = f0 * np.sin(omega * t), f0 * omega * np.cos(omega * t)
    tip_rate = (-first.settings["c1"] * first.phase_scalars[FREE, SCALAR_LOAD_RATE] * force_rate
                + v @ row["tip1"])
    power = -force * tip_rate + force_rate * (forces @ shift1)
    modal_rate = v - force_rate[:, None] * row["drive"]
    dissipation = modal_rate**2 @ (2.0 * row["zeta"] * row["frequency"])
    if params.base_amplitude != 0.0:
        clamp_rate = params.base_amplitude * omega * np.cos(omega * t)
        clamp_acceleration = -omega**2 * params.base_amplitude * np.sin(omega * t)
        push = np.array([run_.settings["side"] * (run_.settings["shaker1"]
                                                  - run_.settings["shaker2"])
                         for run_ in packed.runs])
        power -= clamp_acceleration * (modal_rate @ row["base"]) + clamp_rate * (forces @ push)
    if packed.contacts.damping.any():
        rates = _modal_gap_rates(packed, t, v)
        for a, members in enumerate(packed.members):
            rows = np.flatnonzero(packed.set_of_mask[mask] == a)
            if members and rows.size:
                gap_rates = rates[np.ix_(rows, list(members))]
                dissipation[rows] += np.einsum("ki,ij,kj->k", gap_rates,
                                               packed.contacts.sets[members].effective_damping,
                                               gap_rates)
    return power, dissipation


def _springs_given_up(packed: PackedContacts, run: ContactRun) -> np.ndarray:
    """At each switch, the closed springs' energy before minus after it at the same state (J).

    0 to round-off without dashpots (a contact closes and opens with zero force).
    """
    t, q, v = run.time[1:], run.q[1:], run.v[1:]
    before = contact_quantities(packed, t, q, v, run.mask[:-1])["contact_energy"]
    after = contact_quantities(packed, t, q, v, run.mask[1:])["contact_energy"]
    return before - after
