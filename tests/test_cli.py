"""The ``impactbeams`` command: modes, parameter options and error reporting."""

import json
import subprocess
import sys

import pytest

from impactbeams.cli import main
from impactbeams.modes import contact_frequencies, free_modes
from impactbeams.params import Params


def test_modes_json_matches_the_library(capsys, tmp_path):
    params_file = tmp_path / "p.toml"
    params_file.write_text("[params]\nl2 = 0.15\nthickness1 = 6e-4\n")
    assert main(["modes", "--n", "4", "--json", "--params", str(params_file),
                 "--EI2", "0.02"]) == 0
    result = json.loads(capsys.readouterr().out)
    p = Params.from_mapping({"l2": 0.15, "thickness1": 6e-4, "EI2": 0.02})
    assert result["free"]["beam1"] == free_modes(p.EI1, p.rhoA1, p.l1, 4).omega.tolist()
    assert result["free"]["beam2"] == free_modes(p.EI2, p.rhoA2, p.l2, 4).omega.tolist()
    assert result["contact"] == contact_frequencies(p, 4).tolist()


def test_modes_table(capsys):
    assert main(["modes", "--n", "3"]) == 0
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


def test_console_script_entry_point():
    result = subprocess.run([sys.executable, "-m", "impactbeams.cli", "modes", "--n", "0"],
                            capture_output=True, text=True)
    assert result.returncode == 2 and "must be an integer >= 1" in result.stderr


def test_public_api_names_stay_functions_after_their_modules_load():
    """The lazy top-level names must not be shadowed by submodules of the same name."""
    import importlib

    import impactbeams

    for name, module in impactbeams._LAZY.items():
        importlib.import_module(module)
        assert callable(getattr(impactbeams, name)), name
        assert not isinstance(getattr(impactbeams, name), type(importlib)), name
