"""Fixtures shared by the tests of several ``invflame`` subpackages."""

import pytest

from invflame.experiments.metrics import smoothed
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume


@pytest.fixture(scope="module")
def plume_fields():
    """A synthetic plume on a 10³ pool-fire grid and two estimates of it by name: a perturbed
    ``start`` and the plume ``smoothed``."""
    grid = VoxelGrid.poolfire(10)
    truth = synthetic_plume(grid)
    return truth, {"start": synthetic_plume(grid, perturbation=0.3, seed=0),
                   "smoothed": Field(grid, smoothed(truth.values, 1.0))}
