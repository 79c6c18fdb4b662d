"""Import contracts, read from the source with ``ast`` (every import, lazy ones included).

The package is layered, every import pointing down: orchestration (``cli``; ``sweep``,
``trajectory``; ``plotting`` from saved Datasets) on top, one packing layer, the physics
(``compliant``, ``model``, ``modes``, ``params``), the registries (``variables``, ``io``),
and the kernels at the ground, which see nothing but NumPy, Numba and the standard library's
``math``.
"""

import ast
from pathlib import Path

import pytest

from impactbeams import configuration

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "impactbeams"

# The floor of each top-level part: a module may import parts on lower floors and its own part.
FLOORS = {
    "kernels": 0,
    "configuration": 0.5,  # the variants' objects: the registry names their notes
    "variables": 1, "io": 1, "brent": 1, "blas": 1, "checks": 1,
    "structure": 1.5,  # the beams' parts and modes: Params composes them
    "params": 2,
    "modes": 3, "longtime": 3, "lock": 3,  # lock: io's writer, one per output
    "contact": 4,
    "model": 5, "compliant": 5,  # old import paths, re-exporting contact
    "drive": 5,
    "packing": 6, "preflight": 6, "costs": 6, "compilation": 6, "cached_kernels": 6,
    "active_phases": 6.5,  # several contacts' runs, packed on each contact's: maps and runs
    "progress": 6,
    "sweep": 7, "trajectory": 7, "plotting": 7,
    "orbits": 8,
    "continuation": 9,
    "cli": 10,
}
# What kernels may import from outside the package: NumPy and Numba, ``math``, and the standard
# library modules jit.py (``types``; ``os``, ``importlib`` and ``warnings`` to choose the fast
# or the plain path), linking.py (``pickle`` and Numba's ``llvmlite`` to hand a compile over
# between processes), __init__.py (``hashlib``, ``pathlib``) and records.py (``collections``:
# namedtuples, which Numba compiles) need.
KERNEL_EXTERNAL = {"numpy", "numba", "llvmlite", "math", "types", "pickle", "hashlib", "pathlib",
                   "collections", "os", "importlib", "warnings"}


def _modules():
    return sorted(p for p in PACKAGE.rglob("*.py"))


def _part(path: Path) -> str:
    """The top-level part of the package a module belongs to (``sweep`` for sweep/run.py)."""
    return path.relative_to(PACKAGE).parts[0].removesuffix(".py")


def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """(module, imported names) of every import statement in ``path``, at any depth."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.extend((alias.name, []) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{path}: relative import"
            found.append((node.module, [alias.name for alias in node.names]))
    return found


def _internal_parts(path: Path) -> list[str]:
    """The package parts ``path`` imports (the root's ``__version__`` is metadata, no part)."""
    parts = []
    for module, names in _imports(path):
        pieces = module.split(".")
        if pieces[0] != "impactbeams":
            continue
        if len(pieces) > 1:
            parts.append(pieces[1])
        else:  # from impactbeams import packing, __version__
            parts.extend(name for name in names if name != "__version__")
    return parts


def test_the_contract_covers_every_part():
    parts = {_part(path) for path in _modules()} - {"__init__"}
    assert parts == set(FLOORS)


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_imports_point_down(path):
    part = _part(path)
    if part == "__init__":  # the root's lazy façade names everything, loads it on demand
        return
    for imported in _internal_parts(path):
        assert imported == part or FLOORS[imported] < FLOORS[part], (
            f"{path.relative_to(PACKAGE)} ({part}, floor {FLOORS[part]}) imports {imported} "
            f"(floor {FLOORS[imported]})")


@pytest.mark.parametrize("path", sorted((PACKAGE / "kernels").glob("*.py")),
                         ids=lambda p: p.name)
def test_kernels_import_only_numpy_numba_math(path):
    for module, _ in _imports(path):
        top = module.split(".")[0]
        if top == "impactbeams":
            assert module.startswith("impactbeams.kernels"), f"{path.name} imports {module}"
        else:
            assert top in KERNEL_EXTERNAL, f"{path.name} imports {module}"


def test_sweep_never_imports_trajectory():
    for path in (PACKAGE / "sweep").glob("*.py"):
        assert "trajectory" not in _internal_parts(path), path.name


def _sweep_imports() -> dict[str, set[str]]:
    """The modules of ``sweep/`` each module there imports, lazily too (``plan``, ``run``)."""
    names = {path.stem for path in (PACKAGE / "sweep").glob("*.py")} - {"__init__"}
    graph = {}
    for name in names:
        imported = set()
        for module, members in _imports(PACKAGE / "sweep" / f"{name}.py"):
            if module == "impactbeams.sweep":
                imported.update(members)
            elif module.startswith("impactbeams.sweep."):
                imported.add(module.split(".")[2])
        graph[name] = imported & names - {name}
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    """A cycle of ``graph`` (a path that comes back to its start), or [] if it has none."""
    done: set[str] = set()

    def walk(node: str, path: list[str]) -> list[str]:
        if node in path:
            return path[path.index(node):] + [node]
        if node in done:
            return []
        for after in sorted(graph[node]):
            found = walk(after, [*path, node])
            if found:
                return found
        done.add(node)
        return []

    return next((found for node in sorted(graph) if (found := walk(node, []))), [])


def test_the_sweep_modules_import_without_a_cycle():
    """A sweep's definition, cost estimate and plan each build on the ones before (issue 33).

    The definition imports neither the plan nor the estimate (once it imported the plan, which
    imports it, for its cost check and geometry count).
    """
    assert _cycle(_sweep_imports()) == []
    assert _cycle({"definition": {"plan"}, "plan": {"definition"}, "estimate": set()}) == [
        "definition", "plan", "definition"]


# The contact seam: only the dispatch module and the laws' own modules name a law's index.
CONTACT_SEAM = {"kernels/contact.py", "kernels/contact_tied.py", "kernels/contact_spring.py",
                "kernels/layout.py"}
LAW_INDICES = {"TIED", "SPRING"}


def _law_uses(tree: ast.AST) -> list[int]:
    """Lines that read a contact law's index (``SPRING``, ``layout.TIED``), imports included."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id in LAW_INDICES and isinstance(node.ctx, ast.Load):
            lines.append(node.lineno)
        elif isinstance(node, ast.Attribute) and node.attr in LAW_INDICES:
            lines.append(node.lineno)
        elif isinstance(node, ast.ImportFrom):
            lines.extend(node.lineno for alias in node.names if alias.name in LAW_INDICES)
    return lines


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_contact_law_branches_only_in_the_contact_seam(path):
    """A branch on the contact law goes through `kernels.contact`'s dispatch (issue 21)."""
    if str(path.relative_to(PACKAGE)) in CONTACT_SEAM:
        return
    lines = _law_uses(ast.parse(path.read_text(), str(path)))
    assert not lines, (f"{path.relative_to(PACKAGE)}:{lines[0]} names a contact law's index: "
                       "dispatch in impactbeams.kernels.contact instead")


def test_the_seam_check_sees_a_law_branch():
    """The check above would fail on the branches the kernels had before the seam."""
    code = ("from impactbeams.kernels.layout import SPRING\n"
            "if settings.contact_law == SPRING:\n    pass\n"
            "spring = geometry[GEO_LAW] != layout.TIED\n")
    assert _law_uses(ast.parse(code)) == [1, 2, 4]


# The configuration's seam (issue 33): a contact law, counterpart or shaker mount is named only
# in its objects' module; elsewhere the code asks the object (``params.law.compliant``).
CONFIGURATION_SEAM = {"configuration.py", "kernels/layout.py"}
CONFIGURATION_NAMES = (set(configuration.LAWS) | set(configuration.COUNTERPARTS)
                       | set(configuration.MOUNTS) | set(configuration.SIDES))
# a name that means something else in a module: a stepped sweep's rows (up, down or "both")
OTHER_MEANING = {("longtime.py", "both")}
CHOICE_KEYWORDS = {"contact_law", "counterpart", "shaker", "contact_side"}


def _names_in(node: ast.AST | None, names: set[str]) -> bool:
    """Whether ``node`` is one of ``names`` as a string, or a tuple, list or set holding one."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str) and node.value in names
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(_names_in(element, names) for element in node.elts)
    return False


def _name_branches(tree: ast.AST, names: set[str]) -> list[int]:
    """Lines that branch on a variant's name: compared (``==``, ``in``), matched, a dict's key,
    a subscript, ``.get``/``.index`` of one, or passed as ``contact_law=``/``counterpart=``/
    ``shaker=``."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            hit = any(_names_in(side, names) for side in (node.left, *node.comparators))
        elif isinstance(node, ast.Dict):
            hit = any(_names_in(key, names) for key in node.keys)
        elif isinstance(node, ast.Subscript):
            hit = _names_in(node.slice, names)
        elif isinstance(node, ast.MatchValue):
            hit = _names_in(node.value, names)
        elif isinstance(node, ast.Call):
            hit = ((isinstance(node.func, ast.Attribute) and node.func.attr in ("get", "index")
                    and any(_names_in(arg, names) for arg in node.args[:1]))
                   or any(k.arg in CHOICE_KEYWORDS and _names_in(k.value, names)
                          for k in node.keywords))
        else:
            continue
        if hit:
            lines.append(node.lineno)
    return sorted(set(lines))


# The variants' objects (``SPRING_LAW``, ``STOP``, ``BOTH``, ...): compared with, or one of their
# attributes compared with (``mount.clamps == BOTH.clamps``, ``side != BELOW.name``), they are a
# branch on a variant as much as its name is: the object's own attribute says it.
VARIANT_OBJECTS = {name for name, value in vars(configuration).items() if isinstance(
    value, configuration.ContactLaw | configuration.Counterpart | configuration.Side
    | configuration.Mount)}


def _is_variant(node: ast.AST, imported: set[str]) -> bool:
    """Whether ``node`` is a variant's object, read from one (``BELOW.name``, ``BOTH.clamps[1]``)
    or a tuple, list or set holding one. ``imported``: the names a module imports them as."""
    if isinstance(node, ast.Name):
        return node.id in imported
    if isinstance(node, ast.Attribute):
        return ((isinstance(node.value, ast.Name) and node.value.id == "configuration"
                 and node.attr in VARIANT_OBJECTS) or _is_variant(node.value, imported))
    if isinstance(node, ast.Subscript):
        return _is_variant(node.value, imported)
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(_is_variant(element, imported) for element in node.elts)
    return False


def _variant_branches(tree: ast.AST) -> list[int]:
    """Lines that compare with a variant's object or its attribute, match one, or key a dict
    by one."""
    imported = {alias.asname or alias.name for node in ast.walk(tree)
                if isinstance(node, ast.ImportFrom) and node.module == "impactbeams.configuration"
                for alias in node.names if alias.name in VARIANT_OBJECTS}
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
        elif isinstance(node, ast.Dict):
            operands = [key for key in node.keys if key is not None]
        elif isinstance(node, ast.MatchValue):
            operands = [node.value]
        else:
            continue
        if any(_is_variant(operand, imported) for operand in operands):
            lines.append(node.lineno)
    return sorted(set(lines))


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_configuration_branches_only_in_its_seam(path):
    """A law, counterpart or shaker is asked through its object, never by its name (issue 33)."""
    where = str(path.relative_to(PACKAGE))
    if where in CONFIGURATION_SEAM:
        return
    names = CONFIGURATION_NAMES - {name for module, name in OTHER_MEANING if module == where}
    tree = ast.parse(path.read_text(), str(path))
    lines = sorted(_name_branches(tree, names) + _variant_branches(tree))
    assert not lines, (f"{where}:{lines[0]} branches on a contact law's, counterpart's or "
                       "shaker's name: ask its object (impactbeams.configuration) instead")


def test_the_configuration_check_sees_the_old_branches():
    """Each form of branch the package had before issue 33 is seen, a table of costs keyed by a
    law's name too (a law holds its own, `ContactLaw.impact_cycle`); names in text are not."""
    code = ('if p.contact_law == "tied":\n    pass\n'
            'beams = 1 if p.counterpart == "stop" else 2\n'
            'WORDS = {("both", "beam"): "on both clamps"}\n'
            'x = CLAMPS["beam1"]\n'
            'law in {"spring"}\n'
            'p.replace(contact_law="spring")\n'
            'CONTACT_LAWS.index("tied")\n'
            'match p.shaker:\n    case "beam2":\n        pass\n'
            'message = "with contact_law = \'tied\' the shaker must carry both clamps"\n'
            'COSTS = {"tied": 1.0}\n')
    assert _name_branches(ast.parse(code), CONFIGURATION_NAMES) == [1, 3, 4, 5, 6, 7, 8, 10, 13]


def test_the_configuration_check_sees_a_variant_object_compared():
    """Comparing with a variant's object or its attribute is seen (the forms issue 33 found left
    in params.py), as is matching one or keying a dict by one; a default argument, a default
    field and a word read from one are not branches."""
    code = ("from impactbeams.configuration import BOTH, BELOW as DOWN, STOP, Mount\n"
            "from impactbeams import configuration\n"
            "ok = mount.clamps == BOTH.clamps\n"
            "given = side not in (None, (), configuration.BELOW.name)\n"
            "if params.partner is STOP:\n    pass\n"
            "first = mount.clamps[0] == BOTH.clamps[0]\n"
            "WORDS = {DOWN: 'below'}\n"
            "match params.mount:\n    case configuration.BEAM1:\n        pass\n"
            "def place(mount: Mount = BOTH, side: str = DOWN.name):\n    return STOP.words\n"
            "moves = params.mount.carries_both_clamps\n")
    assert _variant_branches(ast.parse(code)) == [3, 4, 5, 7, 8, 10]


def _settings_records(tree: ast.AST) -> list[int]:
    """Lines that take the settings record out of its array (``settings_array[0]``)."""
    return [node.lineno for node in ast.walk(tree)
            if isinstance(node, ast.Subscript)
            and isinstance(node.value, ast.Name | ast.Attribute)
            and (node.value.id if isinstance(node.value, ast.Name) else node.value.attr)
            == "settings_array"]


@pytest.mark.parametrize("path", sorted((PACKAGE / "kernels").glob("*.py")),
                         ids=lambda p: p.name)
def test_the_settings_record_is_read_in_one_place(path):
    """Only `kernels.cells.settings_of` reads the record out of a run's settings array.

    The record does not keep its array alive; read anywhere else, in the kernel that built
    the array, Numba may free the array while the record is in use (issue 21).
    """
    if path.name == "cells.py":
        return
    lines = _settings_records(ast.parse(path.read_text(), str(path)))
    assert not lines, f"kernels/{path.name}:{lines[0]} reads settings_array[...]: use settings_of"


def test_the_settings_check_sees_the_old_workaround():
    code = "run_events(settings_array[0])\nrun.settings_array[0].t_max = 1.0\n"
    assert _settings_records(ast.parse(code)) == [1, 2]


def test_the_code_digest_covers_every_module_that_decides_a_number():
    """A sweep reuses chunks only from the same numeric code (`sweep.plan.NUMERIC_CODE`).

    Every package module the packing layer imports, at any depth and lazily too, is hashed,
    except the registry of names and units, which decides no number.
    """
    from impactbeams.sweep.plan import NUMERIC_CODE

    hashed = {path for pattern in NUMERIC_CODE for path in PACKAGE.glob(pattern)}
    reached, todo = set(), [PACKAGE / "packing.py"]
    while todo:
        path = todo.pop()
        if path in reached:
            continue
        reached.add(path)
        for module, _ in _imports(path):
            if module.startswith("impactbeams."):
                target = PACKAGE.joinpath(*module.split(".")[1:])
                todo += [p for p in (target.with_suffix(".py"), target / "__init__.py")
                         if p.exists()]
    assert reached - hashed <= {PACKAGE / "variables.py"}, sorted(
        str(p.relative_to(PACKAGE)) for p in reached - hashed)


# The array fields of the event searches' records (`kernels.records`): read in place only.
RECORD_ARRAYS = {"oscillators": {"frequencies", "zeta", "force"}, "event": {"weights"}}


def _bound_record_arrays(tree: ast.AST) -> list[int]:
    """Lines that bind an array field of a record to a name (``zeta = oscillators.zeta``)."""
    lines = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Assign):
            continue
        values = node.value.elts if isinstance(node.value, ast.Tuple) else [node.value]
        lines.extend(node.lineno for value in values
                     if isinstance(value, ast.Attribute) and isinstance(value.value, ast.Name)
                     and value.attr in RECORD_ARRAYS.get(value.value.id, ()))
    return lines


@pytest.mark.parametrize("path", sorted((PACKAGE / "kernels").glob("*.py")),
                         ids=lambda p: p.name)
def test_record_arrays_are_read_in_place(path):
    """No kernel binds an `Oscillators`/`EventFunction` array field to a local name.

    Numba keeps an atomic incref/decref pair for every array variable that lives across a
    call: bound fields slowed the Fig. 5a columns by 4-26% (docs/architecture.md, issue 21).
    """
    lines = _bound_record_arrays(ast.parse(path.read_text(), str(path)))
    assert not lines, (f"kernels/{path.name}:{lines[0]} binds a record's array field: read it "
                       "in place (oscillators.zeta[j])")


def test_the_record_check_sees_a_bound_field():
    code = ("frequencies, zeta = oscillators.frequencies, oscillators.zeta\n"
            "weights = event.weights\nconst = event.const\nw = oscillators.frequencies[j]\n")
    assert _bound_record_arrays(ast.parse(code)) == [1, 1, 2]


# The argument groups that travel as records in the event search (issue 21): any two of a
# group among one kernel's arguments mean the group travels loose again.
LOOSE_GROUPS = ({"frequencies", "zeta", "force"}, {"weights", "const", "sine_amp"})


def _loose_group_kernels(tree: ast.AST) -> list[str]:
    """Functions that take two or more arguments of an `Oscillators`/`EventFunction` group."""
    return [node.name for node in ast.walk(tree) if isinstance(node, ast.FunctionDef)
            and any(len(group & {a.arg for a in node.args.args}) >= 2 for group in LOOSE_GROUPS)]


@pytest.mark.parametrize("name", ["events.py", "rotor.py"])
def test_the_event_search_takes_the_records(name):
    """No kernel of the event search takes (frequencies, zeta, ...) or (weights, const, ...)."""
    path = PACKAGE / "kernels" / name
    assert not _loose_group_kernels(ast.parse(path.read_text(), str(path)))


def test_the_loose_group_check_sees_loose_arguments():
    code = ("def walk(q, frequencies, zeta, force):\n    pass\n"
            "def evaluate(q, v, t, weights, const, sine_amp):\n    pass\n"
            "def walk2(q, oscillators, event):\n    pass\n")
    assert _loose_group_kernels(ast.parse(code)) == ["walk", "evaluate"]


# The switching arrays (issue 33): a run's travel as one switching record, whose fields only
# the contact seam reads; every other kernel takes the record and passes it on whole.
SWITCHING_SEAM = {"contact.py", "contact_tied.py", "contact_spring.py"}
SWITCHING_FIELDS = {"overlap", "shifts", "spring"}
# The active sets' phases of several contacts (issue 33): one active sets record per run
# (`records.ACTIVE_SETS`), which the kernels of several contacts take whole and read in place,
# handing the single contact's kernels one set's arrays (``left``, ``right``); no kernel takes
# a set's change of coordinates or the set index of a mask loose.
ACTIVE_SETS_FIELDS = {"lefts", "rights", "set_of_mask"}


def _kernels_taking(tree: ast.AST, fields: set[str]) -> list[str]:
    """Functions that take one of a record's ``fields`` loose, as a parameter."""
    return [node.name for node in ast.walk(tree) if isinstance(node, ast.FunctionDef)
            and fields & {a.arg for a in node.args.args + node.args.kwonlyargs}]


def _loose_kernels(fields: set[str], readers: set[str] | tuple = ()) -> dict[str, list[str]]:
    """Each kernel module but the record's ``readers``: its kernels taking ``fields`` loose."""
    return {path.name: names for path in sorted((PACKAGE / "kernels").glob("*.py"))
            if path.name not in readers
            for names in [_kernels_taking(ast.parse(path.read_text(), str(path)), fields)]
            if names}


def test_kernels_take_one_switching_record():
    """Outside the contact seam no kernel takes the switching arrays loose."""
    loose = _loose_kernels(SWITCHING_FIELDS, SWITCHING_SEAM)
    assert not loose, ("kernels that take a switching array as a parameter (take the run's "
                       f"switching record, records.SWITCHING, whole): {loose}")


def test_kernels_take_one_active_sets_record():
    """No kernel takes the active sets' arrays loose: the record's readers
    (`kernels/several_contacts.py`, `kernels/contacts_tangent.py`) read its fields in place,
    every other kernel takes one set's."""
    loose = _loose_kernels(ACTIVE_SETS_FIELDS)
    assert not loose, ("kernels that take an active sets array as a parameter (take the run's "
                       f"active sets record, records.ACTIVE_SETS, whole): {loose}")


def test_the_record_checks_see_loose_arguments():
    code = ("def run_events(tables, forces, overlap, shifts, spring, drives, settings):\n"
            "    pass\n"
            "def sample_states(tables, forces, spring, drives, settings):\n    pass\n"
            "def tied(q, *, shifts):\n    pass\n"
            "def run(tables, forces, switching, settings):\n    pass\n"
            "def run_contacts(tables, forces, lefts, rights, set_of_mask, settings):\n"
            "    pass\n"
            "def event_at(sets, settings, a, f, *, lefts):\n    pass\n"
            "def to_contact(q, v, t, left, modes, drives):\n    pass\n"
            "def resume_contacts(sets, settings, early_release, q0, v0):\n    pass\n")
    tree = ast.parse(code)
    assert _kernels_taking(tree, SWITCHING_FIELDS) == ["run_events", "sample_states", "tied"]
    assert _kernels_taking(tree, ACTIVE_SETS_FIELDS) == ["run_contacts", "event_at"]
