"""Work-precision of the spring (compliant) contact law: impactbeams against solve_ivp.

Full dynamics of the paper's Fig. 3 forcing (F0 = 1 mN, Omega = 50 rad/s, clearance 11 um)
under the spring law, c = 0, on the same modal equations in both methods:

* impactbeams: exact propagation of both phases, certified event search; no tolerance, so one
  point per case. Two times are reported: ``events`` (pack_run + the event-driven run + the
  per-contact table: what the compared numbers need) and ``simulate`` (the public
  ``simulate(params, t_max, n_modes, times=[0, t_max])``, whose energy bookkeeping at the output
  times is included). Both after a warm-up run (compile), best of ``repeats``.
* solve_ivp DOP853 (and RK45) with events on the modal equations of
  ``tests/spring_modal_reference.py`` (static correction included; the dashpot passed as the
  package's effective c_e), rtol as the knob.
* Reference: the same DOP853 integration at ``tight_rtol``. Its own accuracy is estimated by
  its distance from the rtol = 10 x tight_rtol run (``reference_floor``). atol follows rtol
  (``ATOL_PER_RTOL``): at the reference module's default atol the tight runs agree with each
  other to 1e-10 but sit 1e-7 (relative) from the truth on some contacts.

Errors, contacts matched by index: worst |onset error| (s); worst relative error of duration,
impulse and peak force over contacts complete in both; contact-count difference (counted
apart). A solve_ivp setting matches impactbeams when it has the same count and each error at
most ``MATCH_FACTOR`` x impactbeams'; the speed-up is the cheapest matching setting's time over
impactbeams'. Without a match, the ratio at the most accurate setting is a lower bound (">=").

Units: SI (s, N, N s, N/m).
"""

from __future__ import annotations

import contextlib
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import spring_modal_reference as reference  # noqa: E402
from impactbeams import Params, simulate  # noqa: E402
from impactbeams.compliant import recommended_modes, spring_contact  # noqa: E402
from impactbeams.model import build_free_phase  # noqa: E402
from impactbeams.packing import pack_run  # noqa: E402
from impactbeams.trajectory.impacts import impact_table  # noqa: E402
from impactbeams.trajectory.phases import run  # noqa: E402

MATCH_FACTOR = 2.0
METRICS = ("onset_max", "duration_rel_max", "impulse_rel_max", "peak_rel_max")
MAX_EVENTS = 200_000
# solve_ivp's atol (relative to the state scale, see spring_modal_reference) follows rtol: with
# the reference module's fixed default (1e-14) atol, not rtol, limits DOP853 below rtol ~1e-10
# (contact quantities ~1e-7 off at rtol 1e-13, unseen by varying rtol alone)
ATOL_PER_RTOL, ATOL_CAP = 1e-4, 1e-14


@dataclasses.dataclass(frozen=True)
class SpringCase:
    """One forced run: spring stiffness (N/m), horizon (s), modes per beam (None: recommended)."""

    name: str
    stiffness: float
    t_max: float
    n_modes: int | None = None


@dataclasses.dataclass(frozen=True)
class SpringConfig:
    """Sizes of the spring-law study; see QUICK_SPRING."""

    cases: tuple[SpringCase, ...] = (
        SpringCase("fig3_k1e4", 1e4, 0.1, 20),
        # the k = 1e5 rattle is sensitive past ~0.03 s (see divergence_horizon)
        SpringCase("fig3_k1e5", 1e5, 0.03),
    )
    dop853_rtols: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    rk45_rtols: tuple[float, ...] = (1e-4, 1e-6, 1e-8)
    tight_rtol: float = 1e-13
    repeats: int = 3
    cost_modes: tuple[int, ...] = (20, 40, 80)
    cost_stiffness: float = 1e4
    cost_t_max: float = 0.1
    divergence_horizon: float | None = 0.1  # k = 1e5 case rerun over this horizon


QUICK_SPRING = SpringConfig(
    cases=(SpringCase("fig3_k1e4", 1e4, 0.03, 20), SpringCase("fig3_k1e5", 1e5, 0.01)),
    dop853_rtols=(1e-6, 1e-10), rk45_rtols=(1e-6,), tight_rtol=1e-12, repeats=2,
    cost_modes=(20, 40), cost_t_max=0.03, divergence_horizon=None)


# ---------------------------------------------------------------------------------------------
# The two methods


def _best_time(function, repeats: int):
    """(last result, best wall time in s) of ``repeats`` >= 1 calls."""
    result, best = None, np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return result, best


def _event_table(params: Params, t_max: float, n_modes: int) -> dict[str, np.ndarray]:
    """The per-contact table by the event-driven run alone (what simulate() builds it from)."""
    packed = pack_run(params, n_modes, t_max, t_max)
    table = impact_table(packed, run(packed, MAX_EVENTS))
    return {"onset": table["impact_onset_time"], "duration": table["impact_duration"],
            "impulse": table["impact_impulse"], "peak": table["impact_peak_force"]}


def _simulate_table(params: Params, t_max: float, n_modes: int) -> dict[str, np.ndarray]:
    ds = simulate(params, t_max, n_modes=n_modes, times=np.array([0.0, t_max]),
                  max_events=MAX_EVENTS)
    return {"onset": ds.impact_onset_time.values, "duration": ds.impact_duration.values,
            "impulse": ds.impact_impulse.values, "peak": ds.impact_peak_force.values}


def warm_up() -> None:
    """Compile (or load from the Numba cache) every kernel simulate() uses, spring law."""
    simulate(Params(contact_stiffness=1e4), 0.01, n_modes=12, times=np.array([0.0, 0.01]))


def time_impactbeams(params: Params, t_max: float, n_modes: int, repeats: int,
                     simulate_repeats: int | None = None) -> tuple[dict, dict[str, float]]:
    """impactbeams' contact table and its best times (s): ``events`` and ``simulate``.

    Call ``warm_up`` first: no call here is discarded as a warm-up.
    """
    table, events = _best_time(lambda: _event_table(params, t_max, n_modes), repeats)
    public, whole = _best_time(lambda: _simulate_table(params, t_max, n_modes),
                               repeats if simulate_repeats is None else simulate_repeats)
    for key in table:  # same numbers by both routes
        np.testing.assert_array_equal(table[key], public[key])
    return table, {"events": events, "simulate": whole}


def effective_damping(params: Params, n_modes: int) -> float:
    """The package's dashpot c_e = c / (1 + k r_N)^2 (N s/m), to hand to the reference."""
    return spring_contact(build_free_phase(params, n_modes), params.tip_compliance,
                          params.damping_ratio, params.contact_stiffness,
                          params.contact_damping).effective_damping


@contextlib.contextmanager
def _ivp_method(method: str):
    """Run the reference module's solve_ivp with ``method`` instead of its DOP853."""
    original = reference.solve_ivp
    reference.solve_ivp = lambda *args, **kw: original(*args, **{**kw, "method": method})
    try:
        yield
    finally:
        reference.solve_ivp = original


def time_ivp(params: Params, t_max: float, n_modes: int, c_e: float, method: str,
             rtol: float) -> tuple[dict, float]:
    """solve_ivp's contact table (same keys as impactbeams') and its wall time (s)."""
    start = time.perf_counter()
    with _ivp_method(method):
        out = reference.spring_modal_contacts(
            params, n_modes, params.contact_stiffness, c=c_e, rtol=rtol, n_contacts=None,
            t_max=t_max, atol_scale=min(ATOL_CAP, ATOL_PER_RTOL * rtol))
    seconds = time.perf_counter() - start
    return {"onset": out["onset"], "duration": out["duration"], "impulse": out["impulse"],
            "peak": out["peak"]}, seconds


# ---------------------------------------------------------------------------------------------
# Errors


def _worst_relative(values: np.ndarray, ref: np.ndarray) -> float:
    keep = np.isfinite(values) & np.isfinite(ref) & (ref != 0)
    return float(np.max(np.abs(values[keep] / ref[keep] - 1))) if keep.any() else 0.0


def contact_errors(table: dict, ref: dict) -> dict[str, float]:
    """Worst errors against ``ref``, contacts matched by index.

    Onsets over the contacts both have; duration, impulse and peak force (relative) over those
    complete in both; ``count_diff`` = contacts - reference contacts.
    """
    k = min(table["onset"].size, ref["onset"].size)
    done = min(k, ref["duration"].size, int(np.sum(np.isfinite(table["duration"]))))
    onset = np.abs(table["onset"][:k] - ref["onset"][:k])
    return {"onset_max": float(onset.max()) if k else 0.0,
            **{f"{key}_rel_max": _worst_relative(table[key][:done], ref[key][:done])
               for key in ("duration", "impulse", "peak")},
            "compared": int(k), "count_diff": int(table["onset"].size - ref["onset"].size)}


def first_divergence(table: dict, ref: dict, threshold: float = 1e-6) -> int | None:
    """Index of the first contact whose onset differs by more than ``threshold`` s."""
    k = min(table["onset"].size, ref["onset"].size)
    far = np.flatnonzero(np.abs(table["onset"][:k] - ref["onset"][:k]) > threshold)
    return int(far[0]) if far.size else None


def _matches(errors: dict, target: dict) -> bool:
    return errors["count_diff"] == 0 and all(
        errors[m] <= MATCH_FACTOR * target[m] for m in METRICS)


def matched_speedup(points: list[dict], ib: dict, method: str, time_key: str) -> dict:
    """impactbeams' speed-up over ``method`` at matched error (or a lower bound)."""
    rows = [p for p in points if p["method"] == method]
    good = [p for p in rows if _matches(p["errors"], ib["errors"])]
    if good:
        best, bound = min(good, key=lambda p: p["seconds"]), False
    else:
        best = min(rows, key=lambda p: (abs(p["errors"]["count_diff"]), p["rtol"]))
        bound = True
    return {"method": method, "time": time_key, "rtol": best["rtol"], "lower_bound": bound,
            "speedup": best["seconds"] / ib["seconds"][time_key]}


# ---------------------------------------------------------------------------------------------
# Studies


def case_study(case: SpringCase, cfg: SpringConfig, log=print) -> dict:
    """impactbeams and solve_ivp at several rtols on one case, against tight DOP853."""
    params = Params(contact_stiffness=case.stiffness)
    n = case.n_modes or recommended_modes(params)
    table, seconds = time_impactbeams(params, case.t_max, n, cfg.repeats)
    c_e = effective_damping(params, n)
    log(f"  {case.name}: impactbeams n={n}: events {seconds['events']:.3g} s, simulate "
        f"{seconds['simulate']:.3g} s, {table['onset'].size} contacts")
    ref, ref_seconds = time_ivp(params, case.t_max, n, c_e, "DOP853", cfg.tight_rtol)
    log(f"  reference DOP853 rtol={cfg.tight_rtol:g}: {ref_seconds:.3g} s, "
        f"{ref['onset'].size} contacts")
    points, tables = [], {}
    runs = [("DOP853", r) for r in cfg.dop853_rtols] + [("RK45", r) for r in cfg.rk45_rtols]
    for method, rtol in runs:
        result, secs = time_ivp(params, case.t_max, n, c_e, method, rtol)
        tables[method, rtol] = result
        points.append({"method": f"solve_ivp {method}", "rtol": rtol, "seconds": secs,
                       "contacts": int(result["onset"].size),
                       "errors": contact_errors(result, ref)})
        log(f"  solve_ivp {method} rtol={rtol:g}: {secs:.3g} s, {result['onset'].size} contacts")
    floor = tables.get(("DOP853", 10 * cfg.tight_rtol))
    if floor is None:
        floor, _ = time_ivp(params, case.t_max, n, c_e, "DOP853", 10 * cfg.tight_rtol)
    ib = {"n_modes": n, "seconds": seconds, "contacts": int(table["onset"].size),
          "errors": contact_errors(table, ref)}
    matched = [matched_speedup(points, ib, method, key)
               for method in sorted({p["method"] for p in points})
               for key in ("events", "simulate")]
    return {**dataclasses.asdict(case), "n_modes": n, "effective_damping": c_e,
            "impactbeams": ib, "points": points, "matched": matched,
            "reference": {"rtol": cfg.tight_rtol, "seconds": ref_seconds,
                          "contacts": int(ref["onset"].size),
                          "floor": contact_errors(floor, ref)}}


def divergence_study(case: SpringCase, horizon: float, tight_rtol: float) -> dict:
    """Where impactbeams and tight DOP853 part ways on a sensitive sequence (long horizon)."""
    params = Params(contact_stiffness=case.stiffness)
    n = case.n_modes or recommended_modes(params)
    table, c_e = _event_table(params, horizon, n), effective_damping(params, n)
    ref, _ = time_ivp(params, horizon, n, c_e, "DOP853", tight_rtol)
    loose, _ = time_ivp(params, horizon, n, c_e, "DOP853", 10 * tight_rtol)
    return {"case": case.name, "t_max": horizon, "n_modes": n,
            "contacts": {"impactbeams": int(table["onset"].size),
                         "reference": int(ref["onset"].size),
                         "dop853_10x_rtol": int(loose["onset"].size)},
            "first_divergent_contact": {
                "impactbeams": first_divergence(table, ref),
                "dop853_10x_rtol": first_divergence(loose, ref)},
            "divergence_threshold": 1e-6,
            "onset_of_divergence": _onset_at(ref, first_divergence(table, ref))}


def _onset_at(table: dict, index: int | None) -> float | None:
    return None if index is None else float(table["onset"][index])


def cost_study(cfg: SpringConfig, log=print) -> list[dict]:
    """impactbeams' cost per simulated second and per contact at n_modes = cfg.cost_modes."""
    params = Params(contact_stiffness=cfg.cost_stiffness)
    rows = []
    for n in cfg.cost_modes:
        table, seconds = time_impactbeams(params, cfg.cost_t_max, n, cfg.repeats,
                                          simulate_repeats=1 if n >= 80 else cfg.repeats)
        contacts = int(table["onset"].size)
        rows.append({"n_modes": n, "contacts": contacts, "seconds": seconds,
                     "per_simulated_second": {k: v / cfg.cost_t_max for k, v in seconds.items()},
                     "per_contact": {k: v / contacts for k, v in seconds.items()}})
        log(f"  cost n={n}: events {seconds['events']:.3g} s, simulate "
            f"{seconds['simulate']:.3g} s, {contacts} contacts")
    return rows


def spring_study(cfg: SpringConfig, log=print) -> dict:
    """The whole spring-law study; JSON-ready."""
    warm_up()
    cases = [case_study(case, cfg, log) for case in cfg.cases]
    out = {"config": dataclasses.asdict(cfg), "cases": cases, "cost": cost_study(cfg, log)}
    if cfg.divergence_horizon is not None:
        out["divergence"] = divergence_study(cfg.cases[-1], cfg.divergence_horizon,
                                             cfg.tight_rtol)
        log(f"  divergence: {out['divergence']}")
    return out


# ---------------------------------------------------------------------------------------------
# Plot and markdown (from the JSON only)


def plot_spring(results: dict, path: Path) -> None:
    """Run time against worst onset error and worst peak-force error, one row per case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = results["cases"]
    fig, axes = plt.subplots(len(cases), 2, figsize=(12, 4.6 * len(cases)),
                             constrained_layout=True, squeeze=False)
    for row, case in zip(axes, cases, strict=True):
        for ax, key, label in zip(row, ("onset_max", "peak_rel_max"),
                                  ("worst |onset error| (s)", "worst peak-force error (rel.)"),
                                  strict=True):
            _panel(ax, case, key)
            ax.set(xlabel=label, ylabel="run time (s)",
                   title=f"k = {case['stiffness']:g} N/m, {case['n_modes']} modes, "
                         f"{case['t_max']} s, {case['reference']['contacts']} contacts")
    fig.suptitle("Spring law, full dynamics: work-precision vs DOP853 at rtol "
                 f"{results['config']['tight_rtol']:g} (labels: rtol [count diff]; "
                 "shaded: reference floor)")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _panel(ax, case: dict, key: str, floor: float = 1e-18) -> None:
    for method, marker in (("solve_ivp DOP853", "o-"), ("solve_ivp RK45", "s-")):
        rows = [p for p in case["points"] if p["method"] == method]
        if not rows:
            continue
        x = [max(p["errors"][key], floor) for p in rows]
        ax.plot(x, [p["seconds"] for p in rows], marker, label=method, alpha=0.8)
        for xi, p in zip(x, rows, strict=True):
            bad = p["errors"]["count_diff"]
            ax.annotate(f"{p['rtol']:g}" + (f" [{bad:+d}]" if bad else ""),
                        (xi, p["seconds"]), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
    ib = case["impactbeams"]
    x = max(ib["errors"][key], floor)
    ax.plot(x, ib["seconds"]["events"], "*", ms=12, color="C3", label="impactbeams (events)")
    ax.plot(x, ib["seconds"]["simulate"], "P", ms=9, color="C2",
            label="impactbeams (simulate())")
    ax.axvspan(floor, max(case["reference"]["floor"][key], floor), color="grey", alpha=0.15)
    ax.set(xscale="log", yscale="log")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7)


def _speedup_text(m: dict) -> str:
    return f"{'>= ' if m['lower_bound'] else ''}{m['speedup']:,.0f}x (rtol {m['rtol']:g})"


def _errors_text(e: dict) -> str:
    return (f"{e['onset_max']:.1e} s | {e['duration_rel_max']:.1e} | {e['impulse_rel_max']:.1e}"
            f" | {e['peak_rel_max']:.1e} | {e['count_diff']:+d}")


def markdown(results: dict) -> str:
    """The spring-law section of docs/benchmarks/README.md."""
    lines = ["## Spring contact law: full dynamics against solve_ivp", "",
             "Fig. 3 forcing (F0 = 1 mN, Omega = 50 rad/s, clearance 11 um), c = 0, same modal "
             "equations (`tests/spring_modal_reference.py`); reference DOP853 at rtol "
             f"{results['config']['tight_rtol']:g}. Errors are worst over the contacts "
             "(matched by index): onset (s); duration, impulse, peak force (relative). "
             "`events` = pack + event-driven run + contact table; `simulate` = the public "
             "`simulate(..., times=[0, t_max])`. Plot: `work_precision_spring.png`; data: "
             "`spring.json` (`benchmarks/spring_precision.py`).", ""]
    for case in results["cases"]:
        lines += _case_table(case)
    lines += _cost_table(results)
    if "divergence" in results:
        d = results["divergence"]
        c, first = d["contacts"], d["first_divergent_contact"]
        lines += ["", f"Sensitivity ({d['case']} over {d['t_max']} s): impactbeams "
                  f"{c['impactbeams']} contacts, reference {c['reference']}, DOP853 at 10x its "
                  f"rtol {c['dop853_10x_rtol']}. First contact whose onset differs from the "
                  f"reference's by more than {d['divergence_threshold']:g} s: impactbeams "
                  f"#{first['impactbeams']}, DOP853 at 10x rtol #{first['dop853_10x_rtol']}. "
                  "The rattle amplifies any difference (the reference's own included), so that "
                  "case is scored over a shorter horizon."]
    return "\n".join(lines) + "\n"


def _case_table(case: dict) -> list[str]:
    ib, ref = case["impactbeams"], case["reference"]
    head = ["", f"### k = {case['stiffness']:g} N/m, {case['n_modes']} modes per beam, "
            f"t_max = {case['t_max']} s, {ref['contacts']} contacts", "",
            "| method | run time (s) | onset | duration | impulse | peak force | count diff |",
            "|---|---|---|---|---|---|---|",
            f"| impactbeams, events | {ib['seconds']['events']:.3g} | "
            f"{_errors_text(ib['errors'])} |",
            f"| impactbeams, simulate() | {ib['seconds']['simulate']:.3g} | (same) | | | | |",
            f"| reference floor (DOP853 rtol {10 * ref['rtol']:g} vs {ref['rtol']:g}) | - | "
            f"{_errors_text(ref['floor'])} |"]
    rows = [f"| {p['method']} rtol {p['rtol']:g} | {p['seconds']:.3g} | "
            f"{_errors_text(p['errors'])} |" for p in case["points"]]
    speed = [f"- speed-up at matched error over {m['method']} ({m['time']} time): "
             f"{_speedup_text(m)}" for m in case["matched"]]
    return head + rows + [f"| reference DOP853 rtol {ref['rtol']:g} | {ref['seconds']:.3g} "
                          "| - | - | - | - | - |", ""] + speed


def _cost_table(results: dict) -> list[str]:
    cfg = results["config"]
    lines = ["", f"### impactbeams' cost, k = {cfg['cost_stiffness']:g} N/m, t_max = "
             f"{cfg['cost_t_max']} s", "",
             "| modes per beam | contacts | events: s per simulated s | events: ms per contact "
             "| simulate(): s per simulated s | simulate(): ms per contact |",
             "|---|---|---|---|---|---|"]
    for r in results["cost"]:
        s, c = r["per_simulated_second"], r["per_contact"]
        lines.append(f"| {r['n_modes']} | {r['contacts']} | {s['events']:.3g} | "
                     f"{1e3 * c['events']:.3g} | {s['simulate']:.3g} | "
                     f"{1e3 * c['simulate']:.3g} |")
    return lines


if __name__ == "__main__":
    import argparse
    import json

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    args = parser.parse_args()
    data = spring_study(QUICK_SPRING if args.quick else SpringConfig())
    from run_all import machine

    data["run"] = {"quick": args.quick, **machine()}
    out = Path(args.out)
    (out / "spring.json").write_text(json.dumps(data, indent=1) + "\n")
    plot_spring(data, out / "work_precision_spring.png")
    print(markdown(data))
