"""Start-up of every command (issue 24): each imports only the heavy libraries it uses.

A budget is a list of modules, not a time, so it cannot flake on a loaded machine; the times
are measured by benchmarks/bench_startup.py. Also here: the replacements that keep heavy
libraries out — Brent's method without ``scipy.optimize`` gives SciPy's roots bit for bit, the
CLI's netCDF writer (no xarray) writes what xarray's writer writes, and kernels loaded from
Numba's cache without its compile registries or ``scipy.linalg`` give Numba's results bit for bit.
"""

import json
import math
import subprocess
import sys
from importlib.util import find_spec

import numpy as np
import pytest
import scipy.optimize

from impactbeams import modes
from impactbeams.brent import brentq
from impactbeams.io import write_netcdf
from impactbeams.kernels.jit import plain_numba
from impactbeams.params import Params
from impactbeams.sweep import load_sweep, run_sweep, write_sweep
from test_resume import KINDS, assert_same_map

# what a command's cost is made of (docs/benchmarks/startup.json)
HEAVY = {"scipy", "scipy.linalg", "scipy.optimize", "numba", "xarray", "pandas", "netCDF4",
         "matplotlib", "matplotlib.pyplot", "dask",
         # the eigen-solvers of beams with attachments and of user structures: only for those
         "impactbeams.structure.cantilever", "impactbeams.structure.user"}
# Numba imports SciPy's top package to check its version; its cached kernels load without
# scipy.linalg in the command's own process (impactbeams.cached_kernels)
NUMBA = {"numba", "scipy"}
NETCDF_MAP = {"xarray", "pandas", "netCDF4"}
DASK = {"dask"} if find_spec("dask") else set()  # xarray imports it where installed
# the plain path (kernels/jit.py) loads cached kernels as Numba does, with scipy.linalg
NUMBA_LOADING = {"scipy.linalg"} if plain_numba() else set()


def _modules_after(code, cwd):
    """The `HEAVY` modules a fresh interpreter has imported after running ``code`` in ``cwd``."""
    check = (f"import json, sys\n{code}\n"  # a module hidden as None was not imported
             f"print(json.dumps(sorted(name for name, module in sys.modules.items() "
             f"if module is not None and name in {sorted(HEAVY)!r})))")
    result = subprocess.run([sys.executable, "-c", check], check=True, capture_output=True,
                            text=True, cwd=cwd)
    return set(json.loads(result.stdout.strip().splitlines()[-1]))


def _command(*argv):
    """Code running ``impactbeams ARGV`` as the console script does, in the command's own
    process (argparse's --help and errors exit)."""
    return (f"import sys\nsys.argv = ['impactbeams', *{list(argv)!r}]\n"
            "from impactbeams.cli import main\ntry:\n    main()\nexcept SystemExit:\n    pass")


def _called(*argv):
    """Code calling ``main(ARGV)`` in a caller's process: nothing is set up for a quick start."""
    return f"from impactbeams.cli import main\nmain({list(argv)!r})"


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A small first-impact sweep, run once here so that its kernels are compiled and cached."""
    folder = tmp_path_factory.mktemp("startup")
    (folder / "tiny.toml").write_text(KINDS["first-impact"])
    write_sweep(folder / "tiny.toml", folder / "warm.nc")
    return folder


BUDGETS = {  # command: the heavy modules it imports, exactly
    "import": ("import impactbeams, impactbeams.cli, impactbeams.sweep", set()),
    "help": (_command("--help"), set()),
    "run --help": (_command("run", "--help"), set()),
    "plot --help": (_command("plot", "--help"), set()),
    "simulate --help": (_command("simulate", "--help"), set()),
    "argument error": (_command("run", "tiny.toml", "--threads", "0"), set()),
    "missing file": (_command("run", "missing.toml"), set()),
    "modes tied": (_command("modes", "--contact-law", "tied"), set()),
    # LAPACK's dlasd4 for the spring's contact oscillators; no scipy.optimize
    "modes spring": (_command("modes"), {"scipy", "scipy.linalg"}),
    "run": (_command("run", "tiny.toml", "-o", "new.nc"), NUMBA | NUMBA_LOADING | {"netCDF4"}),
    "run, finished": (_command("run", "tiny.toml", "-o", "warm.nc"), {"netCDF4"}),
    # in a caller's process Numba loads its kernels as it does (its registries, refreshed
    # first, import scipy.linalg)
    "run, called": (_called("run", "tiny.toml", "-o", "new.nc"),
                    NUMBA | {"scipy.linalg", "netCDF4"}),
    # netCDF4 reads a map's file (not xarray, not pandas); Figure and the Agg canvas draw it,
    # not pyplot; no SciPy, no Dask
    "plot": (_command("plot", "warm.nc", "-o", "map.png"), {"netCDF4", "matplotlib"}),
    "plot, a line": (_command("plot", "warm.nc", "-o", "line.png", "--slice", "omega=200"),
                     {"netCDF4", "matplotlib"}),
    # a caller's xarray Dataset: drawn by the same code, which imports nothing more (xarray
    # imports Dask, if installed, in a caller's process)
    "plot_dataset, xarray": ("import xarray as xr\nfrom impactbeams.plotting import plot_dataset"
                             "\nplot_dataset(xr.open_dataset('warm.nc'), 'xarray.png')",
                             NETCDF_MAP | {"matplotlib"} | DASK),
}


@pytest.mark.parametrize("command", list(BUDGETS))
def test_each_command_imports_only_what_it_uses(command, workdir):
    code, budget = BUDGETS[command]
    (workdir / "new.nc").unlink(missing_ok=True)
    assert _modules_after(code, workdir) == budget


def test_the_budgets_ran_the_commands(workdir):
    """The budgets' commands did their work (a budget of a failed command would prove little)."""
    for name in ("run", "plot", "plot, a line", "plot_dataset, xarray"):
        _modules_after(BUDGETS[name][0], workdir)
    assert (workdir / "new.nc").stat().st_size > 0
    assert all((workdir / f"{name}.png").stat().st_size > 0 for name in ("map", "line", "xarray"))


# --- Brent's method: SciPy's roots, bit for bit ---

def _cases():
    """Functions with brackets: smooth, flat near the root, steep, and a root at an end."""
    rng = np.random.default_rng(24)
    for _ in range(200):
        centre, steepness = rng.uniform(-3, 3), 10 ** rng.uniform(-1, 2)
        yield ((lambda x, c=centre, k=steepness: math.tanh(k * (x - c)) + 0.1 * (x - c) ** 3),
               centre - rng.uniform(0.01, 4), centre + rng.uniform(0.01, 4))
    yield (lambda x: (x - 1.0) ** 3, 0.0, 3.0)  # SciPy fails to converge at tight tolerances
    yield (lambda x: x - 2.0, 2.0, 5.0)


def _outcome(solver, *args, **kwargs):
    """The root, or the error's type and message."""
    try:
        return solver(*args, **kwargs)
    except (ValueError, RuntimeError) as error:
        return type(error), str(error)


@pytest.mark.parametrize(("xtol", "rtol"), [(2e-12, 4 * np.finfo(float).eps),
                                            (1e-300, 4 * np.finfo(float).eps), (1e-6, 1e-9)])
def test_brent_finds_scipys_roots_bitwise(xtol, rtol):
    for f, a, b in _cases():
        assert _outcome(brentq, f, a, b, xtol=xtol, rtol=rtol) == _outcome(
            scipy.optimize.brentq, f, a, b, xtol=xtol, rtol=rtol)


def test_brent_refuses_as_scipy_does():
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1, -1.0, 1.0)
    with pytest.raises(ValueError, match="NaN"):
        brentq(lambda x: math.nan if x > 0.5 else -1.0, 0.0, 1.0)


def test_frequencies_are_those_of_scipys_brent(monkeypatch):
    """Cantilever and clamped-pinned roots, the tied contact frequencies over random beams and
    against a stop: bitwise unchanged."""
    rng = np.random.default_rng(5)
    params = [Params(contact_law="tied")] + [
        Params(contact_law="tied", l1=rng.uniform(0.05, 0.2), l2=rng.uniform(0.05, 0.2),
               EI2=rng.uniform(0.1, 2.0)) for _ in range(10)]
    params.append(Params(contact_law="tied", counterpart="stop"))

    def roots():
        return [modes.cantilever_roots(30), modes.pinned_roots(30),
                *(modes.contact_frequencies(p, 12) for p in params)]

    ours = roots()
    monkeypatch.setattr(modes, "brentq", scipy.optimize.brentq)
    scipys = roots()
    for a, b in zip(ours, scipys, strict=True):
        assert np.array_equal(a, b)


# --- the CLI's writer against xarray's ---

@pytest.mark.parametrize("kind", KINDS)
def test_the_cli_writer_writes_what_xarray_writes(kind, tmp_path):
    """``write_sweep`` (the CLI's path, netCDF4 only) and ``run_sweep`` + xarray's writer: the
    same variables, coordinates, dtypes, attributes and bytes, every kind of map."""
    (tmp_path / "sweep.toml").write_text(KINDS[kind])
    sweep = load_sweep(tmp_path / "sweep.toml")
    write_sweep(sweep, tmp_path / "direct.nc")
    write_netcdf(run_sweep(sweep), tmp_path / "xarray.nc")
    assert_same_map(tmp_path / "direct.nc", tmp_path / "xarray.nc")


# --- kernels loaded from the cache without Numba's compile registries (the CLI's own process) ---

LEAN_RUN = """
import json, sys
from impactbeams.cached_kernels import load_cached_kernels_lean
from impactbeams.sweep import write_sweep
load_cached_kernels_lean()
write_sweep("sweep.toml", "lean.nc")
loaded = {name: name in sys.modules for name in ("numba.np.random.generator_methods",
                                               "numba.typed.typeddict", "scipy.linalg")}
import numba, numpy as np  # a compile after a lean load refreshes Numba's context itself
total = numba.njit(lambda x: np.sum(np.sort(x)) + x.size)(np.arange(4.0))
print(json.dumps({"loaded": loaded, "total": total}))
"""


@pytest.mark.fast_path
@pytest.mark.parametrize("kind", ["first-impact", "dynamics"])
def test_lean_loading_gives_numbas_results(kind, tmp_path):
    """A sweep whose kernels load lean (after this process has cached them) writes the map
    Numba's own loading writes, bit for bit; the registries and scipy.linalg stay unloaded,
    and a later compile in that process works."""
    # fewer cells than test_resume's (the same kernels: both laws in the dynamics)
    (tmp_path / "sweep.toml").write_text(KINDS[kind].replace("num = 20", "num = 4"))
    write_sweep(tmp_path / "sweep.toml", tmp_path / "numba.nc")  # compiles or loads: cached
    result = subprocess.run([sys.executable, "-c", LEAN_RUN], check=True, capture_output=True,
                            text=True, cwd=tmp_path)
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report == {"loaded": {"numba.np.random.generator_methods": False,
                                 "numba.typed.typeddict": False,
                                 # the spring law's contact modes are SciPy's (contact.spring)
                                 "scipy.linalg": kind == "dynamics"},
                      "total": 10.0}
    assert_same_map(tmp_path / "lean.nc", tmp_path / "numba.nc")
