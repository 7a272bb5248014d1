"""Shared fixtures: the line data beside the repository.

JAX runs here as the ``invflame`` command runs it: its 64-bit mode stays off for the process,
and a float64 operator turns it on for its own evaluations only
(:func:`operators.base.precision`). So a float32 test sees the float32 arithmetic a user's run
does. A test that computes float64 references in plain JAX, or calls float64 kernels as JAX
functions, asks for the :func:`x64` fixture, or enters :func:`operators.base.precision` around
its float64 cases.
"""

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


@pytest.fixture
def x64():
    """JAX's 64-bit mode on for the test: for float64 references computed in plain JAX, and
    for float64 kernels and scenes called as JAX functions."""
    with jax.enable_x64(True):
        yield
