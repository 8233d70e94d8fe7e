"""The numerical layers (continuation, solvers, stability, geometry) never import the physics.

Oracle: the import statements of every module of those packages, read from the source
(``ast``: module-level and function-level imports alike). They may import each other,
``supercoil._numba`` and ``supercoil.errors``, and nothing else of the package (not the
rod, contact, Cosserat or problem models, nor the API, I/O, plotting or command line);
the graph of their module-level imports has no cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import supercoil

PACKAGE = Path(supercoil.__file__).resolve().parent
NUMERICS = ("continuation", "solvers", "stability", "geometry")
ALLOWED = {f"supercoil.{name}" for name in NUMERICS} | {"supercoil._numba", "supercoil.errors"}


def _modules() -> dict[str, Path]:
    found = {}
    for package in NUMERICS:
        for path in sorted((PACKAGE / package).rglob("*.py")):
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


def _top(name: str) -> str:
    return ".".join(name.split(".")[:2])


def test_the_numerical_layers_import_no_physics():
    modules = _modules()
    assert len(modules) > 20
    foreign = {name: sorted({_top(i) for i in _imports(path)} - ALLOWED)
               for name, path in modules.items()}
    assert {name: found for name, found in foreign.items() if found} == {}


def test_the_numerical_layers_have_no_import_cycle():
    modules = _modules()
    graph = {name: sorted({i for i in _imports(path, module_level_only=True) if i in modules}
                          - {name})
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
