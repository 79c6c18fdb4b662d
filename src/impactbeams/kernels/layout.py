"""Named rows, columns and fields of every kernel array: the contract between packing and kernels.

`impactbeams.packing` fills the arrays by these names and the kernels read them by these
names; nobody writes a bare offset. Each group of indices is unpacked next to its tuple of
names. Units: SI throughout.

Phase tables, ``tables[phase, row, mode]`` (one geometry; ``FREE = 0``, ``CONTACT = 1``; a
first-impact map packs the free phase alone), rows ``TABLE_ROWS``:

* ``frequency``: natural frequencies (rad/s);
* ``zeta``: modal damping ratios (0 in a geometry's tables; a run sets them);
* ``drive``: b with ``q'' + 2 zeta omega q' + omega^2 q = b (F'' + 2 zeta omega F')``
  (m kg^1/2 / N); also ``-<y_s_t, mode> / F'``, the quasi-static velocity seen by each mode;
* ``event``: weights of the phase's event function on the modal coordinates (free: the gap
  ``s (Y_1n(x1) - Y_2n(x2))`` at the contact points, ``Y_1n(l1) - Y_2n(l2)`` at the tips from
  below, in m; contact: the contact force in N);
* ``tip1``, ``tip2``: tip displacement of each shape on beam 1 / beam 2 (m per unit
  coordinate);
* ``unit1``, ``unit2``: ``<u_1, mode>``, ``<u_2, mode>``, projections of the unit-tip-load
  shapes (the uplift and quasi-static shapes);
* ``base``: the participation factor ``Gamma_n = rhoA int Y_n dx`` of each mode whose beam's
  clamp the shaker moves, 0 for the others (kg^1/2; the base drive is ``-Gamma_n u_b''``).

``forces[phase, mode]``: complex amplitude A of each mode's drive ``Im(A e^(i Omega t))``.

``phase_scalars[phase]``, fields ``PHASE_SCALARS``: the event function is
``e(t) = event_const + event_sine sin(Omega t) + event_cosine cos(Omega t) + event . q(t)``;
``load_rate`` is beam 1's tip load rate per unit ``F'`` (1 free, ``c2 / (c1 + c2)`` in tied
contact, 1 in spring contact, where the free phase's quasi-static part is kept).

``settings``, a record of ``SETTINGS_DTYPE``, fields ``SETTINGS``: clearance (m), tip
compliances c1, c2 (m/N), force amplitude F0 (N), forcing frequency Omega (rad/s), end time
t_max (s), search span (s; the event search restarts from the exactly propagated state this
often), accumulation time (s; see
`impactbeams.kernels.dynamics.run_events`), contact law (``CONTACT_LAWS`` index), and the
spring law's effective stiffness k_e (N/m) and dashpot c_e (N s/m) after the static correction,
the tips' shifts per unit contact force through what the modes miss (``residual1``,
``residual2``, m/N: beam 1's tip moves by residual1 R, beam 2's by -residual2 R; at the tips
from below, r_1 and r_2), the contact's side s (+1.0: the counterpart below beam 1, -1.0:
above), the base amplitude U0 (m) and whether the shaker moves beam 1's and beam 2's clamp
(1.0 or 0.0).

Contact laws: ``TIED`` (the paper's: tips tied in contact, contact modes of the tied pair,
projections at switches: ``overlap``, ``shifts``) and ``SPRING`` (compliant: the free
coordinates kept, the contact phase as the oscillators of `impactbeams.kernels.contact_spring`:
``spring = (left, right, modes)`` per geometry and ``drives`` per run, rows
``SPRING_MODE_ROWS`` and ``SPRING_DRIVE_ROWS``); a run's arrays of both laws travel as one
switching record (`impactbeams.kernels.records.SWITCHING`). In the spring law the contact table
has the oscillators' frequencies and damping ratios, the contact force weights as ``event`` and
zeros in the other rows.

``geometry[g]``, fields ``GEOMETRY``: c1, c2 (m/N), the gap's compliance to the tip force
(``gap_compliance``, s G1(x1, l1), m/N: c1 at the tips), the side s, the accumulation time (s) of
geometry g of a map, which clamps the shaker moves (``shaker1``, ``shaker2``: 1.0 or 0.0) and
the initial state (``start``, an index of ``STARTS``). ``cells[i]``, columns ``CELL_COLUMNS``:
one map cell's parameters and the index of its geometry. ``out[i]``, columns ``OUT_COLUMNS``:
a dynamics map's observables.

Stroboscopic samples of a long run (`impactbeams.kernels.stroboscope`): ``samples[k]``,
columns ``TIP_COLUMNS``, the tip deflections y1(l1), y2(l2) (m) and velocities (m/s) at the k-th
sample time; ``summary``, fields ``STROBOSCOPE_COLUMNS``: the run's status, its contact onsets
and impact episodes that start within the sampled window, and the time (s) the run reached.
"""

import numpy as np

FREE, CONTACT = 0, 1

# each group unpacks range(len(names)) in the names' order: a missing name fails at import
TABLE_ROWS = ("frequency", "zeta", "drive", "event", "tip1", "tip2", "unit1", "unit2", "base")
(ROW_FREQUENCY, ROW_ZETA, ROW_DRIVE, ROW_EVENT, ROW_TIP1, ROW_TIP2, ROW_UNIT1, ROW_UNIT2,
 ROW_BASE) = range(len(TABLE_ROWS))

PHASE_SCALARS = ("event_const", "event_sine", "event_cosine", "load_rate")
SCALAR_CONST, SCALAR_SINE, SCALAR_COSINE, SCALAR_LOAD_RATE = range(len(PHASE_SCALARS))

CONTACT_LAWS = ("tied", "spring")
TIED, SPRING = range(len(CONTACT_LAWS))

SPRING_MODE_ROWS = ("eigenvalue", "phase")
MODE_EIGENVALUE, MODE_PHASE = range(len(SPRING_MODE_ROWS))
SPRING_DRIVE_ROWS = ("rising", "falling", "constant", "equilibrium")
DRIVE_RISING, DRIVE_FALLING, DRIVE_CONSTANT, DRIVE_EQUILIBRIUM = range(len(SPRING_DRIVE_ROWS))

# a structured record (fields read by name in the kernels, ``settings.t_max``)
SETTINGS = ("clearance", "c1", "c2", "force_amplitude", "forcing_frequency", "t_max",
            "search_span", "accumulation", "contact_law", "contact_stiffness", "contact_damping",
            "residual1", "residual2", "side", "base_amplitude", "shaker1", "shaker2")
SETTINGS_DTYPE = np.dtype([(name, np.float64) for name in SETTINGS])

GEOMETRY = ("c1", "c2", "gap_compliance", "side", "accumulation", "contact_law",
            "contact_stiffness", "contact_damping", "residual1", "residual2", "shaker1", "shaker2",
            "start")
(GEO_C1, GEO_C2, GEO_GAP_COMPLIANCE, GEO_SIDE, GEO_ACCUMULATION, GEO_LAW, GEO_STIFFNESS,
 GEO_DAMPING, GEO_RESIDUAL1, GEO_RESIDUAL2, GEO_SHAKER1, GEO_SHAKER2,
 GEO_START) = range(len(GEOMETRY))

# initial states (``start``): at rest in the absolute frame, or on the no-contact steady state
STARTS = ("rest", "steady")
REST, STEADY = range(len(STARTS))

# the cell parameters are named as in impactbeams.params, with the geometry's index; the base
# amplitude comes after it, and a row without it (built before base excitation) has U0 = 0
# (read through ``kernels.drive.base_amplitude``)
CELL_COLUMNS = ("clearance", "force_amplitude", "omega", "uplift1", "uplift2", "damping_ratio",
                "geometry", "base_amplitude")
(CELL_CLEARANCE, CELL_F0, CELL_FORCING_FREQUENCY, CELL_UPLIFT1, CELL_UPLIFT2, CELL_ZETA,
 CELL_GEOMETRY,
 CELL_U0) = range(len(CELL_COLUMNS))

OUT_COLUMNS = ("first_impact_time", "impact_count", "max_contact_force", "mean_restitution",
               "contact_fraction", "dynamics_status")
(OUT_FIRST_IMPACT, OUT_IMPACTS, OUT_MAX_FORCE, OUT_RESTITUTION, OUT_CONTACT_FRACTION,
 OUT_STATUS) = range(len(OUT_COLUMNS))

TIP_COLUMNS = ("deflection1", "deflection2", "velocity1", "velocity2")
TIP_Y1, TIP_Y2, TIP_V1, TIP_V2 = range(len(TIP_COLUMNS))

STROBOSCOPE_COLUMNS = ("status", "onsets", "episodes", "t_end")
STROBE_STATUS, STROBE_ONSETS, STROBE_EPISODES, STROBE_T_END = range(len(STROBOSCOPE_COLUMNS))
