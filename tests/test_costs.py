"""The cost model's structure, its calibration, the compile report and progress without effect.

No timing here (timings in unit tests are banned): the model's constants must be those of the
calibration file, its estimates must grow with cells, modes and periods, and showing progress
must not change a result by one bit. The estimates against actual times are in
docs/limits.md, generated from docs/benchmarks/estimates.json (checked below).
"""

import importlib.util
import io
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from impactbeams import Params, costs
from impactbeams.compilation import kernels_cached, reporting_compiles
from impactbeams.configuration import LAWS
from impactbeams.packing import pack_run
from impactbeams.sweep.definition import sweep_from_mapping
from impactbeams.sweep.estimate import expected_seconds
from impactbeams.sweep.plan import first_impact_kernel
from impactbeams.trajectory import phases, simulate

ROOT = Path(__file__).resolve().parents[1]
CALIBRATION = ROOT / "docs" / "benchmarks" / "costs.json"


def _load_benchmark(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _as_json(value):
    """A module constant as the calibration file holds it (tuples as lists, keys as text)."""
    return json.loads(json.dumps(value))


def test_the_constants_are_those_of_the_calibration_file():
    """costs.py's constants, and each contact law's costs per impacting cycle (issue 33)."""
    constants = json.loads(CALIBRATION.read_text())["constants"]
    cycle = constants.pop("IMPACT_CYCLE")
    for name, value in constants.items():
        assert _as_json(getattr(costs, name)) == value, name
    assert cycle == _as_json({kind: {law.name: law.impact_cycle[kind] for law in LAWS.values()
                                     if kind in law.impact_cycle} for kind in cycle})
    assert all(set(law.impact_cycle) <= set(cycle) for law in LAWS.values())


def test_the_calibration_writes_the_constants_blocks_as_they_are():
    """The calibration's writer, fed the calibration file, gives the modules' blocks unchanged:
    the constants are written there by it (a law's costs in configuration.py), not by hand."""
    calibrate = _load_benchmark("calibrate_costs")
    constants = json.loads(CALIBRATION.read_text())["constants"]
    for path, block in calibrate.module_blocks(constants).items():
        found = calibrate.CONSTANTS_BLOCK.search(path.read_text())
        assert found and found.group(2) == block, path.name


def test_the_calibration_records_its_load():
    calibration = json.loads(CALIBRATION.read_text())
    assert len(calibration["load_average_before"]) == 3
    assert len(calibration["load_average_after"]) == 3


def _sweep(n_modes=8, num=6, observables=("impact_count",), **extra):
    data = {"n_modes": n_modes, "observables": list(observables),
            "params": {"force_amplitude": 5e-3, "damping_ratio": 0.01},
            "axes": {"omega": {"min": 100.0, "max": 800.0, "num": num}}, **extra}
    if "sampled_periods" not in data:
        data.setdefault("t_max", 0.5)
    return sweep_from_mapping(data)


@pytest.mark.parametrize("observables, extra", [
    (("first_impact_time",), {}),
    (("impact_count",), {}),
    (("lyapunov_exponent",), {}),
    (("response_period",), {"transient_periods": 50, "sampled_periods": 20}),
])
def test_a_sweep_costs_more_with_more_cells_and_modes(observables, extra):
    base = expected_seconds(_sweep(8, 6, observables, **extra), 1)
    assert expected_seconds(_sweep(8, 12, observables, **extra), 1) > base
    assert expected_seconds(_sweep(16, 6, observables, **extra), 1) > base
    set_up = costs.geometry_seconds(1, 8)  # serial; the cells over the threads
    assert expected_seconds(_sweep(8, 6, observables, **extra), 2) - set_up == pytest.approx(
        (base - set_up) / costs.THREAD_SPEEDUP[2], rel=1e-12)


def test_a_sweep_costs_more_with_a_longer_horizon():
    assert (expected_seconds(_sweep(t_max=1.0), 1) > expected_seconds(_sweep(t_max=0.5), 1))
    short, long = ({"transient_periods": periods, "sampled_periods": 20} for periods in (50, 100))
    assert (expected_seconds(_sweep(observables=("response_period",), **long), 1)
            > expected_seconds(_sweep(observables=("response_period",), **short), 1))


def test_impacting_cells_cost_more_than_free_ones():
    values = {**Params(omega=300.0, damping_ratio=0.01).numeric()}
    loud = {**values, "force_amplitude": 1e-2}
    quiet = {**values, "force_amplitude": 1e-8}
    assert costs.impacts(loud, 8, 1.0) and not costs.impacts(quiet, 8, 1.0)
    for law in LAWS.values():
        assert (costs.dynamics_seconds(loud, law, 8, 1.0, "dynamics")
                > costs.dynamics_seconds(quiet, law, 8, 1.0, "dynamics"))


def test_the_impact_prediction_follows_the_static_deflection():
    """Far below resonance beam 1's tip moves F0 c1, c1 = l^3 / (3 EI) (the modes' sum of
    Y_n(l)^2 / omega_n^2): impacts iff that reaches the clearance."""
    values = Params(omega=1e-3, damping_ratio=0.01).numeric()
    c1 = values["l1"] ** 3 / (3 * values["EI1"])
    threshold = values["clearance"] / c1
    assert costs.impacts({**values, "force_amplitude": 1.01 * threshold}, 20, 1e4)
    assert not costs.impacts({**values, "force_amplitude": 0.99 * threshold}, 20, 1e4)


@pytest.mark.parametrize("law", list(LAWS.values()), ids=list(LAWS))
def test_the_cost_per_cycle_grows_with_the_modes(law):
    for scale, power in law.impact_cycle.values():
        assert scale > 0 and power > 0


def test_a_law_without_a_tangent_flow_has_no_lyapunov_cost():
    """Lyapunov exponents need a tangent flow: only such a law is calibrated for them."""
    assert all(("lyapunov" in law.impact_cycle) == law.tangent_flow for law in LAWS.values())


def test_first_impact_cost_grows_with_cells_and_modes():
    assert costs.first_impact_seconds(2e6, 5) > costs.first_impact_seconds(1e6, 5)
    assert costs.first_impact_seconds(1e6, 10) > costs.first_impact_seconds(1e6, 5)


def test_a_first_map_expects_the_compile_of_the_twin_it_calls():
    # a map of more than one block calls the parallel twin, which compiles longer (calibrated
    # apart); no other kind has twins
    small, large = (sweep_from_mapping({"t_max": 0.1, "axes": {"omega": {
        "min": 100.0, "max": 300.0, "num": num}}}) for num in (4, 300))
    twins = [costs.compile_time("first_impact", first_impact_kernel(sweep))
             for sweep in (small, large)]
    assert twins == [costs.COMPILE["first_impact"], costs.COMPILE["first_impact_parallel"]]
    assert twins[1] > twins[0]
    assert (costs.compile_time("dynamics", "first_impact_map_parallel")
            == costs.COMPILE["dynamics"])


def test_an_empty_numba_cache_is_told_apart(tmp_path):
    """A process whose cache folder is empty would compile: ``kernels_cached`` says so."""
    code = "from impactbeams.compilation import kernels_cached; print(kernels_cached('simulate'))"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                            text=True, check=True)
    assert result.stdout.strip() == "False"


def test_a_run_leaves_its_kernels_cached():
    simulate(Params(contact_law="tied"), 0.01, n_modes=3)
    assert kernels_cached("simulate")


ESTIMATE = costs.CompileEstimate(8.0, 17.0, 7.2, 3.0, 2, 0.5)


@pytest.fixture
def fresh(monkeypatch):
    """A kernel not compiled yet, whose every compile is reported (however short)."""
    from impactbeams import compilation

    monkeypatch.setattr(compilation, "REPORTED_COMPILE", 0.0)

    @numba.njit(cache=False)
    def fresh(x):
        return x + 1

    return fresh


def test_a_compile_is_announced_with_its_range_here_and_timed_beside_it(fresh):
    stream = io.StringIO()
    with reporting_compiles(ESTIMATE, stream=stream):
        fresh(1)
        fresh(2)  # compiled already: no new line
    lines = stream.getvalue().splitlines()
    assert lines[0] == (
        "impactbeams: compiling the kernels of this kind of run (once per install: later runs "
        "load them from the disk cache), expected 8-17 s here (2 cores at load 3.0, 50 % of a "
        "core to this process just now; measured "
        f"7.2 s at load {costs.COMPILE_LOAD:.1f} on {costs.COMPILE_CORES} cores)")
    assert re.fullmatch(r"impactbeams: compiled 1 kernels in \d+\.\d s \(cached for later "
                        r"runs; announced 8-17 s\)", lines[1]) and len(lines) == 2


def test_a_run_whose_kernels_are_cached_announces_no_install_compile(fresh):
    """A kernel missing from the cache of a warm run's kind is no compile "once per install"."""
    stream = io.StringIO()
    with reporting_compiles(ESTIMATE, cached=True, stream=stream):
        fresh(1)
    lines = stream.getvalue().splitlines()
    assert lines[0] == ("impactbeams: compiling kernels missing from the disk cache (the run's "
                        "others load from it)")
    assert "announced" not in lines[1]


def test_the_compile_estimate_scales_with_the_load_here():
    # calibrated at COMPILE_LOAD on COMPILE_CORES: the same there; at load 5 on 2 cores a
    # compile gets a third of a core's share (issue 32: 25.9 s where 7.2 s was quoted)
    there = costs.compile_estimate("first_impact", load=costs.COMPILE_LOAD,
                                   cores=costs.COMPILE_CORES, share=1.0)
    assert there.low < costs.COMPILE["first_impact"] < there.high
    busy = costs.compile_estimate("first_impact", "first_impact_map_parallel", load=5.0, cores=2,
                                  share=1.0)
    assert busy.low < 25.9 < busy.high
    assert busy.low > costs.COMPILE["first_impact_parallel"]
    assert "2 cores at load 5.0, 100 % of a core" in busy.describe()
    # a process that gets a quarter of a core now waits four times as long, whatever the load
    starved = costs.compile_estimate("first_impact", load=0.0, cores=2, share=0.25)
    assert starved.low == pytest.approx(4 * there.low)


def test_the_share_of_a_core_is_measured():
    assert 0.0 < costs.cpu_share() <= 1.0
    assert costs.compile_estimate("orbits") is None  # not calibrated: no time is stated


def test_every_kind_names_kernels_that_exist():
    from impactbeams.compilation import ENTRY_KERNELS, _kernel

    for kind, entries in ENTRY_KERNELS.items():
        for module, names in entries:
            for name in names:
                assert hasattr(_kernel(module, name), "py_func"), (kind, module, name)


def test_a_terminal_shows_the_group_being_compiled():
    """On a terminal the line names the kernels' module and counts the kernels done."""

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    stream = Terminal()

    @numba.njit(cache=False)
    def inner(x):
        return x + 1

    @numba.njit(cache=False)
    def outer(x):
        return 2 * inner(x)

    with reporting_compiles(ESTIMATE, stream=stream):
        outer(1)
    group = outer.py_func.__module__.split(".")[0]
    assert f"\rimpactbeams: compiling kernels, expected 8-17 s: {group}, 1 compiled, " \
           in stream.getvalue()


def test_a_loaded_kernel_prints_nothing():
    stream = io.StringIO()
    with reporting_compiles(ESTIMATE, stream=stream):
        simulate(Params(contact_law="tied"), 0.01, n_modes=3)
    assert stream.getvalue() == ""


FIELDS = ("time", "phase", "sustained", "q", "v", "end_q", "end_v")


@pytest.mark.parametrize("law, n_modes, max_events", [
    ("spring", 8, 200_000), ("tied", 5, 200_000), ("spring", 8, 300)])
def test_a_run_in_windows_is_bitwise_the_uninterrupted_run(monkeypatch, law, n_modes,
                                                           max_events):
    """Windows of a few segments, resumed many times, against one call of the kernel."""
    params = Params(contact_law=law, omega=400.0, force_amplitude=5e-3, damping_ratio=0.01)
    packed = pack_run(params, n_modes, 0.3, 0.3)
    whole = phases.run(packed, max_events)  # one window: the first one holds every segment
    monkeypatch.setattr(phases, "_WINDOW", 16)
    monkeypatch.setattr(phases, "_MIN_WINDOW", 16)
    monkeypatch.setattr(phases, "WINDOW_SECONDS", 0.0)
    reached = []
    windowed = phases.run(packed, max_events, lambda t, phases_so_far: reached.append(
        (t, phases_so_far)))
    assert len(reached) >= 5 and reached == sorted(reached)
    for field in FIELDS:
        assert np.array_equal(getattr(windowed, field), getattr(whole, field)), field
    assert (windowed.status, windowed.t_end) == (whole.status, whole.t_end)


def test_the_first_window_holds_a_short_run():
    """The reference above: a run shorter than the first window is one call of the kernel."""
    packed = pack_run(Params(omega=400.0, force_amplitude=5e-3), 8, 0.3, 0.3)
    assert phases.run(packed, 200_000).time.size < phases._WINDOW


def test_progress_does_not_change_a_simulation(capsys):
    params = Params(contact_law="tied", omega=400.0, force_amplitude=5e-3)
    quiet = simulate(params, 0.2, n_modes=8, dt_output=1e-3)
    assert capsys.readouterr().err == ""
    shown = simulate(params, 0.2, n_modes=8, dt_output=1e-3, progress=True)
    err = capsys.readouterr().err
    assert "expected: roughly" in err and "s simulated" in err and "peak forces" in err
    assert set(quiet.variables) == set(shown.variables)
    for name in quiet.variables:
        assert quiet[name].values.tobytes() == shown[name].values.tobytes(), name


def test_the_docs_table_is_generated_from_the_json():
    table = _load_benchmark("estimate_table")
    result = json.loads(table.OUTPUT.read_text())
    assert table.render_table(result) in (ROOT / "docs" / "limits.md").read_text()


def test_a_map_searched_cell_by_cell_walks_the_horizon_of_its_free_cells():
    """Along omega alone (no column axis) a cell without impact walks all of t_max."""
    def seconds(t_max, force):
        return expected_seconds(sweep_from_mapping({
            "t_max": t_max, "n_modes": 5, "params": {"force_amplitude": force},
            "axes": {"omega": {"min": 300.0, "max": 600.0, "num": 1000}}}), 1)

    assert seconds(2.0, 1e-8) == pytest.approx(2 * seconds(1.0, 1e-8), rel=0.01)
    assert seconds(1.0, 1e-2) == seconds(2.0, 1e-2)  # impacting cells stop at their impact


def test_cells_that_meet_only_in_the_start_from_rest_vibration_are_charged_for_its_duration():
    """Above beam 1's first resonance, a damped tip whose steady motion misses the clearance
    meets it only while the free vibration of the start from rest lasts: a time that does
    not depend on the horizon (so the share of the horizon falls as 1 / horizon). Undamped,
    that vibration never decays: the whole horizon."""
    values = Params(damping_ratio=0.05).numeric()
    omega_1 = 1.8751040687**2 / values["l1"] ** 2 * math.sqrt(values["EI1"] / values["rhoA1"])
    values = {**values, "omega": 2.0 * omega_1, "uplift1": 0.0, "uplift2": 0.0}
    steady = 4.0 / (values["rhoA1"] * values["l1"]) / (3.0 * omega_1**2)  # mode 1, per newton
    cell = {**values, "force_amplitude": 0.6 * values["clearance"] / steady}
    shares = [float(costs.impacting_fraction(cell, 8, horizon)) for horizon in (10.0, 40.0)]
    assert 0.0 < shares[1] < shares[0] < 1.0
    assert shares[0] * 10.0 == pytest.approx(shares[1] * 40.0, rel=1e-12)
    assert costs.impacting_fraction({**cell, "damping_ratio": 0.0}, 8, 40.0) == 1.0
    assert costs.impacting_fraction({**cell, "force_amplitude": 1e-3 * cell["force_amplitude"]},
                                    8, 40.0) == 0.0


def test_a_stop_costs_beam_one_coordinates_only():
    """Against a stop the run has n_modes coordinates, not 2 n_modes: the estimate follows.

    The calibrated cost per cycle grows like n^p (p from the calibration): the stop's estimate is
    that of two beams with half the modes each, 2^-p of the two-beam estimate at the same n_modes.
    """
    from impactbeams.configuration import SPRING_LAW
    from impactbeams.sweep.definition import sweep_from_mapping
    from impactbeams.sweep.estimate import expected_seconds

    mapping = {"n_modes": 28, "observables": ["response_period"], "transient_periods": 50,
               "sampled_periods": 20, "params": {"force_amplitude": 0.0, "base_amplitude": 5e-6,
                                                 "damping_ratio": 0.03},
               "axes": {"omega": {"min": 100.0, "max": 1000.0, "num": 40}}}
    beams = expected_seconds(sweep_from_mapping(mapping))
    mapping["params"]["counterpart"] = "stop"
    stop = expected_seconds(sweep_from_mapping(mapping))
    mapping["params"]["counterpart"] = "beam"
    mapping["n_modes"] = 14
    halved = expected_seconds(sweep_from_mapping(mapping))
    power = SPRING_LAW.impact_cycle["long_time"][1]  # the calibrated n^p per impacting cycle
    assert stop < 1.05 * 2.0 ** -power * beams  # n modes in all, not 2 n: 2^-p of the work
    assert abs(stop - halved) < 0.2 * halved  # the same work, bar the impacting share's rule


def _quadrature_panels(packed, trajectory, times):
    """The panels `kernels.reductions.work_of_force` takes over a run (its own rule: at most
    half the shortest period of each segment's phase, cut at every output time)."""
    from impactbeams.kernels.layout import ROW_FREQUENCY

    ends = np.append(trajectory.time[1:], trajectory.t_end)
    cuts = np.unique(np.concatenate([trajectory.time, times, [trajectory.t_end]]))
    segment = np.searchsorted(trajectory.time, cuts[:-1], side="right") - 1
    fastest = np.array([max(packed.tables[phase][ROW_FREQUENCY].max(), packed.params.omega)
                        for phase in trajectory.phase])[segment]
    widths = np.minimum(np.diff(cuts), ends[segment] - cuts[:-1])
    return int(np.sum(np.maximum(1, np.ceil(widths * fastest / math.pi))))


@pytest.mark.parametrize(("law", "n_modes"), [("spring", 16), ("tied", 5)])
def test_the_energy_balance_is_in_the_estimate(law, n_modes):
    """simulate --energy-balance announced 26 min for a run whose quadratures alone would take
    days: their cost was not in the estimate. It is now, and its count of quadrature panels
    follows the kernel's (here within a factor 3: the contacts' phases have higher
    frequencies, and their switches cut panels, neither known before a run)."""
    from impactbeams.preflight import highest_frequency
    from impactbeams.trajectory.simulation import simulation_cost

    params = Params(contact_law=law)
    fastest = float(highest_frequency(params.numeric(), n_modes))
    t_max, n_times = 0.3, 301
    plain, balanced = (simulation_cost(params, t_max, n_modes, n_times, False, 41, energy, 1000)
                       for energy in (False, True))
    assert balanced.seconds - plain.seconds == pytest.approx(
        costs.energy_seconds(fastest, n_modes, t_max, n_times), rel=1e-12)
    packed = pack_run(params, n_modes, t_max, t_max)
    trajectory = phases.run(packed, 200_000)
    modelled = t_max * fastest / math.pi + n_times
    counted = _quadrature_panels(packed, trajectory, np.linspace(0.0, t_max, n_times))
    assert modelled / 3 < counted < 3 * modelled


def test_the_energy_quadratures_report_progress(capsys):
    """The quadratures ran silent for 30+ CPU-minutes; each now reports the simulated time it
    has integrated, to its end, and the results are the same bits."""
    params = Params(contact_law="tied", omega=400.0, force_amplitude=5e-3, damping_ratio=0.01)
    quiet = simulate(params, 0.2, n_modes=8, dt_output=1e-3, energy_balance=True)
    capsys.readouterr()
    shown = simulate(params, 0.2, n_modes=8, dt_output=1e-3, energy_balance=True,
                     progress=True)
    err = capsys.readouterr().err.splitlines()
    for what in ("work and dissipation", "episodes' energies"):
        lines = [line for line in err if f"s integrated ({what})" in line]
        assert len(lines) >= 2 and "100.0% 0.2/0.2 s integrated" in lines[-1], what
    for name in quiet.variables:
        assert quiet[name].values.tobytes() == shown[name].values.tobytes(), name


def test_a_run_stopped_early_announces_its_energy_balance_again(capsys):
    """Announced for the whole t_max (3.3 days for the issue's 1e4 s), the quadratures of a
    run the event cap stopped at 318 s cover those 318 s only: said again, for that time."""
    from impactbeams.preflight import format_time, highest_frequency

    params = Params(contact_law="tied", omega=400.0, force_amplitude=5e-3, damping_ratio=0.01)
    with pytest.warns(RuntimeWarning, match="status 'event_limit'"):
        run = simulate(params, 2.0, n_modes=8, dt_output=1e-3, energy_balance=True,
                       max_events=300, progress=True)
    t_end = run.attrs["t_end"]
    reached = int(np.count_nonzero(run.time.values <= t_end))
    expected = costs.energy_seconds(float(highest_frequency(params.numeric(), 8)), 8, t_end,
                                    reached)
    assert (f"simulate: the energy balance over the {t_end:.4g} s simulated: roughly "
            f"{format_time(expected)}\n") in capsys.readouterr().err


def test_a_stepped_sweep_checks_the_cache_for_its_own_kernel(monkeypatch):
    """A stepped long-time sweep after a plain one compiles the stepped map's kernels (169 in
    38 s at load 4, issue 32): announced as a compile of its kind, not as kernels missing."""
    from impactbeams import compilation
    from impactbeams.sweep.plan import entry_kernel

    plain = sweep_from_mapping({"observables": ["response_period"], "sampled_periods": 4,
                                "axes": {"omega": {"min": 300.0, "max": 400.0, "num": 2}}})
    stepped = sweep_from_mapping({"observables": ["response_period"], "sampled_periods": 4,
                                  "stepping": "up",
                                  "axes": {"omega": {"min": 300.0, "max": 400.0, "num": 2}}})
    assert entry_kernel(plain) == "stroboscope_map_serial"
    assert entry_kernel(stepped) == "stepped_map_serial"
    # only the plain sweep's kernel in the cache
    cached = compilation._kernel("stroboscope", "stroboscope_map_serial")
    monkeypatch.setattr(compilation, "_has_machine_code", lambda kernel: kernel is cached)
    assert kernels_cached("long_time", entry_kernel(plain))
    assert not kernels_cached("long_time", entry_kernel(stepped))


def test_a_wait_for_the_compile_helper_is_reported_and_kept_alive(fresh, monkeypatch):
    """The run waiting for the helper process's share of a cold compile (issue 32: under load
    two silent minutes after the announcement) is a compile of its own in the report: announced,
    a "still compiling" line after every COMPILE_HEARTBEAT s without one, timed at its end."""
    import time

    from impactbeams import compilation
    from impactbeams.kernels import linking

    monkeypatch.setattr(compilation, "COMPILE_HEARTBEAT", 0.2)
    key = (fresh, ("int64",))
    monkeypatch.setitem(linking.COMPILED_ELSEWHERE, key, lambda: time.sleep(0.9) or "file")
    stream = io.StringIO()
    with reporting_compiles(ESTIMATE, stream=stream):
        assert linking._wait_elsewhere(*key) == "file"
        assert linking._wait_elsewhere(*key) is None  # waited for once
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("impactbeams: compiling the kernels of this kind of run")
    beats = [line for line in lines if line.startswith("impactbeams: still compiling: ")]
    assert 1 <= len(beats) <= 5 and beats[0].endswith(", expected 8-17 s")
    assert re.fullmatch(r"impactbeams: compiled 1 kernels in \d+\.\d s \(cached for later runs; "
                        r"announced 8-17 s\)", lines[-1])


# --- several contacts (issue 33) -------------------------------------------------------------

def _contacts_sweep(contacts, observables=("impact_count",), **extra):
    params = {"counterpart": "stop", "force_amplitude": 1e-3, "contact_stiffness": 1e4,
              "damping_ratio": 0.01, **contacts}
    return sweep_from_mapping({"t_max": 0.2, "n_modes": 8, "observables": list(observables),
                               "params": params,
                               "axes": {"omega": {"min": 300.0, "max": 500.0, "num": 6}},
                               **extra})


TIP = {"clearance": 6e-6}
MID_AND_TIP = [{"position1": 0.05, "clearance": 2e-6}, TIP]


def test_a_first_impact_map_of_several_contacts_costs_each_contacts_map():
    """It runs each contact's own map (`plan._first_contact`): the sum of their estimates, and
    with the tip stop among them more than the tip stop's map alone."""
    from impactbeams.sweep.definition import contact_sweeps

    sweep = _contacts_sweep({"contacts": MID_AND_TIP}, ("first_impact_time",))
    total = expected_seconds(sweep, 1)
    assert total == pytest.approx(sum(expected_seconds(each, 1)
                                      for each in contact_sweeps(sweep)), rel=1e-14)
    assert total > expected_seconds(_contacts_sweep(TIP, ("first_impact_time",)), 1)


def test_a_cell_of_several_contacts_costs_its_contacts_runs_and_their_handling():
    """A cell of the full dynamics: each contact's own run's events (one contact's model of
    them, with its own clearance: a contact 1 mm away costs a free run's cycles) and
    CONTACT_CELL per contact and run (the long run is a second run); one contact given as
    ``contacts`` is the flat keys' estimate (folded: the same sweep)."""
    from impactbeams.sweep.estimate import cell_seconds, sample_points

    far = [TIP, {"position1": 0.05, "clearance": 1e-3}]
    sweep = _contacts_sweep({"contacts": far})
    single = _contacts_sweep(TIP)
    points, alone = sample_points(sweep), sample_points(single)
    far_runs = [point.each_contact()[1] for point in points]
    free = np.array([costs.dynamics_seconds(run.numeric(), run.law, 8, 0.2, "dynamics",
                                            run.partner) for run in far_runs])
    assert not any(costs.impacts(run.numeric(), 8, 0.2) for run in far_runs)
    expected = cell_seconds(single, alone) + 2 * costs.CONTACT_CELL + free
    np.testing.assert_allclose(cell_seconds(sweep, points), expected, rtol=1e-12)
    both = _contacts_sweep({"contacts": far}, ("impact_count", "response_period"),
                           transient_periods=20, sampled_periods=4)
    long_run = _contacts_sweep({"contacts": far}, ("response_period",), transient_periods=20,
                               sampled_periods=4)
    assert float(np.mean(cell_seconds(both, points))) == pytest.approx(float(np.mean(
        cell_seconds(long_run, points) + cell_seconds(sweep, points))), rel=1e-12)
    assert expected_seconds(_contacts_sweep({"contacts": [TIP]}), 1) == expected_seconds(
        single, 1)
    four = MID_AND_TIP + [{"position1": 0.05, "side": "above", "clearance": 3e-6},
                          {"side": "above", "clearance": 8e-6}]
    assert (expected_seconds(single, 1) < expected_seconds(_contacts_sweep(
        {"contacts": MID_AND_TIP}), 1) < expected_seconds(_contacts_sweep({"contacts": four}), 1))


def test_the_several_contacts_calibration_is_the_models_and_within_a_factor_of_three():
    """The calibration's cases (1, 2, 4 contacts at 8 and 16 modes, benchmarks/
    calibrate_costs.py --only-contacts): their recorded estimates are what the model gives
    now, and each measured time per cell is within a factor of 3 of it, the spread of one
    contact's estimates of the shipped sweeps and random runs (docs/limits.md, "Time")."""
    from impactbeams.sweep.estimate import cell_seconds, sample_points

    calibrate = _load_benchmark("calibrate_costs")
    cases = json.loads(CALIBRATION.read_text())["measured"]["contacts"]
    assert {(case["contacts"], case["n_modes"]) for case in cases} == {
        (count, n) for count in (1, 2, 4) for n in calibrate.CONTACT_MODES}
    for case in cases:
        sweep = calibrate.contacts_sweep(case["contacts"], case["n_modes"])
        estimate = float(np.mean(cell_seconds(sweep, sample_points(sweep, limit=sweep.size))))
        assert case["estimated_s_per_cell"] == pytest.approx(estimate, rel=1e-12)
        assert 1 / 3 < case["measured_s_per_cell"] / estimate < 3


def test_a_structures_own_damping_is_estimated_as_its_smallest_ratio():
    """Modal data with its own ratios (5 % to 20 %) cost, in a run's estimate and a map's,
    what the same data without them and damping_ratio = 0.05 cost (the slowest decay), bit
    for bit; with neither, 18 times more: at twice beam 1's first frequency the tips meet
    only while the start's free vibration lasts, which the damping shortens."""
    from impactbeams.trajectory.simulation import simulation_cost
    from test_user_structure import analytic_modal_data

    values = Params().numeric()
    omega_1 = 1.8751040687**2 / values["l1"] ** 2 * math.sqrt(values["EI1"] / values["rhoA1"])
    steady = 4.0 / (values["rhoA1"] * values["l1"]) / (3.0 * omega_1**2)  # mode 1, per newton
    fixed = {"counterpart": "stop", "omega": 2.0 * omega_1, "uplift1": 0.0,
             "force_amplitude": 0.6 * values["clearance"] / steady}
    undamped = analytic_modal_data(8)  # the run's damping_ratio damps its modes
    runs = [{"structure1": undamped, "damping_ratio": 0.05},
            {"structure1": analytic_modal_data(8, damping_ratios=np.linspace(0.2, 0.05, 8))},
            {"structure1": undamped}]
    run_costs = [simulation_cost(Params(**fixed, **run), 2.0, 8, 10, False, 0, False,
                                 1000).seconds for run in runs]
    map_costs = [expected_seconds(sweep_from_mapping({
        "t_max": 2.0, "n_modes": 8, "observables": ["impact_count"], "params": {**fixed, **run},
        "axes": {"clearance": {"min": 1e-5, "max": 2e-5, "num": 2}}}), 1) for run in runs]
    for today, own, undamped in (run_costs, map_costs):
        assert own == today
        assert undamped > 10.0 * own
