"""A run compiles only the kernels it needs, each once (issue 24: the first run's compile).

The fast checks read the kernels' call graph from their source (a kernel calls another through
a name its module imports, which Numba resolves when it compiles); the slow one runs a first
map in a fresh process with an empty Numba cache and lists what Numba reports compiling.
"""

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

KERNELS = Path(__file__).parents[1] / "src" / "impactbeams" / "kernels"
# the kernels of the full dynamics and what only they use: a first-impact map needs none
DYNAMICS_ONLY = {"dynamics", "contact", "contact_spring", "contact_tied", "reductions",
                 "observables", "stroboscope", "lyapunov", "tangent", "cells"}
FIRST_IMPACT_ENTRIES = {("first_impact", "first_impact_map_parallel"),
                        ("first_impact", "first_impact_map_serial"),
                        ("first_impact", "first_impact_cells")}


def _module_graph(module: str) -> dict[tuple[str, str], set[tuple[str, str]]]:
    """Each function of a kernels module -> the (module, name) it calls, names resolved."""
    tree = ast.parse((KERNELS / f"{module}.py").read_text())
    names: dict[str, tuple[str, str]] = {}  # a local name -> (module, name)
    modules: dict[str, str] = {}  # a local name -> a kernels module
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.module == "impactbeams.kernels":
            modules.update((alias.asname or alias.name, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                "impactbeams.kernels."):
            source = node.module.rsplit(".", 1)[1]
            names.update((alias.asname or alias.name, (source, alias.name))
                         for alias in node.names)
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = (module, node.name)
    graph = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            graph[(module, node.name)] = {
                callee for call in ast.walk(node) if isinstance(call, ast.Call)
                for callee in [_callee(call.func, names, modules)] if callee}
        elif isinstance(node, ast.Assign) and isinstance(node.value, ast.Call):
            # ``parallel, serial = parallel_kernel(function)``: each target compiles function
            wrapped = {_callee(argument, names, modules) for argument in node.value.args} - {None}
            for target in ast.walk(node):
                if isinstance(target, ast.Name) and isinstance(target.ctx, ast.Store):
                    graph[(module, target.id)] = wrapped
    return graph


def _callee(function: ast.expr, names: dict, modules: dict) -> tuple[str, str] | None:
    if isinstance(function, ast.Name):
        return names.get(function.id)
    if isinstance(function, ast.Attribute) and isinstance(function.value, ast.Name):
        module = modules.get(function.value.id)
        return (module, function.attr) if module else None
    return None


def call_graph() -> dict[tuple[str, str], set[tuple[str, str]]]:
    """Every kernel module's functions and what each calls."""
    graph = {}
    for path in sorted(KERNELS.glob("*.py")):
        graph.update(_module_graph(path.stem))
    return graph


def reachable(graph: dict, entries: set) -> set[tuple[str, str]]:
    """The functions compiled with ``entries``: everything they call, transitively."""
    seen, todo = set(), list(entries)
    while todo:
        function = todo.pop()
        if function not in seen:
            seen.add(function)
            todo.extend(graph.get(function, ()))
    return seen


def test_the_call_graph_reads_the_kernels_calls():
    """The graph knows a few calls of each form (a name, a module's attribute, a twin)."""
    graph = call_graph()
    assert ("events", "walk") in graph[("events", "search_root")]
    assert ("contact", "switch_state") in graph[("dynamics", "run_events")]
    assert graph[("first_impact", "first_impact_map_serial")] == {
        ("first_impact", "_first_impact_map")}
    assert ("dynamics", "run_events") in reachable(graph, {("observables",
                                                             "observables_map_parallel")})


def test_a_first_impact_map_compiles_no_dynamics_kernel():
    compiled = reachable(call_graph(), FIRST_IMPACT_ENTRIES)
    assert {module for module, _ in compiled} & DYNAMICS_ONLY == set()


COLD_MAP = """
import json, sys
from numba.core import event
from impactbeams.sweep import run_sweep
with event.install_recorder("numba:compile") as recorder:
    run_sweep(sys.argv[1], threads=2)
from impactbeams.compilation import kernels_cached
print(json.dumps([(e.data["dispatcher"].py_func.__module__, e.data["dispatcher"].__name__)
                  for _, e in recorder.buffer if e.is_start] + [kernels_cached("first_impact")]))
"""


@pytest.mark.fast_path
@pytest.mark.slow
def test_a_cold_first_map_compiles_each_kernel_once_and_no_dynamics(tmp_path):
    """A 100-cell map with an empty cache (about 20 s of compile on 2 cores), then cached."""
    sweep = tmp_path / "map.toml"
    sweep.write_text("t_max = 1.0\nn_modes = 5\n[params]\nclearance = 1.1e-5\n[axes.omega]\n"
                     "min = 10.0\nmax = 400.0\nnum = 10\n[axes.force_amplitude]\nmin = 1e-6\n"
                     "max = 1e-3\nnum = 10\nscale = \"log\"\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, "-c", COLD_MAP, str(sweep)], env=env, check=True,
                            capture_output=True, text=True)
    *pairs, cached = json.loads(result.stdout.splitlines()[-1])
    assert cached, "the next run would announce a compile"
    compiled = [tuple(pair) for pair in pairs]
    ours = [(module.rsplit(".", 1)[1], name) for module, name in compiled
            if module.startswith("impactbeams.kernels.")]
    assert {module for module, _ in ours} & DYNAMICS_ONLY == set()
    assert len(ours) == len(set(ours)), "a kernel compiled twice (two signatures)"
    if (os.cpu_count() or 1) >= 2:  # handed over by the helper (a stale LINK_JOBS signature
        assert ("events", "walk") not in ours  # would compile it here as well)
    # 100 cells are one block of work: the serial twin, not the parallel one
    assert ("first_impact", "_first_impact_map_serial") in ours
    assert ("first_impact", "_first_impact_map") not in ours
    assert set(ours) <= reachable(call_graph(), FIRST_IMPACT_ENTRIES) | {
        ("first_impact", "_first_impact_map_serial")}


LINKED = """
import json, sys
from pathlib import Path
from impactbeams.kernels.jit import kernel

@kernel
def twice(x):
    if x < 0.0:
        print("negative:", x)  # calls Python: reads the kernel's Environment
    return 2.0 * x

@kernel
def caller(x):
    return twice(x) + 1.0

def cached(name):  # a kernel's cache index in NUMBA_CACHE_DIR
    return any(Path(sys.argv[1]).rglob(f"*.{name}-*.nbi"))

result = [caller(1.5), callable(next(iter(twice.overloads.values())).entry_point),
          cached("caller"), cached("twice")]
result += [twice(1.5), callable(next(iter(twice.overloads.values())).entry_point),
           cached("twice"), caller(-0.5)]
print(json.dumps(result))
"""


@pytest.mark.fast_path
def test_a_kernel_called_by_a_kernel_is_only_linked_until_python_calls_it(tmp_path):
    """``kernels/linking.py``: a callee gets no machine code or cache entry of its own; a call
    from Python then compiles it in full (callable, cached) with the same result. A linked
    kernel calling Python (``print``) finds its Environment (it hung without it)."""
    script = tmp_path / "linked.py"
    script.write_text(LINKED)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, str(script), str(tmp_path / "cache")], env=env,
                            check=True, capture_output=True, text=True, timeout=300)
    printed, values = result.stdout.splitlines()
    assert printed == "negative: -0.5"
    assert json.loads(values) == [4.0, False, True, False, 3.0, True, True, 0.0]


BORROWED = """
import json
import numpy as np
from impactbeams.kernels.jit import borrowing_kernel, kernel

@borrowing_kernel
def norm(x):  # borrows x: no reference counts
    return abs(x[0]) + abs(x[1])

@borrowing_kernel
def lent(x):  # would hand its caller a reference it never took
    return x, 1.0

@kernel
def caller(x):
    return norm(x) + lent(x)[1]

try:
    caller(np.array([3.0, -4.0]))
    print(json.dumps(None))
except TypeError as error:
    print(json.dumps(str(error)))
"""


@pytest.mark.fast_path
def test_a_borrowing_kernel_returns_no_array(tmp_path):
    """``kernels/linking.py``: a kernel compiled without reference counts that returned an array
    would leave its caller releasing a reference it never got: refused when it compiles."""
    script = tmp_path / "borrowed.py"  # a file: Numba caches only kernels defined in one
    script.write_text(BORROWED)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, str(script)], env=env, check=True,
                            capture_output=True, text=True, timeout=300)
    assert "lent borrows its arrays and cannot return one" in json.loads(result.stdout)


CALLED = """
import json, warnings
from impactbeams import Params, simulate
from impactbeams.compilation import AHEAD_JOBS, HELPER_JOBS, _kernel, signature_text
from impactbeams.kernels.linking import _LinkedEntry

warnings.simplefilter("ignore")
simulate(Params(), 0.01, n_modes=3)
print(json.dumps({f"{module}.{name}": [
    signature_text(args) for args, compiled in _kernel(module, name).overloads.items()
    if not isinstance(compiled.entry_point, _LinkedEntry)]
    for module, name, _ in HELPER_JOBS["simulate"] + AHEAD_JOBS["simulate"]}))
"""


@pytest.mark.fast_path
def test_the_compile_plan_has_the_signatures_a_run_calls():
    """``compilation``'s jobs name kernels that a simulate calls from Python, with the
    argument types it calls them with (a stale job would compile in vain): a run without the
    helper (its own process, so that no job compiled ahead counts) calls each."""
    from impactbeams.compilation import AHEAD_JOBS, HELPER_JOBS

    env = {**os.environ, "IMPACTBEAMS_COMPILE_HELPER": "0"}
    result = subprocess.run([sys.executable, "-c", CALLED], env=env, check=True,
                            capture_output=True, text=True, timeout=600)
    called = json.loads(result.stdout.splitlines()[-1])
    for module, name, text in HELPER_JOBS["simulate"] + AHEAD_JOBS["simulate"]:
        assert text in called[f"{module}.{name}"], \
            f"{module}.{name}: the run called it with {called[f'{module}.{name}']}"


LINKED_BY_A_MAP = """
import json, sys
from impactbeams.compilation import LINK_JOBS, _kernel, signature_text
from impactbeams.sweep import run_sweep

run_sweep(sys.argv[1])
print(json.dumps({f"{module}.{name}": [signature_text(args) for args in
                                       _kernel(module, name).overloads]
                  for module, name, _ in LINK_JOBS["first_impact"]}))
"""


@pytest.mark.fast_path
def test_the_link_jobs_have_the_signatures_a_map_links(tmp_path):
    """``compilation.LINK_JOBS``: a cold first map without the helper (an empty cache: linked
    kernels are compiled anew in each process) links each job's kernel with its signature."""
    from impactbeams.compilation import LINK_JOBS

    sweep = tmp_path / "map.toml"
    sweep.write_text("t_max = 0.1\nn_modes = 2\n[axes.omega]\nmin = 10.0\nmax = 400.0\n"
                     "num = 2\n[axes.force_amplitude]\nmin = 1e-6\nmax = 1e-3\nnum = 2\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "IMPACTBEAMS_COMPILE_HELPER": "0"}
    result = subprocess.run([sys.executable, "-c", LINKED_BY_A_MAP, str(sweep)], env=env,
                            check=True, capture_output=True, text=True, timeout=600)
    linked = json.loads(result.stdout.splitlines()[-1])
    for module, name, text in LINK_JOBS["first_impact"]:
        assert text in linked[f"{module}.{name}"], \
            f"{module}.{name}: the map linked it with {linked[f'{module}.{name}']}"


SPLIT = """
import sys
from numba.core import event
from impactbeams import compilation
from impactbeams.kernels.records import segments

compilation.kernels_cached = lambda *arguments: False  # this process's cache is empty
compilation.HELPER_JOBS["test"] = (("records", "segments", "int64, int64"),)
if sys.argv[1] == "fails":
    compilation._helper_command = lambda: [sys.executable, "-c", "import sys; sys.exit(3)"]
compilation.compile_in_two_processes("test", stream=sys.stdout)
with event.install_recorder("numba:compile") as recorder:
    arrays = segments(4, 3)
helper = compilation._helpers["test"]
helper.wait()
print(arrays.q.shape, len(recorder.buffer) > 0, helper.returncode)
"""


@pytest.mark.fast_path
@pytest.mark.parametrize("helper", ["compiles", "fails"])
def test_a_helper_process_compiles_a_kernel_or_leaves_it_to_the_run(tmp_path, helper):
    """With a helper, the run loads the kernel from the cache the helper wrote (no compile
    of its own); when the helper fails, the run says so and compiles it itself."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, "-c", SPLIT, helper], env=env, check=True,
                            capture_output=True, text=True, timeout=300)
    lines = result.stdout.splitlines()
    if helper == "compiles":
        assert lines == ["(4, 3) False 0"]
    else:
        assert lines == ["impactbeams: the compile helper process did not compile segments "
                         "(exit 3): compiling it here", "(4, 3) True 3"]


HANDOVER = """
import sys
import numpy as np
from numba.core import event
from impactbeams import compilation
from impactbeams.kernels.drive import modal_acceleration_at

compilation.kernels_cached = lambda *arguments: False  # this process's cache is empty
compilation.LINK_JOBS["test"] = (("drive", "compiled_modal_acceleration",
                                  "complex128[::1], float64[::1], float64[::1], float64[::1], "
                                  "float64[::1], float64, float64"),)
if sys.argv[1] == "fails":
    compilation._helper_command = lambda: [sys.executable, "-c", "import sys; sys.exit(3)"]
compilation.compile_in_two_processes("test", stream=sys.stdout)
modes = np.linspace(1.0, 2.0, 3)
with event.install_recorder("numba:compile") as recorder:
    acceleration = modal_acceleration_at(modes * (1 + 2j), modes * 30.0, modes * 0.01, modes,
                                         -modes, 20.0, 0.3)
compiled = {e.data["dispatcher"].py_func.__name__ for _, e in recorder.buffer}
print(acceleration.tobytes().hex(), "modal_acceleration" in compiled,
      compilation._helpers["test"].wait())
"""


@pytest.mark.fast_path
def test_a_helper_hands_over_a_compile_to_link_with_the_same_results(tmp_path):
    """A link job: the helper compiles a kernel that kernels call and hands it over; the run
    links it into its caller without compiling it, with the results, bit for bit, of the run
    that compiles it itself (the helper failed)."""
    outputs = {}
    for helper in ("links", "fails"):
        env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / helper)}
        result = subprocess.run([sys.executable, "-c", HANDOVER, helper], env=env, check=True,
                                capture_output=True, text=True, timeout=300)
        outputs[helper] = result.stdout.splitlines()[-1].split()
    assert outputs["links"][1:] == ["False", "0"]
    assert outputs["fails"][1:] == ["True", "3"]
    assert outputs["links"][0] == outputs["fails"][0]


COLD_SIMULATE = """
import sys
import numpy as np
from impactbeams import Params, compilation, simulate
dataset = simulate(Params(), 0.01, n_modes=3)
np.savez(sys.argv[1], **{name: dataset[name].values for name in dataset.data_vars})
print("simulate" in compilation._helpers)
"""


@pytest.mark.fast_path
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:n_modes = 3 does not resolve")
def test_a_cold_simulate_in_two_processes_is_bitwise_the_warm_one(tmp_path):
    """A simulate with an empty cache (about 15 s of compile on 2 cores, half of it in the
    helper process) gives the arrays of a run with the kernels cached, bit for bit."""
    from impactbeams import Params, simulate

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, "-c", COLD_SIMULATE, str(tmp_path / "cold.npz")],
                            env=env, check=True, capture_output=True, text=True, timeout=600)
    assert result.stdout.split() == ["True"], "the cold run had no helper"
    warm = simulate(Params(), 0.01, n_modes=3)
    with np.load(tmp_path / "cold.npz") as cold:
        assert set(cold.files) == set(warm.data_vars)
        for name in cold.files:
            assert np.array_equal(cold[name], warm[name].values, equal_nan=True), name
