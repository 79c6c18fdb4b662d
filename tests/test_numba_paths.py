"""The two ways kernels compile (``kernels/jit.py``): the fast path through Numba's internals,
and plain ``numba.njit`` kernels, asked for or taken when an internal is missing.

Each case runs in a fresh process: the path is chosen once per process, when the first kernel
is made.
"""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from impactbeams.kernels import jit
from test_resume import assert_same_map

ROOT = Path(__file__).resolve().parents[1]
# the kernel modules, imported to make every kernel; prints what the child saw as JSON
_CHILD = """
import json, sys, warnings
{before}
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import pkgutil, importlib
    import numba.core.registry
    import impactbeams.kernels as package
    from impactbeams.kernels import jit
    modules = [importlib.import_module(f"impactbeams.kernels.{{info.name}}")
               for info in pkgutil.iter_modules(package.__path__) if info.name != "linking"]
    kernels = [value for module in modules for value in vars(module).values()
               if isinstance(value, numba.core.registry.CPUDispatcher)]
    from impactbeams.kernels.drive import modal_acceleration_at
    import numpy as np
    modes = np.linspace(1.0, 2.0, 3)
    result = modal_acceleration_at(modes * (1 + 2j), modes * 30.0, modes * 0.01, modes,
                                   -modes, 40.0, 0.3).tolist()
{after}
print(json.dumps({{
    "plain": jit.plain_numba(), "linking": "impactbeams.kernels.linking" in sys.modules,
    "kernels": len(kernels),
    "linked": sum(type(k).__module__ == "impactbeams.kernels.linking" for k in kernels),
    "private_options": sorted({{name for k in kernels for name in k.targetoptions
                               if name.startswith("_")}}),
    "unnamed_apart": [k.py_func.__qualname__ for k in kernels
                      if not k.py_func.__qualname__.endswith("_plain")],
    "warnings": [str(w.message) for w in caught], "result": result, **extra}}))
"""


def _child(before: str = "", after: str = "", env: dict | None = None) -> dict:
    code = _CHILD.format(before=before, after=after or "extra = {}")
    environment = {key: value for key, value in os.environ.items() if key != jit.PLAIN_NUMBA}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={**environment, **(env or {})}, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_the_fast_path_is_taken_on_the_tested_numba():
    seen = _child()
    assert not seen["plain"] and seen["linking"] and not seen["warnings"]
    assert seen["linked"] > 100  # every kernel but the inlined ones and the twins' wrappers
    assert "_nrt" in seen["private_options"]


# a Numba without one of the fast path's internals: deleted before the first kernel is made
# (Numba uses it only to load some cache entries: the child's cache is empty)
_MISSING = """
import llvmlite.binding
del llvmlite.binding.parse_bitcode
"""


def test_a_missing_internal_takes_the_plain_path_with_one_warning(tmp_path):
    fast, seen = _child(), _child(before=_MISSING, env={"NUMBA_CACHE_DIR": str(tmp_path)})
    assert seen["plain"] and not seen["linking"]
    assert seen["warnings"] == [
        f"{jit.FALLBACK} (slower to compile and to run, the same results): Numba "
        f"{_numba_version()} has no llvmlite.binding.parse_bitcode, which its fast path uses"]
    assert seen["linked"] == 0 and seen["private_options"] == [] and not seen["unnamed_apart"]
    assert seen["kernels"] == fast["kernels"] and seen["result"] == fast["result"]


def test_every_internal_listed_is_found_on_the_tested_numba():
    """No name on the list is misspelt: the fast path is taken because each one is found."""
    assert [name for name in jit.FAST_PATH_INTERNALS if not jit._present(name)] == []
    assert jit._fast_path_missing(check_version=True) is None


# Numba's private names the fast path's modules use that the list need not name: a namedtuple's
# public ``_replace``; a code library's ``_final_module`` and ``_finalized``, which linking.py
# sets itself (as Numba's ``finalize`` does)
_UNLISTED = {"_replace", "_final_module", "_finalized"}
FAST_PATH_MODULES = [ROOT / "src" / "impactbeams" / "kernels" / "linking.py",
                     ROOT / "src" / "impactbeams" / "cached_kernels.py"]


@pytest.mark.parametrize("path", FAST_PATH_MODULES, ids=lambda path: path.name)
def test_the_list_names_every_internal_the_fast_path_uses(path):
    """Each name imported from ``numba.core``'s modules, and each private attribute of Numba's
    objects read or set, in the fast path's modules is on `jit.FAST_PATH_INTERNALS`."""
    import ast

    tree = ast.parse(path.read_text())
    own = {node.name for node in ast.walk(tree)
           if isinstance(node, ast.FunctionDef | ast.ClassDef)}
    own |= {target.id for node in ast.walk(tree) if isinstance(node, ast.Assign)
            for target in node.targets if isinstance(target, ast.Name)}
    private = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
               and node.attr.startswith("_") and not node.attr.startswith("__")}
    listed = {part for name in jit.FAST_PATH_INTERNALS for part in name.split(".")}
    assert private - own - _UNLISTED - listed == set()
    imported = {f"{node.module}.{alias.name}" for node in ast.walk(tree)
                if isinstance(node, ast.ImportFrom) and node.module.startswith("numba.core.")
                for alias in node.names}
    assert {name for name in imported if name != "numba.core.types"
            and not any(entry.startswith(name) for entry in jit.FAST_PATH_INTERNALS)} == set()


def test_the_dependency_starts_at_the_tested_numba():
    """pyproject.toml's lower bound is the series the fast path is tested with; no upper bound
    (a later Numba takes the plain path)."""
    text = (ROOT / "pyproject.toml").read_text()
    assert re.findall(r'"numba[^"]*"', text) == [f'"numba>={jit.TESTED_NUMBA}"']


def _numba_version() -> str:
    import numba

    return numba.__version__


_NEWER = "import numba\nnumba.__version__ = '0.69.0'\n"


@pytest.mark.parametrize("setting", ["", "0"])
def test_an_untested_numba_takes_the_plain_path_unless_told(setting):
    seen = _child(before=_NEWER, env={jit.PLAIN_NUMBA: setting} if setting else None)
    if setting == "0":  # a maintainer trying the fast path on a newer Numba
        assert not seen["plain"] and seen["linked"] > 100 and not seen["warnings"]
    else:
        assert seen["plain"] and seen["linked"] == 0
        assert seen["warnings"] == [
            f"{jit.FALLBACK} (slower to compile and to run, the same results): its fast path is "
            f"tested with Numba {jit.TESTED_NUMBA} only, this is 0.69.0 "
            f"({jit.PLAIN_NUMBA}=0 tries it)"]


def test_the_warning_fails_no_test():
    """The suite on an untested Numba: the warning (``filterwarnings = error`` but for it) is shown,
    the tests run, on the plain path."""
    code = (_NEWER + "import sys, pytest\nsys.exit(pytest.main(['-q', '-p', 'no:cacheprovider', "
            "'tests/test_numba_paths.py::test_the_dependency_starts_at_the_"
            "tested_numba']))")
    environment = {key: value for key, value in os.environ.items() if key != jit.PLAIN_NUMBA}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env=environment, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 passed, 1 warning" in done.stdout and jit.FALLBACK in done.stdout


# what the plain path leaves out around the kernels: the helper process, the lean loading
_AROUND = """
from impactbeams import compilation
from impactbeams.cached_kernels import load_cached_kernels_lean
from numba.core import caching
load_cached_kernels_lean()
compilation.AHEAD_JOBS.clear()  # this process's share of a cold compile: not needed here
compilation.compile_in_two_processes("simulate")
extra = {"helpers": len(compilation._helpers),
         "lean": getattr(caching.Cache.load_overload, "lean", False)}
"""


def test_asked_for_the_plain_path_makes_plain_kernels_without_a_warning(tmp_path):
    """``IMPACTBEAMS_PLAIN_NUMBA=1``: public options only, no helper, Numba's own loading."""
    env = {jit.PLAIN_NUMBA: "1", "NUMBA_CACHE_DIR": str(tmp_path)}  # a cold simulate
    seen = _child(after=_AROUND, env=env)
    assert seen["plain"] and not seen["linking"] and not seen["warnings"]
    assert seen["linked"] == 0 and seen["private_options"] == [] and not seen["unnamed_apart"]
    assert seen["helpers"] == 0 and not seen["lean"]
    fast = _child(after=_AROUND, env={"NUMBA_CACHE_DIR": str(tmp_path / "fast")})
    assert fast["helpers"] == 1 and fast["lean"]  # what the plain path leaves out


def test_the_function_asks_for_the_plain_path_before_kernels_are_made():
    seen = _child(before="from impactbeams.kernels import jit\njit.use_plain_numba()",
                  after="import os\nextra = {'env': os.environ.get('IMPACTBEAMS_PLAIN_NUMBA')}")
    assert seen["plain"] and seen["linked"] == 0 and seen["env"] == "1"
    late = _child(after="try:\n    jit.use_plain_numba()\n    extra = {'late': 'taken'}\n"
                        "except RuntimeError as error:\n    extra = {'late': str(error)}")
    assert late["late"].startswith("use_plain_numba: kernels are already made on the fast path")


def test_a_bad_setting_is_refused_in_one_line():
    done = subprocess.run([sys.executable, "-c", "import impactbeams.kernels.events"],
                          capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, jit.PLAIN_NUMBA: "yes"})
    assert done.returncode != 0
    assert ("ValueError: IMPACTBEAMS_PLAIN_NUMBA = 'yes': allowed are 1 (plain Numba kernels), "
            "0 (the fast path, on any Numba that has its internals) or unset") in done.stderr


# --- the same results on both paths: the benchmark maps at a reduced size, a simulate run -----

MAPS = sorted((ROOT / "benchmarks" / "maps").glob("*.toml"))
REDUCED = 24  # cells along each axis of a benchmark map (400 as shipped)


def _reduced(path: Path, folder: Path) -> Path:
    out = folder / path.name
    out.write_text(re.sub(r"(?m)^num = \d+$", f"num = {REDUCED}", path.read_text()))
    return out


def _run(argv: list[str], plain: bool) -> None:
    env = {key: value for key, value in os.environ.items() if key != jit.PLAIN_NUMBA}
    if plain:
        env[jit.PLAIN_NUMBA] = "1"
    code = "import sys\nfrom impactbeams.cli import main\nsys.exit(main(sys.argv[1:]))"
    done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True,
                          env=env, cwd=ROOT)
    assert done.returncode == 0, done.stderr


SIMULATE = ["simulate", "--t-max", "0.05", "--fields"]


@pytest.mark.slow
def test_both_paths_give_the_same_maps_and_runs_bitwise(tmp_path):
    """Every benchmark map at 24 x 24 cells and a simulate of each contact law, in a process
    of each path: the same bytes (cold plain compiles, some 3 min on 2 cores)."""
    runs = [[*SIMULATE, "--contact-law", law] for law in ("tied", "spring")]
    for index, (path, argv) in enumerate([*((p, ["run", str(_reduced(p, tmp_path))])
                                            for p in MAPS),
                                          *((None, argv) for argv in runs)]):
        outputs = {plain: tmp_path / f"{index}-{'plain' if plain else 'fast'}.nc"
                   for plain in (False, True)}
        for plain, out in outputs.items():
            _run([*argv, "-o", str(out)] + (["--quiet"] if path else []), plain)
        assert_same_map(outputs[True], outputs[False])
