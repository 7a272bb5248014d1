"""Imports point one way: operators -> (nothing of ours), solvers -> operators, invflame -> both."""

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
FORBIDDEN = {"operators": {"solvers", "invflame"}, "solvers": {"invflame"}}


def imported_top_levels(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_does_not_import_upwards(package):
    files = sorted((REPO / package).rglob("*.py"))
    assert files, f"no Python files found in {package}/"
    offenders = {
        str(f.relative_to(REPO)): sorted(imported_top_levels(f) & FORBIDDEN[package])
        for f in files
    }
    offenders = {k: v for k, v in offenders.items() if v}
    assert not offenders, f"{package} must not import {sorted(FORBIDDEN[package])}: {offenders}"


def test_checker_sees_imports(tmp_path):
    sample = tmp_path / "m.py"
    sample.write_text("import invflame.geometry\nfrom solvers import get\nfrom . import x\n")
    assert imported_top_levels(sample) == {"invflame", "solvers"}
