"""The ``impactbeams`` command: modes, parameter options and error reporting."""

import importlib.util
import json
import os
import shutil
import subprocess
import sys
from importlib.metadata import entry_points
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from impactbeams.cli import main
from impactbeams.model import build_free_phase
from impactbeams.modes import contact_frequencies, free_modes
from impactbeams.params import Params
from references import free_tip_gap, reference_first_impact


def test_modes_json_matches_the_library(capsys, tmp_path):
    params_file = tmp_path / "p.toml"
    params_file.write_text("[params]\nl2 = 0.15\nthickness1 = 6e-4\n")
    assert main(["modes", "--n", "4", "--json", "--params", str(params_file),
                 "--EI2", "0.02", "--contact-law", "tied"]) == 0
    result = json.loads(capsys.readouterr().out)
    p = Params.from_mapping({"l2": 0.15, "thickness1": 6e-4, "EI2": 0.02})
    assert result["free"]["beam1"] == free_modes(p.EI1, p.rhoA1, p.l1, 4).frequencies.tolist()
    assert result["free"]["beam2"] == free_modes(p.EI2, p.rhoA2, p.l2, 4).frequencies.tolist()
    assert result["contact"] == contact_frequencies(p, 4).tolist()
    # and the options reached the model: closed forms omega_n = sqrt(EI / rhoA) (b_n / l)^2
    # with the steel strip's EI = E b h^3 / 12, rhoA = rho b h (beam 1 h = 0.6 mm; beam 2
    # EI2 = 0.02 given, default h = a / sqrt(E / (12 rho)) with a = 0.7)
    roots = np.array([*CANTILEVER_ROOTS, 10.9955407349])
    E, rho, b = 210e9, 7850.0, 5e-3
    beam1 = np.sqrt(E * b * 6e-4**3 / 12 / (rho * b * 6e-4)) * (roots / 0.1) ** 2
    h2 = 0.7 / np.sqrt(E / (12 * rho))
    beam2 = np.sqrt(0.02 / (rho * b * h2)) * (roots / 0.15) ** 2
    assert result["free"]["beam1"] == pytest.approx(beam1, rel=1e-9)  # 10-digit roots
    assert result["free"]["beam2"] == pytest.approx(beam2, rel=1e-9)


def test_help_opens_with_what_the_program_does(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    description = " ".join(capsys.readouterr().out.split("\n\n")[1].split())
    assert description == ("Two cantilever beams impacting across a clearance: frequencies, "
                           "trajectories, sweeps, plots.")


@pytest.mark.parametrize("set_by_user", [None, "30"])
def test_the_command_lets_idle_blas_threads_sleep_unless_told_otherwise(set_by_user):
    # OpenBLAS reads the variable when SciPy loads it, after the command starts (issue 24); a
    # command in its own process sets it, a caller's process is left alone
    environment = {k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
    if set_by_user is not None:
        environment["OPENBLAS_THREAD_TIMEOUT"] = set_by_user
    shown = "print('timeout', os.environ.get('OPENBLAS_THREAD_TIMEOUT'))\n"
    script = ("import os, sys\nfrom impactbeams.cli import main\n"
              f"main(['modes', '--n', '1'])\n{shown}"
              f"sys.argv = ['impactbeams', 'modes', '--n', '1']\nmain()\n{shown}")
    printed = subprocess.run([sys.executable, "-c", script], env=environment, check=True,
                             capture_output=True, text=True).stdout.splitlines()
    assert [line for line in printed if line.startswith("timeout")] == [
        f"timeout {set_by_user}", f"timeout {set_by_user or 4}"]


def test_modes_table(capsys):
    assert main(["modes", "--n", "3", "--contact-law", "tied"]) == 0
    out = capsys.readouterr().out
    assert "rad/s" in out and "246.121069" in out and "208.046178" in out


@pytest.mark.parametrize(("argv", "message"), [
    (["modes", "--clearance=-1e-5"], "clearance = -1e-05 is not allowed: must be > 0 (m)"),
    (["modes", "--params", "missing.toml"], "file 'missing.toml' does not exist"),
    (["modes", "--EI1", "1.0", "--E1", "2e11"], "both EI1 and material keys E1"),
])
def test_errors_exit_2_with_a_clear_message(capsys, argv, message):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def console_script():
    """The installed ``impactbeams`` executable: the one beside this interpreter (its venv),
    else the first on PATH. ``python -m impactbeams`` only if the package has a __main__."""
    beside = Path(sys.executable).with_name("impactbeams")
    found = str(beside) if beside.is_file() else shutil.which("impactbeams")
    if found is not None:
        return [found]
    if importlib.util.find_spec("impactbeams.__main__") is not None:
        return [sys.executable, "-m", "impactbeams"]
    pytest.fail("the impactbeams console script is not installed: pip install -e '.[test]'")


def run_console(*args, cwd=None):
    return subprocess.run([*console_script(), *args], capture_output=True, text=True, cwd=cwd,
                          timeout=600)  # a loaded CI machine; a fresh cache compiles kernels


def test_console_script_is_declared_for_cli_main():
    (entry,) = entry_points(group="console_scripts", name="impactbeams")
    assert entry.value == "impactbeams.cli:main"


# cantilever roots b_n of cos b cosh b = -1 (10 digits, tables) and MODEL.md's contact values
CANTILEVER_ROOTS = (1.8751040687, 4.6940911330, 7.8547574382)
CONTACT = ("208.046", "844.946", "1364.32")


def test_console_script_prints_the_known_frequencies():
    result = run_console("modes", "--n", "3", "--json", "--contact-law", "tied")
    assert result.returncode == 0, result.stderr
    modes = json.loads(result.stdout)
    p = Params()  # default steel strip: a = 0.7 m^2/s on both beams
    for beam, length in (("beam1", p.l1), ("beam2", p.l2)):
        closed_form = [0.7 * (b / length) ** 2 for b in CANTILEVER_ROOTS]
        # roots to 10 digits: 1e-10 relative in b, 2e-10 in omega
        assert modes["free"][beam] == pytest.approx(closed_form, rel=1e-9)
    assert modes["free"]["beam1"] == pytest.approx([246.121, 1542.41, 4318.81], abs=0.005)
    assert modes["free"]["beam2"] == pytest.approx([170.917, 1071.12, 2999.17], abs=0.005)
    for value, text in zip(modes["contact"], CONTACT, strict=True):
        decimals = len(text.split(".")[1])  # MODEL.md rounds: half a unit of the last digit
        assert abs(value - float(text)) <= 0.5 * 10.0**-decimals, (value, text)


def test_console_script_reports_bad_options_with_exit_code_2():
    result = run_console("modes", "--n", "0")
    assert result.returncode == 2 and "must be an integer from 1 to 200" in result.stderr
    result = run_console("modes", "--clearance=-1e-5")
    assert result.returncode == 2
    assert "clearance = -1e-05 is not allowed: must be > 0 (m)" in result.stderr


def test_console_script_runs_a_sweep_and_writes_netcdf(tmp_path):
    """``impactbeams run`` on a 2 x 2 sweep: exit code 0, a CF netCDF file whose cells equal the
    textbook free-phase solution's first impacts (references.py, long double)."""
    sweep_file = tmp_path / "tiny.toml"
    sweep_file.write_text(
        "t_max = 0.3\nn_modes = 4\n[params]\nclearance = 1.1e-5\n"
        "[axes.omega]\nmin = 50.0\nmax = 200.0\nnum = 2\n"
        "[axes.force_amplitude]\nmin = 1e-4\nmax = 1e-3\nnum = 2\n")
    out = tmp_path / "tiny.nc"
    result = run_console("run", str(sweep_file), "-o", str(out), "--quiet", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # --quiet: nothing but warnings and errors (it said 3 lines)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.nc", "tiny.toml"]
    free = build_free_phase(Params(), 4)
    c1 = Params().tip_compliance[0]
    with xr.open_dataset(out) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["t_max"] == 0.3
        assert ds.first_impact_time.dims == ("omega", "force_amplitude")
        assert ds.first_impact_time.attrs["units"] == "s"
        np.testing.assert_array_equal(ds.omega.values, [50.0, 200.0])
        np.testing.assert_array_equal(ds.force_amplitude.values, [1e-4, 1e-3])
        for i, omega in enumerate(ds.omega.values):
            for j, force in enumerate(ds.force_amplitude.values):
                args = (free, c1, 1.1e-5, float(force), float(omega))
                reference = reference_first_impact(
                    free_tip_gap(*args), 0.3, free.frequencies.max(),
                    scan=free_tip_gap(*args, dtype=np.float64))
                got = float(ds.first_impact_time[i, j])
                assert np.isnan(got) == np.isnan(reference)
                # both locate the root to the last ulp or so (see test_sweep)
                assert np.isnan(reference) or abs(got - reference) <= 1e-12 * reference
                assert int(ds.impacted[i, j]) == int(np.isfinite(reference))
        assert int(ds.impacted.sum()) >= 1  # not a map of NaN only


def test_public_api_names_stay_functions_after_their_modules_load():
    """The lazy top-level names must not be shadowed by submodules of the same name."""
    import importlib

    import impactbeams

    for name, module in impactbeams._LAZY.items():
        importlib.import_module(module)
        assert callable(getattr(impactbeams, name)), name
        assert not isinstance(getattr(impactbeams, name), type(importlib)), name


def test_version(capsys):
    import impactbeams

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"impactbeams {impactbeams.__version__}\n"


def every_command():
    from impactbeams.cli import build_parser

    parser = build_parser()
    return parser, parser.commands


def test_every_argument_has_a_one_line_help_and_every_command_is_quiet():
    """Help text for every argument (SWEEP.toml, IN.nc, simulate -o had none), none a formula
    (--damping-ratio's was five lines), and --quiet on every command."""
    parser, commands = every_command()
    assert sorted(commands) == ["basins", "contacts", "continue", "grazing", "modes", "plot",
                                "run", "simulate"]
    assert all(action.help for action in parser._actions)
    for name, command in commands.items():
        for action in command._actions:
            assert action.help, (name, action.dest)
            assert len(action.help) <= 150, (name, action.dest, action.help)
        assert "--quiet" in command._option_string_actions, name


@pytest.mark.parametrize(("argv", "usage"), [
    (["simulate", "--t-max", "1", "--clear", "1e-5", "-o", "r.nc"],
     "usage: impactbeams simulate --t-max SECONDS -o RUN.nc [OPTIONS] [PARAMETER OPTIONS]"),
    (["run"], "usage: impactbeams run SWEEP.toml [-o OUT.nc] [OPTIONS]"),
    (["plot", "x.nc", "--dpi", "0"], "usage: impactbeams plot IN.nc [-o OUT.png] [OPTIONS]"),
])
def test_argument_errors_show_the_usage_then_one_line(capsys, argv, usage):
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == usage and len(err) == 2 and err[1].startswith("impactbeams: error: ")


def test_run_announces_a_stop_sweep_in_modes_of_beam_1(capsys, tmp_path):
    """'16 modes per beam' for a stop (one beam), '400 = 400 cells over omega' (one axis)."""
    from impactbeams.cli import _announce, build_parser
    from impactbeams.sweep import sweep_from_mapping

    sweep = sweep_from_mapping({"t_max": 0.3, "n_modes": 16, "params": {"counterpart": "stop"},
                                "axes": {"omega": {"min": 50.0, "max": 200.0, "num": 400}}},
                               source="s.toml")
    _announce(sweep, tmp_path / "s.nc", build_parser().parse_args(["run", "s.toml"]))
    first = capsys.readouterr().err.splitlines()[0]
    assert first == (f"s.toml: 400 cells over omega; t_max = 0.3 s, 16 modes of beam 1 -> "
                     f"{tmp_path / 's.nc'}")


def test_a_run_stopped_by_the_event_cap_says_where_and_when_it_will(tmp_path, capsys):
    """The bar ended at '600/600 s simulated' for a run stopped at 318 s; the cap was neither
    announced nor settable. Now --max-events sets it, the pace of the first window warns that
    it will be reached, and the bar's last line says where the run stopped."""
    output = tmp_path / "r.nc"
    assert main(["simulate", "--t-max", "5", "--max-events", "3000", "-o", str(output)]) == 3
    err = capsys.readouterr().err.splitlines()
    with xr.open_dataset(output) as run:
        t_end = run.attrs["t_end"]
        assert run.attrs["status"] == "event_limit" and run.attrs["n_phases"] == 3000
    warning = next(line for line in err if "at its pace so far" in line)
    assert warning.endswith("and stops there: raise max_events (--max-events) to go on")
    assert "reaches max_events = 3000 phases at about t = " in warning
    last_bar = next(line for line in err if "stopped: event_limit" in line)
    assert err.index(warning) < err.index(last_bar)
    assert last_bar.endswith(f"stopped: event_limit at t = {t_end:.6g} s")
    assert f" {t_end:.4g}/5 s simulated" in last_bar
    assert not any("5/5 s simulated" in line for line in err)


@pytest.mark.parametrize(("clearance", "hinted"), [("0.011", True), ("1.1e-5", False)])
def test_a_clearance_beyond_any_motion_of_the_drive_gets_a_hint(tmp_path, capsys, clearance,
                                                                 hinted):
    """simulate --clearance 0.011 (mm typed as m) ran to 0 impacts without a word. The tip's
    linear response by t_max = 0.6 s: its static deflection F0 l1^3 / (3 EI1) = 3.70e-5 m
    amplified by 1 / (1 - (Omega / omega_1)^2) = 1.043 (the steady part, 3.86e-5 m), plus the
    free vibration of the start from rest, at most Omega / omega_n of each mode's."""
    assert main(["simulate", "--t-max", "0.6", "--clearance", clearance, "-o",
                 str(tmp_path / "r.nc"), "--quiet"]) == 0
    err = capsys.readouterr().err
    p = Params()
    static = p.force_amplitude * p.tip_compliance[0]
    steady = static / (1 - (p.omega / (1.8751040687**2 * 0.7 / p.l1**2)) ** 2)
    if not hinted:
        assert err == ""
        return
    (line,) = err.splitlines()
    reach = float(line.split("by t_max (")[1].split(" m")[0])
    assert steady < reach < steady * (1 + p.omega / 246.121)  # plus the free vibration
    assert steady == pytest.approx(3.856e-5, rel=1e-3)
    ratio = float(line.split(" m is ")[1].split(" times")[0])
    assert ratio == pytest.approx(0.011 / reach, rel=5e-3)  # both printed to 3 digits
    assert line == (f"impactbeams: warning: clearance = 0.011 m is {ratio:.3g} times the "
                    "largest tip motion the drive is expected to give beam 1 by t_max "
                    f"({reach:.3g} m, its linear response): the tips will most likely never "
                    "meet. A clearance in mm typed in m? (0.011 mm is 1.1e-05 m)")
