"""Importing our packages changes nothing in the process: no torch, no JAX x64.

Each module of ``operators`` and ``solvers`` that is not torch-specific is imported alone in a
fresh interpreter, which then reports whether torch got imported and whether JAX's 64-bit mode
changed. Importing ``package.module`` runs the package's ``__init__`` first, so a module that the
package's own import already loads is covered by the probe of the package: only the others get
an interpreter of their own. None of their modules imports matplotlib: figures are drawn by
``invflame.plotting``. (That the import graph has no cycle is ``test_import_direction.py``'s.)
"""

import ast
import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("operators", "solvers")
#: Modules that exist to talk to torch: the only ones allowed to import it.
TORCH_MODULES = {"operators.torch_operator", "operators.torch_bridge"}

PROBE = """
import json, sys
import jax
before = bool(jax.config.jax_enable_x64)
import {module}
print(json.dumps({{"torch": "torch" in sys.modules,
                  "x64_before": before, "x64_after": bool(jax.config.jax_enable_x64),
                  "loaded": sorted(sys.modules)}}))
"""


def module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> list[str]:
    return sorted(module_name(p) for package in PACKAGES for p in (REPO / package).rglob("*.py"))


def imports_of(path: Path) -> set[str]:
    """Every module named by an import statement in ``path``, at any depth of the code."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def probe(module: str) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE.format(module=module)], cwd=REPO,
                         capture_output=True, text=True, timeout=300, check=False)
    assert out.returncode == 0, f"importing {module} failed:\n{out.stderr}"
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_leaves_torch_out_and_x64_unchanged():
    with ThreadPoolExecutor(max_workers=4) as pool:  # fresh interpreters, side by side
        reports = dict(zip(("invflame", *PACKAGES),
                           pool.map(probe, ("invflame", *PACKAGES)), strict=True))
        loaded = set().union(*(r["loaded"] for r in reports.values()))
        alone = [m for m in modules() if m not in TORCH_MODULES and m not in loaded]
        reports.update(zip(alone, pool.map(probe, alone), strict=True))
    torch = [m for m, r in reports.items() if r["torch"]]
    x64 = [m for m, r in reports.items() if r["x64_after"] != r["x64_before"]]
    assert not torch, f"importing these modules alone imported torch: {torch}"
    assert not x64, f"importing these modules alone changed jax_enable_x64: {x64}"
    covered = set(reports) | loaded
    assert {m for m in modules() if m not in TORCH_MODULES} <= covered


def test_only_the_torch_modules_import_torch_at_module_level():
    offenders = []
    for package in PACKAGES:
        for path in (REPO / package).rglob("*.py"):
            tree = ast.parse(path.read_text(), filename=str(path))
            top = set()
            for node in tree.body:
                if isinstance(node, ast.Import):
                    top.update(a.name.split(".")[0] for a in node.names)
                elif isinstance(node, ast.ImportFrom) and node.module:
                    top.add(node.module.split(".")[0])
            if "torch" in top and module_name(path) not in TORCH_MODULES:
                offenders.append(module_name(path))
    assert not offenders, f"modules importing torch at import time: {offenders}"


def test_operators_and_solvers_draw_nothing():
    drawing = {package: sorted(module_name(path) for path in (REPO / package).rglob("*.py")
                               if any(name.split(".")[0] == "matplotlib"
                                      for name in imports_of(path)))
               for package in PACKAGES}
    assert drawing == {package: [] for package in PACKAGES}, "figures belong to invflame.plotting"


def test_the_import_reader_sees_function_level_imports(tmp_path):
    sample = tmp_path / "m.py"
    sample.write_text("def f():\n    from operators.torch_operator import TorchFunction\n")
    assert "operators.torch_operator" in imports_of(sample)


def test_float64_operators_compute_in_float64_without_turning_x64_on_for_the_process():
    code = """
import json
import jax, jax.numpy as jnp, numpy as np
import operators as op
def fun(x):
    return (x + 1e-9) ** 3 - x ** 3  # 3e-9 in float64, 0 in float32

f64 = op.Operator.from_jax(fun, (3,), (3,))
f32 = op.Operator.from_jax(fun, (3,), (3,), dtype=np.float32)
class Own(op.Operator):  # an operator with its own linearize, computing in JAX
    def __init__(self):
        super().__init__((3,), (3,))

    def linearize(self, x):
        value = np.asarray(fun(jnp.asarray(x, jnp.float64)))
        return op.Jacobian(self, x, value, jvp=lambda v: v, vjp=lambda w: w)

x = np.ones(3)
J = f64.linearize(x)
print(json.dumps({"value": float(f64(x)[0]), "dtype": str(f64(x).dtype),
                  "jvp": float(J(np.ones(3))[0]), "own": float(Own().linearize(x).value[0]),
                  "f32": str(f32(x.astype(np.float32)).dtype),
                  "x64": bool(jax.config.jax_enable_x64)}))
"""
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                         timeout=300, check=False)
    assert out.returncode == 0, out.stderr
    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert report["dtype"] == "float64" and report["f32"] == "float32"
    assert abs(report["value"] - 3e-9) < 1e-14  # float32 gives 0
    assert abs(report["own"] - 3e-9) < 1e-14
    assert abs(report["jvp"] - 6e-9) < 1e-14   # 3 (x + 1e-9)^2 - 3 x^2
    assert report["x64"] is False
