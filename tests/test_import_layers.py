"""The layers of the package, read from the import statements of its modules.

Oracle: the import statements of every module, read from the source (``ast``;
module-level and function-level imports alike where a rule says what a layer may
import, module-level ones for the cycles, which are what Python runs on import):

* the numerical layers (continuation, solvers, stability, geometry) import each other,
  ``supercoil._numba`` and ``supercoil.errors``, and nothing else of the package (not
  the rod, contact, Cosserat or problem models, nor the API, I/O, plotting or command
  line);
* plotting and I/O import no solver, stability analysis or continuation algorithm: of
  the continuation only its records (the ``Branch`` and ``SpecialPoint`` of
  ``continuation.branch``, the status of ``continuation.options``);
* the command line sits on top: no module outside ``supercoil.cli`` imports it;
* the graph of the package's module-level imports has no cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import supercoil

PACKAGE = Path(supercoil.__file__).resolve().parent
NUMERICS = ("continuation", "solvers", "stability", "geometry")
ALLOWED = {f"supercoil.{name}" for name in NUMERICS} | {"supercoil._numba", "supercoil.errors"}


def _modules(packages=NUMERICS) -> dict[str, Path]:
    """Module name -> source file of every module of ``packages`` (subpackages of
    ``supercoil``; None: the whole package)."""
    found = {}
    roots = [PACKAGE] if packages is None else [PACKAGE / package for package in packages]
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


def _imports(path: Path, module_level_only: bool = False) -> list[str]:
    """The ``supercoil`` modules (or names) that the file imports."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = tree.body if module_level_only else ast.walk(tree)
    out = []
    for node in nodes:
        if isinstance(node, ast.Import):
            out += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{path}: relative import"
            out.append(node.module)
            out += [f"{node.module}.{alias.name}" for alias in node.names]
    return [name for name in out if name == "supercoil" or name.startswith("supercoil.")]


def _imported_modules(path: Path, modules) -> set[str]:
    """The modules of ``modules`` that the file imports at module level: ``import X`` and
    ``from X import Y`` name X, unless X.Y is itself a module (``from supercoil import
    checks``), which they name instead."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in tree.body:
        if isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            for alias in node.names:
                name = f"{node.module}.{alias.name}"
                out.add(name if name in modules else node.module)
    return out & set(modules)


def _top(name: str) -> str:
    return ".".join(name.split(".")[:2])


def test_the_numerical_layers_import_no_physics():
    modules = _modules()
    assert len(modules) > 20
    foreign = {name: sorted({_top(i) for i in _imports(path)} - ALLOWED)
               for name, path in modules.items()}
    assert {name: found for name, found in foreign.items() if found} == {}


def test_the_package_has_no_import_cycle():
    modules = _modules(None)
    assert len(modules) > 150
    graph = {name: sorted(_imported_modules(path, modules) - {name})
             for name, path in modules.items()}
    state: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(name: str, path: list[str]) -> None:
        state[name] = 1
        for other in graph[name]:
            assert state.get(other) != 1, " -> ".join([*path, name, other])
            if other not in state:
                visit(other, [*path, name])
        state[name] = 2

    for name in graph:
        if name not in state:
            visit(name, [])


def test_nothing_below_the_command_line_imports_it():
    # supercoil.__main__ (python -m supercoil) is the command line's entry, as the
    # console script is: it belongs to that layer
    modules = _modules(None)
    below = {name: path for name, path in modules.items()
             if name not in ("supercoil.cli", "supercoil.__main__")
             and not name.startswith("supercoil.cli.")}
    assert len(below) > 150 and len(below) < len(modules)
    found = {name: sorted(i for i in _imports(path)
                          if i == "supercoil.cli" or i.startswith("supercoil.cli."))
             for name, path in below.items()}
    assert {name: names for name, names in found.items() if names} == {}


# what plotting and I/O may take from the numerical layers: the continuation's records
RECORDS = {"supercoil.continuation.branch", "supercoil.continuation.branch.Branch",
           "supercoil.continuation.branch.SpecialPoint", "supercoil.continuation.branch.jsonable",
           "supercoil.continuation.options",
           "supercoil.continuation.options.ContinuationStatus",
           # the carried frames a branch stores with its points: an immutable record of
           # named arrays (the module holds no algorithm, only the Carried mixin)
           "supercoil.solvers.carried", "supercoil.solvers.carried.Frames"}
ALGORITHMS = ("supercoil.solvers", "supercoil.stability", "supercoil.continuation")


def test_plotting_and_io_import_no_solver_or_continuation_algorithm():
    modules = _modules(("plotting", "io"))
    assert len(modules) > 15
    found = {name: sorted(i for i in _imports(path)
                          if _top(i) in ALGORITHMS and i not in RECORDS)
             for name, path in modules.items()}
    assert {name: names for name, names in found.items() if names} == {}
