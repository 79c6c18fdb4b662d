"""Several contacts closed at once: the run's packed phases, the run, and its samples.

`pack_contacts` packs one run of ``Params.contacts`` for `impactbeams.kernels.several_contacts`:
every active set's contact phase (`impactbeams.contact.active_sets`), and in each one event
function per contact (its force if closed, its physical gap if open) as oscillators of the
single contact's contact-phase layout, then (functions n + f) each open contact's force in the
set with it added, negated, which a dashpot's early release follows. The free drive, the gaps'
clearances and harmonic parts come from each contact's own packed run (`Params.each_contact`),
which share the free phase.

In active set S, with each contact's modal gap g_j = Delta_j + Im(S_j e^(i Omega t)) + b_j . q,
the active forces are R_S = -K_eff g_S - C_eff g_S', that is const_S = -K_eff Delta_S,
harmonic H_S = -(K_eff + i Omega C_eff) S_S and modal weights ``force_weights``; the modes'
drive is the free one plus B_S (H_S harmonic, const_S constant); an open contact i's physical
gap is g_i + R_N[i, S] R_S.

The phases travel to the kernels as one active sets record (`impactbeams.kernels.records.
ACTIVE_SETS`: a plain tuple of the tables, forces, scalars, modes, drives, lefts, rights and
``set_of_mask`` arrays, read by the indices ``SET_*``), built once per packed run
(`PackedContacts.active_sets`), every array C-contiguous.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from impactbeams.contact.active_sets import SeveralContacts, possible_sets, several_contacts
from impactbeams.contact.spring import polar
from impactbeams.kernels import several_contacts as kernel
from impactbeams.kernels.contact_spring import contact_states, spring_drives, to_contact
from impactbeams.kernels.contacts_tangent import contacts_lyapunov_sums
from impactbeams.kernels.dynamics import EVENT_LIMIT, STATUS_NAMES
from impactbeams.kernels.events import phase_event
from impactbeams.kernels.layout import (
    DRIVE_EQUILIBRIUM,
    FREE,
    PHASE_SCALARS,
    ROW_EVENT,
    ROW_FREQUENCY,
    SCALAR_CONST,
    SCALAR_COSINE,
    SCALAR_SINE,
    TABLE_ROWS,
    TIP_COLUMNS,
    TIP_V1,
    TIP_V2,
    TIP_Y1,
    TIP_Y2,
)
from impactbeams.kernels.records import (
    ACTIVE_SETS,
    SET_DRIVES,
    SET_LEFTS,
    SET_MODES,
    SET_OF_MASK,
    SET_SCALARS,
    SET_TABLES,
)
from impactbeams.kernels.stroboscope import tip_motions as tip_motions_kernel
from impactbeams.longtime import LongTime, response_period, steady_rate
from impactbeams.packing import Packed, pack_run, section_gap
from impactbeams.params import ParameterError

# the per-contact quantities of a run (`episodes`), as `impactbeams.simulate`'s impact table's
IMPACT_COLUMNS = ("impact_onset_time", "impact_duration", "impact_impulse",
                  "impact_peak_force", "impact_velocity", "separation_velocity")
# the statuses of `kernels.several_contacts.run_contacts`
CONTACT_STATUS_NAMES = (*STATUS_NAMES, "impossible_set")


@dataclasses.dataclass(frozen=True)
class PackedContacts:
    """One run of several contacts, packed (layout: `impactbeams.kernels.several_contacts`).

    ``runs``: each contact's own packed run (the free phase, settings, start); ``contacts``:
    the active sets' phases; ``members``: each set's contacts, by the kernels' set index;
    ``active_sets``: the same phases as the kernels take them, the active sets record
    (`impactbeams.kernels.records.ACTIVE_SETS`, fields read by the indices ``SET_*``);
    ``early_release``: whether a contact can open with its gap still closed (a dashpot).
    """

    runs: tuple[Packed, ...]
    contacts: SeveralContacts
    members: tuple[tuple[int, ...], ...]
    active_sets: tuple  # (tables, forces, scalars, modes, drives, lefts, rights, set_of_mask)
    early_release: bool

    @property
    def settings(self) -> np.void:
        """The run's settings record (t_max, search span, forcing frequency)."""
        return self.runs[0].settings

    @property
    def set_of_mask(self) -> np.ndarray:
        """The set index of each bit mask of closed contacts, -1 where no set (int64, 2^n).

        The active sets record's ``SET_OF_MASK`` field.
        """
        return self.active_sets[SET_OF_MASK]

    @property
    def gap_weights(self) -> np.ndarray:
        """Each contact's modal gap weights b_j (rows, m per unit coordinate): its own run's."""
        return np.array([run.tables[FREE, ROW_EVENT] for run in self.runs])

    def tangent_arguments(self) -> tuple:
        """The arguments `kernels.contacts_tangent` takes before a run's phases.

        The active sets record, the settings, whether a dashpot releases early, the gap
        weights and the free modes' frequencies (rad/s; the energy product a renormalisation
        uses).
        """
        return (self.active_sets, self.settings, self.early_release, self.gap_weights,
                self.runs[0].tables[FREE, ROW_FREQUENCY])


def _gap_terms(runs: tuple[Packed, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Each contact's clearance Delta_j (m) and gap harmonic S_j (m, sine + i cosine)."""
    scalars = np.array([run.phase_scalars[FREE] for run in runs])
    return scalars[:, SCALAR_CONST], scalars[:, SCALAR_SINE] + 1j * scalars[:, SCALAR_COSINE]


def _functions(contacts: SeveralContacts, members: tuple[int, ...], runs: tuple[Packed, ...],
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each contact's event function in set ``members``: weights c (n, M), const, harmonic H."""
    phase = contacts.sets[members]
    clearance, harmonic = _gap_terms(runs)
    omega = runs[0].params.omega
    index = list(members)
    const_s = -phase.effective_stiffness @ clearance[index]
    harmonic_s = -(phase.effective_stiffness + 1j * omega * phase.effective_damping
                   ) @ harmonic[index]
    m = phase.eigenvalues.size
    coupling = contacts.residual[:, index]
    weights = contacts.gap_weights @ phase.right[:m] + coupling @ phase.force_weights
    const = clearance + coupling @ const_s
    harmonics = harmonic + coupling @ harmonic_s
    weights[index], const[index], harmonics[index] = phase.force_weights, const_s, harmonic_s
    return weights, const, harmonics


def _would_be_forces(contacts: SeveralContacts, members: tuple[int, ...],
                     runs: tuple[Packed, ...], functions: tuple[np.ndarray, ...],
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each open contact f's -R_f in set ``members`` + f, in set ``members``' modes.

    The force f would have if closed, negated (k g + c g' for one contact): after an early
    release it rises through 0 where R does (`kernels.dynamics.reonset_or_opening`). Weights
    c (n, M), const, harmonic H as `_functions`' (a closed contact's, or one whose set with f
    cannot occur: its row of ``functions``, those of `_functions`, never used).
    """
    weights, const, harmonics = (array.copy() for array in functions)
    clearance, harmonic = _gap_terms(runs)
    omega = runs[0].params.omega
    right = contacts.sets[members].right
    m = right.shape[1]
    for f in set(range(len(runs))) - set(members):
        together = tuple(sorted((*members, f)))
        if together not in contacts.sets:
            continue
        phase = contacts.sets[together]
        index, row = list(together), together.index(f)
        k_row, c_row = phase.effective_stiffness[row], phase.effective_damping[row]
        gaps = contacts.gap_weights[index]
        weights[f] = k_row @ gaps @ right[:m] + c_row @ gaps @ right[m:]
        const[f] = k_row @ clearance[index]
        harmonics[f] = (k_row + 1j * omega * c_row) @ harmonic[index]
    return weights, const, harmonics


def pack_contacts(params, n_modes: int, t_max: float, search_span: float,
                  contacts: SeveralContacts | None = None) -> PackedContacts:
    """Pack a run of ``params``' contacts with ``n_modes`` per beam (t_max, search_span in s).

    ``contacts``: their active sets' phases if built already (`several_contacts` of these
    contacts' geometry, stiffnesses, dashpots and damping ratio: a map's cells share them).
    """
    runs = tuple(pack_run(run, n_modes, t_max, search_span) for run in params.each_contact())
    if contacts is None:
        contacts = several_contacts(params, n_modes)
    members = tuple(possible_sets(params))
    n, m = len(runs), runs[0].q0.size
    set_of_mask = np.full(2**n, -1, dtype=np.int64)
    tables = np.zeros((len(members), 2 * n, len(TABLE_ROWS), m))
    forces = np.empty((len(members), 2 * n, m), dtype=complex)
    scalars = np.empty((len(members), 2 * n, len(PHASE_SCALARS)))
    modes = np.empty((len(members), 2 * n, 2, m), dtype=complex)
    drives = np.empty((len(members), 2 * n, 4, m), dtype=complex)
    lefts = np.empty((len(members), 2 * m, m), dtype=complex)
    rights = np.empty((len(members), m, 2 * m), dtype=complex)
    free_drive, omega = runs[0].forces[FREE], runs[0].params.omega
    weights_b = contacts.gap_weights
    for a, active in enumerate(members):
        set_of_mask[sum(1 << j for j in active)] = a
        phase = contacts.sets[active]
        lefts[a], rights[a] = phase.left.T, phase.right.T
        functions = _functions(contacts, active, runs)
        weights, const, harmonic = functions
        index = list(active)
        set_harmonic = free_drive + weights_b[index].T @ harmonic[index]
        set_constant = weights_b[index].T @ const[index]
        weights, const, harmonic = (np.concatenate(pair) for pair in zip(
            functions, _would_be_forces(contacts, active, runs, functions), strict=True))
        for f in range(2 * n):
            rho, magnitude = polar(weights[f])
            modes[a, f] = phase.eigenvalues, rho
            drives[a, f] = spring_drives(lefts[a], modes[a, f], set_harmonic, set_constant,
                                         omega, forces[a, f])
            tables[a, f, TABLE_ROWS.index("frequency")] = phase.frequencies
            tables[a, f, TABLE_ROWS.index("zeta")] = (-phase.eigenvalues.real
                                                      / phase.frequencies)
            tables[a, f, TABLE_ROWS.index("event")] = magnitude
            scalars[a, f] = (const[f] + magnitude @ drives[a, f, DRIVE_EQUILIBRIUM].real,
                             harmonic[f].real, harmonic[f].imag, 1.0)
    fields = {"tables": tables, "forces": forces, "scalars": scalars, "modes": modes,
              "drives": drives, "lefts": lefts, "rights": rights, "set_of_mask": set_of_mask}
    return PackedContacts(runs, contacts, members, tuple(fields[name] for name in ACTIVE_SETS),
                          bool(np.any(contacts.damping > 0.0)))


@dataclasses.dataclass(frozen=True)
class ContactRun:
    """A recorded run of several contacts (`kernels.several_contacts.run_contacts`).

    Phase k starts at ``time[k]`` (s) with the contacts of bit mask ``mask[k]`` closed, in
    the free state (q[k], v[k]), after contact ``switched[k]`` switched (-1: the start);
    ``impulses[k, f]`` (N s), ``peaks[k, f]`` (N): closed contact f's over the phase.
    """

    time: np.ndarray
    mask: np.ndarray
    switched: np.ndarray
    q: np.ndarray
    v: np.ndarray
    impulses: np.ndarray
    peaks: np.ndarray
    status: str
    t_end: float

    def arrays(self) -> tuple[np.ndarray, ...]:
        """(time, mask, switched, q, v): the phases as `kernels.contacts_tangent` reads them."""
        return self.time, self.mask, self.switched, self.q, self.v


# phases per kernel call of a run that reports its progress (it resumes at its last phase)
PROGRESS_WINDOW = 512


def run_contacts(packed: PackedContacts, max_phases: int,
                 start: tuple[np.ndarray, np.ndarray, int] | None = None,
                 report: Callable[[float, int], None] | None = None) -> ContactRun:
    """Run ``packed`` from ``start`` to t_max; at most ``max_phases`` phases.

    ``start``: the free state (q, q') at t = 0 and the bit mask of the contacts closed then
    (default: rest or the uplifts, all contacts open). ``report(t, phases)``: called after each
    window of ``PROGRESS_WINDOW`` phases with the time reached (s); the run is resumed at its
    last recorded phase, whose search the kernel repeats: the same bits as one call.
    """
    n, m = len(packed.runs), packed.runs[0].q0.size
    recorded = (np.empty(max_phases), np.empty(max_phases, dtype=np.int64),
                np.empty(max_phases, dtype=np.int64), np.empty((max_phases, m)),
                np.empty((max_phases, m)), np.empty((max_phases, n)), np.empty((max_phases, n)))
    q, v, mask = (packed.runs[0].q0, packed.runs[0].v0, 0) if start is None else start
    t, early, first = 0.0, 0, 0
    window = max_phases if report is None else PROGRESS_WINDOW
    while True:
        stop = min(first + window, max_phases)
        switched = recorded[2][first]
        count, status, t_end = kernel.resume_contacts(
            packed.active_sets, packed.settings, packed.early_release, q, v, t, mask, early,
            tuple(array[first:stop] for array in recorded))
        if first:  # the resumed phase's own switch, as first recorded
            recorded[2][first] = switched
        count += first
        if status != EVENT_LIMIT or stop == max_phases or report is None:
            break
        first = count - 1
        q, v, t, mask = recorded[3][first], recorded[4][first], recorded[0][first], int(
            recorded[1][first])
        early = _early_releases(packed, recorded[1][:first + 1], recorded[2][:first + 1])
        report(float(t), first)
    if report is not None:
        report(float(t_end), count)
    return ContactRun(*(array[:count] for array in recorded), CONTACT_STATUS_NAMES[status],
                      float(t_end))


def _early_releases(packed: PackedContacts, masks: np.ndarray, switched: np.ndarray) -> int:
    """The bit mask of the contacts released early at the last of these recorded phases.

    As the kernel keeps it: with dashpots, a contact whose last switch was its release (its
    gap may still be closed; the kernel clears the bit again where it finds the gap open).
    """
    if not packed.early_release:
        return 0
    n, early = len(packed.runs), 0
    for mask, f in zip(masks[1:], switched[1:], strict=True):
        contact = f % n
        released = f < n and not (mask >> f) & 1
        early = early | (1 << contact) if released else early & ~(1 << contact)
    return early


def sample(packed: PackedContacts, run: ContactRun, times: np.ndarray,
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Free states (q, v) at ``times`` (s, ascending, <= the run's end) and each one's mask."""
    times = np.ascontiguousarray(times, dtype=float)
    q, v = np.empty((times.size, run.q.shape[1])), np.empty((times.size, run.q.shape[1]))
    kernel.sample_contacts(packed.active_sets, packed.settings, run.time, run.mask, run.q,
                           run.v, times, q, v)
    phase = np.searchsorted(run.time, times, side="right") - 1
    return q, v, run.mask[phase]


def contacts_start(packed: PackedContacts, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The run's start from the free state z = (q, q') at t = 0: (q, q', closed contacts' mask).

    The contacts closed are the set S whose forces R_S = -K_S g_S - C_S g_S' are all > 0 while
    every other contact's physical gap is >= 0 (as one contact starts closed iff g < 0 and
    R > 0); the smallest such set (without dashpots there is one). A state that no set
    fits (a contact overlapping while its force would pull) is refused (ParameterError).
    """
    modal = np.array([section_gap(run, z) for run in packed.runs])
    gaps, rates = modal[:, 0], modal[:, 1]
    for members in packed.members:
        index = list(members)
        phase = packed.contacts.sets[members]
        forces = -phase.effective_stiffness @ gaps[index] - phase.effective_damping @ rates[index]
        physical = gaps + packed.contacts.residual[:, index] @ forces
        others = [j for j in range(len(packed.runs)) if j not in members]
        if np.all(forces > 0.0) and np.all(physical[others] >= 0.0):
            m = z.size // 2
            return z[:m].copy(), z[m:].copy(), sum(1 << j for j in members)
    raise ParameterError(
        f"initial_state is not allowed: no set of closed contacts fits it (modal gaps "
        f"{gaps.tolist()!r} m, rates {rates.tolist()!r} m/s: a contact overlaps while its "
        "force would pull); start from an open state or an earlier run's end")


def gap_rate(packed: PackedContacts, mask: int, contact: int, q: np.ndarray, v: np.ndarray,
             t: float) -> float:
    """The rate (m/s) of open ``contact``'s physical gap in the phase of ``mask`` at (q, v, t)."""
    sets, a = packed.active_sets, packed.set_of_mask[mask]
    m = q.size
    y, y_rate = np.empty(m), np.empty(m)
    to_contact(q, v, t, sets[SET_LEFTS][a], sets[SET_MODES][a, contact],
               sets[SET_DRIVES][a, contact], packed.settings["forcing_frequency"], y, y_rate)
    _, rate = phase_event(sets[SET_TABLES][a, contact], sets[SET_SCALARS][a, contact], y,
                          y_rate, t, packed.settings["forcing_frequency"])
    return float(rate)


def _modal_gap_rates(packed: PackedContacts, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each contact's modal gap rate g_j' (m/s) at the free velocities v, shape (k, n)."""
    omega = packed.settings["forcing_frequency"]
    out = np.empty((t.size, len(packed.runs)))
    for j, run in enumerate(packed.runs):
        scalars = run.phase_scalars[FREE]
        out[:, j] = (omega * (scalars[SCALAR_SINE] * np.cos(omega * t)
                              - scalars[SCALAR_COSINE] * np.sin(omega * t))
                     + v @ run.tables[FREE, TABLE_ROWS.index("event")])
    return out


def contact_quantities(packed: PackedContacts, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                       mask: np.ndarray) -> dict[str, np.ndarray]:
    """Each contact's modal gap, force (N) and physical gap (m), and the contacts' energy (J).

    Shapes (k, n) and (k,): the closed contacts' forces are R_S = -K_eff g_S - C_eff g_S'
    (their modal gaps g_S and rates), the energy ``g_S^T K_eff g_S / 2`` (the springs' and
    the flexibility the modes miss, in series).
    """
    n, k = len(packed.runs), t.size
    modal = np.empty((k, n))
    states = np.empty((k, 3))
    phases = np.full(k, FREE, dtype=np.int64)
    for j, run in enumerate(packed.runs):
        contact_states(run.tables, run.forces, run.phase_scalars, run.settings, phases, t, q, v,
                       states)
        modal[:, j] = states[:, 0]
    rates = _modal_gap_rates(packed, t, v) if packed.early_release else None
    force, gap, energy = np.zeros((k, n)), modal.copy(), np.zeros(k)
    for a, active in enumerate(packed.members):
        rows = np.flatnonzero(packed.set_of_mask[mask] == a)
        if not active or not rows.size:
            continue
        phase, index = packed.contacts.sets[active], list(active)
        force[np.ix_(rows, index)] = -modal[np.ix_(rows, index)] @ phase.effective_stiffness
        if rates is not None:
            force[np.ix_(rows, index)] -= rates[np.ix_(rows, index)] @ phase.effective_damping
        gap[rows] += force[rows][:, index] @ packed.contacts.residual[:, index].T
        energy[rows] = 0.5 * np.einsum("ki,ij,kj->k", modal[np.ix_(rows, index)],
                                       phase.effective_stiffness, modal[np.ix_(rows, index)])
    return {"modal_gap": modal, "contact_force": force, "gap": gap, "contact_energy": energy}


def episodes(packed: PackedContacts, run: ContactRun) -> dict[str, list[float]]:
    """Each contact episode of ``run`` (onset to release of one contact), in order of onset.

    One still closed at the run's end has a NaN duration and separation velocity, one closed
    at its start (``simulate``'s ``initial_state``) its start as onset and a NaN impact velocity.

    ``impact_contact`` and the columns of ``IMPACT_COLUMNS``: the impulse and peak force over
    the phases it spans, the gap's rates at its onset and after its release (m/s).
    """
    rows: dict[str, list[float]] = {name: [] for name in ("impact_contact", *IMPACT_COLUMNS)}
    open_rows: dict[int, int] = {}
    for f in range(len(packed.runs)):
        if (run.mask[0] >> f) & 1:  # closed at the start
            open_rows[f] = len(rows["impact_contact"])
            for name, value in zip(("impact_contact", *IMPACT_COLUMNS),
                                   (f, run.time[0], math.nan, 0.0, 0.0, math.nan, math.nan),
                                   strict=True):
                rows[name].append(value)
    for k in range(1, run.time.size):
        f = int(run.switched[k])
        if f >= len(packed.runs):  # a gap opened after an early release: no switch
            continue
        if (run.mask[k] >> f) & 1:  # an onset: the gap's rate in the phase before
            open_rows[f] = len(rows["impact_contact"])
            rate = gap_rate(packed, run.mask[k - 1], f, run.q[k], run.v[k], run.time[k])
            for name, value in zip(("impact_contact", *IMPACT_COLUMNS),
                                   (f, run.time[k], math.nan, 0.0, 0.0, rate, math.nan),
                                   strict=True):
                rows[name].append(value)
        else:
            row = open_rows.pop(f)
            rows["impact_duration"][row] = run.time[k] - rows["impact_onset_time"][row]
            rows["separation_velocity"][row] = gap_rate(packed, run.mask[k], f, run.q[k],
                                                        run.v[k], run.time[k])
    for k in range(run.time.size):  # each phase's share of its closed contacts' episodes
        for f in range(len(packed.runs)):
            if (run.mask[k] >> f) & 1:
                row = _episode_row(rows, f, run.time[k])
                rows["impact_impulse"][row] += run.impulses[k, f]
                rows["impact_peak_force"][row] = max(rows["impact_peak_force"][row],
                                                     run.peaks[k, f])
    return rows


def _episode_row(rows: dict[str, list[float]], contact: int, t: float) -> int:
    """The row of ``contact``'s episode that is closed at time t (its last onset <= t)."""
    return max(i for i, (f, onset) in enumerate(zip(rows["impact_contact"],
                                                    rows["impact_onset_time"], strict=True))
               if f == contact and onset <= t)


def cell_observables(params, n_modes: int, t_max: float, max_phases: int, dynamics: bool = True,
                     long_time: LongTime | None = None, transient_periods: int = 0,
                     contacts: SeveralContacts | None = None, lyapunov: bool = False,
                     start: Callable[[PackedContacts], tuple[np.ndarray, np.ndarray, int]]
                     | None = None) -> dict[str, object]:
    """A map cell of several contacts: its runs' observables, as `simulate` makes the runs.

    ``dynamics``: the run over [0, t_max] (s) summarised (`summarize`); ``lyapunov``: that
    run's largest Lyapunov exponent after ``transient_periods`` (`largest_exponent`);
    ``long_time``: the run over (transient + sampled) forcing periods and its long-time values
    (`long_time_values`, the episode separation a quarter period of the slowest free mode, as
    a single contact's map), ``dynamics_status`` then the worse of the two runs'
    (``first_contact`` the long run's without the other), and its end state z = (q, q') as
    ``final_displacement``, ``final_velocity`` (`impactbeams.simulate`'s; NaN where the run
    stopped early). n_modes per beam, from rest or the uplifts (the long run from
    ``start(packed)``'s state and closed contacts if given: a stepped sweep's), the search
    span the run's horizon, at most ``max_phases`` phases per run; ``contacts``: the active
    sets' phases, if built already.
    """
    out: dict[str, object] = {}
    if dynamics or lyapunov:
        packed = pack_contacts(params, n_modes, t_max, t_max, contacts)
        run = run_contacts(packed, max_phases)
        out.update(summarize(packed, run, t_max))
        if lyapunov:
            out["lyapunov_exponent"] = largest_exponent(packed, run, transient_periods)
    if long_time is not None:
        horizon = float(long_time.horizon(params.omega, transient_periods))
        packed = pack_contacts(params, n_modes, horizon, horizon, contacts)
        run = run_contacts(packed, max_phases, None if start is None else start(packed))
        summary = summarize(packed, run, horizon)
        out.setdefault("first_contact", summary["first_contact"])
        status = summary["dynamics_status"]
        impacts = {name: np.array(values) for name, values in episodes(packed, run).items()}
        separation = 0.5 * math.pi / float(np.min(packed.runs[0].dynamics.free.frequencies))
        out.update(long_time_values(packed, run, impacts, long_time, transient_periods,
                                    separation))
        out["dynamics_status"] = max(status, out.get("dynamics_status", 0))
        end = (np.concatenate(sample(packed, run, np.array([run.t_end]))[:2], axis=1)[0]
               if run.status == "complete" else np.full(2 * run.q.shape[1], math.nan))
        out["final_displacement"], out["final_velocity"] = np.split(end, 2)
    return out


def largest_exponent(packed: PackedContacts, run: ContactRun, transient_periods: int) -> float:
    """The largest Lyapunov exponent (1/s) of a recorded run, NaN without a complete period.

    Averaged over the renormalisation intervals after ``transient_periods`` (as
    `impactbeams.simulate`'s ``lyapunov``, `kernels.contacts_tangent.contacts_lyapunov_sums`).
    """
    sums, counts, interval = contacts_lyapunov_sums(*packed.tangent_arguments(), run.arrays(),
                                                    run.t_end, 1, transient_periods, 1)
    periods = int(counts.sum())
    return float(sums[0, 0] / (periods * interval)) if periods else math.nan


def summarize(packed: PackedContacts, run: ContactRun, t_max: float) -> dict[str, float]:
    """A run's map observables, as a single contact's map gives them (`kernels.reductions`).

    ``first_impact_time`` (s, NaN without any) and ``first_contact`` (its contact, -1);
    ``impact_count``: every contact's onsets; ``max_contact_force`` (N, 0 without any);
    ``mean_restitution``: the separation speeds over the approach speeds of the contacts that
    closed with an approach and separated (NaN if none); ``contact_fraction``: the time with
    any contact closed over t_max (s); ``contact_impact_count``, ``contact_max_force``: each
    contact's onsets and largest force (N); ``dynamics_status``: the run's status code.
    """
    if run.status not in STATUS_NAMES:
        raise RuntimeError(f"the run of several contacts stopped at t = {run.t_end!r} s: "
                           f"status {run.status!r}; please report this as a bug")
    rows = {name: np.array(values, dtype=float) for name, values in episodes(packed, run).items()}
    approach, separation = rows["impact_velocity"], rows["separation_velocity"]
    counted = (approach < 0.0) & np.isfinite(separation)
    approach_sum = -float(np.sum(approach[counted]))
    closed = run.mask != 0
    durations = np.append(run.time[1:], run.t_end) - run.time
    count = rows["impact_onset_time"].size
    return {
        "first_impact_time": rows["impact_onset_time"][0] if count else math.nan,
        "first_contact": int(rows["impact_contact"][0]) if count else -1,
        "impact_count": count,
        "max_contact_force": float(np.max(rows["impact_peak_force"])) if count else 0.0,
        "mean_restitution": (float(np.sum(separation[counted])) / approach_sum
                             if approach_sum > 0.0 else math.nan),
        "contact_fraction": float(np.sum(durations[closed])) / t_max,
        "contact_impact_count": np.bincount(rows["impact_contact"].astype(np.int64),
                                            minlength=len(packed.runs)),
        "contact_max_force": np.array([np.max(rows["impact_peak_force"][
            rows["impact_contact"] == j], initial=0.0) for j in range(len(packed.runs))]),
        "dynamics_status": STATUS_NAMES.index(run.status),
    }


def episode_labels(impacts: dict[str, np.ndarray], separation: float) -> np.ndarray:
    """The episode of each contact (in order of onset) of several contacts' ``impacts``.

    A contact opens a new episode unless its onset follows the latest release before it by
    less than ``separation`` (s); one still closed at the end holds its episode open. For one
    contact's contacts, `impactbeams.trajectory.episodes.episode_labels`.
    """
    onset = impacts["impact_onset_time"]
    release = np.nan_to_num(onset + impacts["impact_duration"], nan=math.inf)
    labels = np.zeros(onset.size, dtype=np.int64)
    latest = -math.inf
    for k in range(onset.size):
        labels[k] = labels[k - 1] + (not onset[k] - latest < separation) if k else 0
        latest = max(latest, release[k])
    return labels


def force_rates(packed: PackedContacts, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                mask: np.ndarray) -> np.ndarray:
    """Each closed contact's force rate R_j' (N/s) at the sampled free states, shape (k, n).

    The rate of its event function in the phase (its force there, `gap_rate`'s oscillators):
    with dashpots R' = -K_e g' - C_e g'' needs the gaps' accelerations, which these hold.
    """
    out = np.zeros((t.size, len(packed.runs)))
    for k in np.flatnonzero(mask != 0):
        for f in range(len(packed.runs)):
            if (mask[k] >> f) & 1:
                out[k, f] = gap_rate(packed, int(mask[k]), f, q[k], v[k], float(t[k]))
    return out


def tip_motions(packed: PackedContacts, t: np.ndarray, q: np.ndarray, v: np.ndarray,
                mask: np.ndarray, forces: np.ndarray) -> dict[str, np.ndarray]:
    """The tips' deflections (m) and velocities (m/s) at the sampled states, as `simulate` gives.

    The free phase's (`impactbeams.trajectory.observables`' formula, the kernels') plus what
    the closed ``forces`` (N, shape (k, n)) move each tip through the flexibility the modes
    miss, ``+s_1 . R`` on beam 1 and ``-s_2 . R`` on beam 2 (and their rates).
    """
    first = packed.runs[0]
    tips = np.empty((t.size, len(TIP_COLUMNS)))
    tip_motions_kernel(first.tables, first.forces, first.phase_scalars, first.settings,
                       np.full(t.size, FREE, dtype=np.int64), np.ascontiguousarray(t),
                       np.ascontiguousarray(q), np.ascontiguousarray(v), tips)
    shift1 = np.array([run.dynamics.spring.tip_shift1 for run in packed.runs])
    shift2 = np.array([run.dynamics.spring.tip_shift2 for run in packed.runs])
    rates = force_rates(packed, t, q, v, mask)
    return {"tip_deflection_1": tips[:, TIP_Y1] + forces @ shift1,
            "tip_deflection_2": tips[:, TIP_Y2] - forces @ shift2,
            "tip_velocity_1": tips[:, TIP_V1] + rates @ shift1,
            "tip_velocity_2": tips[:, TIP_V2] - rates @ shift2}


def long_time_values(packed: PackedContacts, run: ContactRun, impacts: dict[str, np.ndarray],
                     long_time: LongTime, transient_periods: int, separation: float,
                     ) -> dict[str, np.ndarray | float]:
    """The long-time observables of a run of several contacts (`impactbeams.longtime`).

    The tips at the stroboscopic samples (``poincare_deflection2`` is beam 2's tip itself, as
    several contacts' ``tip_deflection_2``: 0 against stops), their response period, and the
    contacts (every contact's onsets) and episodes of all contacts together (`episode_labels`
    with ``separation``, s) per second in the sampled window.
    """
    omega = packed.runs[0].params.omega
    times = long_time.sample_times(omega, transient_periods)
    reached = times[times <= run.t_end]
    q, v, mask = sample(packed, run, reached)
    forces = contact_quantities(packed, reached, q, v, mask)["contact_force"]
    motions = tip_motions(packed, reached, q, v, mask, forces)
    tips = [np.concatenate([motions[name], np.full(times.size - reached.size, np.nan)])
            for name in ("tip_deflection_1", "tip_deflection_2", "tip_velocity_1",
                         "tip_velocity_2")]
    start, end = times[0], long_time.horizon(omega, transient_periods)
    onsets = impacts["impact_onset_time"]
    episode_onsets = onsets[np.flatnonzero(np.diff(episode_labels(impacts, separation),
                                                   prepend=-1))]

    def rate(events: np.ndarray) -> float:
        count = np.count_nonzero((events >= start) & (events < end))
        return float(steady_rate(count, start, end, run.t_end))

    return {"poincare_deflection1": tips[0], "poincare_deflection2": tips[1],
            "poincare_velocity1": tips[2], "poincare_velocity2": tips[3],
            "response_period": int(response_period(*tips, omega, long_time.period_tolerance,
                                                   long_time.max_period)),
            "steady_impact_rate": rate(onsets), "steady_episode_rate": rate(episode_onsets)}
