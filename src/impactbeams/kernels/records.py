"""Named kernel records: groups of arrays that always travel together, with one allocator each.

Numba compiles a ``collections.namedtuple`` of arrays and scalars in nopython mode, its
fields read by name; Python code gets the same namedtuple back. SI units.

Hot kernels read a record's array fields in place (``oscillators.zeta[j]``) and pass the
record on whole; they do not bind an array field to a local name or pass it on loose. Numba
increfs every array variable where it is defined and decrefs it where it dies (NRT_incref /
NRT_decref: an atomic update each), and its reference-count pruning removes a pair only
within a basic block or a simple branch: an array variable that lives across a call or a
loop keeps its pair, paid on every call of the kernel. A field read in place is a temporary
that dies in its own block, and its pair is pruned; a local bound to a field is one more
array variable (measured on the event searches: +4% on a Fig. 5a map by columns when `walk`
bound its four array fields, +26% with the per-step kernels binding theirs too).

* `Segments`: the recorded phases of a run as `impactbeams.kernels.dynamics.run_events`
  fills them; segment k starts at ``time[k]`` (s) in ``phase[k]`` (``sustained[k]``: a contact
  entered by the accumulation rule) in state ``q[k], v[k]`` and ends in ``end_q[k], end_v[k]``.
  Allocated by `segments` only; the kernels that read a run's recorded segments take them as
  one record holding those segments alone (`recorded_prefix` of a larger allocation).
* `RunInputs`: one run's inputs (`impactbeams.kernels.forcing.run_inputs`), with the
  settings as their one-element array, see `RunInputs`.
* `Oscillators`: a phase's modes as driven oscillators, ``q'' + 2 zeta omega q' + omega^2 q =
  Im(A e^(i Omega t))``: ``frequencies`` omega (rad/s) and ``zeta`` per mode, ``force`` their
  complex drive amplitudes A, ``forcing_frequency`` Omega (rad/s)
  (`impactbeams.kernels.propagation.advance`).
* `EventFunction`: ``e(t) = const + Im(sine_amp e^(i Omega t)) + weights . q(t)``, the
  functional whose roots the searches of `impactbeams.kernels.events` locate; ``sine_amp`` a
  float (a sine alone) or a complex (sine + i cosine), ``forcing_frequency`` Omega (rad/s).
* `Rotor`: the arrays of an event function's rotor (`impactbeams.kernels.rotor`), and the
  work arrays of the search that uses it (the state and drives with the steady states split off).
* the switching record: a plain tuple, not a namedtuple (see `SWITCHING`).
* the active sets record: a run of several contacts' phases, a plain tuple (see `ACTIVE_SETS`).
* `Tangent`: the tangent vectors of a run and Benettin's sums
  (`impactbeams.kernels.tangent.carry_tangents`); ``clock[CLOCK_TIME]`` is the time (s) the
  tangents are at, ``clock[CLOCK_RENORMALIZATIONS]`` the renormalisations done.
"""

from collections import namedtuple

import numpy as np

from impactbeams.kernels.jit import kernel

Segments = namedtuple("Segments", ("time", "phase", "sustained", "q", "v", "end_q", "end_v"))

RunInputs = namedtuple("RunInputs", ("tables", "forces", "phase_scalars", "settings_array", "q0",
                                     "v0", "switching"))
RunInputs.__doc__ = """One run's inputs; ``settings_array`` holds its settings record,
``switching`` its switching record (`SWITCHING`).

The record ``settings_array[0]`` is a view that does not keep its array alive, and Numba
frees an array after its last use in the frame that owns it: a kernel that built a RunInputs
passes it on whole, and only a kernel that received it as an argument (whose caller holds it
for the whole call) reads ``run.settings_array[0]``. `impactbeams.kernels.cells` does both.
"""

Oscillators = namedtuple("Oscillators", ("frequencies", "zeta", "force", "forcing_frequency"))

EventFunction = namedtuple("EventFunction", ("weights", "const", "sine_amp", "forcing_frequency"))

Rotor = namedtuple("Rotor", ("amplitudes", "eigenvalues", "driven", "levels", "factors", "rates",
                             "split", "split_force"))

# The switching record: the state machine's switching arrays of one run, those of its contact
# law, whichever it is, as the plain tuple (overlap, shifts, spring, drives), its fields read by
# the indices ``SWITCH_*`` (Numba freezes a module's ints: ``switching[SWITCH_SPRING]`` is a
# static getitem). The tied law's ``overlap`` (M, M) = <Z_m, Y_n> and static ``shifts`` (rows
# ``FREE``, ``CONTACT``; `impactbeams.kernels.contact_tied`), the spring law's ``spring`` =
# (left, right, modes) and its per-run mode ``drives`` (`impactbeams.kernels.contact_spring`);
# the other law's arrays are zeros of the same size, or empty (drives); every array
# C-contiguous, so that each kernel has one signature whoever built the record. A geometry's
# record (`impactbeams.packing.dynamics_arrays`) has empty drives;
# `impactbeams.kernels.forcing.run_inputs` returns the run's, with its drives. Only
# `impactbeams.kernels.contact` and the law modules it dispatches to (and `run_inputs`, which
# builds it) read its fields; every other kernel passes it on whole. A plain tuple, not a
# namedtuple: a kernel's call from Python with a namedtuple argument took 0.7 us more than with
# a plain tuple (measured on the namedtuple version); the plain tuple's cold compiles and calls
# against main's with the arrays loose: CHANGELOG.md, issue 33.
SWITCHING = ("overlap", "shifts", "spring", "drives")
SWITCH_OVERLAP, SWITCH_SHIFTS, SWITCH_SPRING, SWITCH_DRIVES = range(len(SWITCHING))
# A map's geometries' switching records stacked field by field (index g: geometry g's), flat,
# the spring arrays a field each: a parallel map's loop takes the fields of a record it receives
# as arguments of their own, and an array may be one, a tuple of arrays may not (Numba's parfor
# lowering: "scalar type UniTuple(...) given for non scalar argument"). `geometry_switching`
# takes one out.
STACKED_SWITCHING = ("overlap", "shifts", "left", "right", "modes", "drives")

# The active sets record: the contact phases of a run of several contacts, one per active set
# (the contacts closed together), as the plain tuple (tables, forces, scalars, modes, drives,
# lefts, rights, set_of_mask), its fields read by the indices ``SET_*`` as the switching
# record's. Set a's event function f (contact f's force if closed, its physical gap if open;
# n + f: the force open contact f would have with it added, negated) is the oscillators of
# ``tables[a, f]`` (rows of `impactbeams.kernels.layout.TABLE_ROWS`), ``forces[a, f]`` (their
# drive amplitudes A, complex), ``scalars[a, f]`` (`layout.PHASE_SCALARS`), ``modes[a, f]``
# (eigenvalues and the function's phases rho) and ``drives[a, f]`` (the set's mode drives,
# `layout.SPRING_DRIVE_ROWS`); ``lefts[a]``, ``rights[a]`` are the set's change of coordinates
# between the free coordinates and its complex modes, and ``set_of_mask[mask]`` the set of a
# bit mask of closed contacts (-1: one that cannot occur). Built once per packed run
# (`impactbeams.active_phases.pack_contacts`), every array C-contiguous, so that each kernel
# has one signature; every kernel of several contacts (`impactbeams.kernels.several_contacts`,
# `impactbeams.kernels.contacts_tangent`) takes it as one argument, ``sets``, reads its fields
# in place and hands the single contact's kernels one set's arrays.
ACTIVE_SETS = ("tables", "forces", "scalars", "modes", "drives", "lefts", "rights",
               "set_of_mask")
(SET_TABLES, SET_FORCES, SET_SCALARS, SET_MODES, SET_DRIVES, SET_LEFTS, SET_RIGHTS,
 SET_OF_MASK) = range(len(ACTIVE_SETS))

Tangent = namedtuple("Tangent", ("q", "v", "clock", "sums", "counts"))
CLOCK = ("time", "renormalizations")
CLOCK_TIME, CLOCK_RENORMALIZATIONS = range(len(CLOCK))


@kernel
def segments(capacity, n_coords):
    """Empty `Segments` for ``capacity`` segments of ``n_coords`` coordinates."""
    return Segments(np.empty(capacity), np.empty(capacity, dtype=np.int64),
                    np.empty(capacity, dtype=np.bool_), np.empty((capacity, n_coords)),
                    np.empty((capacity, n_coords)), np.empty((capacity, n_coords)),
                    np.empty((capacity, n_coords)))


@kernel
def recorded_prefix(recorded, count):
    """The first ``count`` segments of `Segments` ``recorded``, as views."""
    return Segments(recorded.time[:count], recorded.phase[:count], recorded.sustained[:count],
                    recorded.q[:count], recorded.v[:count], recorded.end_q[:count],
                    recorded.end_v[:count])


@kernel
def geometry_switching(stacked, g):
    """Geometry ``g``'s switching record of a map's stacked records ``stacked`` (views)."""
    overlap, shifts, left, right, modes, drives = stacked
    return overlap[g], shifts[g], (left[g], right[g], modes[g]), drives[g]
