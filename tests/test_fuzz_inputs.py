"""A seeded fuzz of mutated sweep and parameter files through the command line: no traceback.

The shipped sweeps (sweeps/*.toml) and a few parameter and sweep files that reach the contact
law, the full dynamics, the Lyapunov exponent and the long-time keys are mutated (values of
other types or sizes, keys deleted, renamed or added, axis tables broken, lines duplicated or
cut) and run in-process through :func:`impactbeams.cli.main` as a user would: ``run`` for a
sweep, ``modes --params`` and ``simulate --params`` for a parameter file. The compute is a
stub, so that a valid file costs nothing: ``write_sweep`` writes an empty result, and
``simulate`` stops where it would build the model (every check of its inputs runs before).

Each file must give exit code 0 (valid) or 2 (refused, with exactly one ``impactbeams: error:``
line); any exception out of ``main`` fails the test with the file's text. The same seed gives
the same files. CI runs a fast subset; the full 10,000 files are marked slow.
"""

import copy
import json
import math
import random
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactbeams.sweep
import impactbeams.trajectory.simulation
from impactbeams.cli import main
from impactbeams.sweep.definition import LONG_TIME_KEYS, OBSERVABLES, STEPPING_KEYS
from impactbeams.variables import PARAMETERS

# a warning (an unresolved spring contact) is one line of the command line's, as for a user;
# the suite's "error" filter would raise it out of main instead
pytestmark = pytest.mark.filterwarnings("always")

SWEEPS = sorted((Path(__file__).parents[1] / "sweeps").glob("*.toml"))
# sweeps of the kinds the shipped ones lack, and parameter files of both laws
EXTRA_SWEEPS = [
    'observables = ["impact_count", "max_contact_force", "mean_restitution", '
    '"contact_fraction"]\nt_max = 0.2\nn_modes = 6\n[params]\ncontact_law = "tied"\n'
    '[axes.contact_law]\nvalues = ["tied", "spring"]\n'
    '[axes.omega]\nmin = 50.0\nmax = 300.0\nnum = 4\n',
    'observables = ["lyapunov_exponent"]\nt_max = 2.0\nn_modes = 8\ntransient_periods = 5\n'
    '[params]\ncontact_stiffness = 1e5\ncontact_damping = 0.1\ndamping_ratio = 0.01\n'
    '[axes.force_amplitude]\nmin = 1e-3\nmax = 1e-2\nnum = 3\nscale = "log"\n',
    'observables = ["response_period", "steady_impact_rate"]\nn_modes = 8\n'
    'transient_periods = 10\nsampled_periods = 8\nmax_period = 4\nperiod_tolerance = 1e-3\n'
    '[params]\nE1 = 7e10\nthickness2 = 5e-4\n'
    '[axes.uplift1]\nmin = -1e-5\nmax = 1e-5\nnum = 3\n',
]
PARAMETER_FILES = [
    "[params]\nclearance = 1.1e-5\nforce_amplitude = 1e-3\nomega = 50.0\n",
    '[params]\ncontact_law = "tied"\nl1 = 0.1\nl2 = 0.12\nuplift1 = 1e-6\ndamping_ratio = 0.02\n',
    "[params]\nE1 = 7e10\nrho1 = 2700.0\nwidth1 = 5e-3\nthickness1 = 5e-4\n"
    "contact_stiffness = 1e5\ncontact_damping = 0.5\n",
    "[params]\nEI2 = 1e-3\nrhoA2 = 0.02\nuplift2 = -2e-6\n",
]

NAN, INF = math.nan, math.inf
ODD_VALUES = ["", "abc", "1e-5", "nan", "spring", "tied", "linear", "log", True, False, 0, 1,
              -1, 2, 7, 2**31, 2**63 - 1, -(2**63), 0.0, -0.0, 5e-324, 1e-300, 1e-12, 1e-5, 0.5,
              -1.5, 1e12, 1e300, 1.7976931348623157e308, NAN, INF, -INF, [], [1], [1, 2],
              ["x"], [[]], [{}], {}, {"a": 1}, {"min": 1.0, "max": 2.0, "num": 2},
              {"values": ["tied"]}]
KEYS = sorted({"t_max", "n_modes", "observables", "params", "axes", "transient_periods",
               *LONG_TIME_KEYS, *STEPPING_KEYS, *PARAMETERS, "min", "max", "num", "scale",
               "values", "step", "bogus"})
STUB_ATTRIBUTES = {"status": "complete"}


class ModelBuilt(Exception):
    """Raised by the stub of pack_run: every check of simulate() passed."""


def _odd(rng):
    """One of ODD_VALUES, a copy: later changes to the file must not change the list."""
    return copy.deepcopy(rng.choice(ODD_VALUES))


def _perturbed(rng, value):
    """A number near, far from, or of another kind than ``value``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return _odd(rng)
    whole = int(value) if abs(value) < 2**63 else value  # TOML's integers have 64 bits
    return rng.choice([value * 10.0 ** rng.randint(-12, 12), -value, whole, float(value),
                       value + 1, 0, value * (1 + 1e-15)])


def _value(rng, old):
    """A replacement for ``old``: an odd value, a perturbed one, or (for lists) a changed list."""
    if isinstance(old, list) and old and rng.random() < 0.5:
        new = list(old)
        choice = rng.random()
        if choice < 0.3:
            new.pop(rng.randrange(len(new)))
        elif choice < 0.6:
            new.append(rng.choice([*OBSERVABLES, "bogus", "tied", "spring", 1]))
        else:
            new[rng.randrange(len(new))] = _odd(rng)
        return new
    return _perturbed(rng, old) if rng.random() < 0.4 else _odd(rng)


def _tables(data):
    """Every table (dict) in ``data``, itself included."""
    found = [data]
    for value in data.values():
        if isinstance(value, dict):
            found.extend(_tables(value))
    return found


def _observables(rng):
    return rng.sample(OBSERVABLES, rng.randint(1, 4))


def mutate(rng, data):
    """Apply one random change to the parsed file ``data`` (in place)."""
    table = rng.choice(_tables(data))
    keys = list(table)
    operation = rng.random()
    if keys and operation < 0.35:
        key = rng.choice(keys)
        table[key] = _value(rng, table[key])
    elif keys and operation < 0.5:
        del table[rng.choice(keys)]
    elif keys and operation < 0.6:
        key = rng.choice(keys)
        renamed = rng.choice([rng.choice(KEYS), key.upper(), key[:-1], key + "s"])
        table[renamed] = table.pop(key)
    elif operation < 0.75:
        table[rng.choice(KEYS)] = rng.choice([_odd(rng), _perturbed(rng, 1.0)])
    elif operation < 0.85:  # the long-time and Lyapunov keys, with their observables
        data["observables"] = _observables(rng)
        key = rng.choice(["transient_periods", *LONG_TIME_KEYS])
        data[key] = rng.choice([0, 1, 2, 3, 20, 200, 10**6, 10**9, 2**63 - 1, -1, 2.5, 1e-4,
                                0.5, "5", True, []])
    else:  # an axis table rebuilt from odd parts
        axes = data.setdefault("axes", {}) if isinstance(data.get("axes", {}), dict) else {}
        name = rng.choice([*PARAMETERS, "bogus"])
        axes[name] = ({"values": rng.sample(["tied", "spring", "rigid", 1], rng.randint(0, 3))}
                      if name == "contact_law" and rng.random() < 0.7 else
                      {key: _value(rng, 1.0) for key in ("min", "max", "num", "scale")
                       if rng.random() < 0.8})


def mutate_text(rng, text):
    """A change to the file's text: a line duplicated or deleted, the text cut, a byte added."""
    lines = text.splitlines(keepends=True) or [""]
    where = rng.randrange(len(lines))
    operation = rng.randrange(4)
    if operation == 0:
        lines.insert(where, lines[where])
    elif operation == 1:
        del lines[where]
    elif operation == 2:
        return text[: rng.randrange(len(text) + 1)]
    else:
        position = rng.randrange(len(text) + 1)
        return text[:position] + rng.choice("=[]{}\"'#,.\n\x00x1-") + text[position:]
    return "".join(lines)


def _key(name):
    return name if re.fullmatch(r"[A-Za-z0-9_-]+", name) else json.dumps(name)


def _inline(value):
    """A TOML value (inline tables and arrays inside)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(_inline, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_inline(v)}" for k, v in value.items()) + "}"
    return str(value)


def to_toml(data, prefix=()):
    """The TOML text of ``data``: values first, then each sub-table as a [section]."""
    lines = [f"{_key(k)} = {_inline(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for key, value in data.items():
        if isinstance(value, dict):
            header = ".".join(map(_key, (*prefix, key)))
            lines.append(f"\n[{header}]\n" + to_toml(value, (*prefix, key)))
    return "\n".join(lines) + "\n"


def fuzz_files(count, seed):
    """``count`` (kind, text) pairs, the same for the same seed: "sweep" or "params"."""
    import tomllib

    rng = random.Random(seed)
    seeds = ([("sweep", path.read_text()) for path in SWEEPS]
             + [("sweep", text) for text in EXTRA_SWEEPS]
             + [("params", text) for text in PARAMETER_FILES])
    for _ in range(count):
        kind, text = rng.choice(seeds)
        if rng.random() < 0.15:
            yield kind, mutate_text(rng, text)
            continue
        data = tomllib.loads(text)
        for _ in range(rng.choice([1, 1, 2, 3])):
            mutate(rng, data)
        yield kind, to_toml(data)


def _write_empty_result(sweep, output, *args, **kwargs):
    """The stub of write_sweep: an empty result file (the CLI reads a dynamics map's status)."""
    xr.Dataset().to_netcdf(output)
    return True


def _simulate_until_the_model(*args, **kwargs):
    """simulate() with all its checks; a stand-in result once it would build the model."""
    try:
        return SIMULATE(*args, **kwargs)
    except ModelBuilt:
        return xr.Dataset({"impact": ("impact", np.arange(0))}, attrs=STUB_ATTRIBUTES)


def _stop(*args, **kwargs):
    raise ModelBuilt


SIMULATE = impactbeams.trajectory.simulation.simulate


@pytest.fixture
def stubbed(tmp_path, monkeypatch):
    """A scratch folder, and the compute replaced by the stubs above."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(impactbeams.sweep, "write_sweep", _write_empty_result)
    monkeypatch.setattr(impactbeams.trajectory.simulation, "pack_run", _stop)
    monkeypatch.setattr(impactbeams.trajectory, "simulate", _simulate_until_the_model)
    return tmp_path


def _commands(kind, number):
    if kind == "sweep":
        return ["run", "f.toml", "-o", "out.nc", "--quiet"]
    if number % 2:
        return ["modes", "--params", "f.toml", "--n", "3"]
    return ["simulate", "--t-max", "0.01", "--params", "f.toml", "-o", "out.nc"]


def run_fuzz(folder, capsys, count, seed):
    """Run ``count`` fuzzed files; return how many were valid and how many refused."""
    outcomes = {0: 0, 2: 0}
    for number, (kind, text) in enumerate(fuzz_files(count, seed)):
        (folder / "f.toml").write_text(text)
        argv = _commands(kind, number)
        try:
            code = main(argv)
        except BaseException as error:
            raise AssertionError(f"file {number} ({' '.join(argv)}) raised {error!r}:\n{text}"
                                 ) from error
        err = capsys.readouterr().err
        errors = [line for line in err.splitlines() if line.startswith("impactbeams: error:")]
        assert code in outcomes and len(errors) == (code == 2), (number, argv, code, err, text)
        assert "Traceback" not in err
        outcomes[code] += 1
        (folder / "out.nc").unlink(missing_ok=True)
    return outcomes


def test_fuzz_files_are_reproducible():
    assert list(fuzz_files(50, seed=3)) == list(fuzz_files(50, seed=3))
    assert list(fuzz_files(50, seed=3)) != list(fuzz_files(50, seed=4))


def test_a_fuzz_of_1000_files_raises_nothing(stubbed, capsys):
    outcomes = run_fuzz(stubbed, capsys, 1000, seed=2026)
    # both paths are exercised: valid files reach the stub, the others are refused
    assert outcomes[0] > 50 and outcomes[2] > 500, outcomes


@pytest.mark.slow
def test_a_fuzz_of_10000_files_raises_nothing(stubbed, capsys):
    outcomes = run_fuzz(stubbed, capsys, 10_000, seed=20)
    assert outcomes[0] + outcomes[2] == 10_000
