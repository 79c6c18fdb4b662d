"""Expected wall time of a run: a cost model calibrated on this project's 2-core machine.

A run's time is the interpreter's start-up, the kernels' compile (only when they are not in
Numba's disk cache, `impactbeams.compilation`) and the compute, per cell of a sweep:

* a first-impact map: ``FIRST_IMPACT_CELL + FIRST_IMPACT_MODE n`` per cell (n modes per beam;
  a cell's search stops at its first impact, and by columns the next cell starts from there,
  a column ending at its first cell without impact). A map that is not run by columns (its
  last axis is not F0 or the clearance) searches each cell alone: ``FIRST_IMPACT_ALONE n``
  per impacting cell, and a cell without impact walks its whole horizon, ``FIRST_IMPACT_WALK``
  per cycle (below) and mode;
* the full dynamics: per *cycle*, the horizon over the period of the forcing or of the
  slowest free mode, whichever is shorter (a beam that is not forced fast still rings at its
  own first mode). A cell that impacts costs ``a n^p`` per cycle, its contact law's
  (``ContactLaw.impact_cycle[kind]``, `impactbeams.configuration`): the events' searches, the
  switches and the chatter within an impact grow with the modes, the spring law's switches as
  n^2, and so do the dynamics observables' peak-force searches; one that never impacts
  ``FREE_CYCLE n`` (one walk of the free search). Whether a cell impacts is told by
  `impacts`, from the linear response of beam 1's tip (a Lyapunov run without impact still
  carries its tangent vectors through every cycle: ``LYAPUNOV_FREE_CYCLE n``).
  The kinds: ``dynamics``
  (a map's run over t_max with its observables), ``lyapunov`` (its windowed run with the
  tangent vectors), ``long_time`` (transient + sampled forcing periods, stroboscopic samples)
  and ``simulate`` (one run, then every contact's peak force and the impact table; plus
  ``SAMPLING`` per output time and mode, and with the energy balance its two quadratures,
  `energy_seconds`).

A cell of several contacts (`impactbeams.sweep.estimate.cell_seconds`) costs each contact's own
run's events as above and ``CONTACT_CELL`` per contact and run: the packing of its run and
of the active sets' event functions, and the reading of the run in Python.

Time on T threads: the compute divided by ``THREAD_SPEEDUP[T]`` (measured on 2 cores).

The constants are measured by ``python benchmarks/calibrate_costs.py``, which writes
docs/benchmarks/costs.json (its ``constants``: ``tests/test_costs.py`` checks that these and
the laws' ``impact_cycle`` are the same); the measured load average is stored with them.
Estimates against the actual times of the shipped sweeps and of random runs: docs/limits.md,
"Time".
"""

from __future__ import annotations

import dataclasses
import functools
import os
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.configuration import BEAM, ContactLaw, Counterpart

if TYPE_CHECKING:
    from impactbeams.params import Params

# --- constants from docs/benchmarks/costs.json (benchmarks/calibrate_costs.py) ---------------
FIRST_IMPACT_CELL = 2.1e-07
FIRST_IMPACT_MODE = 2.5e-08
FIRST_IMPACT_ALONE = 4.2e-06
FIRST_IMPACT_WALK = 5.2e-08
FREE_CYCLE = 1.7e-07
LYAPUNOV_FREE_CYCLE = 6.2e-07
SAMPLING = 1.2e-07
ENERGY_NODE = 1.7e-07
GEOMETRY = 8.9e-06
THREAD_SPEEDUP = {1: 1.0, 2: 1.8}
COMPILE = {
    "first_impact": 8.2,
    "first_impact_parallel": 11.0,
    "dynamics": 24.0,
    "lyapunov": 28.0,
    "long_time": 17.0,
    "simulate": 17.0,
}
START_UP = 0.63
COMPILE_LOAD = 1.0
COMPILE_CORES = 2
CONTINUATION_POINT = (0.0017, 0.53)
CONTACT_CELL = 0.0019
# ----------------------------------------------------------------------------------------------

# The announced range about the load-scaled compile (`compile_estimate`): the load can rise
# during a compile, which the range's top allows for in part; and an idle machine's own speed
# drifts, which the bottom allows for: the same code's cold first map took 6.0 s on the
# development machine at 07:10 and 8.3 s at 20:29 the same day, load 1 both times
# (benchmarks/bench_compile.py). The compile announced against the compile taken, on a fresh
# cache: docs/benchmarks/newcomer.json (scripts/newcomer.py).
COMPILE_RANGE = (0.6, 1.5)

def compile_time(kind: str, entry: str | None = None) -> float:
    """Expected cold compile (s) of a run of ``kind`` (``COMPILE``).

    ``entry``: a first map's kernel (`impactbeams.sweep.plan.first_impact_kernel`); its
    parallel twin, which a map of more than one block calls, compiles longer than the serial
    one (``first_impact_parallel``).
    """
    parallel = entry is not None and entry.endswith("_parallel")
    return COMPILE.get(f"{kind}_parallel", COMPILE[kind]) if parallel else COMPILE[kind]


@dataclasses.dataclass(frozen=True)
class CompileEstimate:
    """A cold compile's expected wall time on this machine now, as a range (s).

    ``calibrated``: the measured time (s) at load ``COMPILE_LOAD`` on ``COMPILE_CORES`` cores;
    ``load``: this machine's load average over the last minute (None where the system does
    not tell it); ``cores``: its cores; ``share``: the share of a core this process got in a
    short busy probe just before (`cpu_share`).
    """

    low: float
    high: float
    calibrated: float
    load: float | None
    cores: int
    share: float

    def describe(self) -> str:
        """The range, this machine and its load, and the calibration's, in one phrase."""
        here = (f"{self.cores} cores, load unknown" if self.load is None else
                f"{self.cores} cores at load {self.load:.1f}")
        return (f"{self.low:.0f}-{self.high:.0f} s here ({here}, {100 * self.share:.0f} % of a "
                f"core to this process just now; measured {self.calibrated:.2g} s at load "
                f"{COMPILE_LOAD:.1f} on {COMPILE_CORES} cores)")


def compile_estimate(kind: str, entry: str | None = None, load: float | None = None,
                     cores: int | None = None,
                     share: float | None = None) -> CompileEstimate | None:
    """The cold compile of a run of ``kind`` expected here and now (None: not calibrated).

    The calibrated time (`compile_time`) scaled by the contention for the cores: the larger of
    max(1, (L + 1) / C), with load average L (a process wanting a core among L others) on C
    cores, and 1 / the share of a core this process gets now, against the same at
    calibration; ``COMPILE_RANGE`` about that. ``load``, ``cores``, ``share``: this machine's
    (``os.getloadavg``, ``os.cpu_count``, `cpu_share`) unless given.
    """
    if kind not in COMPILE:
        return None
    cores = cores or os.cpu_count() or 1
    if load is None and hasattr(os, "getloadavg"):
        load = os.getloadavg()[0]
    share = cpu_share() if share is None else share
    calibrated = compile_time(kind, entry)
    contention = max(1.0 if load is None else _contention(load, cores), 1.0 / max(share, 0.01))
    centre = calibrated * contention / _contention(COMPILE_LOAD, COMPILE_CORES)
    return CompileEstimate(centre * COMPILE_RANGE[0], centre * COMPILE_RANGE[1], calibrated,
                           load, cores, share)


def _contention(load: float, cores: int) -> float:
    return max(1.0, (load + 1.0) / cores)


@functools.cache
def cpu_share(seconds: float = 0.1) -> float:
    """The share of a core this thread gets now: its CPU time over ``seconds`` of busy wall time.

    Measured once per process (a cold run's announcement only: the 0.1 s is not spent when
    the kernels are cached). 1 on an idle core; about C / (L + 1) among L busy threads.
    """
    wall, cpu = time.perf_counter(), time.thread_time()
    while time.perf_counter() - wall < seconds:
        pass
    return min(1.0, (time.thread_time() - cpu) / (time.perf_counter() - wall))


def continuation_point_seconds(coordinates: int) -> float:
    """Expected CPU time (s) per branch point of a continuation of ``coordinates`` = 2 N.

    ``CONTINUATION_POINT`` = (a, p): a (2 N)^p, measured on the shipped continuation (a soft
    stop, one contact per orbit) at 5 to 200 modes; a stiffer contact, with more contacts per
    orbit, costs more per point.
    """
    scale, power = CONTINUATION_POINT
    return scale * coordinates ** power


def speedup(threads: int) -> float:
    """Measured speed-up of a sweep on ``threads`` threads (the largest measured beyond)."""
    known = max(count for count in THREAD_SPEEDUP if count <= max(threads, 1))
    return THREAD_SPEEDUP[known]


def cycles(values: Mapping[str, Any], horizon: Any) -> np.ndarray:
    """Cycles of a run over ``horizon`` (s): horizon max(Omega, omega_1) / 2 pi.

    omega_1 is the slowest free mode of the two beams (rad/s). ``values``: numeric parameters
    (floats or arrays that broadcast).
    """
    first = 1.8751040687**2
    slowest = np.minimum(*(first / np.asarray(values[f"l{i}"]) ** 2
                           * np.sqrt(np.asarray(values[f"EI{i}"]) / values[f"rhoA{i}"])
                           for i in ("1", "2")))
    return np.asarray(horizon) * np.maximum(np.asarray(values["omega"], dtype=float),
                                            slowest) / (2 * np.pi)


def run_values(params: Params, n_modes: int) -> dict[str, float]:
    """``params.numeric()`` as the estimates read them, with ``n_modes`` modes per beam.

    A structure's own damping counts as its ``damping_ratio`` (then 0): the smallest of its
    lowest modes' own ratios, the slowest decay the estimates allow for.
    """
    from impactbeams.modes import beam

    values = params.numeric()
    if params.structure1 is not None and params.structure1.has_damping:
        own = beam(params, 1)
        values["damping_ratio"] = float(np.min(own.own_damping_ratios(
            min(n_modes, own.mode_limit))))
    return values


def impacts(values: Mapping[str, Any], n_modes: int, horizon: Any) -> np.ndarray:
    """Whether the tips are expected to meet within ``horizon`` (s): a bool per point."""
    return impacting_fraction(values, n_modes, horizon) > 0.0


def impacting_fraction(values: Mapping[str, Any], n_modes: int, horizon: Any) -> np.ndarray:
    """The share of ``horizon`` (s) over which the tips are expected to meet, per point.

    Beam 1's tip under F0 sin(Omega t) from rest, mode by mode at its tip (mass-normalised
    cantilever modes have Y_n(l)^2 = 4 / (rhoA l)): a mode of frequency omega_n moves
    F0 Y_n(l)^2 / |omega_n^2 - Omega^2 + 2 i zeta omega_n Omega| in the steady state, and the
    start from rest adds its free vibration, Omega / omega_n times that, at most; a mode near
    resonance grows like t, i.e. has at least the damping ratio 1 / (omega_n horizon). The
    tips meet for the whole horizon if the steady motions, plus the uplifts, reach the
    clearance; if only the free vibration's help reaches it, for as long as that vibration,
    decaying like exp(-zeta omega_1 t), still makes up the difference (the whole horizon
    without damping); else never. A shaker's U0 counts like the tip force, mode by mode with
    its participation (``Gamma_n Y_n(l) ~ 4 / (k_n l)``, driven by ``U0 Omega^2``), plus the
    clamp's own U0 (which a shaker carrying both clamps does not add: an overestimate).
    """
    lasting, passing, slowest = tip_reach(values, n_modes, horizon)
    gap = np.asarray(values["clearance"]) - lasting
    damping = np.asarray(values["damping_ratio"], dtype=float)
    decay = damping * slowest * np.asarray(horizon)  # free vibration's decay over it
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(decay > 0.0, np.log(passing / gap) / decay, 1.0)
    return np.where(gap <= 0.0, 1.0, np.where(passing >= gap, np.clip(share, 0.0, 1.0), 0.0))


def tip_reach(values: Mapping[str, Any], n_modes: int, horizon: Any,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Beam 1's tip motion (m) by the linear response over ``horizon`` (s), per point.

    Returns the steady part plus the uplifts, which last (m), the free vibration of the start
    from rest, which passes with the damping (m), and beam 1's slowest frequency (rad/s), as
    `impacting_fraction` describes them.
    """
    from impactbeams.modes import cantilever_roots

    roots = cantilever_roots(n_modes)
    length, rho_a = np.asarray(values["l1"])[..., None], np.asarray(values["rhoA1"])[..., None]
    omega_n = (roots / length) ** 2 * np.sqrt(np.asarray(values["EI1"])[..., None] / rho_a)
    big_omega = np.asarray(values["omega"], dtype=float)[..., None]
    damping = np.asarray(values["damping_ratio"], dtype=float)
    zeta = np.maximum(damping[..., None], 1.0 / (omega_n * np.asarray(horizon)[..., None]))
    steady = 4.0 / (rho_a * length) / np.abs(omega_n**2 - big_omega**2
                                             + 2j * zeta * omega_n * big_omega)
    force = np.asarray(values["force_amplitude"])
    uplifts = np.abs(values["uplift1"]) + np.abs(values["uplift2"])
    lasting = force * np.sum(steady, axis=-1) + uplifts
    passing = force * np.sum(steady * big_omega / omega_n, axis=-1)
    base = np.asarray(values.get("base_amplitude", 0.0), dtype=float)
    if np.any(base):
        shaken = steady * (rho_a * length) / roots * big_omega**2  # per unit U0
        lasting = lasting + base * (1.0 + np.sum(shaken, axis=-1))
        passing = passing + base * np.sum(shaken * big_omega / omega_n, axis=-1)
    return lasting, passing, omega_n[..., 0]


# a clearance this many times the tip motion the drive is expected to give is worth a hint
IMPLAUSIBLE_CLEARANCE = 10.0


def clearance_hint(params: Params, t_max: float) -> str | None:
    """A hint if the clearance is far beyond any motion the drive gives beam 1's tip by t_max.

    The motion is the linear response's (`tip_reach`: the steady part, the start's free
    vibration and the uplifts, growing through a resonance until t_max). A
    clearance of IMPLAUSIBLE_CLEARANCE times that or more is most likely a unit slip (mm
    typed as m); None if it is not, or if nothing drives the beams at all.
    """
    lasting, passing, _ = tip_reach(params.numeric(), 10, t_max)
    reach = float(lasting + passing)
    ratio = params.clearance / reach if reach > 0 else 0.0
    if ratio < IMPLAUSIBLE_CLEARANCE:
        return None
    return (f"clearance = {params.clearance:g} m is {ratio:.3g} times the largest tip motion "
            f"the drive is expected to give beam 1 by t_max ({reach:.3g} m, its linear "
            "response): the tips will most likely never meet. A clearance in mm typed in m? "
            f"({params.clearance:g} mm is {params.clearance * 1e-3:g} m)")


def dynamics_seconds(values: Mapping[str, Any], law: ContactLaw, n_modes: int, horizon: Any,
                     kind: str, partner: Counterpart = BEAM) -> np.ndarray:
    """Seconds on one core of full-dynamics runs over ``horizon`` (s), per point of ``values``.

    ``kind``: of the law's ``impact_cycle`` (dynamics, lyapunov, long_time, simulate); ``law``:
    the contact law of every point. The constants are per mode of each of two beams: against a
    stop (``partner`` of one beam), beam 1's ``n_modes`` coordinates cost as half as many per
    beam.
    """
    scale, power = law.impact_cycle[kind]
    free = LYAPUNOV_FREE_CYCLE if kind == "lyapunov" else FREE_CYCLE
    share = impacting_fraction(values, n_modes, horizon)
    per_beam = n_modes * partner.beams / 2
    per_cycle = share * scale * per_beam**power + (1.0 - share) * free * per_beam
    return cycles(values, horizon) * per_cycle


ENERGY_NODES = 12  # Gauss nodes per panel of the energy quadrature (kernels.reductions)
ENERGY_QUADRATURES = 2  # over the output times, and over the episodes' ends


def energy_seconds(fastest: float, n_modes: int, horizon: float, n_times: float) -> float:
    """Seconds of a simulated run's energy balance (`kernels.reductions.work_of_force`).

    Each of its ENERGY_QUADRATURES quadratures evaluates the power at ENERGY_NODES nodes per
    panel of at most half the ``fastest`` period (rad/s: the highest mode's), over the
    ``horizon`` (s) and at least once between output times: ``ENERGY_NODE n_modes`` each
    (the propagation of both beams' coordinates). The panels the contacts' switches cut
    are left out: a run's events are not known before it runs.
    """
    panels = horizon * fastest / np.pi + n_times
    return ENERGY_QUADRATURES * ENERGY_NODES * panels * ENERGY_NODE * n_modes


def first_impact_seconds(cells: float, n_modes: int) -> float:
    """Seconds on one core of a first-impact map of ``cells`` cells."""
    return cells * (FIRST_IMPACT_CELL + FIRST_IMPACT_MODE * n_modes)


def cell_search_seconds(values: Mapping[str, Any], n_modes: int, t_max: float) -> np.ndarray:
    """Seconds on one core of first-impact cells searched alone (not by columns), per point."""
    return np.where(impacts(values, n_modes, t_max), FIRST_IMPACT_ALONE * n_modes,
                    FIRST_IMPACT_WALK * n_modes * cycles(values, t_max))


def geometry_seconds(geometries: int, n_modes: int) -> float:
    """Seconds of the serial set-up of ``geometries`` geometries (modes, tables, switching)."""
    return geometries * GEOMETRY * n_modes**2
