"""What the README and the docs say is what the code does (issue 32).

Each test pins a claim a new user could check and found false: the docs' home page behind the
README, a count of subcommands typed by hand, a contact-law axis said to be refused and then
used, parameters missing from the model page's table, a sweep file's comments about its own
map, "results converge" said of a chaotic rattle, and the tests the accuracy table cites.
"""

import argparse
import ast
import dataclasses
import functools
import re
from pathlib import Path

import numpy as np

import impactbeams as ib
from impactbeams.modes import cantilever_roots
from impactbeams.sweep.definition import _AXIS_KEYS, sweep_from_mapping

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
DOCS = ROOT / "docs"
TESTS = ROOT / "tests"


def _features(text: str) -> str:
    """The bulleted feature list that opens a page, links made relative to docs/."""
    start = text.index("- **Two contact laws.**")
    return text[start:text.index("\n\n", start)].replace("](docs/", "](")


def test_the_docs_home_page_lists_the_readmes_features():
    assert _features((DOCS / "index.md").read_text()) == _features(README)
    for feature in ("counterpart = \"stop\"", "base_amplitude", "Periodic orbits",
                    "continuation"):
        assert feature in _features(README)
    assert "one modal response" not in (DOCS / "index.md").read_text()


def test_the_command_line_page_counts_its_subcommands_right():
    from impactbeams.cli import build_parser

    commands = next(action for action in build_parser()._actions
                    if isinstance(action, argparse._SubParsersAction)).choices
    words = {"one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7,
             "eight": 8, "nine": 9}
    for count in re.findall(rf"\b({'|'.join(words)}|\d+) subcommands",
                            (DOCS / "cli.md").read_text()):
        assert (words.get(count) or int(count)) == len(commands), count


def test_no_page_says_the_spring_law_converges_without_saying_what():
    # its first contacts and episodes' totals converge in n_modes; the trace after the first
    # rattle does not: the motion is chaotic (docs/lyapunov.md, docs/modal_convergence.md)
    pages = [ROOT / "README.md", *DOCS.rglob("*.md"),
             ROOT / "src" / "impactbeams" / "variables.py"]
    unqualified = re.compile(r"results converge|[Ii]t converges in `n_modes`|"
                             r"\(the default\): converges\.|compliant, converges in|"
                             r"the default; converges in")
    found = [f"{page.relative_to(ROOT)}: {match[0]}" for page in pages
             for match in unqualified.finditer(page.read_text())]
    assert not found


def test_the_sweep_files_page_documents_every_axis_key_and_the_law_axis():
    page = (DOCS / "sweep-files.md").read_text()
    for key in (*_AXIS_KEYS, "values"):
        assert f"| `{key}` |" in page, key
    assert "not `contact_law`" not in page
    law_axis = sweep_from_mapping({"t_max": 0.01, "n_modes": 3, "observables": ["impact_count"],
                                   "axes": {"contact_law": {"values": ["tied", "spring"]}}})
    assert law_axis.shape == (2,)


def test_the_model_page_lists_every_parameter():
    section = (DOCS / "model.md").read_text().split("## Parameters", 1)[1]
    table = section[section.index("| name"):].split("\n\n", 1)[0]
    missing = [field.name for field in dataclasses.fields(ib.Params)
               if f"`{field.name}`" not in table]
    assert not missing


def test_the_fig5a_sweep_says_where_its_funnel_ends():
    """The comment's smallest impacting force at the resonance, against that column's run."""
    path = ROOT / "sweeps" / "fig5a-omega-force.toml"
    comment = " ".join(line.lstrip("# ") for line in path.read_text().splitlines()
                       if line.startswith("#"))
    assert "hatched" not in comment  # the map draws the no-impact region plain grey
    stated = float(re.search(r"its tip is at F0 = (\S+) N", comment)[1])
    sweep = ib.load_sweep(path)
    omega = sweep.axes[0].values
    params = ib.Params()
    first = (cantilever_roots(1)[0] / params.l1) ** 2 * np.sqrt(params.EI1 / params.rhoA1)
    resonance = omega[np.argmin(np.abs(omega - first))]
    column = sweep_from_mapping({
        "t_max": sweep.t_max, "n_modes": sweep.n_modes, "params": {"clearance": 1.1e-5},
        "axes": {"omega": {"min": resonance, "max": resonance, "num": 1},
                 "force_amplitude": {"min": 1e-6, "max": 1e-3, "num": 1000, "scale": "log"}}})
    impacted = ib.run_sweep(column).impacted.values[0].astype(bool)
    forces = column.axes[1].values
    assert not impacted[0]  # the smallest force of the range
    assert f"{forces[impacted].min():.2g}" == f"{stated:.2g}"


def test_the_newcomer_script_finds_the_readme_job_and_the_three_tasks():
    """CI's newcomer run (scripts/newcomer.py) reads its commands from the README and the page."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("newcomer", ROOT / "scripts" / "newcomer.py")
    newcomer = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(newcomer)
    assert [command.split()[:2] for command in newcomer.readme_commands()] == [
        ["impactbeams", "run"], ["impactbeams", "plot"]]
    tasks = newcomer.task_commands()
    assert {task for task, _, _ in tasks} == set(newcomer.TASKS)
    assert any(code == 2 for _, _, code in tasks)  # the refused input, as the page shows it
    assert any(command.startswith("impactbeams simulate") for _, command, _ in tasks)


def _accuracy_table_rows() -> list[str]:
    """The rows of the README's accuracy table (header and rule left out)."""
    section = README.split("## Accuracy: what is checked, against what", 1)[1]
    table = section[section.index("| claim"):].split("\n\n", 1)[0]
    return table.splitlines()[2:]


@functools.cache
def _test_functions(file: str) -> set[str]:
    """The names of the test functions pytest collects from tests/``file`` (module level and
    in classes); none if there is no such file."""
    path = TESTS / file
    if not path.is_file():
        return set()
    tree = ast.parse(path.read_text())
    bodies = [tree.body, *(node.body for node in tree.body if isinstance(node, ast.ClassDef))]
    return {node.name for body in bodies for node in body
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")}


def test_every_test_the_accuracy_table_cites_exists():
    """Each `file.py::test_name` of the accuracy table, and each `::test_name` after it in the
    same cell (the same file), names a test function of tests/; each `file.py` a file."""
    cited, missing = 0, []
    for row in _accuracy_table_rows():
        for cell in row.strip().strip("|").split(" | "):
            current = None
            for file, name in re.findall(r"`([\w/.]+\.py)?(?:::(\w+))?`", cell):
                if file:
                    current = file
                    if not any(path.is_file() for path in (ROOT / file, TESTS / file)):
                        missing.append(file)
                if name:
                    cited += 1
                    if current is None or name not in _test_functions(Path(current).name):
                        missing.append(f"{current}::{name}")
    assert cited > 40  # the table was parsed
    assert not missing
