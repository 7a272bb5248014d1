"""The flame's radiative transfer stays in :mod:`operators.rte`: the rest of :mod:`operators`
imports nothing of it, except the package's ``__init__``, which exports its user names."""

import ast
from pathlib import Path

import operators
import operators.rte
from operators import planck

OPERATORS = Path(__file__).resolve().parents[2] / "operators"


def imported(path: Path) -> set[str]:
    """Every module an import statement of ``path`` names, and every ``module.name`` of a
    ``from module import name``."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def test_operators_outside_rte_import_nothing_of_it():
    offenders = {}
    for path in sorted(OPERATORS.rglob("*.py")):
        relative = path.relative_to(OPERATORS)
        if relative.parts[0] == "rte" or relative == Path("__init__.py"):
            continue
        found = sorted(n for n in imported(path)
                       if n == "operators.rte" or n.startswith("operators.rte."))
        if found:
            offenders[str(relative)] = found
    assert not offenders, f"operators outside operators/rte import it: {offenders}"


def test_the_user_names_of_rte_are_those_of_operators():
    for name in ("EmissionRTE", "RTETables", "emission_radiance", "emission_radiance_jvp"):
        assert getattr(operators, name) is getattr(operators.rte, name), name
    assert planck is operators.rte.planck.planck  # the function, from its module
