"""The one registry of names: data variables, parameters and global attributes.

Parameters appear as coordinates (swept) or attributes (fixed). Used both to build Datasets
(`attributes`, `parameter_attributes`, `global_attributes`) and to check
them (`validate`, on every Dataset the package writes or reads). Imports nothing heavy:
`impactbeams.params` takes its units from here.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from impactbeams.configuration import LAWS, counterpart_named

if TYPE_CHECKING:
    import xarray as xr

CONVENTIONS = "CF-1.8"
REFERENCES = "Dzyubak & Bhaskar, Procedia Engineering 199 (2017) 589-594"
DAMPING_LAW = ("modal: each cantilever mode's whole coordinate eta_n = <y, Y_n> obeys "
               "eta'' + 2 zeta omega_n eta' + omega_n^2 eta = generalised force, quasi-static "
               "part included (mass- or stiffness-proportional and modal damping all give this; "
               "docs/model.md)")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """A model parameter: its CF ``units`` and ``long_name`` (as a coordinate or attribute).

    ``symbol``: the paper's symbol in matplotlib mathtext, for axis labels ("" if none).
    """

    units: str
    long_name: str
    symbol: str = ""


_BEAM_PARAMETERS = {"l": ("m", "length", "l"), "EI": ("N m^2", "bending stiffness", "EI"),
                    "rhoA": ("kg/m", "mass per unit length", r"\rho A")}
# material alternative to EI/rhoA (see impactbeams.params)
_MATERIAL_PARAMETERS = {"E": ("Pa", "Young's modulus", "E"),
                        "rho": ("kg/m^3", "density", r"\rho"),
                        "width": ("m", "strip width", "b"),
                        "thickness": ("m", "strip thickness", "h")}

# every parameter that can be given, fixed or swept, in the order of options and messages
PARAMETERS: dict[str, Parameter] = {
    **{key + i: Parameter(unit, f"{name} of beam {i}", f"${symbol}_{i}$")
       for key, (unit, name, symbol) in _BEAM_PARAMETERS.items() for i in ("1", "2")},
    "clearance": Parameter("m", "clearance between the tips at rest (Delta)", r"$\Delta$"),
    "force_amplitude": Parameter("N", "amplitude of the tip force on beam 1 (F0)", "$F_0$"),
    "omega": Parameter("rad/s", "forcing frequency (Omega)", r"$\Omega$"),
    "uplift1": Parameter("m", "initial tip uplift of beam 1 (delta_1)", r"$\delta_1$"),
    "uplift2": Parameter("m", "initial tip uplift of beam 2 (delta_2)", r"$\delta_2$"),
    "damping_ratio": Parameter("1", "modal damping ratio (zeta)", r"$\zeta$"),
    "contact_law": Parameter("1", "tip contact law: spring (compliant; first contacts and "
                                  "episodes converge in n_modes) or tied (the paper's)"),
    "contact_stiffness": Parameter("N/m", "stiffness k of the tip contact spring", "$k$"),
    "contact_damping": Parameter("N s/m", "damping c of the tip contact dashpot", "$c$"),
    "counterpart": Parameter("1", "what beam 1's tip meets: beam (beam 2's tip) or stop (a fixed "
                                  "rigid stop, clearance below it)"),
    "contact_position1": Parameter("m", "where the contact acts on beam 1: distance from its "
                                        "clamp (default: the tip, l1)", "$x_1$"),
    "contact_position2": Parameter("m", "where the contact acts on beam 2: distance from its "
                                        "clamp (default: the tip, l2)", "$x_2$"),
    "contact_side": Parameter("1", "which way beam 1 closes the contact: below (it moves down "
                                   "onto its counterpart, default) or above (up onto it)"),
    "base_amplitude": Parameter("m", "amplitude of the shaker's clamp motion (U0)", "$U_0$"),
    "shaker": Parameter("1", "clamps the shaker moves: both, beam1 or beam2 (beam 2's clamp or "
                             "the stop's mount)"),
    "start": Parameter("1", "initial state: rest (at rest in the absolute frame) or steady (on "
                            "the no-contact steady response)"),
    **{key + i: Parameter(unit, f"{name} of beam {i}", f"${symbol}_{i}$")
       for key, (unit, name, symbol) in _MATERIAL_PARAMETERS.items() for i in ("1", "2")},
}


@dataclasses.dataclass(frozen=True)
class Variable:
    """An output variable: its dimensions, CF ``units``, ``long_name`` and a description.

    ``symbol``: its symbol in matplotlib mathtext, for axis labels ("" if none). ``dtype``: its
    NumPy type wherever it is stored (a map in memory or on disk, a sweep's saved chunks, a
    run's Dataset). ``flags``: the meanings of the codes 0, 1, ... of a status variable,
    stored as CF ``flag_values`` and ``flag_meanings`` (CF conventions 3.5; none if empty).
    """

    dims: tuple[str, ...]
    units: str
    long_name: str
    description: str
    symbol: str = ""
    dtype: str = "float64"
    flags: tuple[str, ...] = ()


# how a full-dynamics run ended, by its code (the kernels' impactbeams.kernels.dynamics
# STATUS_NAMES: kernels cannot import this registry, a test keeps the two equal)
DYNAMICS_STATUSES = ("complete", "event_limit", "stuck", "search_limit")


# dims "*" = the swept parameters of a map, in sweep order
VARIABLES: dict[str, Variable] = {
    "first_impact_time": Variable(
        ("*",), "s", "time before the first impact",
        "first time in (0, t_max] at which the tip gap closes; NaN where no impact by t_max",
        symbol="$t^*$"),
    "impacted": Variable(
        ("*",), "1", "impact flag",
        "1 where the tips impact by t_max, 0 where they do not", dtype="int8"),
    "first_contact": Variable(
        ("*",), "1", "contact that closes first",
        "index in the run's contacts of the contact whose gap closes first (the lowest of equal "
        "times); -1 where none closes by t_max (maps of several contacts)", dtype="int32"),
    "impact_count": Variable(
        ("*",), "1", "number of impacts",
        "number of contact onsets in [0, t_max] (full dynamics)", dtype="int32"),
    "max_contact_force": Variable(
        ("*",), "N", "largest contact force",
        "largest contact force R over [0, t_max]; 0 where no impact (full dynamics)",
        symbol=r"$R_\max$"),
    "mean_restitution": Variable(
        ("*",), "1", "mean coefficient of restitution",
        "approach-speed-weighted mean of e = -(dg/dt at separation) / (dg/dt at onset): "
        "sum of separation speeds over sum of approach speeds, over impacts that closed and "
        "separated (impacts with a near-zero approach speed, whose own e is a truncation "
        "artefact, barely count); NaN where none did (full dynamics)", symbol=r"$\bar e$"),
    "dynamics_status": Variable(
        ("*",), "1", "status of the full-dynamics run",
        "0 complete: reached t_max; 1 event_limit: stopped at the cap on phases per cell; "
        "2 stuck: a run of zero-length phases; 3 search_limit: an event search reached its "
        "step cap; observables then cover the part before the stop", dtype="int8",
        flags=DYNAMICS_STATUSES),
    "contact_fraction": Variable(
        ("*",), "1", "fraction of time in contact",
        "time spent in the contact phase divided by t_max (full dynamics)"),
    "contact_impact_count": Variable(
        ("*", "contact"), "1", "number of impacts of each contact",
        "number of each contact's onsets in [0, t_max] (several contacts, Params.contacts; "
        "full dynamics)", dtype="int32"),
    "contact_max_force": Variable(
        ("*", "contact"), "N", "largest force of each contact",
        "largest force R_j of each contact over [0, t_max]; 0 where it never closes (several "
        "contacts, Params.contacts; full dynamics)"),
}

# simulate(): one trajectory on an output grid ("time") and its impacts ("impact")
VARIABLES.update({
    "time": Variable(("time",), "s", "time", "output time", "$t$"),
    "impact": Variable(("impact",), "1", "impact number",
                       "index of the contact phase, in order of onset (from 0)", dtype="int64"),
    "x1": Variable(("x1",), "m", "position along beam 1", "distance from the clamped end",
                   "$x_1$"),
    "x2": Variable(("x2",), "m", "position along beam 2", "distance from the clamped end",
                   "$x_2$"),
    "tip_deflection_1": Variable(
        ("time",), "m", "tip deflection of beam 1",
        "y1(l1, t), upward positive; absolute (the clamp's motion included under a shaker)",
        "$y_1(l_1)$"),
    "tip_deflection_2": Variable(
        ("time",), "m", "tip deflection of beam 2 minus the clearance",
        "y2(l2, t) - Delta, upward positive (as in the paper's Fig. 3a); in contact it equals "
        "tip_deflection_1; against a stop (counterpart = stop) the stop's position, -Delta",
        symbol=r"$y_2(l_2) - \Delta$"),
    "tip_velocity_1": Variable(("time",), "m s-1", "tip velocity of beam 1", "dy1(l1, t)/dt"),
    "tip_velocity_2": Variable(("time",), "m s-1", "tip velocity of beam 2",
                               "dy2(l2, t)/dt; 0 against a stop"),
    "contact_deflection_1": Variable(
        ("time",), "m", "deflection of beam 1 at the contact point",
        "y1(x1, t) at x1 = contact_position1, upward positive, absolute like the tips; only "
        "when the contact acts elsewhere than the tips (there it is tip_deflection_1)",
        "$y_1(x_1)$"),
    "contact_deflection_2": Variable(
        ("time",), "m", "deflection of beam 2 at the contact point",
        "y2(x2, t) at x2 = contact_position2 (not minus the clearance), upward positive; only "
        "for two beams whose contact acts elsewhere than the tips", "$y_2(x_2)$"),
    "gap": Variable(
        ("time",), "m", "gap at the contact point",
        "g = Delta + s (y1(x1) - y2(x2)) at the contact points x1, x2 (the tips by default), "
        "s = +1 with the counterpart below beam 1 (contact_side = below, default), -1 above "
        "(y2 the stop's motion against a stop); 0 in contact; just after a release it is the "
        "free basis' representation of the contact field (a truncation error of the modal "
        "model)"),
    "contact_force": Variable(
        ("time",), "N", "contact force",
        "R(t) = EI2 d3y2/dx3 (l2, t) (against a stop -EI1 d3y1/dx3 (l1, t)) in contact, 0 out "
        "of contact", "$R$"),
    "contact": Variable(("contact",), "1", "contact number",
                        "index of the contact in Params.contacts (several contacts), from 0",
                        dtype="int64"),
    "contact_gaps": Variable(
        ("time", "contact"), "m", "gap of each contact",
        "g_j = Delta_j + s_j (y1(x1j) - y2(x2j)) of each of several contacts (Params.contacts), "
        "-R_j / k_j while closed (docs/model.md, Several contacts)"),
    "contact_forces": Variable(
        ("time", "contact"), "N", "force of each contact",
        "R_j of each of several contacts (Params.contacts), 0 while open"),
    "impact_contact": Variable(
        ("impact",), "1", "contact of the impact",
        "which of Params.contacts closes (its index)", dtype="int64"),
    "in_contact": Variable(
        ("time",), "1", "contact flag", "1 in the contact phase, 0 in the free phase"),
    "energy": Variable(
        ("time",), "J", "total mechanical energy",
        "kinetic plus strain energy of the deflection fields of both beams; with the spring "
        "law also the spring's k_e g^2 / 2 while the tips overlap and -r_1 F R "
        "(docs/model.md, Compliant contact)"),
    "kinetic_energy": Variable(
        ("time",), "J", "kinetic energy", "kinetic energy of the deflection fields"),
    "unresolved_kinetic_energy": Variable(
        ("time",), "J", "kinetic energy outside the modal basis",
        "1/2 |(1 - P) y_s_t|^2: kinetic energy of the part of the quasi-static velocity field "
        "that the phase's modes do not represent; within a phase energy - "
        "unresolved_kinetic_energy changes exactly by work_of_force - damping_dissipation"),
    "work_of_force": Variable(
        ("time",), "J", "work done by the tip force",
        "integral from 0 to t of F(s) (-dy1(l1, s)/ds) ds (F downward, y upward), plus under a "
        "shaker the work of the inertial load -rhoA u_b'' on the motion relative to the clamps "
        "(attribute energy_frame)"),
    "damping_dissipation": Variable(
        ("time",), "J", "energy dissipated by modal damping",
        "integral from 0 to t of the modal damping power (0 without damping)"),
    "deflection_1": Variable(("time", "x1"), "m", "deflection of beam 1",
                             "y1(x1, t); absolute (the clamp's motion included under a shaker)"),
    "deflection_2": Variable(("time", "x2"), "m", "deflection of beam 2",
                             "y2(x2, t); absolute (the clamp's motion included under a shaker); "
                             "0 against a stop (no beam 2)"),
    "impact_onset_time": Variable(
        ("impact",), "s", "impact onset time", "time at which the gap closes (contact onset)"),
    "impact_duration": Variable(
        ("impact",), "s", "impact duration",
        "release time minus onset time (0 for an instantaneous impact, whose force is not "
        "positive right after onset); NaN if still in contact at the end of the run"),
    "impact_impulse": Variable(
        ("impact",), "N s", "impact impulse",
        "integral of the contact force over the contact phase (up to the end of the run)"),
    "impact_peak_force": Variable(
        ("impact",), "N", "peak impact force", "largest contact force during the contact phase"),
    "restitution_coefficient": Variable(
        ("impact",), "1", "coefficient of restitution",
        "e = -(dg/dt just after release) / (dg/dt just before onset); NaN if not released. "
        "Negative under the tied law where the release's projection onto the truncated free "
        "modes leaves the tips still approaching (a truncation artefact, the exact rigid "
        "release has e = 0; docs/model.md, What comes out); the spring law gives e >= 0",
        "$e$"),
    "impact_sustained": Variable(
        ("impact",), "1", "sustained-contact flag",
        "1 if the contact followed an instantaneous impact whose released state closed again "
        "within half a period of the fastest free mode (an accumulation), so that it was kept "
        "until the force, rising from <= 0, fell back to 0 or peaked below 0", dtype="int8"),
    "impact_velocity": Variable(
        ("impact",), "m s-1", "gap rate at onset", "dg/dt just before the onset (<= 0)"),
    "separation_velocity": Variable(
        ("impact",), "m s-1", "gap rate at separation",
        "dg/dt just after the release, in the free basis (the tips move together just before)"),
    "impact_energy_loss": Variable(
        ("impact",), "J", "energy lost at onset",
        "total mechanical energy just before minus just after the onset (the tied law's "
        "projection loss; 0 with the spring law, whose switches keep the state)"),
    "impact_kinetic_energy_loss": Variable(
        ("impact",), "J", "kinetic energy lost at onset",
        "kinetic energy just before minus just after the onset projection"),
    "release_energy_change": Variable(
        ("impact",), "J", "energy change at release",
        "total mechanical energy just after minus just before the release projection (a "
        "truncation effect: the highest contact modes are not spanned by the free modes); "
        "with several contacts the closed springs' energy a dashpot's early release gives up "
        "(one contact's energy keeps it while the gap reopens)"),
    "release_gap": Variable(
        ("impact",), "m", "gap just after release",
        "gap of the released state in the free basis (0 in the exact model)"),
    "release_contact_force": Variable(
        ("impact",), "N", "contact force at release", "R at the located release (0 to round-off)"),
})

# simulate(): impact episodes, clusters of contacts (trajectory.episodes)
VARIABLES.update({
    "episode": Variable(("episode",), "1", "episode number",
                        "index of the impact episode (a cluster of contacts), from 0",
                        dtype="int64"),
    "episode_onset_time": Variable(("episode",), "s", "episode onset time",
                                   "onset of the episode's first contact"),
    "episode_duration": Variable(
        ("episode",), "s", "episode duration",
        "first onset to last release; NaN if the last contact is still open at the end"),
    "episode_contact_count": Variable(("episode",), "1", "contacts in the episode",
                                      "number of (micro-)contacts of the episode",
                                      dtype="int32"),
    "episode_impulse": Variable(("episode",), "N s", "episode impulse",
                                "integral of the contact force over the episode's contacts"),
    "episode_peak_force": Variable(("episode",), "N", "episode peak force",
                                   "largest contact force of the episode"),
    "episode_dissipated_energy": Variable(
        ("episode",), "J", "energy dissipated in the episode",
        "modal damping and dashpot dissipation from the first onset to the last release"),
    "episode_restitution": Variable(
        ("episode",), "1", "kinematic restitution of the episode",
        "-(dg/dt after the last release) / (dg/dt before the first onset)"),
    "episode_energetic_restitution": Variable(
        ("episode",), "1", "energetic restitution of the episode",
        "sqrt(work of R while the tips separate / work of R while they approach), over the "
        "episode's contacts (Stronge's energetic coefficient; quadrature, ~1e-6 relative)"),
})

# simulate() of several contacts: each contact's own episodes (its contacts clustered alone,
# trajectory.several_run), beside the episodes of all contacts together ("episode")
VARIABLES.update({
    "contact_episode": Variable(
        ("contact_episode",), "1", "episode number of one contact",
        "index of an episode of one of several contacts (its own contacts clustered alone), "
        "in order of onset, from 0", dtype="int64"),
    "contact_episode_contact": Variable(
        ("contact_episode",), "1", "contact of the episode",
        "which of Params.contacts (its index) the episode's contacts are", dtype="int64"),
    **{"contact_" + name: dataclasses.replace(
        VARIABLES[name], dims=("contact_episode",), long_name=f"{VARIABLES[name].long_name} "
        "(one contact's episodes)") for name in (
            "episode_onset_time", "episode_duration", "episode_contact_count",
            "episode_impulse", "episode_peak_force", "episode_dissipated_energy",
            "episode_restitution", "episode_energetic_restitution")},
})

# Lyapunov exponents (docs/model.md, "Lyapunov exponents"): of a map's cells ("*") and of a run
_LYAPUNOV_METHOD = ("of the flow in the modal state (q, q') of both beams (4 n_modes "
                    "dimensions; the forcing phase as explicit time): tangent vectors propagated "
                    "exactly within each phase, saltation matrix at the switches, Benettin "
                    "renormalisation (energy norm of the free modes) every forcing period, log "
                    "growth averaged over the complete periods after the transient; spring "
                    "contact law only")
_BATCH_ERROR = "standard error of the mean of batch means (consecutive groups of forcing periods)"
VARIABLES.update({
    "lyapunov_exponent": Variable(
        ("*",), "s-1", "largest Lyapunov exponent",
        f"largest Lyapunov exponent {_LYAPUNOV_METHOD}; > 0 chaotic, < 0 a stable orbit; NaN "
        "where no complete period follows the transient", symbol=r"$\lambda_1$"),
    "lyapunov_exponent_error": Variable(
        ("*",), "s-1", "standard error of the largest Lyapunov exponent",
        _BATCH_ERROR),
    "exponent": Variable(("exponent",), "1", "exponent number",
                         "index of the Lyapunov exponent, from the largest (0)", dtype="int64"),
    "lyapunov_spectrum": Variable(
        ("exponent",), "s-1", "leading Lyapunov exponents",
        f"leading Lyapunov exponents, descending, {_LYAPUNOV_METHOD} (Gram-Schmidt in the "
        "energy product)", symbol=r"$\lambda$"),
    "lyapunov_spectrum_error": Variable(
        ("exponent",), "s-1", "standard error of the leading Lyapunov exponents",
        _BATCH_ERROR),
})


# a run's final modal state (simulate's initial_state of a run that continues it)
_MODAL_UNITS = "kg^1/2 m^1/2"  # q_n = rhoA int y Y_n dx, Y_n mass-normalised
VARIABLES.update({
    "coordinate": Variable(
        ("coordinate",), "1", "free modal coordinate number",
        "index of the free modal coordinates: beam 1's n_modes cantilever modes, then beam 2's "
        "(none against a stop)", dtype="int64"),
    "final_displacement": Variable(
        ("*", "coordinate"), _MODAL_UNITS, "modal displacements at t_end",
        "free modal coordinates q at the run's end t_end, the quasi-static part of the tip "
        "force taken out (docs/model.md); NaN if a tied-law run ends in contact; in a "
        "stepped-sine sweep, each cell's at its horizon (the state the next cell starts from; "
        "NaN if the run stopped early)"),
    "final_velocity": Variable(
        ("*", "coordinate"), _MODAL_UNITS + " s-1", "modal velocities at t_end",
        "dq/dt of the free modal coordinates at the run's end t_end (see final_displacement)"),
})


# a periodic orbit's Floquet multipliers (impactbeams.orbits.PeriodicOrbit.to_dataset)
VARIABLES.update({
    "multiplier": Variable(("multiplier",), "1", "Floquet multiplier number",
                           "index of the Floquet multiplier, by decreasing modulus",
                           dtype="int64"),
    "floquet_multiplier_real": Variable(
        ("multiplier",), "1", "real part of the Floquet multipliers",
        "eigenvalues mu of the orbit's monodromy matrix (the period map's Jacobian over p "
        "forcing periods), by decreasing modulus; Newton-Picard: the leading ones only"),
    "floquet_multiplier_imag": Variable(
        ("multiplier",), "1", "imaginary part of the Floquet multipliers",
        "see floquet_multiplier_real"),
    "floquet_exponent": Variable(
        ("multiplier",), "s-1", "Floquet exponents of the orbit",
        "ln|mu| / (p 2 pi / Omega): the orbit's Lyapunov exponents, exact (no averaging)",
        symbol=r"$\lambda$"),
})


# long-time response (impactbeams.longtime): stroboscopic samples along "period", after a
# transient; in a map "*" is the swept axes, in simulate() nothing
VARIABLES.update({
    "period": Variable(
        ("period",), "1", "forcing periods before the sample",
        "number of forcing periods 2 pi / Omega from t = 0 to the stroboscopic sample: "
        "transient_periods + k for the k-th sample", dtype="int64"),
    "sweep_direction": Variable(
        ("sweep_direction",), "1", "direction of a stepped-sine sweep",
        "up: the stepped axis' values in increasing order, each cell starting from the state "
        "the previous (lower) one ended in; down: in decreasing order (docs/model.md, "
        "Stepped-sine sweeps)", dtype="str"),
    "poincare_deflection1": Variable(
        ("*", "period"), "m", "stroboscopic tip deflection of beam 1",
        "y1(l1, t) once per forcing period at forcing phase 0, t = period * 2 pi / Omega "
        "(Poincare section; a bifurcation diagram plots it against a swept axis)"),
    "poincare_deflection2": Variable(
        ("*", "period"), "m", "stroboscopic tip deflection of beam 2 minus the clearance",
        "y2(l2, t) - Delta (as tip_deflection_2) once per forcing period at forcing phase 0"),
    "poincare_velocity1": Variable(
        ("*", "period"), "m s-1", "stroboscopic tip velocity of beam 1",
        "dy1(l1, t)/dt once per forcing period at forcing phase 0"),
    "poincare_velocity2": Variable(
        ("*", "period"), "m s-1", "stroboscopic tip velocity of beam 2",
        "dy2(l2, t)/dt once per forcing period at forcing phase 0"),
    "response_period": Variable(
        ("*",), "1", "period of the steady response in forcing periods",
        "smallest p from 1 to max_period with |x(k + p) - x(k)| <= period_tolerance * scale "
        "over the samples, x = (y1, y2, v1 / Omega, v2 / Omega) at the tips and scale the "
        "largest |x| component; 0 if none (chaotic, quasi-periodic, longer period, or a "
        "transient not yet decayed)", dtype="int32"),
    "steady_impact_rate": Variable(
        ("*",), "s-1", "contact onsets per second in the steady state",
        "contact onsets in the sampled window [transient_periods, transient_periods + "
        "sampled_periods) forcing periods, per second (every micro-contact of a rattle)"),
    "steady_episode_rate": Variable(
        ("*",), "s-1", "impact episodes per second in the steady state",
        "impact episodes (clusters of contacts, docs/model.md) starting in the sampled window, "
        "per second"),
})

# continuation (impactbeams.continuation): periodic orbits along a branch ("branch_point"), in
# the order they were found, branches one after the other
STABILITY = ("unstable", "stable")
BIFURCATIONS = ("none", "fold", "period_doubling", "neimark_sacker", "grazing",
                "branch_point", "contact_merge", "contact_split", "chatter")  # events.LABELS
VARIABLES.update({
    "branch_point": Variable(("branch_point",), "1", "branch point number",
                             "index of the periodic orbit along the continuation, from 0",
                             dtype="int64"),
    "branch": Variable(("branch_point",), "1", "branch number",
                       "0 for the branch started from the guess; each period doubling followed "
                       "starts the next (attribute branch_origins)", dtype="int32"),
    "orbit_period": Variable(("branch_point",), "1", "period of the orbit in forcing periods",
                             "the orbit repeats after this many forcing periods 2 pi / Omega",
                             dtype="int32"),
    # "multiplier": the coordinate of impactbeams.orbits' multipliers (below), shared
    "multiplier_modulus": Variable(
        ("branch_point", "multiplier"), "1", "modulus of the Floquet multiplier",
        "|mu| of the eigenvalues mu of the orbit's monodromy matrix (the Jacobian of its "
        "period map), largest first; < 1 for all: stable", symbol=r"$|\mu|$"),
    "multiplier_argument": Variable(
        ("branch_point", "multiplier"), "rad", "argument of the Floquet multiplier",
        "arg mu in (-pi, pi]: 0 real positive, pi real negative"),
    "stable": Variable(("branch_point",), "1", "stability of the periodic orbit",
                       "1 if every Floquet multiplier has |mu| < 1, else 0", dtype="int8",
                       flags=STABILITY),
    "bifurcation": Variable(
        ("branch_point",), "1", "bifurcation located at the branch point",
        "0 none; 1 fold (a multiplier through +1, the branch turns back in the parameter); 2 "
        "period_doubling (a real multiplier through -1); 3 neimark_sacker (a complex pair "
        "through |mu| = 1); 4 grazing (the orbit's smallest free-flight gap through 0, the "
        "contact sequence changes); 5 branch_point (a real multiplier through +1 where the "
        "branch does not turn: another branch crosses it); 6 contact_merge and 7 contact_split "
        "(a free interval between two contacts closes or opens, in the direction the branch "
        "is followed): each located to the attribute locate_tolerance in the parameter; 8 "
        "chatter (the contacts within an episode changed between the previous point and this "
        "one, not located: micro_contacts = summarise). Fold, period doubling, "
        "Neimark-Sacker and branch point are smooth bifurcations, found only within one "
        "smooth piece (the same contact sequence); a change of stability across a nonsmooth "
        "event (4, 6, 7, 8) belongs to that event", dtype="int8", flags=BIFURCATIONS),
    "newton_iterations": Variable(("branch_point",), "1", "Newton iterations",
                                  "corrector iterations that found the branch point",
                                  dtype="int32"),
    "state": Variable(("state",), "1", "state component",
                      "index into the section state: the modal coordinates, then their "
                      "velocities", dtype="int64"),
    "section_state": Variable(
        ("branch_point", "state"), "1", "state of the orbit on the stroboscopic section",
        "the orbit's state at t = 0 mod the forcing period, forcing phase 0: the modal "
        "coordinates q (units kg^(1/2) m) then their rates (kg^(1/2) m/s) of the free modes, "
        "beam 1's then beam 2's (docs/continuation.md)"),
    "tip_amplitude_1": Variable(("branch_point",), "m", "largest tip deflection of beam 1",
                                "max |y1(l1, t)| over the orbit", symbol=r"$\max|y_1(l_1)|$"),
    "tip_amplitude_2": Variable(("branch_point",), "m", "largest tip deflection of beam 2",
                                "max |y2(l2, t)| over the orbit (0 against a stop)",
                                symbol=r"$\max|y_2(l_2)|$"),
    "tip_relative_amplitude_1": Variable(
        ("branch_point",), "m", "largest tip deflection of beam 1 relative to its clamp",
        "max |y1(l1, t) - u_b1(t)| over the orbit, u_b1 = U0 sin(Omega t) where the shaker "
        "carries beam 1's clamp (else 0: equal to tip_amplitude_1)",
        symbol=r"$\max|y_1(l_1) - u_b|$"),
    "transmissibility": Variable(
        ("branch_point",), "1", "transmissibility of the base motion to beam 1's tip",
        "tip_amplitude_1 / base_amplitude: the largest absolute tip deflection over the shaker's "
        "amplitude U0 (below contact, the modulus of the linear transmissibility |Y(l1)| / U0); "
        "NaN without base motion", symbol=r"$\max|y_1(l_1)| / U_0$"),
    "max_impact_velocity": Variable(
        ("branch_point",), "m s-1", "largest impact velocity",
        "max of -dg/dt at a contact's onset over the orbit (the gap's closing speed, "
        "impact_velocity of a simulated run), of the onsets inside the period (a contact "
        "under way at the section has its onset outside it); 0 without one",
        symbol=r"$v_\max$"),
    "peak_contact_force": Variable(("branch_point",), "N", "largest contact force",
                                   "max R(t) over the orbit; 0 without contact",
                                   symbol=r"$R_\max$"),
    "contact_impulse": Variable(("branch_point",), "N s", "contact impulse per forcing period",
                                "integral of R over the orbit divided by its period in forcing "
                                "periods"),
    "section": Variable(("section",), "1", "stroboscopic section of the orbit",
                        "k of the orbit's k-th stroboscopic sample, at t = k 2 pi / Omega, "
                        "from 0 to its period minus 1", dtype="int64"),
    "section_deflection_1": Variable(
        ("branch_point", "section"), "m", "tip deflection of beam 1 on the sections",
        "y1(l1) at t = k 2 pi / Omega (forcing phase 0), k from 0 to the orbit's period minus "
        "1 (NaN beyond): the orbit's stroboscopic samples, as poincare_deflection1 of a "
        "bifurcation diagram", symbol="$y_1(l_1)$"),
    "contacts_per_orbit": Variable(("branch_point",), "1", "contacts per orbit",
                                   "contact onsets over one period of the orbit", dtype="int32"),
    "grazing_gap": Variable(
        ("branch_point",), "m", "signed distance of the orbit from grazing",
        "the smallest local minimum of the gap in free flight (> 0), or minus the overlap of "
        "the orbit's shallowest contact, its peak force over the contact stiffness (< 0), "
        "whichever is nearer 0: it passes through 0 where a contact appears or vanishes "
        "(docs/continuation.md); NaN if neither exists"),
})

# grazing curves of the non-impacting steady orbit (impactbeams.orbits.grazing): points of the
# curve in the plane of Omega and a drive or the clearance, along "grazing_point"; the
# parameters whose grazing value a curve gives at each Omega in closed form
GRAZING_PARAMETERS = ("force_amplitude", "base_amplitude", "clearance")
VARIABLES.update({
    "grazing_point": Variable(("grazing_point",), "1", "grazing curve point number",
                              "index of the point along the grazing curve, from 0",
                              dtype="int64"),
    "grazing_phase": Variable(
        ("grazing_point",), "rad", "forcing phase of the grazing contact",
        "Omega t mod 2 pi, in [0, 2 pi), at which the steady non-impacting orbit's gap "
        "touches zero at the point (its minimum over the forcing period; phase 0 where the "
        "drives' sines rise through 0); NaN where the curve has no point"),
    "grazing_contact": Variable(
        ("grazing_point",), "1", "contact that grazes",
        "index in the run's contacts of the contact whose gap touches zero first at the point "
        "(grazing curves of several contacts); -1 where the curve has no point",
        dtype="int32"),
})

# bifurcation curves in two parameters (impactbeams.continuation.twoparameter), along
# "branch_point" like a branch: the codimension-two points met on the way
CURVE_EVENTS = ("none", "end", "turning_point", "cusp", "grazing", "contact_merge",
                "contact_split", "resonance_1_1", "resonance_1_2", "resonance_1_3",
                "resonance_1_4", "fold_neimark_sacker", "flip_neimark_sacker")
VARIABLES.update({
    "curve_condition": Variable(
        ("branch_point",), "1", "bifurcation test function",
        "the augmented system's condition at the point, zero on the curve to the corrector's "
        "tolerance: the signed grazing value (m) on a grazing curve; the minimally augmented "
        "system's s (the bordered M - sigma I's last unknown, sigma = +1 for a fold, -1 for a "
        "period doubling; of the bialternate product M (.) M - I on a Neimark-Sacker curve) on a "
        "multiplier's curve"),
    "curve_tangent_1": Variable(
        ("branch_point",), "1", "tangent's part along the first parameter",
        "the first parameter's component of the curve's unit tangent in the scaled unknowns "
        "(per the first parameter's box): 0 where that parameter turns back along the curve"),
    "curve_tangent_2": Variable(
        ("branch_point",), "1", "tangent's part along the second parameter",
        "the second parameter's component of the curve's unit tangent in the scaled unknowns "
        "(per the second parameter's range): 0 where that parameter turns back along the "
        "curve"),
    "curve_stable": Variable(
        ("branch_point",), "1", "stability of the orbit but for the bifurcating multiplier",
        "1 if every Floquet multiplier has |mu| < 1, leaving out on a fold or period-doubling "
        "curve the one nearest +1 or -1, on a Neimark-Sacker curve the complex pair nearest "
        "the unit circle (on the curve, at it to round-off), else 0: whether the orbit is "
        "stable on one side of the bifurcation", dtype="int8", flags=STABILITY),
    "curve_pair_cosine": Variable(
        ("branch_point",), "1", "cosine of the Neimark-Sacker pair's argument",
        "(mu + mu') / 2 of the two Floquet multipliers whose product is nearest 1 (on a "
        "Neimark-Sacker curve the pair e^(+-i theta) on the unit circle: cos theta; beyond +1 "
        "or -1 the pair is real, a neutral saddle): 1 at a 1:1 resonance, -1 at 1:2, -1/2 at "
        "1:3, 0 at 1:4"),
    "curve_event": Variable(
        ("branch_point",), "1", "codimension-two point located at the curve point",
        "0 none; 1 end (the curve's last point: the attribute curve_ending says why); 2 "
        "turning_point (the second parameter turns back: the tangent's part along it changes "
        "sign); 3 cusp (a turning point of a fold curve where the tangent's part along the "
        "first parameter is below 1e-3 as well); 4 grazing (the orbit's grazing value changes "
        "sign along a fold, period-doubling or Neimark-Sacker curve: the curve ends there); 5 "
        "contact_merge, 6 contact_split (the orbit's contacts per orbit fall or rise there "
        "without a contact at zero depth: a multiplier's curve ends there); on a "
        "Neimark-Sacker curve, where the cosine of its pair's argument (curve_pair_cosine) "
        "passes 7 resonance_1_1 (+1), 8 resonance_1_2 (-1), 9 resonance_1_3 (-1/2), 10 "
        "resonance_1_4 (0) (at 1:1 and 1:2 the pair turns real: the curve ends there), and "
        "where a real multiplier but the pair passes +1, 11 fold_neimark_sacker, or -1, 12 "
        "flip_neimark_sacker; each located to the attribute locate_tolerance",
        dtype="int8", flags=CURVE_EVENTS),
})

# basins of attraction (impactbeams.orbits.basin_map): one label per initial state ("*": the plane's
# two axes, or "cell" for a list of states), and the attractors found, along "attractor"
BASIN_LABELS = {-1: "not_settled", -2: "stopped"}  # the labels that name no attractor
BASIN_POINTS = 41  # initial states along each axis of a basin map's grid, by default
VARIABLES.update({
    "start_tip_deflection": Variable(
        ("*",), "m", "initial tip deflection of beam 1",
        "y1(l1) at t = 0 given to beam 1's first free mode, every other coordinate at rest: "
        "q_1 = y / Y_1(l1)", symbol="$y_1(l_1, 0)$"),
    "start_tip_velocity": Variable(
        ("*",), "m s-1", "initial tip velocity of beam 1",
        "dy1(l1)/dt at t = 0 given to beam 1's first free mode, every other coordinate at "
        "rest: q_1' = v / Y_1(l1) added to the rest velocity", symbol=r"$\dot y_1(l_1, 0)$"),
    "cell": Variable(("cell",), "1", "initial state number",
                     "index of the initial state, from 0", dtype="int64"),
    "start_displacement": Variable(
        ("*", "coordinate"), _MODAL_UNITS, "initial modal displacements",
        "free modal coordinates q at t = 0 (forcing phase 0) of each initial state"),
    "start_velocity": Variable(
        ("*", "coordinate"), _MODAL_UNITS + " s-1", "initial modal velocities",
        "dq/dt of the free modal coordinates at t = 0 of each initial state"),
    "basin": Variable(
        ("*",), "1", "attractor reached",
        "index along attractor of the attractor the run from the initial state settles on; -1 "
        "not_settled: its stroboscopic samples did not repeat within max_periods; -2 stopped: "
        "the run stopped early (event limit) or the tied law refused the start (tips "
        "overlapping)", dtype="int32"),
    "settle_periods": Variable(
        ("*",), "1", "forcing periods to settle",
        "forcing periods from t = 0 until the stroboscopic samples repeat with the attractor's "
        "period to settle_tolerance of their scale; the periods run if not settled",
        dtype="int32"),
    "attractor": Variable(("attractor",), "1", "attractor number",
                          "index of the attractor: the given orbits first, then those found, "
                          "in the order of the first initial state reaching each",
                          dtype="int64"),
    "attractor_period": Variable(("attractor",), "1", "period of the attractor",
                                 "its period in forcing periods 2 pi / Omega", dtype="int32"),
    "attractor_contacts": Variable(("attractor",), "1", "contacts per orbit",
                                   "contact onsets over one period of the attractor",
                                   dtype="int32"),
    "attractor_amplitude": Variable(
        ("attractor",), "m", "tip amplitude of the attractor",
        "max |y1(l1)| over one period of the attractor, sampled 256 times per forcing period",
        symbol=r"$\max |y_1(l_1)|$"),
    "attractor_displacement": Variable(
        ("attractor", "coordinate"), _MODAL_UNITS, "section state of the attractor: q",
        "free modal coordinates q on the section t = 0 mod 2 pi / Omega (a periodic orbit's "
        "state), converged to state_tolerance; NaN for a tied-law orbit in contact there"),
    "attractor_velocity": Variable(
        ("attractor", "coordinate"), _MODAL_UNITS + " s-1", "section state of the attractor: q'",
        "dq/dt of the free modal coordinates on the section (see attractor_displacement)"),
    "attractor_section_deflection1": Variable(
        ("attractor", "section"), "m", "tip deflection of beam 1 on the sections",
        "y1(l1) at the attractor's stroboscopic samples, k = 0 .. period - 1 (NaN beyond)"),
    "attractor_section_velocity1": Variable(
        ("attractor", "section"), "m s-1", "tip velocity of beam 1 on the sections",
        "dy1(l1)/dt at the attractor's stroboscopic samples (NaN beyond its period)"),
    "attractor_multiplier_real": Variable(
        ("attractor", "multiplier"), "1", "real part of the attractor's Floquet multipliers",
        "eigenvalues of the period map's Jacobian over the attractor's period at its section "
        "state, by decreasing modulus (NaN where unknown: the tied law has no tangent flow)"),
    "attractor_multiplier_imag": Variable(
        ("attractor", "multiplier"), "1", "imaginary part of the attractor's Floquet "
        "multipliers", "see attractor_multiplier_real"),
    "attractor_given": Variable(("attractor",), "1", "attractor given as a periodic orbit",
                                "1 for an orbit given by the caller, 0 for one found",
                                dtype="int8"),
    "attractor_residual": Variable(
        ("attractor",), "1", "relative residual of the attractor's state",
        "max |x(t + p T) - x(t)| / max |x| of its last stroboscopic samples x = (y1, y2, "
        "v1 / Omega, v2 / Omega) (a found attractor run on to state_tolerance; a given orbit's "
        "shooting residual)"),
    "basin_fraction": Variable(("attractor",), "1", "basin fraction",
                               "fraction of the initial states that settle on the attractor"),
    "basin_fraction_error": Variable(
        ("attractor",), "1", "standard error of the basin fraction",
        "sqrt(f (1 - f) / n) over the n initial states: the sampling error of f for random "
        "initial states (for a grid, the same number as a guide; refine the grid to check)"),
    "basin_fraction_low": Variable(
        ("attractor",), "1", "lower end of the basin fraction's confidence interval",
        "Wilson score interval at basin_confidence (random initial states)"),
    "basin_fraction_high": Variable(
        ("attractor",), "1", "upper end of the basin fraction's confidence interval",
        "Wilson score interval at basin_confidence (random initial states)"),
})

# what the long-time response gives: computed over sampled_periods forcing periods after
# transient_periods, not over [0, t_max] (the sweeps' long-time observables; plot titles name
# that window instead of t_max)
POINCARE_VARIABLES = ("poincare_deflection1", "poincare_deflection2", "poincare_velocity1",
                      "poincare_velocity2")
LONG_TIME_VARIABLES = (*POINCARE_VARIABLES, "response_period", "steady_impact_rate",
                       "steady_episode_rate")
# what a sweep's map can hold along its grid ("*"): observables and what comes with them (a basin
# map's "*" is its initial states')
BASIN_MAP_VARIABLES = ("start_tip_deflection", "start_tip_velocity", "start_displacement",
                       "start_velocity", "basin", "settle_periods")
MAP_VARIABLES = tuple(name for name, variable in VARIABLES.items()
                      if variable.dims[0] == "*" and name not in BASIN_MAP_VARIABLES)


def attributes(name: str) -> dict[str, Any]:
    """CF attributes (units, long_name, description; a status' flags) of a registered variable."""
    variable = VARIABLES[name]
    return {"units": variable.units, "long_name": variable.long_name,
            "description": variable.description, **_flag_attributes(variable)}


def _flag_attributes(variable: Variable) -> dict[str, Any]:
    """CF ``flag_values`` (of the variable's own type, as CF asks) and ``flag_meanings``."""
    if not variable.flags:
        return {}
    return {"flag_values": np.arange(len(variable.flags), dtype=variable.dtype),
            "flag_meanings": " ".join(variable.flags)}


def parameter_attributes(name: str) -> dict[str, str]:
    """CF attributes (units, long_name) of a parameter used as a coordinate."""
    parameter = PARAMETERS[name]
    return {"units": parameter.units, "long_name": parameter.long_name}


def global_attributes(title: str, action: str, parameters: Mapping[str, Any],
                      **run: Any) -> dict[str, Any]:
    """Global attributes of a Dataset: CF conventions, provenance, damping law, parameters.

    ``action`` completes the ``history`` line (timestamp, package version, what was run);
    ``parameters`` are the model parameters by name (SI units), ``run`` the run's settings.
    """
    from impactbeams import __version__

    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    return {
        "Conventions": CONVENTIONS,
        "title": title,
        "history": f"{now}: impactbeams {__version__} {action}",
        "source": f"impactbeams {__version__}",
        "references": REFERENCES,
        "damping_law": DAMPING_LAW,
        **({"contact_law_note": LAWS[parameters["contact_law"]].note}
           if "contact_law" in parameters else {}),
        **run,
        **_described(parameters),
    }


def parameter_text(value: Any) -> Any:
    """A parameter as an attribute or JSON holds it: numbers and names as they are.

    A tuple of parts (a beam's attachments, `impactbeams.structure`) becomes one text, each part
    as Python writes it (``"PointMass(position=0.1, mass=0.002, rotary_inertia=0.0)"``), joined
    by "; "; any other object (a user structure) its text (``"MatrixStructure(80 DOFs, ...)"``).
    """
    if isinstance(value, tuple):
        return "; ".join(map(repr, value))
    return value if isinstance(value, (str, int, float, np.number)) else repr(value)


def _described(parameters: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters that describe the run: against a stop, none of beam 2's (its defaults).

    A beam's attachments become one text attribute (`parameter_text`).
    """
    described = {name: parameter_text(value) for name, value in parameters.items()}
    if counterpart_named(parameters.get("counterpart")).has_beam2:
        return described
    return {name: value for name, value in described.items() if name not in _BEAM2_FIELDS}


_BEAM2_FIELDS = ("l2", "EI2", "rhoA2")  # Params' fields of beam 2 (params.BEAM2_KEYS' part)


# what describes one variable: its dimensions, NumPy type and attributes
Description = tuple[tuple[str, ...], np.dtype, Mapping[str, Any]]


def validate(dataset: xr.Dataset, strict: bool = True) -> None:
    """Raise ValueError, saying what, if a registered name in ``dataset`` is not as registered.

    See `check_variables`; every Dataset the package writes or reads goes through it.
    """
    check_variables({str(name): (variable.dims, variable.dtype, variable.attrs)
                     for name, variable in dataset.variables.items()}, strict)


def check_variables(variables: Mapping[str, Description], strict: bool = True) -> None:
    """Raise ValueError, saying what, if a registered variable or parameter is not as registered.

    A registered variable (data variable or coordinate) must have its units, long_name,
    dtype, dimensions (``"*"``: any swept axes before the rest) and flags; a parameter as a
    coordinate its units and long_name. Other names are not checked (a user's additions).
    ``strict=False`` (files read) allows what files of earlier versions lack: the flags.
    Only metadata is read, never data: a lazily opened file stays unread.
    """
    for name, (dims, dtype, attrs) in variables.items():
        if name in VARIABLES:
            _check_variable(name, VARIABLES[name], (tuple(dims), np.dtype(dtype), attrs), strict)
        elif name in PARAMETERS:
            _check_attributes(name, attrs, parameter_attributes(name), ("units", "long_name"))


def _check_variable(name: str, variable: Variable, found: Description, strict: bool) -> None:
    dims, dtype, attrs = found
    expected = attributes(name)
    keys = ["units", "long_name"]
    if variable.flags and (strict or "flag_meanings" in attrs or "flag_values" in attrs):
        keys += ["flag_values", "flag_meanings"]
    _check_attributes(name, attrs, expected, keys)
    if variable.dtype == "str" and dtype.kind in "OUS":  # text: any NumPy or netCDF string
        pass
    elif dtype != np.dtype(variable.dtype):
        raise ValueError(f"variable {name!r} has dtype {dtype}, expected {variable.dtype}")
    if not _dims_match(dims, variable.dims):
        wanted = ("(the swept axes, " + ", ".join(variable.dims[1:]) + ")"
                  if variable.dims[:1] == ("*",) else f"{variable.dims}")
        raise ValueError(f"variable {name!r} has dimensions {dims}, expected {wanted}")


def _check_attributes(name: str, attrs: Mapping[str, Any], expected: Mapping[str, Any],
                      keys: Sequence[str]) -> None:
    for key in keys:
        value = attrs.get(key)
        if not np.array_equal(np.asarray(value, dtype=object), np.asarray(expected[key],
                                                                          dtype=object)):
            raise ValueError(f"variable {name!r} has {key} = {_shown(value)}, expected "
                             f"{_shown(expected[key])}")


def _shown(value: Any) -> str:
    return repr(value.tolist() if isinstance(value, np.ndarray) else value)


def _dims_match(dims: tuple[str, ...], registered: tuple[str, ...]) -> bool:
    """Whether ``dims`` are ``registered``, ``"*"`` standing for any number of swept axes."""
    if registered[:1] != ("*",):
        return dims == registered
    rest = registered[1:]
    split = len(dims) - len(rest)
    return split >= 0 and dims[split:] == rest and not set(dims[:split]) & set(rest)


# a labelled point of the same kind as an earlier one whose parameter equals its to this many
# significant digits, and its tip amplitude to AMPLITUDE_DIGITS, is that event again (the
# two sides of one event; a dataset joined from runs that share a part); the amplitude tells
# apart two events of a kind at one parameter on two parts of a folded branch
EVENT_DIGITS, AMPLITUDE_DIGITS = 9, 6


def located_events(dataset: xr.Dataset) -> np.ndarray:
    """The indices of the dataset's labelled points, each located event once.

    Of the points with one kind, one value of the continued parameter to ``EVENT_DIGITS``
    significant digits and one ``tip_amplitude_1`` (if the dataset has it) to
    ``AMPLITUDE_DIGITS``, the first. What the run's summary counts and what `impactbeams
    plot` marks and counts in its legend, so that the two agree (a run stores each located
    event on one point: `impactbeams.continuation.branch`).
    """
    codes = dataset["bifurcation"].values
    parameter = dataset[dataset.attrs["continued_parameter"]].values
    amplitude = (dataset["tip_amplitude_1"].values if "tip_amplitude_1" in dataset
                 else np.zeros(codes.size))
    seen: set[tuple[int, str, str]] = set()
    kept = []
    for index in np.flatnonzero(codes):
        key = (int(codes[index]), f"{parameter[index]:.{EVENT_DIGITS}g}",
               f"{amplitude[index]:.{AMPLITUDE_DIGITS}g}")
        if key not in seen:
            seen.add(key)
            kept.append(index)
    return np.array(kept, dtype=np.int64)


def basin_fraction_text(dataset: xr.Dataset, k: int, interval: bool) -> str:
    """Attractor ``k``'s basin fraction and standard error, ``0.855 ± 0.018``.

    With ``interval`` (random states) its confidence interval too: ``0.855 ± 0.018 (95 %
    interval 0.817 to 0.886)``.
    """
    text = (f"{float(dataset.basin_fraction[k]):.3f} ± "
            f"{float(dataset.basin_fraction_error[k]):.3f}")
    if interval:
        text += (f" ({100 * float(dataset.attrs['basin_confidence']):g} % interval "
                 f"{float(dataset.basin_fraction_low[k]):.3f} to "
                 f"{float(dataset.basin_fraction_high[k]):.3f})")
    return text
