"""The package's shape: an acyclic module import graph, no borrowed private names, short functions.

The graph is built from the source with :mod:`ast` (module-level *and* in-function imports), so
a cycle hidden inside a function body counts. A package's ``__init__`` re-exporting its own
children is not an edge of the graph: it is how a subpackage publishes its API.
"""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ocio_vp"
MAX_FUNCTION_LINES = 80
MAX_TOP_LEVEL_MODULES = 12


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


MODULES = _modules()


def _imports(path: Path) -> list[tuple[str, tuple[str, ...], int]]:
    """(module, imported names, line) for every ``import``/``from`` of ocio_vp in a file."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] == "ocio_vp":
                out.append((node.module, tuple(a.name for a in node.names), node.lineno))
        elif isinstance(node, ast.Import):
            out += [(a.name, (), node.lineno) for a in node.names if a.name.startswith("ocio_vp")]
    return out


def _target(module: str, name: str) -> str:
    """The module an import really reads: ``from pkg import mod`` names a submodule."""
    return f"{module}.{name}" if f"{module}.{name}" in MODULES else module


def import_graph() -> dict[str, set[str]]:
    """Module -> modules it imports, leaving out a package ``__init__``'s own children."""
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for module, path in MODULES.items():
        is_init = path.name == "__init__.py"
        for imported, names, _ in _imports(path):
            for target in {_target(imported, n) for n in names} or {imported}:
                if target == module or target not in MODULES:
                    continue
                if is_init and target.startswith(module + "."):
                    continue  # a package publishing its children
                graph[module].add(target)
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as a list of nodes (first == last), or None (iterative DFS)."""
    state: dict[str, int] = {}
    for root in graph:
        if root in state:
            continue
        stack = [(root, iter(sorted(graph[root])))]
        path = [root]
        state[root] = 1
        while stack:
            node, children = stack[-1]
            child = next(children, None)
            if child is None:
                state[node] = 2
                stack.pop()
                path.pop()
            elif state.get(child) == 1:
                return [*path[path.index(child) :], child]
            elif child not in state:
                state[child] = 1
                path.append(child)
                stack.append((child, iter(sorted(graph[child]))))
    return None


def test_find_cycle_finds_a_planted_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


def test_the_import_graph_has_no_cycle():
    cycle = find_cycle(import_graph())
    assert cycle is None, " -> ".join(cycle or [])


#: docs/architecture.md's rows, from the leaves (0) up to the commands: a module may import a
#: module of its own package or of a package on its row or below, never above.
ROWS = {
    "metrics": 0, "spectra": 0, "errors": 0, "choices": 0, "skin_data": 0,
    "deprecation": 0, "svg": 0,
    "formats": 1, "wall": 1, "staging": 1, "model": 1, "patterns": 1,
    "calibration": 2,
    "correction": 3, "ocio": 3, "plates": 3, "hdri": 3, "fixtures": 3,
    "pipeline": 4,
    "simulator": 5, "synthesis": 5,
    "report": 6, "exports": 6, "footage": 6, "validation": 6,
    "commands": 7, "cli": 7, "__main__": 7,
}  # fmt: skip


def _room(module: str) -> str | None:
    """The package (or top-level module) ``module`` belongs to; None for the facade."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def upward_imports(graph: dict[str, set[str]]) -> list[str]:
    """Imports that go up a row of :data:`ROWS` ("a -> b"), leaving out the facade."""
    found = []
    for module, targets in sorted(graph.items()):
        for target in sorted(targets):
            here, there = _room(module), _room(target)
            if None in (here, there) or here == there:
                continue
            if ROWS[there] > ROWS[here]:
                found.append(f"{module} -> {target}")
    return found


def test_every_package_has_a_row():
    rooms = {_room(m) for m in MODULES} - {None}
    assert rooms == set(ROWS), rooms ^ set(ROWS)


def test_no_import_goes_up_a_row():
    assert upward_imports(import_graph()) == []


def test_upward_imports_finds_a_planted_one():
    graph = {
        "ocio_vp.correction.perceptual": {"ocio_vp.simulator.data"},
        "ocio_vp": {"ocio_vp.cli"},
    }
    assert upward_imports(graph) == ["ocio_vp.correction.perceptual -> ocio_vp.simulator.data"]


def test_the_graph_sees_in_function_imports():
    # ocio_vp.plates.detection imports scipy lazily; the graph must at least
    # see the ocio_vp imports of a function body (pipeline.py imports the wall lazily, say).
    edges = sum(len(v) for v in import_graph().values())
    assert edges > 100


def test_no_module_imports_another_modules_private_name():
    offenders = []
    for module, path in MODULES.items():
        for imported, names, line in _imports(path):
            private = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if private and imported != module:
                offenders.append(f"{path.relative_to(PACKAGE.parent)}:{line} {private}")
    assert not offenders, offenders


def test_no_function_is_longer_than_80_lines():
    long = []
    for path in MODULES.values():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                name = f"{path.relative_to(PACKAGE.parent)}:{node.name}"
                if lines > MAX_FUNCTION_LINES:
                    long.append(f"{name} ({lines})")
    assert not long, long


def test_at_most_a_dozen_modules_at_the_top():
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top


SUBPACKAGES = sorted(m for m, p in MODULES.items() if p.name == "__init__.py" and "." in m)


@pytest.mark.parametrize("package", SUBPACKAGES)
def test_every_subpackage_imports_first_in_a_fresh_interpreter(package):
    # A subpackage imported first, on its own, must not trip over a half-initialised sibling.
    run = subprocess.run(
        [sys.executable, "-c", f"import {package}"], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr.strip().splitlines()[-1:]


HEAVY = ("colour", "scipy", "matplotlib", "dask")

#: What a command imports before it does its job: parsing its arguments, and for ``apply`` the
#: modules that post-correct frames. None of them may load colour-science (its own import loads
#: matplotlib and scipy: ~2 s, more than post-correcting six 4K frames) or scipy or dask.
LIGHT_PATHS = {
    "parser": "from ocio_vp.cli import build_parser; build_parser()",
    "apply": "from ocio_vp.cli import build_parser; build_parser(); "
    "import ocio_vp.footage.apply, ocio_vp.footage.stream, ocio_vp.footage.sequences, "
    "ocio_vp.formats.solution, ocio_vp.commands.apply",
    "package": "import ocio_vp; ocio_vp.__version__; ocio_vp.InputError",
}


@pytest.mark.parametrize("path", sorted(LIGHT_PATHS))
def test_commands_do_not_import_heavy_libraries_they_do_not_use(path):
    # colour.plotting's stand-in (ocio_vp/__init__.py: colour-science not loaded) is no import.
    code = (
        f"import sys; {LIGHT_PATHS[path]}; print(sorted({{m.split('.')[0] for m, v in "
        "sys.modules.items() if type(v).__name__ != '_DeferredModule'}))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr.strip().splitlines()[-1:]
    loaded = set(ast.literal_eval(run.stdout))
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))
    if path == "parser":  # ``ocio-vp --help`` and every start: not even numpy (~0.2 s)
        assert "numpy" not in loaded


def test_the_package_exports_load_on_first_use():
    # ``import ocio_vp`` (which every command pays) loads none of its modules...
    code = "import sys, ocio_vp; print(sorted(m for m in sys.modules if m.startswith('ocio_vp.')))"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert ast.literal_eval(run.stdout) == []
    # ...and each public name is loaded when first used.
    import ocio_vp

    for name in ocio_vp.__all__:  # each public name resolves, to what its module defines
        value = getattr(ocio_vp, name)
        assert value is getattr(importlib.import_module(ocio_vp._EXPORTS[name]), name)
    assert sorted(ocio_vp.__all__) == sorted(ocio_vp._EXPORTS)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        ocio_vp.nope  # noqa: B018


@pytest.mark.parametrize("package", ["ocio_vp.formats", "ocio_vp.ocio"])
def test_subpackage_names_load_on_first_use(package):
    # formats/ and ocio/ publish their names lazily (export and apply import one module of
    # each): every public name still resolves, to what its module defines.
    module = importlib.import_module(package)
    assert sorted(module.__all__) == sorted(module._EXPORTS)
    for name in module.__all__:
        value = getattr(module, name)
        assert value is getattr(importlib.import_module(module._EXPORTS[name]), name)
        assert name in dir(module)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        module.nope  # noqa: B018


#: What ``export --target nuke`` or ``unreal`` never runs: the solvers, the fixture drives, the
#: cube baker, the bake of the LUT chains and the config writer.
NOT_EXPORTED_BY_NUKE_OR_UNREAL = (
    "ocio_vp.correction",
    "ocio_vp.fixtures",
    "ocio_vp.exports.cube",
    "ocio_vp.exports.lights",
    "ocio_vp.ocio.bake",
    "ocio_vp.ocio.writer",
)


def test_an_export_loads_its_own_targets_modules_only():
    code = (
        "import sys, ocio_vp.exports, ocio_vp.exports.nuke, ocio_vp.exports.unreal; "
        "print(sorted(m for m in sys.modules if m.startswith('ocio_vp.')))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr.strip().splitlines()[-1:]
    loaded = ast.literal_eval(run.stdout)
    assert "ocio_vp.formats.solution" in loaded  # the check sees what an export reads
    assert [m for m in loaded if m.startswith(NOT_EXPORTED_BY_NUKE_OR_UNREAL)] == []


def _tested_source(test_name: str) -> list[Path]:
    """Where ``test_<package>_<module>.py`` (or ``test_<module>.py``) may point in ocio_vp/."""
    parts = test_name.removeprefix("test_").split("_")
    candidates = []
    for split in range(len(parts) + 1):
        folder, stem = "_".join(parts[:split]), "_".join(parts[split:])
        base = PACKAGE / folder if folder else PACKAGE
        candidates += [base / f"{stem}.py", base / stem / "__init__.py"] if stem else []
    return [c for c in candidates if c.is_file()]


def test_tests_mirror_the_package():
    # tests/test_calibration_equations.py tests ocio_vp/calibration/equations.py, tests/test_report.py
    # the report/ subpackage: a newcomer finds a module's tests by its name, and the other way.
    tests = sorted(Path(__file__).parent.glob("test_*.py"))
    unmatched = [
        t.name for t in tests if t.stem != "test_architecture" and not _tested_source(t.stem)
    ]
    assert not unmatched, f"name these after the module or subpackage they test: {unmatched}"


def test_colour_science_loads_without_its_plotting_until_that_is_used():
    """Every solve imports colour-science (ΔE2000, camera data); its ``__init__`` would import
    ``colour.plotting`` and matplotlib's pyplot (~0.3 s), which ocio_vp never uses. In the
    command (``ocio_vp.cli.main`` defers them) they load on first use only, and then they are
    the real ones; ``import ocio_vp`` alone changes nothing in someone else's process."""
    plain = "import sys, ocio_vp; print('colour.plotting' in sys.modules)"
    run = subprocess.run([sys.executable, "-c", plain], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.strip() == "False", run.stderr
    code = (
        "import sys; from ocio_vp.cli import _defer_colour_plotting; _defer_colour_plotting(); "
        "import colour; before = 'matplotlib' in sys.modules; "
        "d = colour.delta_E([50, 2, 3], [51, 2, 4]); "
        "from colour.plotting import plot_single_colour_swatch as f; "
        "print([before, 'matplotlib' in sys.modules, f.__module__, "
        "sys.modules['colour.plotting'] is colour.plotting, type(colour.plotting).__name__, "
        "float(d)])"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr.strip().splitlines()[-1:]
    before, after, module, same, kind, delta_e = ast.literal_eval(run.stdout)
    assert (before, after, same, kind) == (False, True, True, "module")
    assert module.startswith("colour.plotting")
    assert delta_e > 0


#: Most functions whose signature mentions ``Any``: a value truly of any type (a YAML/JSON
#: reader's narrowing helpers, keyword forwarding, reflection over record fields). Everything
#: else crossing a function boundary has a named type (a record, a protocol, an array, JsonValue).
MAX_ANY_SIGNATURES = 40


def any_signatures(source: str, name: str = "<source>") -> list[str]:
    """``name:line function`` for each function whose parameter or return annotations mention
    ``Any`` (``ast.unparse`` of the annotation contains "Any")."""
    found = []
    for node in ast.walk(ast.parse(source, name)):
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        args = node.args
        params = [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]
        annotations = [p.annotation for p in params if p is not None and p.annotation]
        annotations += [node.returns] if node.returns else []
        if any("Any" in ast.unparse(a) for a in annotations):
            found.append(f"{name}:{node.lineno} {node.name}")
    return found


def test_any_signatures_finds_planted_ones():
    source = (
        "def a(x: Any) -> int: ...\n"
        "def b(*, y: dict[str, Any]) -> None: ...\n"
        "def c(**z: Any): ...\n"
        "def d() -> list[Any]: ...\n"
        "def e(x: int, y: 'Anything') -> str: ...\n"  # a name that contains Any counts too
        "def f(x: int, *rest: float) -> JsonValue: ...\n"
    )
    assert [s.split()[1] for s in any_signatures(source)] == ["a", "b", "c", "d", "e"]


def test_at_most_40_functions_take_or_return_any():
    found = [
        hit
        for path in sorted(PACKAGE.rglob("*.py"))
        for hit in any_signatures(path.read_text(), str(path.relative_to(PACKAGE.parent)))
    ]
    assert len(found) <= MAX_ANY_SIGNATURES, "\n".join(found)
