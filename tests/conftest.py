"""Shared fixtures: the line data beside the repository.

JAX runs here as the ``invflame`` command runs it: its 64-bit mode stays off for the process,
and a float64 operator turns it on for its own evaluations only
(:func:`operators.base.precision`). So a float32 test sees the float32 arithmetic a user's run
does. A test that computes float64 references in plain JAX, or calls float64 kernels as JAX
functions, asks for the :func:`x64` fixture, or enters :func:`operators.base.precision` around
its float64 cases.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import jax
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session")
def shared_linedata() -> Path:
    """Folder ``../shared/linedata``; tests that need it skip when it is absent."""
    path = SHARED / "linedata"
    if not path.is_dir():
        pytest.skip(f"shared line data not found at {path} (clone with ../shared beside it)")
    return path


@pytest.fixture(scope="session")
def h2o_par() -> Path:
    """The HITRAN2012 H₂O records of 600–800 cm⁻¹ that the package ships (its data folder)."""
    return REPO / "invflame" / "data" / "H2O_HITRAN2012_600-800.par"


@pytest.fixture
def x64():
    """JAX's 64-bit mode on for the test: for float64 references computed in plain JAX, and
    for float64 kernels and scenes called as JAX functions."""
    with jax.enable_x64(True):
        yield


@pytest.fixture(scope="session")
def script_report():
    """Run a check script in a Python process of its own; ``script_report(path, **environment)``
    returns the JSON object on the last line the script prints. The process gets this process's
    environment with ``environment`` added; a script that exits non-zero fails the test with the
    end of its standard error."""
    def run(path, **environment) -> dict:
        done = subprocess.run([sys.executable, str(path)], env={**os.environ, **environment},
                              capture_output=True, text=True, timeout=600, check=False)
        assert done.returncode == 0, done.stderr[-3000:]
        return json.loads(done.stdout.strip().splitlines()[-1])
    return run
