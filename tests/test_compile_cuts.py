"""What a kernel must not write, because Numba compiles it at great cost (issue 24).

Measured with ``benchmarks/bench_compile.py``'s per-kernel table (docs/benchmarks/compile.md):

* an array or a tuple assigned to a slice or a row (``out[k, :] = q``, ``stack[0] = a, b``)
  compiles Numba's string formatting for the shape-mismatch message, about 2 s of a cold
  simulate: kernels copy element by element (``contact.copy_state``);
* ``@`` and ``np.dot`` compile NumPy's BLAS bindings, 0.1-0.3 s per signature, and BLAS sums
  in an order that follows its thread count (issue 32): kernels sum in loops;
* ``np.max``/``np.min`` of an array compile ``take_impl`` (0.3 s of a cold first map).

The fast checks read the source; the slow one lists what a cold ``simulate`` compiles.
"""

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

KERNELS = Path(__file__).parents[1] / "src" / "impactbeams" / "kernels"


def _assigned_slices(tree: ast.AST) -> list[int]:
    """Lines assigning a non-constant value to a slice, or a tuple to one subscript."""
    lines = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Assign) or len(node.targets) != 1:
            continue
        target = node.targets[0]
        if not isinstance(target, ast.Subscript):
            continue
        index = target.slice.elts if isinstance(target.slice, ast.Tuple) else [target.slice]
        sliced = any(isinstance(part, ast.Slice) for part in index)
        scalar = _constant(node.value)
        if (sliced and not scalar) or isinstance(node.value, ast.Tuple):
            lines.append(node.lineno)
    return lines


def _constant(value: ast.expr) -> bool:
    """A number, ``-number`` or a constant of ``np``/``math`` (``np.nan``): a scalar fill."""
    if isinstance(value, ast.UnaryOp):
        value = value.operand
    return isinstance(value, ast.Constant) or (
        isinstance(value, ast.Attribute) and isinstance(value.value, ast.Name)
        and value.value.id in ("np", "math"))


def _blas_calls(tree: ast.AST) -> list[tuple[str, int]]:
    """(function, line) of each ``a @ b`` and ``np.dot`` call."""
    found = []
    for function in ast.walk(tree):
        if not isinstance(function, ast.FunctionDef):
            continue
        for node in ast.walk(function):
            if (isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult)) or (
                    isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "dot"):
                found.append((function.name, node.lineno))
    return found


def _array_extrema(tree: ast.AST) -> list[int]:
    """Lines calling ``np.max``/``np.min`` (or ``amax``/``amin``)."""
    return sorted(node.lineno for node in ast.walk(tree) if isinstance(node, ast.Call)
                  and isinstance(node.func, ast.Attribute)
                  and isinstance(node.func.value, ast.Name) and node.func.value.id == "np"
                  and node.func.attr in ("max", "min", "amax", "amin"))


def _tree(path: Path) -> ast.AST:
    return ast.parse(path.read_text(), str(path))


@pytest.mark.parametrize("path", sorted(KERNELS.glob("*.py")), ids=lambda p: p.name)
def test_no_kernel_assigns_an_array_to_a_slice(path):
    lines = _assigned_slices(_tree(path))
    assert not lines, (f"kernels/{path.name}:{lines[0]} assigns an array or a tuple to a "
                       "slice or row: copy element by element (contact.copy_state)")


def test_the_slice_check_sees_slice_and_tuple_assignments():
    code = ("q[:] = q_s\nseg_q[k, :] = q\nstack[0] = a, b, r_a, r_b\nq[:] = record.q\n"
            "samples[:] = np.nan\nlevels[:4] = 0\nx[:2] = -1.0\nout[k, 0], out[k, 1] = a, b\n"
            "q[j] = q_s[j]\n")
    assert sorted(_assigned_slices(ast.parse(code))) == [1, 2, 3, 4]


@pytest.mark.parametrize("path", sorted(KERNELS.glob("*.py")), ids=lambda p: p.name)
def test_kernels_sum_in_loops_not_blas(path):
    calls = _blas_calls(_tree(path))
    assert not calls, f"kernels/{path.name}:{calls[0][1]} ({calls[0][0]}) calls BLAS"


def test_the_blas_check_sees_products():
    code = "def f(a, b):\n    return a @ b\ndef g(a, b):\n    return np.dot(a, b) + a.sum()\n"
    assert _blas_calls(ast.parse(code)) == [("f", 2), ("g", 4)]


@pytest.mark.parametrize("name", ["first_impact.py", "events.py", "rotor.py",
                                  "propagation.py", "drive.py", "forcing.py"])
def test_a_first_impact_map_takes_no_array_extremum(name):
    """The modules a first-impact map compiles (tests/test_compile.py's call graph)."""
    lines = _array_extrema(_tree(KERNELS / name))
    assert not lines, f"kernels/{name}:{lines[0]} calls np.max/np.min: use a loop"


def test_the_extremum_check_sees_np_max():
    assert _array_extrema(ast.parse("f = max(np.max(a), w)\ng = np.min(b)\nh = max(a, b)\n")) == [
        1, 2]


COLD_SIMULATE = """
import json, sys
from numba.core import event
from impactbeams.cli import main
with event.install_recorder("numba:compile") as recorder:
    code = main(["simulate", "--t-max", "0.01", "-o", sys.argv[1]])
print(json.dumps([code] + [[e.data["dispatcher"].py_func.__module__,
                            e.data["dispatcher"].py_func.__qualname__]
                           for _, e in recorder.buffer if e.is_start]))
"""


@pytest.mark.fast_path
@pytest.mark.slow
def test_a_cold_simulate_compiles_no_string_formatting_or_array_extremum(tmp_path):
    """simulate with an empty cache (about 17 s of compile on 2 cores)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, "-c", COLD_SIMULATE, str(tmp_path / "run.nc")],
                            env=env, check=True, capture_output=True, text=True)
    code, *compiled = json.loads(result.stdout.splitlines()[-1])
    assert code == 0
    modules = {module for module, _ in compiled}
    assert "impactbeams.kernels.dynamics" in modules  # it did compile
    assert not {m for m in modules if m.startswith("numba.cpython.unicode")}
    assert ["numba.np.arraymath", "impl_max"] not in compiled
    assert not [pair for pair in compiled if pair[0] == "numba.np.linalg"]  # no BLAS
