"""Regenerate the README's numbers: the sections between ``<!-- generated: NAME -->`` markers.

    python scripts/update_readme.py            # rewrite README.md in place
    python scripts/update_readme.py --check    # exit 1 if README.md is out of date

README.md is read on the forge, not built, so its numbers cannot be computed when it is shown.
Each marked section is produced here instead: from short runs of the library (the first
contacts and the episodes of the Fig. 3 case, which do not follow round-off) or from the
benchmark results files in docs/benchmarks/ (never re-measured here). ``tests/test_docs.py``
fails when README.md differs from what this script writes.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
BENCHMARKS = ROOT / "docs" / "benchmarks"
FIGURES = ROOT / "docs" / "figures"
MARKER = re.compile(r"(<!-- generated: (?P<name>[\w-]+) .*?-->\n)(?P<body>.*?)"
                    r"(<!-- end generated: (?P=name) -->)", re.DOTALL)


def _results(name: str) -> dict:
    return json.loads((BENCHMARKS / f"{name}.json").read_text())


def _run_all():
    """benchmarks/run_all.py, whose helpers render the benchmarks page's rows."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import run_all
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return run_all


def recorded(report: dict) -> str:
    """When and where a results file was measured (the benchmarks page's rule)."""
    return ", ".join(dict.fromkeys(_run_all().recorded(report)))  # "not recorded" once


def transcript(*arguments: str) -> str:
    """A console block: ``impactbeams ARGUMENTS`` and what it prints (stdout and stderr)."""
    import contextlib
    import io

    from impactbeams.cli import main

    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
        main(list(arguments))
    return f"```console\n$ impactbeams {' '.join(arguments)}\n{printed.getvalue()}```\n"


def trajectory() -> str:
    """The Fig. 3 case over 0.6 s: its episodes, and the tied law's impacts at 5 modes."""
    import impactbeams as ib

    run = ib.simulate(ib.Params(), t_max=0.6, times=[0.0, 0.6])
    tied = ib.simulate(ib.Params(contact_law="tied"), t_max=0.6, times=[0.0, 0.6])
    return (f"Over these 0.6 s the default run's contacts come in {run.sizes['episode']} "
            "episodes, one per forcing period, and the tied run has "
            f"{tied.sizes['impact']} impacts. The number of contacts within an episode of the "
            "undamped spring run follows round-off (a stiff, undamped rattle is chaotic: a "
            "change in the last bits of an event time changes the micro-contacts that follow), "
            "so it is not quoted here; the first contacts and the episodes are robust. See "
            "[the trajectory tutorial](docs/tutorials/trajectory.md#what-is-robust), whose "
            "numbers are computed when the documentation is built.\n")


def spring_convergence() -> str:
    """The first contact and the first episode at 16, 32 and 64 modes."""
    import impactbeams as ib

    rows = {"first onset (s)": [], "first contact duration (ms)": [],
            "first peak force (mN)": [], "first impulse (uN s)": [],
            "first episode's impulse (uN s)": []}
    for n in (16, 32, 64):
        with warnings.catch_warnings():  # 16 modes do not resolve the contact: on purpose
            warnings.simplefilter("ignore")
            run = ib.simulate(ib.Params(), t_max=0.06, n_modes=n, times=[0.0, 0.06])
        first = run.isel(impact=0)
        rows["first onset (s)"].append(f"{float(first.impact_onset_time):.12f}")
        rows["first contact duration (ms)"].append(f"{1e3 * float(first.impact_duration):.4f}")
        rows["first peak force (mN)"].append(f"{1e3 * float(first.impact_peak_force):.3f}")
        rows["first impulse (uN s)"].append(f"{1e6 * float(first.impact_impulse):.5f}")
        rows["first episode's impulse (uN s)"].append(
            f"{1e6 * float(run.episode_impulse[0]):.3f}")
    lines = ["| quantity | 16 | 32 (default) | 64 |", "|---|---|---|---|"]
    lines += [f"| {name} | {' | '.join(values)} |" for name, values in rows.items()]
    return "\n".join(lines) + "\n"


def _robust_count(impacts: int, n_modes: int) -> str:
    """An impact count as far as it is reproducible: its scale only from 10 tied modes on.

    From there it follows round-off: the BLAS thread count alone moves it by a few per cent.
    """
    if n_modes < 10:
        return str(impacts)
    return "hundreds" if impacts < 1000 else "thousands"


def tied_convergence() -> str:
    """The tied law at 4 to 50 modes: the first impact, and the impacts over 0.6 s."""
    import impactbeams as ib

    counts = (4, 5, 10, 20, 50)
    runs = {n: ib.simulate(ib.Params(contact_law="tied"), t_max=0.6, n_modes=n,
                           times=[0.0, 0.6]) for n in counts}
    first = {n: run.isel(impact=0) for n, run in runs.items()}
    onset = {n: float(first[n].impact_onset_time) for n in counts}
    rows = {
        f"first onset, distance from {counts[-1]} modes (s)":
            [f"{abs(onset[n] - onset[counts[-1]]):.1e}" for n in counts[:-1]] + ["-"],
        "energy lost at the first onset (nJ)":
            [f"{1e9 * float(first[n].impact_energy_loss):.3g}" for n in counts],
        "first contact duration (ms)":
            [f"{1e3 * float(first[n].impact_duration):#.2g}" for n in counts],
        "first peak force (mN)": [f"{1e3 * float(first[n].impact_peak_force):#.2g}"
                                  for n in counts],
        "impacts in 0.6 s": [_robust_count(runs[n].sizes["impact"], n) for n in counts],
    }
    lines = ["| quantity | " + " | ".join(map(str, counts)) + " |",
             "|---" * (len(counts) + 1) + "|"]
    lines += [f"| {name} | {' | '.join(values)} |" for name, values in rows.items()]
    return "\n".join(lines) + "\n"


def performance() -> str:
    """Headline costs, each read from its results file with its date and machine.

    One figure per quantity, the current code's: the cold compile is the first-run table's
    (compile.json); older runs (the full suite's scaling series) are the benchmarks page's
    history, labelled there.
    """
    columns, sweep, cube = _results("columns"), _results("sweep"), _results("cube")
    continuation = _results("continuation")
    branch = next(row for row in continuation["cases"] if row["n_modes"] == 32)
    best = columns["best_s"]
    full = next(run for run in cube["runs"] if run["cells"] == 10**9)
    rows = [
        ("Fig. 5a map, 10^6 cells, t_max = 1 s, 5 modes per beam, compute in-process "
         "([columns](docs/benchmarks/columns.md))",
         f"{best['columns, 1 thread(s)']:.2f} s on 1 thread, "
         f"{best['columns, 2 thread(s)']:.2f} s on 2 by columns; "
         f"{best['cells, 1 thread(s)']:.1f} s / {best['cells, 2 thread(s)']:.1f} s cell by "
         f"cell (same classification in every cell: {columns['same_classification']}, t* "
         f"within {columns['max_time_difference_s']:.1e} s)", recorded(columns)),
        ("the same map as a command, `impactbeams run sweeps/fig5a-omega-force.toml -o "
         "OUT.nc`, warm Numba cache ([phases](docs/benchmarks/sweep.md))",
         f"{sweep['command_s']:.1f} s, of which {sweep['command_overhead_s']:.1f} s "
         "interpreter, imports, loading the kernels and writing", recorded(sweep)),
        ("(Omega, Delta, F0) cube of 1000^3 = 10^9 cells streamed into netCDF, 2 threads "
         "([details](docs/benchmarks/cube.md))",
         f"{full['wall_s']:.0f} s, {full['cpu_s']:.0f} s of CPU, peak memory "
         f"{full['peak_rss_mb']:.0f} MB, {full['file_mb']:.0f} MB file",
         recorded({**cube, "date": full.get("date", cube.get("date"))})),
        ("a continuation's branch point, default Hertz contact, zeta = 0.05, 32 modes per beam, "
         "period-1 impacting branch in Omega, micro-contacts summarised "
         "([continuation](docs/benchmarks/continuation.md))",
         f"{1e3 * branch['newton-picard']['seconds_per_point']:.0f} ms by Newton-Picard "
         f"(of which {1e3 * branch['measures']:.0f} ms the point's measures), "
         f"{1e3 * branch['newton']['seconds_per_point']:.0f} ms by Newton",
         recorded(continuation)),
    ]
    stiff = _results("stiff_continuation")
    rows.append(("frequency response of a stiff stop on a shaker, 0.5 to 2 omega_1, up and down, "
                 f"default settings but max_points {stiff['max_points']}, each run "
                 "stopped at "
                 f"{stiff['cap']:.0f} s ([stiff continuation]"
                 "(docs/benchmarks/stiff_continuation.md))",
                 "; ".join(_stiff_case(case, stiff.get("baseline", "").split(" ")[0])
                           for case in stiff["cases"]), recorded(stiff)))
    two = _results("two_parameter")
    curve, branch_point = (two["cases"]["stop fold, 5 modes"][part]
                           for part in ("curve", "branch"))
    ratio = curve["cpu_seconds_per_point"] / branch_point["cpu_seconds_per_point"]
    rows.append(("a point of a fold curve in (Omega, F0), soft stop, 5 modes per beam "
                 "([two-parameter](docs/benchmarks/two_parameter.md))",
                 f"{1e3 * curve['seconds_per_point']:.0f} ms, {ratio:.1f} times a branch point",
                 recorded(two)))
    lines = ["| quantity | value | measured |", "|---|---|---|"]
    lines += [f"| {what} | {value} | {when} |" for what, value, when in rows]
    return "\n".join(lines) + "\n"


def _stiff_case(case: dict, baseline: str) -> str:
    """One run of the stiff continuation benchmark, and the earlier version's (``baseline``).

    Its wall and CPU time (the wall time follows the machine's load; the run is on one core)
    and what branch 0 covered.
    """
    def covered(run: dict) -> str:
        low, high = (float(v) for v in run["covered"][0].split(":"))
        ending = "stopped at the cap" if run["capped"] else f"ended {run['endings'][0]}"
        return (f"{low:.1f} to {high:.1f} rad/s in {run['seconds']:.0f} s "
                f"({run['cpu_seconds']:.0f} s of CPU), {ending}")

    contact = ("Hertz" if case["stiffness"] is None else f"k = {case['stiffness']:g} N/m")
    before = f" ({baseline}: {covered(case['before'])})" if "before" in case else ""
    return f"{contact}, {case['n_modes']} modes, {case['direction']}: {covered(case)}{before}"


def speed_targets() -> str:
    """Issue 24's speed targets, now and in the previous release (the benchmarks page's)."""
    return _run_all().speed_targets(BENCHMARKS)


def first_run() -> str:
    """The first run's compile and each command's start-up (compile.json, startup.json)."""
    return _run_all().first_run_table(_results("compile"), _results("startup"))


def longtime() -> str:
    """The long-time bifurcation diagram's cost, from ``longtime.json``."""
    report = _results("longtime")
    soft, full = report["variant"], report["full_run"]
    return (f"`sweeps/{report['sweep']}`, {report['diagram_cells']} values of Omega, "
            f"{report['transient_periods']} + {report['sampled_periods']} forcing periods "
            f"each, default Hertz contact (k = {report['contact_stiffness']:.3g} N/m) at its "
            f"resolved {report['n_modes']} modes: **{full['wall_s']:.0f} s on 2 threads** "
            f"({full['cpu_s']:.0f} s of CPU; one core: {report['diagram_one_core_s']:.0f} s, "
            f"extrapolated from every {report['stride']}th cell), "
            f"{1e3 * report['s_per_period']:.2f} ms per forcing period, up to "
            f"{report['onsets_per_period_max']:.0f} contact onsets per period; with k = "
            f"{soft['contact_stiffness']:g} N/m at its {soft['n_modes']} modes, "
            f"{soft['full_run']['wall_s']:.0f} s ({recorded(report)}).\n")


def _sci(value: float, digits: int = 0) -> str:
    """``value`` in the README's exponent style: 1e-6, 1.4e-11, 1e5."""
    mantissa, exponent = f"{value:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _ranged(values, scale: float = 1.0, digits: int = 0) -> str:
    """``low-high`` of ``values`` times ``scale``, rounded to ``digits`` (one value if equal)."""
    low, high = (f"{scale * value:.{digits}f}" for value in (min(values), max(values)))
    return low if low == high else f"{low}-{high}"


def longtime_profile() -> str:
    """Where a long-time run's time goes, from the profiled cells of ``longtime.json``."""
    report = _results("longtime")
    profile = report["profile"]
    search_us = [row["search_us_per_segment"] for row in profile]
    omegas = ", ".join(f"{row['omega']:g}" for row in profile)
    return (f"Where the time goes now (profile of {len(profile)} cells at Omega = {omegas} "
            "rad/s, "
            f"{profile[0]['periods']} periods each): the certified event search, "
            f"{_ranged([row['search_fraction'] for row in profile], 100)} % of a run "
            f"({_ranged([us['free'] for us in search_us])} us per free phase, "
            f"{_ranged([us['contact'] for us in search_us])} us per contact), switches "
            f"{_ranged([row['switches_s'] / row['run_s'] for row in profile], 100)} %, the "
            "closed-form propagation to each segment's end "
            f"{_ranged([row['propagation_us_per_segment'] for row in profile])} us "
            f"({recorded(report)}). On 2 threads the diagram takes "
            f"{report['full_run']['cpu_s'] / report['diagram_one_core_s']:.2f} times the CPU "
            "time of one core (1 would be ideal scaling).\n")


def spring_precision() -> str:
    """The spring law against solve_ivp, and its cost per simulated second (spring.json)."""
    report = _results("spring")
    case, stiff = report["cases"]
    dop853 = {point["rtol"]: point for point in case["points"]
              if point["method"] == "solve_ivp DOP853"}
    finest, coarsest = min(dop853), max(dop853)
    matched = {m["time"]: m for m in stiff["matched"] if m["method"] == "solve_ivp DOP853"}
    cost = report["cost"]
    config = report["config"]

    def per_second(key: str) -> str:
        return ", ".join(f"{row['per_simulated_second'][key]:.2g}" for row in cost)

    return (
        "impactbeams' contact table sits below what DOP853 at rtol "
        f"{_sci(config['tight_rtol'])} can confirm (its distance from rtol {_sci(finest)} is "
        f"{_sci(dop853[finest]['errors']['onset_max'], 1)} s on onsets, "
        f"{_sci(dop853[finest]['errors']['peak_rel_max'])} relative on peaks), so the speed-ups "
        f"are lower bounds; DOP853 gets only "
        f"{dop853[finest]['seconds'] / dop853[coarsest]['seconds']:.0f}x cheaper from rtol "
        f"{_sci(finest)} to {_sci(coarsest)} (the fastest mode limits its steps). At k = "
        f"{_sci(stiff['stiffness'])} ({stiff['t_max']:g} s, {stiff['impactbeams']['contacts']} "
        f"contacts, {stiff['impactbeams']['n_modes']} modes): >= "
        f"{matched['events']['speedup']:.0f}x (event-driven run), >= "
        f"{matched['simulate']['speedup']:.0f}x (`simulate()`, which then always computed the "
        f"work of F; {recorded(report)}). Cost per simulated second at k = "
        f"{_sci(config['cost_stiffness'])} ({config['cost_t_max']:g} s, "
        f"{_ranged([row['contacts'] for row in cost])} contacts), re-measured "
        f"{report['run']['cost_date']}: {per_second('events')} s for the event-driven run at "
        f"{', '.join(str(row['n_modes']) for row in cost)} modes, {per_second('simulate')} s "
        "through `simulate()`.\n")


def map_threads() -> str:
    """The two-thread speed-ups of the Fig. 5a map and every benchmark map (columns.json)."""
    report = _results("columns")
    gain = report["speedup_2_threads"]
    over = report["speedup_columns_over_cells"]
    return (f"Two threads give {gain['columns']:.1f}x by columns ({gain['cells']:.1f}x cell by "
            "cell: a column is one thread's); columns are "
            f"{over['1']:.1f}x faster than cell by cell on one thread, {over['2']:.1f}x on two "
            f"([columns](docs/benchmarks/columns.md); date and machine: {recorded(report)}).\n"
            + ("\nEvery benchmark map (`benchmarks/maps/`), by columns:\n\n"
               + _run_all().maps_table(report) if "maps" in report else ""))


def several_contacts() -> str:
    """What several contacts cost against one, per evaluation and map cell (contacts.json)."""
    report = _results("contacts")
    rows = {(row["contacts"], row["n_modes"]): row for row in report["rows"]}
    modes = sorted({n for _, n in rows})
    counts = sorted(count for count in {count for count, _ in rows} if count > 1)

    def ratios(key: str) -> str:
        return ", ".join(" / ".join(f"{rows[count, n][key]:.1f}" for count in counts)
                         + f" at {n} modes" for n in modes)

    return (f"Several contacts (`benchmarks/bench_contacts.py`, beam 1 against "
            f"{' / '.join(map(str, counts))} stops): a first-impact map cell costs "
            f"{ratios('map_cell_over_one_contact')} times one contact's (each contact's own "
            f"map, the earliest kept), a `first_contact` call "
            f"{ratios('evaluation_over_one_contact')} times ([benchmarks]"
            f"(docs/benchmarks/README.md#several-contacts); date and machine: "
            f"{recorded(report)}, load average {report['load_average']:.1f}).\n")


def lyapunov_fig4() -> dict[int, dict]:
    """n_modes -> the long window's exponent, from scripts/lyapunov_fig4.py's results file."""
    report = json.loads((FIGURES / "lyapunov_fig4.json").read_text())
    return {row["n_modes"]: {**row, "horizon_s": report["horizon_s"], "date": report["date"]}
            for row in report["windows"] if row["window"] == "long"}


def fig4() -> str:
    """Fig. 4's distances (scripts/make_figures.py's fig4.json) and its Lyapunov exponent."""
    report = json.loads((FIGURES / "fig4.json").read_text())
    spring, tied = report["spring"], report["tied"]
    exponents = lyapunov_fig4()
    um = 1e6
    return (
        f"Fig. 4 (uplift 0 vs {_sci(spring['uplift_m'])} m): with the default spring law "
        f"({spring['n_modes']} modes) the two trajectories of beam 1's tip differ by at most "
        f"{um * spring['distance_max_first_0.1s_m']:.1f} um (the perturbation) over the first "
        f"0.1 s, then by up to {um * spring['distance_max_m']:.0f} um over the "
        f"{spring['t_max_s']:g} s (tip amplitude {um * spring['tip_amplitude_m']:.0f} um): a "
        "slow growth, not the paper's exponential divergence. These distances, like every "
        "quantity of this undamped run after its first rattle, follow round-off: they are those "
        f"of the figure's runs (`docs/figures/fig4.json`, written by `scripts/make_figures.py` "
        f"on {report['date']}). Yet the motion is chaotic: its largest Lyapunov exponent over "
        f"{next(iter(exponents.values()))['t_start']:.0f}-"
        f"{next(iter(exponents.values()))['horizon_s']:g} s is "
        + " and ".join(f"{row['exponent']:.0f} ± {row['error']:.0f} 1/s at {n} modes"
                       for n, row in exponents.items())
        + " (`docs/figures/lyapunov_fig4.json`, written by `scripts/lyapunov_fig4.py` on "
        f"{next(iter(exponents.values()))['date']}; [Lyapunov exponents](docs/lyapunov.md)); a "
        f"{_sci(spring['tiny_uplift_m'])} m uplift already moves the tip by "
        f"{um * spring['tiny_uplift_distance_at_first_episode_end_m']:.2f} um by the end of the "
        f"first impact episode ({1e3 * spring['first_episode_end_s']:.0f} ms), so a "
        f"{um * spring['uplift_m']:.0f} um perturbation starts where the growth has saturated. "
        f"Under the tied law at {tied['n_modes']} modes they stay within "
        f"{um * tied['distance_max_m']:.1f} um of each other over {tied['t_max_s']:g} s.\n")


def spring_limits() -> str:
    """The resolution rule's modes over k, and the cost per simulated second (spring.json).

    Indented by two spaces: the section sits inside an item of the Limits list.
    """
    import impactbeams as ib
    from impactbeams.compliant import required_modes
    from impactbeams.params import MAX_MODES

    default = ib.Params().contact_stiffness
    stiffnesses = (1e4, 1e5, default, 1e6, 1e7, 1e8)
    modes = [required_modes(ib.Params(contact_stiffness=k)) for k in stiffnesses]
    grid = [10 ** (exponent / 20) for exponent in range(160, 240)]  # 20 per decade
    beyond = next(k for k in grid if required_modes(ib.Params(contact_stiffness=k)) > MAX_MODES)
    report = _results("spring")
    cost = report["cost"]
    names = [f"{_sci(k, 2)} (default)" if k == default else _sci(k) for k in stiffnesses]
    seconds = [row["per_simulated_second"]["events"] for row in cost]
    growth = seconds[-1] / seconds[0] / (cost[-1]["n_modes"] / cost[0]["n_modes"])
    pace = "faster than" if growth > 1.1 else "more slowly than" if growth < 0.9 else "about like"
    return (f"  {', '.join(map(str, modes))} modes at k = {', '.join(names)} N/m; above about "
            f"{_sci(beyond)} N/m it asks for more than the package's {MAX_MODES} modes per "
            f"beam. The run time per simulated second grows {pace} the number of modes ("
            + ", ".join(f"{value:.2g}" for value in seconds)
            + " s at " + ", ".join(str(row["n_modes"]) for row in cost) + " modes for k = "
            f"{_sci(report['config']['cost_stiffness'])}, "
            "[benchmarks](docs/benchmarks/README.md)).\n  ")


def docs_build() -> str:
    """How long a strict docs build takes (docs_build.json, benchmarks/bench_docs_build.py)."""
    report = _results("docs_build")

    def build(name: str) -> str:
        run = report[name]
        return (f"{run['wall_s']:.0f} s ({run['cpu_s']:.0f} s of CPU, load "
                f"{run['load_average_before'][0]:.1f} to {run['load_average_after'][0]:.1f})")

    return (f"Building the site runs every example of the pages: `mkdocs build --strict` took "
            f"{build('cold')} with an empty Numba cache, as after a fresh install, and "
            f"{build('warm')} with the kernels cached ({report['date']}, {report['machine']}, "
            f"{report['cores']} cores; `python benchmarks/bench_docs_build.py`, "
            "`docs/benchmarks/docs_build.json`). The examples run in a temporary folder: the "
            "build writes only into its site folder, never into `results/`.\n")


def newcomer() -> str:
    """The compile announced against the compile taken, per command (newcomer.json)."""
    report = _results("newcomer")
    rows = ["| step | command | compile announced | compile taken | command's wall time |",
            "|---|---|---|---|---|"]
    for step in report["steps"]:
        announced = ("-" if step["announced_s"] is None else
                     f"{step['announced_s'][0]}-{step['announced_s'][1]} s ({step['machine']})")
        compiled = "-" if step["compiled_s"] is None else f"{step['compiled_s']:.1f} s"
        rows.append(f"| {step['task']} | `{step['command']}` | {announced} | {compiled} | "
                    f"{step['wall_s']:.1f} s |")
    return ("\n".join(rows) + f"\n\n{report['date']}, {report['machine']}, {report['cores']} "
            f"cores, load {report['load_average_end']:.1f} at the end "
            "(`python scripts/newcomer.py --output docs/benchmarks/newcomer.json`).\n")


SECTIONS: dict[str, Callable[[], str]] = {
    "longtime": longtime,
    "bad-input": lambda: transcript("modes", "--clearance=-1e-5"),
    "trajectory": trajectory,
    "spring-convergence": spring_convergence,
    "tied-convergence": tied_convergence,
    "performance": performance,
    "speed-targets": speed_targets,
    "first-run": first_run,
    "longtime-profile": longtime_profile,
    "spring-precision": spring_precision,
    "map-threads": map_threads,
    "several-contacts": several_contacts,
    "fig4": fig4,
    "spring-limits": spring_limits,
    "docs-build": docs_build,
    "newcomer": newcomer,
}


def render(text: str) -> str:
    """``text`` with every generated section recomputed."""
    found = {match["name"] for match in MARKER.finditer(text)}
    if found != set(SECTIONS):
        raise SystemExit(f"README.md markers {sorted(found)} != sections {sorted(SECTIONS)}")
    return MARKER.sub(lambda m: m[1] + SECTIONS[m["name"]]() + m[4], text)


def main() -> None:
    """Rewrite README.md, or with --check report whether it is up to date."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if README.md is stale")
    args = parser.parse_args()
    text = README.read_text()
    new = render(text)
    if args.check:
        sys.exit(0 if new == text else 1)
    README.write_text(new)
    print("README.md up to date" if new == text else "README.md regenerated")


if __name__ == "__main__":
    main()
