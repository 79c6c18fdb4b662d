"""Benchmark: harmonic balance (pyHarm) against impactbeams' exact orbits on one reduced model.

The model (`impactbeams.packing.reduced_model`): the two default beams with ``N_MODES``
cantilever modes each, modal damping, the tip force F0 sin(Omega t) on beam 1 and the spring
contact law with its static correction, written for pyHarm as two linear substructures plus a
`PenaltyUnilateralGap` element. Each substructure's dofs are a massless tip point, the modes'
tip displacement tip . eta and the other modal coordinates; the point hangs on a spring
1 / r_i (the residual flexibility the truncated modes miss) and carries the tip loads, and the
gap element (the law's k) acts between the two points: in series they give the law's effective
k_e, so both codes solve the same equations (checked below on the linear case, to round-off).

* **Exact side**: Newton on z = P(z) with impactbeams' exact period map and its monodromy
  (`impactbeams.orbits.PeriodMap`), started from a long `simulate`; the tip amplitude
  max |y1(l1, t)| over the orbit comes from the map's own measure (Brent-refined).
* **Harmonic balance**: pyHarm's fixed-frequency solve (scipy's hybr, no continuation) with nh
  harmonics and nti = 64 (2 nh + 1) (rounded up to a power of 2) AFT samples per period, for nh
  increasing until the tip amplitude is within 1e-6 (relative) of the exact one. Each solve
  starts from the best start there is: the linear response to the exact orbit's contact force
  truncated to nh harmonics (so the time measured is that of the solve alone; pyHarm's own
  continuation from the non-impacting branch stops at grazing, see ``continuation`` below).
* **Costs**: pyHarm's time per solve and per branch point of its arc-length continuation on
  the impacting branch, at the nh that reaches 1e-3; ours: one period map with its monodromy,
  and a Newton correction from the orbit 0.5 rad/s away (what a continuation step costs).

Writes docs/benchmarks/harmonic_balance.json and harmonic_balance.md. pyHarm is an optional
peer (``pip install -e .[peers]``, package ``pyharm-os``): without it the script says so and
exits. Timings are wall times on a machine that may be shared.

    python benchmarks/bench_harmonic_balance.py [--max-harmonics 96]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import logging
import math
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from impactbeams import __version__, simulate
from impactbeams.orbits import PeriodMap
from impactbeams.packing import ReducedModel, reduced_model
from impactbeams.params import Params

ROOT = Path(__file__).parents[1]
OUT = ROOT / "docs" / "benchmarks"
N_MODES = 3  # per beam: a reduced model small enough for dense harmonic balance
BASE = Params(damping_ratio=0.02, force_amplitude=1e-4)  # impacts only near resonance
# impacting period-1 orbits (simulate from rest reaches them): 1 to 4 contacts per period,
# 270 rad/s next to the impacting resonance's peak; 350 rad/s never touches (sanity check)
OMEGAS = (270.0, 280.0, 290.0, 350.0)
TARGETS = (1e-3, 1e-6)  # relative error of the tip amplitude to reach
HARMONICS = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256)
NEWTON_TOLERANCE = 1e-12  # ||P(z) - z|| / ||z||: the orbit to round-off
HB_TOLERANCE = 1e-9  # ||residual|| in units of F0: a converged harmonic-balance solve
REST_HARMONICS = 8  # pyHarm's continuation from the non-impacting branch
COSTLY = 48  # above this nh, no AFT or continuation check (minutes per pyHarm solve)
STEP = 0.5  # rad/s, the neighbouring orbit a continuation step starts from


# ---------------------------------------------------------------- exact side (impactbeams)

def newton_orbit(period_map: PeriodMap, guess: np.ndarray) -> tuple[np.ndarray, int]:
    """The period-1 orbit's section state by Newton on z = P(z), and the iterations taken."""
    z = guess
    for iteration in range(1, 30):
        result = period_map(z, directions="all", measures=False)
        residual = result.state - z
        if np.linalg.norm(residual) <= NEWTON_TOLERANCE * np.linalg.norm(z):
            return z, iteration
        z = z - np.linalg.solve(result.jacobian - np.eye(z.size), residual)
    raise RuntimeError(f"Newton on the period map did not converge at {period_map.params}")


def steady_guess(params: Params, periods: int = 400) -> np.ndarray:
    """The section state after ``periods`` forcing periods from rest (a stable orbit's basin)."""
    with warnings.catch_warnings():  # 3 modes do not resolve the Hertz contact: intended
        warnings.simplefilter("ignore", RuntimeWarning)
        run = simulate(params, periods * 2 * math.pi / params.omega, N_MODES, times=[0.0])
    return np.concatenate([run.final_displacement.values, run.final_velocity.values])


def exact_orbit(params: Params) -> dict:
    """The exact orbit at ``params.omega``: amplitude, contacts, contact force, costs."""
    period_map = PeriodMap(params, N_MODES)
    z, _ = newton_orbit(period_map, steady_guess(params))
    orbit = period_map(z)
    start = time.perf_counter()
    period_map(z, directions="all", measures=False)
    map_s = time.perf_counter() - start
    near = period_map.params.replace(omega=params.omega - STEP)
    z_near, _ = newton_orbit(PeriodMap(near, N_MODES), z)
    start = time.perf_counter()
    _, iterations = newton_orbit(PeriodMap(params, N_MODES), z_near)
    step_s = time.perf_counter() - start
    return {"amplitude_m": orbit.max_tip1, "contacts_per_period": orbit.contacts,
            "peak_force_N": orbit.peak_force, "state": z,
            "monodromy_map_s": map_s, "newton_step_s": step_s, "newton_iterations": iterations}


def orbit_samples(params: Params, state: np.ndarray, samples: int,
                  ) -> tuple[np.ndarray, float]:
    """R(t) on ``samples`` uniform times of one period of the orbit through ``state``, and
    max |tip . eta| (m), the modes' own tip without the static correction r1 (R - F).

    That maximum: the sampled peak refined by the parabola through its neighbours (an error
    of order (Omega T / samples)^3, below 1e-8 here).
    """
    period = 2 * math.pi / params.omega
    times = period * np.arange(samples) / samples
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        run = simulate(params, period, N_MODES, times=times, initial_state=state)
    force = run.contact_force.values
    model = reduced_model(params, N_MODES)
    loads = force - params.force_amplitude * np.sin(params.omega * times)
    modal = np.abs(run.tip_deflection_1.values - model.residual1 * loads)
    i = int(np.argmax(modal))
    before, peak, after = modal[i - 1], modal[i], modal[(i + 1) % samples]
    return force, float(peak + (after - before) ** 2 / (8 * (2 * peak - before - after)))


# ----------------------------------------------------------------- the model for pyHarm

def beam_matrices(model: ReducedModel, beam: int) -> dict[str, np.ndarray]:
    """M, K, C of one beam, scaled: lengths in clearances, forces in F0 (order-one numbers).

    Dofs: beam 1 (0) (tip point, tip . eta, eta_2, ...), beam 2 (1) (tip . eta, eta_2, ...).
    """
    n = model.frequencies.size // 2
    modes = slice(beam * n, (beam + 1) * n)
    tip = (model.tip1, model.tip2)[beam][modes]
    to_modal = np.eye(n)  # eta = to_modal @ (tip . eta, eta_2, ..., eta_n)
    to_modal[0] = -tip / tip[0]
    to_modal[0, 0] = 1.0 / tip[0]
    point = 1 if beam == 0 else 0  # beam 1's massless tip point comes first
    matrices = {}
    for name, diagonal in (("M", np.ones(n)), ("K", model.frequencies[modes] ** 2),
                           ("C", model.damping[modes])):
        matrix = np.zeros((n + point, n + point))
        matrix[point:, point:] = to_modal.T @ np.diag(diagonal) @ to_modal
        matrices[name] = matrix
    if point:
        matrices["K"][:2, :2] += np.array([[1.0, -1.0], [-1.0, 1.0]]) / model.residual1
    scale = model.clearance / model.force_amplitude
    return {name: matrix * scale for name, matrix in matrices.items()}


def gap_stiffness(model: ReducedModel) -> float:
    """The gap element's k' = k / (1 + k r2): in series with 1 / r1 it gives k_e."""
    return model.stiffness / (1.0 + model.stiffness * model.residual2)


def aft_samples(harmonics: int) -> int:
    """AFT time samples: 64 per Fourier coefficient, rounded up to a power of 2.

    With 16 per coefficient pyHarm's solver stalled at 48 harmonics (the contact set flips
    between samples at every Newton step); with 64 to 256 it converged in 3 Newton steps.
    """
    return 1 << math.ceil(math.log2(64 * (2 * harmonics + 1)))


def pyharm_input(model: ReducedModel, harmonics: int, omega: float, nti: int | None = None,
                 **analysis) -> dict:
    """pyHarm's input dictionary: the two beams, the tip force, the gap; one FRF analysis."""
    scale = model.clearance / model.force_amplitude
    frf = {"study": "frf", "puls_inf": omega, "puls_sup": omega + 1.0, "verbose": False,
           "solver": "scipyroot",
           "solver_options": {"root": {"method": "hybr", "options": {"xtol": 1e-13}}}}
    return {
        "system": {"type": "Base", "nh": harmonics, "nti": nti or aft_samples(harmonics)},
        "substructures": {f"beam{beam + 1}": {"type": "substructure", "ndofs": 1,
                                              "matrix": beam_matrices(model, beam)}
                          for beam in (0, 1)},
        "connectors": {
            # F0 sin(Omega t) downward on beam 1's tip point: pyHarm's dofs point up
            "force": {"type": "SinusForcing", "connect": {"beam1": [0]}, "dirs": [0],
                      "amp": -1.0},
            # force k' (x2 - x1 - clearance) while beam 2's tip is above beam 1's point less
            # the clearance
            "gap": {"type": "PenaltyUnilateralGap", "connect": {"beam2": [0], "beam1": [0]},
                    "dirs": [0], "g": 1.0, "k": gap_stiffness(model) * scale}},
        "analysis": {"frf": {**frf, **analysis}},
    }


def maestro(model: ReducedModel, harmonics: int, omega: float, nti: int | None = None,
            **analysis):
    """A pyHarm Maestro for the model, its banner and logs silenced."""
    from pyHarm.Maestro import Maestro

    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Numba's performance warnings on pyHarm's kernels
        built = Maestro(pyharm_input(model, harmonics, omega, nti, **analysis))
    logging.disable(logging.CRITICAL)
    return built


def coefficients(system, x: np.ndarray, node: int, sub: str = "beam1",
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Cosine and sine coefficients (harmonics 0..nh) of one dof in pyHarm's vector ``x``."""
    dofs = system.expl_dofs
    rows = dofs[(dofs["sub"] == sub) & (dofs["node_num"] == node)]
    size = int(rows["harm"].max()) + 1
    cosine, sine = np.zeros(size), np.zeros(size)
    for index, harmonic, kind in zip(rows.index, rows["harm"], rows["cs"], strict=True):
        (cosine if kind == "c" else sine)[harmonic] = x[index]
    return cosine, sine


def series_maximum(cosine: np.ndarray, sine: np.ndarray) -> float:
    """max |sum_h c_h cos(h tau) + s_h sin(h tau)| over tau, to round-off.

    A grid of 32 points per period of the highest harmonic, then Newton on the derivative
    from the grid's best point.
    """
    h = np.arange(cosine.size)
    tau = np.linspace(0.0, 2 * np.pi, 32 * cosine.size + 64, endpoint=False)
    values = np.cos(np.outer(tau, h)) @ cosine + np.sin(np.outer(tau, h)) @ sine
    t = tau[np.argmax(np.abs(values))]
    for _ in range(8):
        first = h @ (sine * np.cos(h * t) - cosine * np.sin(h * t))
        second = -(h**2) @ (cosine * np.cos(h * t) + sine * np.sin(h * t))
        t -= first / second
    return float(abs(cosine @ np.cos(h * t) + sine @ np.sin(h * t)))


def tip_amplitude(model: ReducedModel, system, x: np.ndarray) -> float:
    """max |y1(l1, t)| (m) of a pyHarm solution: beam 1's tip point, y1 = tip . eta + r1 (R - F).

    The engine's tip carries the static correction under both tip loads, as this point does.
    """
    return series_maximum(*coefficients(system, x, node=0)) * model.clearance


def modal_tip_amplitude(model: ReducedModel, system, x: np.ndarray) -> float:
    """max |tip . eta| (m) of a pyHarm solution: beam 1's modes' own tip (node 1)."""
    return series_maximum(*coefficients(system, x, node=1)) * model.clearance


def harmonic_start(model: ReducedModel, system, force: np.ndarray) -> np.ndarray:
    """pyHarm's unknowns of the linear response to F and the sampled contact force ``force``.

    The exact orbit is that response to its own contact force: truncated to nh harmonics it
    is the closest start a harmonic-balance solve can get.
    """
    n = model.frequencies.size // 2
    omega, harmonics = model.omega, int(system.nh)
    contact = np.fft.rfft(force)[:harmonics + 1] / force.size * 2  # R = Re(sum R_h e^(ih wt))
    contact[0] /= 2
    drive = np.zeros(harmonics + 1, complex)
    drive[1] = -1j * model.force_amplitude  # F0 sin = Re(-i F0 e^(i w t))
    h = np.arange(harmonics + 1)[:, None]
    dynamic = model.frequencies**2 - (h * omega) ** 2 + 1j * h * omega * model.damping
    eta = (np.outer(contact - drive, model.tip1) - np.outer(contact, model.tip2)) / dynamic
    x = np.zeros(system.ndofs)
    dofs = system.expl_dofs
    for beam in (0, 1):
        tip = (model.tip1, model.tip2)[beam][beam * n:(beam + 1) * n]
        modal = eta[:, beam * n:(beam + 1) * n]
        point = [modal @ tip + model.residual1 * (contact - drive)] if beam == 0 else []
        nodes = np.column_stack([*point, modal @ tip, modal[:, 1:]]) / model.clearance
        rows = dofs[dofs["sub"] == f"beam{beam + 1}"]
        for index, harmonic, kind, node in zip(rows.index, rows["harm"], rows["cs"],
                                               rows["node_num"], strict=True):
            value = nodes[harmonic, node]
            x[index] = value.real if kind == "c" else -value.imag
    return x


def hb_solve(model: ReducedModel, harmonics: int, start: np.ndarray | None,
             force: np.ndarray | None = None, nti: int | None = None) -> dict:
    """One fixed-frequency pyHarm solve with ``harmonics``; its amplitude, residual, time.

    ``start``: pyHarm's unknowns (without Omega), or None for the linear response; with
    ``force`` (exact contact force samples), the start is built from it. ``nti``: AFT
    samples (default `aft_samples`).
    """
    nti = nti or aft_samples(harmonics)
    built = maestro(model, harmonics, model.omega, nti)
    analysis = built.nls["frf"]
    if force is not None:
        start = harmonic_start(model, built.system, force)
    begin = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        analysis.initialise(start)
    seconds = time.perf_counter() - begin
    solution = analysis.SolList[0]
    x = solution.x[:-1]
    return {"harmonics": harmonics, "nti": nti, "solve_s": seconds,
            "residual": float(np.linalg.norm(solution.R)),
            "converged": bool(np.linalg.norm(solution.R) <= HB_TOLERANCE),
            "amplitude_m": tip_amplitude(model, built.system, x),
            "modal_amplitude_m": modal_tip_amplitude(model, built.system, x), "x": x}


# ------------------------------------------------------------------------- the studies

def harmonic_study(model: ReducedModel, exact: dict, force: np.ndarray, modal: float,
                   max_harmonics: int) -> list[dict]:
    """Solves with increasing nh until the 1e-6 target (or ``max_harmonics``)."""
    rows = []
    for harmonics in (h for h in HARMONICS if h <= max_harmonics):
        row = hb_solve(model, harmonics, None, force)
        row.pop("x")
        row["error"] = abs(row["amplitude_m"] - exact["amplitude_m"]) / exact["amplitude_m"]
        row["modal_error"] = abs(row["modal_amplitude_m"] / modal - 1.0)
        rows.append(row)
        print(f"  nh {harmonics:4d}: error {row['error']:.2e} (modal tip "
              f"{row['modal_error']:.2e}), residual {row['residual']:.1e}, "
              f"{row['solve_s']:.3f} s", flush=True)
        if row["converged"] and row["error"] <= TARGETS[-1]:
            break
    return rows


def needed(rows: list[dict], target: float) -> dict | None:
    """The first converged solve within ``target``, if any stays so for all larger nh."""
    good = [row["converged"] and row["error"] <= target for row in rows]
    for index, row in enumerate(rows):
        if all(good[index:]):
            return row
    return None


def continuation(model: ReducedModel, harmonics: int, start: np.ndarray | None,
                 low: float, high: float, max_points: int = 200) -> dict:
    """pyHarm's arc-length continuation in Omega over [low, high] from ``start``.

    Returns the accepted points, the time per accepted point and where it ended (Omega and
    the tip amplitude of the last point).
    """
    built = maestro(model, harmonics, low, puls_inf=low, puls_sup=high, puls_start=model.omega,
                    ds0=0.5, ds_max=2.0, ds_min=1e-5, stopper="solnumber",
                    stopper_options={"max_solutions": max_points})
    analysis = built.nls["frf"]
    begin = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        analysis.Solve(start)
    seconds = time.perf_counter() - begin
    accepted = [s for s in analysis.SolList if s.flag_accepted]
    last = accepted[-1]
    return {"harmonics": harmonics, "points": len(analysis.SolList),
            "accepted": len(accepted), "seconds": seconds,
            "seconds_per_point": seconds / max(len(accepted), 1),
            "omega_range": [min(s.x[-1] for s in accepted), max(s.x[-1] for s in accepted)],
            "last_omega": float(last.x[-1]),
            "last_amplitude_m": tip_amplitude(model, built.system, last.x[:-1])}


def linear_check(model: ReducedModel) -> dict:
    """nh = 1 without contact against the closed-form linear response (same equations)."""
    row = hb_solve(model, 1, None)
    dynamic = model.frequencies**2 - model.omega**2 + 1j * model.omega * model.damping
    response = model.tip1 @ (-model.tip1 * -1j * model.force_amplitude / dynamic)
    response -= model.residual1 * -1j * model.force_amplitude
    return {"amplitude_m": row["amplitude_m"], "closed_form_m": float(abs(response)),
            "relative_difference": abs(row["amplitude_m"] / abs(response) - 1.0)}


def case(omega: float, max_harmonics: int) -> dict:
    """Everything at one forcing frequency."""
    params = BASE.replace(omega=omega)
    model = reduced_model(params, N_MODES)
    exact = exact_orbit(params)
    print(f"Omega {omega}: exact amplitude {exact['amplitude_m']:.12e} m, "
          f"{exact['contacts_per_period']} contacts per period", flush=True)
    result = {"omega": omega, **{k: v for k, v in exact.items() if k != "state"}}
    if exact["contacts_per_period"] == 0:
        result["linear_check"] = linear_check(model)
        result["hb"] = [{k: v for k, v in hb_solve(model, 1, None).items() if k != "x"}]
        result["hb"][0]["error"] = abs(result["hb"][0]["amplitude_m"] / exact["amplitude_m"]
                                       - 1.0)
        return result
    force, modal = orbit_samples(params, exact["state"], 1 << 14)
    result["modal_amplitude_m"] = modal
    rows = harmonic_study(model, exact, force, modal, max_harmonics)
    result["hb"] = rows
    for target in TARGETS:
        row = needed(rows, target)
        result[f"harmonics_for_{target:g}"] = None if row is None else row["harmonics"]
    coarse = result[f"harmonics_for_{TARGETS[0]:g}"]
    if coarse is not None and coarse <= COSTLY:  # the AFT's error (twice the samples); a branch
        start = hb_solve(model, coarse, None, force)
        doubled = hb_solve(model, coarse, None, force, nti=2 * start["nti"])
        result["nti_doubled_change"] = abs(doubled["amplitude_m"] / start["amplitude_m"] - 1)
        result["continuation"] = continuation(model, coarse, start["x"], omega, omega + 5.0,
                                              max_points=10)
    return result


def markdown(report: dict) -> str:
    """The report as a Markdown page (docs/benchmarks/harmonic_balance.md)."""
    return section(report, heading="#") + "\n" + details(report)


def section(report: dict, heading: str = "##") -> str:
    """The summary table (also the benchmarks page's section, `run_all.py`)."""
    impacting = [row for row in report["cases"] if row["contacts_per_period"]]
    stall = ""
    if impacting and all(row.get("harmonics_for_1e-06") is None for row in impacting):
        most = max(row["hb"][-1]["harmonics"] for row in impacting)
        stall = f", 1e-6 reached by none of the impacting orbits up to {most} harmonics"
    lines = [f"{heading} Harmonic balance (pyHarm) against the exact orbits", "",
             f"`bench_harmonic_balance.py` ({report['date']}; {report['machine']}; pyHarm "
             f"{report['pyharm']}): the same reduced model ({report['n_modes']} modes per beam, "
             f"spring law k = {report['stiffness']:.4g} N/m with its static correction, "
             f"zeta = {report['damping_ratio']}, F0 = {report['force_amplitude']} N), tip "
             "amplitude max |y1(l1, t)| of the period-1 orbit. Harmonics nh that pyHarm needs "
             "for a relative error of 1e-3 and 1e-6 (from the closest start there is, see "
             f"[harmonic_balance.md](harmonic_balance.md)){stall}; without contact one harmonic "
             "is exact. Times are wall times on a "
             "2-core machine shared with other jobs: seconds are inflated, orders of "
             "magnitude are not. Ours: no harmonics, the exact orbit (Newton on the period "
             "map to 1e-12).", "",
             "| Omega (rad/s) | contacts / period | exact amplitude (m) | nh for 1e-3 | "
             "nh for 1e-6 | pyHarm solve at 1e-3 (s) | pyHarm s / branch point | ours: "
             "period map + monodromy (s) | ours: Newton step (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in report["cases"]:
        coarse = row.get("harmonics_for_0.001")
        solve = next((r["solve_s"] for r in row["hb"] if r["harmonics"] == coarse), None)
        branch = row.get("continuation", {}).get("seconds_per_point")
        lines.append(
            f"| {row['omega']:g} | {row['contacts_per_period']} | {row['amplitude_m']:.6e} | "
            f"{_count(row, 'harmonics_for_0.001', 1)} | {_count(row, 'harmonics_for_1e-06', 1)}"
            f" | {_seconds(solve)} | {_seconds(branch)} | {row['monodromy_map_s']:.4f} | "
            f"{row['newton_step_s']:.4f} ({row['newton_iterations']} maps) |")
    return "\n".join(lines) + "\n"


def _count(row: dict, key: str, linear: int) -> str:
    if row["contacts_per_period"] == 0:
        return f"{linear} (linear)"
    value = row.get(key)
    return f"> {row['hb'][-1]['harmonics']}" if value is None else str(value)


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def details(report: dict) -> str:
    """How the error falls with nh, the linear check and where pyHarm's continuation ends."""
    depth = max(row["peak_force_N"] / report["stiffness"] / row["amplitude_m"]
                for row in report["cases"])
    lines = ["## Error against harmonics", "",
             "Relative errors of max |y1(l1, t)| (the tip, static correction r1 (R - F) "
             "included, as the engine reports it) and of max |tip . eta| (the modes' own tip, "
             "without it). Harmonic balance smooths the contact: the force is the law's k "
             "times the penetration of a truncated Fourier series, a penetration (peak force "
             f"over k) at most {depth:.1e} of the tip amplitude here, so the truncation's "
             "error in the relative tip motion "
             "comes back multiplied in the force, and the contact's onset and release (corners "
             "of R(t)) fall between AFT samples that change with nh: the error falls steeply "
             "to about 1e-3 and then slowly and not monotonically. The modes' own tip "
             "converges no faster than the tip: the static correction's corner is not what "
             "limits. Residual: pyHarm's, in units of F0; above 1e-9 the solve did not "
             "converge (hybr stopped; its amplitude is then that of where it stopped).", "",
             "| Omega | nh | nti | error, tip | error, modes' tip | residual (F0) | solve (s) |",
             "|---|---|---|---|---|---|---|"]
    for row in report["cases"]:
        for r in row["hb"]:
            modal = f"{r['modal_error']:.2e}" if "modal_error" in r else "-"
            lines.append(f"| {row['omega']:g} | {r['harmonics']} | {r['nti']} | "
                         f"{r['error']:.2e} | {modal} | {r['residual']:.1e} | "
                         f"{r['solve_s']:.3f} |")
    lines += ["", "## Linear sanity check", ""]
    for row in report["cases"]:
        if "linear_check" in row:
            check = row["linear_check"]
            lines.append(f"- Omega = {row['omega']:g} rad/s, no contact: pyHarm nh = 1 "
                         f"against the closed form {check['relative_difference']:.1e}, "
                         f"against the exact orbit {row['hb'][0]['error']:.1e}.")
    stall = report["from_rest_branch"]
    lines += ["", "## pyHarm's continuation", "",
              f"- From the non-impacting branch ({stall['omega_range'][0]:g} rad/s upward, "
              f"nh = {stall['harmonics']}): {stall['accepted']} accepted points of "
              f"{stall['points']}, ending at Omega = {stall['last_omega']:.6f} rad/s with tip "
              f"amplitude {stall['last_amplitude_m']:.6e} m against the clearance "
              f"{report['clearance']:g} m: the step shrinks at grazing and the branch never "
              "reaches the impacting orbits."]
    for row in report["cases"]:
        if "nti_doubled_change" in row:
            lines.append(f"- AFT samples: at {row['omega']:g} rad/s the solve with nh = "
                         f"{row['harmonics_for_0.001']} and twice the samples changes the tip "
                         f"amplitude by {row['nti_doubled_change']:.1e} (relative).")
    for row in report["cases"]:
        if "continuation" in row:
            c = row["continuation"]
            lines.append(f"- From the solution at {row['omega']:g} rad/s (nh = "
                         f"{c['harmonics']}) up to {row['omega'] + 5:g} rad/s: "
                         f"{c['accepted']} accepted "
                         f"points of {c['points']} over [{c['omega_range'][0]:.3f}, "
                         f"{c['omega_range'][1]:.3f}] rad/s, {c['seconds_per_point']:.3f} s "
                         "each.")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--max-harmonics", type=int, default=96)
    args = parser.parse_args()
    try:
        import pyHarm
    except ImportError:
        print("bench_harmonic_balance: pyHarm is not installed (pip install -e '.[peers]', "
              "package pyharm-os); skipped", file=sys.stderr)
        return
    report = {"version": __version__, "pyharm": pyHarm.__version__,
              "date": time.strftime("%Y-%m-%d %H:%M"),
              "machine": f"{platform.machine()}, Python {platform.python_version()}",
              "n_modes": N_MODES, "damping_ratio": BASE.damping_ratio,
              "force_amplitude": BASE.force_amplitude, "clearance": BASE.clearance,
              "stiffness": BASE.contact_stiffness, "targets": list(TARGETS), "cases": []}
    OUT.mkdir(parents=True, exist_ok=True)
    # from rest at a low nh: the stall at grazing does not depend on it (seen at 4 and 8)
    report["from_rest_branch"] = continuation(
        reduced_model(BASE.replace(omega=150.0), N_MODES), REST_HARMONICS, None, 150.0, 320.0,
        max_points=100)
    for omega in OMEGAS:
        report["cases"].append(case(omega, args.max_harmonics))
        (OUT / "harmonic_balance.json").write_text(json.dumps(report, indent=1) + "\n")
    (OUT / "harmonic_balance.md").write_text(markdown(report))


if __name__ == "__main__":
    main()
