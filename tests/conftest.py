"""Shared fixtures: the line data beside the repository and float64 JAX."""

from pathlib import Path

import jax
import pytest

jax.config.update("jax_enable_x64", True)

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session")
def shared_linedata() -> Path:
    """Folder ``../shared/linedata``; tests that need it skip when it is absent."""
    path = SHARED / "linedata"
    if not path.is_dir():
        pytest.skip(f"shared line data not found at {path} (clone with ../shared beside it)")
    return path
