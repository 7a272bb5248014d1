"""Imports point down the layers of :data:`LAYERS` and close no circle.

The graph has a node per module of operators, solvers and invflame and an edge per module an
import statement names. ``from package import name`` is an edge to ``package.name`` when that
is a module, else to ``package`` (its ``__init__``); the package of an imported submodule is not
an edge of its own, since a package's ``__init__`` importing its own modules is no circle.

Imports inside functions (and under ``if TYPE_CHECKING:``) count like those at the top: a lazy
import puts off the loading, not the dependency, so a lazy upward import is as wrong as an eager
one, and a circle closed by a lazy import is still a circle. The command line's lazy imports of
what its commands compute with point down and pass.
"""

import ast
from itertools import pairwise
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("operators", "solvers", "invflame")

LAYERS = (
    ("operators",),  # the operator algebra and the concrete operators
    ("solvers",),  # generic solvers on the operators' interface
    # the package's version, its errors, files written whole, the process's memory
    ("invflame", "invflame.errors", "invflame.atomic_files", "invflame.process_memory"),
    ("invflame.geometry", "invflame.spectroscopy"),  # grids, cameras, rays; gas absorption
    # what is measured (spectra, backgrounds) and what it is measured of (fields)
    ("invflame.field", "invflame.background", "invflame.measurement",
     "invflame.measurement_checks"),
    # the forward map, the data and background files, ground truths and their export
    ("invflame.scene_settings", "invflame.scene", "invflame.measurement_file",
     "invflame.background_file", "invflame.phantoms", "invflame.openfoam", "invflame.export"),
    ("invflame.representations", "invflame.plotting"),  # parameterizations; figures
    ("invflame.experiments",),  # configurations, runs and studies
    ("invflame.cli",),  # the command line
)
"""Lowest first. A unit is a package or module; its modules may import the units of its own
layer and of lower ones. A unit that holds other units (``invflame``) is its own module only."""


def module_names(root: Path, packages) -> dict[str, Path]:
    """Dotted name → file of every module of ``packages`` under ``root``."""
    names = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return names


def _absolute(node: ast.ImportFrom, package: str) -> str:
    """The absolute name of the module a ``from ... import`` in ``package`` imports from."""
    if not node.level:
        return node.module
    parts = package.split(".")
    return ".".join([*parts[:len(parts) - node.level + 1], *filter(None, [node.module])])


def import_graph(root: Path, packages) -> dict[str, dict[str, int]]:
    """Module → {module it imports: line of the import}, over the modules of ``packages``."""
    names = module_names(root, packages)

    def known(name: str) -> str | None:
        while name and name not in names:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for module, path in names.items():
        here = module if path.name == "__init__.py" else module.rpartition(".")[0]
        edges = {}
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _absolute(node, here)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in names else base
                           for a in node.names]
            else:
                continue
            for target in filter(None, map(known, targets)):
                if target != module:
                    edges.setdefault(target, node.lineno)
        graph[module] = edges
    return graph


def find_cycle(graph: dict[str, dict[str, int]]) -> list[str] | None:
    """One circle of imports, as ``[a, b, ..., a]``, or None."""
    state = {}
    for start in sorted(graph):
        if start in state:
            continue
        path, todo = [start], [iter(sorted(graph[start]))]
        state[start] = "open"
        while todo:
            nxt = next(todo[-1], None)
            if nxt is None:
                state[path.pop()] = "done"
                todo.pop()
            elif state.get(nxt) == "open":
                return [*path[path.index(nxt):], nxt]
            elif nxt not in state:
                state[nxt] = "open"
                path.append(nxt)
                todo.append(iter(sorted(graph.get(nxt, ()))))
    return None


def unit_of(module: str, layers) -> str | None:
    """The unit of :data:`LAYERS` that ``module`` belongs to, or None."""
    units = [u for layer in layers for u in layer]
    holders = {u for u in units if any(v.startswith(f"{u}.") for v in units)}
    matches = [u for u in units
               if module == u or (u not in holders and module.startswith(f"{u}."))]
    return max(matches, key=len, default=None)


def upward_imports(graph: dict[str, dict[str, int]], layers) -> list[str]:
    """Every import of a module of a higher layer, in words."""
    level = {u: i for i, layer in enumerate(layers) for u in layer}
    found = []
    for module, edges in sorted(graph.items()):
        mine = unit_of(module, layers)
        for target, line in sorted(edges.items()):
            theirs = unit_of(target, layers)
            if mine and theirs and level[theirs] > level[mine]:
                found.append(f"{module} (layer {level[mine]}, line {line}) imports {target} "
                             f"(layer {level[theirs]})")
    return found


@pytest.fixture(scope="module")
def graph():
    return import_graph(REPO, PACKAGES)


def test_every_module_has_a_layer(graph):
    unplaced = sorted(m for m in graph if unit_of(m, LAYERS) is None)
    assert not unplaced, f"put these modules (or their package) in a layer of LAYERS: {unplaced}"


def test_the_import_graph_has_no_cycle(graph):
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + "".join(
        f"{a} (line {graph[a][b]}) -> " for a, b in pairwise(cycle)) + cycle[-1]


def test_no_module_imports_a_higher_layer(graph):
    found = upward_imports(graph, LAYERS)
    assert not found, "imports up the layers:\n" + "\n".join(found)


def test_the_checks_find_a_cycle_and_an_upward_import(tmp_path):
    files = {"pkg/__init__.py": "",
             "pkg/a.py": "from . import b\n",
             "pkg/b.py": "def f():\n    from pkg.a import x\n",
             "pkg/low.py": "def g():\n    import pkg.high.deep\n",
             "pkg/high/__init__.py": "",
             "pkg/high/deep.py": "from ..low import g\nfrom pkg import low\n",
             "pkg/stray.py": "import os\n"}
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    layers = (("pkg", "pkg.a", "pkg.b", "pkg.low"), ("pkg.high",))
    found = import_graph(tmp_path, ("pkg",))
    assert found["pkg.high.deep"] == {"pkg.low": 1}
    assert find_cycle(found) == ["pkg.a", "pkg.b", "pkg.a"]
    assert upward_imports(found, layers) == [
        "pkg.low (layer 0, line 2) imports pkg.high.deep (layer 1)"]
    assert [m for m in found if unit_of(m, layers) is None] == ["pkg.stray"]
    assert find_cycle({"x": {"y": 1}, "y": {}}) is None
