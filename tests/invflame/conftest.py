"""Fixtures shared by the tests of several ``invflame`` subpackages; among them a tiny
measurement scene: 8³ grid, 2 cameras of 6×6 pixels, 99 wavenumbers (every 19th point of the
default 650–725 cm⁻¹ table); one ray per pixel, or 2 × 2 sub-rays per pixel."""

import numpy as np
import pytest

from invflame.experiments.metrics import smoothed
from invflame.field import Field
from invflame.geometry import CameraRig, VoxelGrid, paper_rig
from invflame.phantoms import synthetic_plume
from invflame.scene import Scene
from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.co2_lines import generate_co2_lines
from invflame.spectroscopy.linelist import read_par


@pytest.fixture(scope="module")
def plume_fields():
    """A synthetic plume on a 10³ pool-fire grid and two estimates of it by name: a perturbed
    ``start`` and the plume ``smoothed``."""
    grid = VoxelGrid.poolfire(10)
    truth = synthetic_plume(grid)
    return truth, {"start": synthetic_plume(grid, perturbation=0.3, seed=0),
                   "smoothed": Field(grid, smoothed(truth.values, 1.0))}


@pytest.fixture(scope="session")
def table(h2o_par) -> AbsorptionTable:
    """A small absorption table at 250, 800 and 1600 K: the generated CO2 lines of
    691.4–692.7 cm⁻¹ and the packaged H2O lines of 624–751 cm⁻¹."""
    linelists = {"CO2": generate_co2_lines().window(691.4, 692.7),
                 "H2O": read_par(h2o_par, nu_range=(624, 751))}
    return AbsorptionTable.build(linelists, temperatures=[250.0, 800.0, 1600.0])


@pytest.fixture(scope="session")
def tiny_table() -> AbsorptionTable:
    return AbsorptionTable.default(progress=False).take_bins(slice(None, None, 19))


def _scene(table, dtype, rays_per_pixel: int = 1) -> Scene:
    grid = VoxelGrid.poolfire(8)
    rig = CameraRig(paper_rig(grid, n_pixels=6).cameras[:2])
    return Scene(grid, rig, table, dtype=dtype, rays_per_pixel=rays_per_pixel)


@pytest.fixture(scope="session")
def tiny_scene(tiny_table) -> Scene:
    """float32 scene."""
    return _scene(tiny_table, np.float32)


@pytest.fixture(scope="session")
def tiny_scene64(tiny_table) -> Scene:
    """float64 scene, for derivative checks."""
    return _scene(tiny_table, np.float64)


@pytest.fixture(scope="session")
def pixel_scene64(tiny_table) -> Scene:
    """float64 scene with 4 sub-rays per pixel."""
    return _scene(tiny_table, np.float64, rays_per_pixel=4)


@pytest.fixture(scope="session")
def plume() -> np.ndarray:
    """Smooth plume fields (4, 8, 8, 8) on the tiny scene's grid (T in K, mole fractions)."""
    return synthetic_plume(VoxelGrid.poolfire(8)).values.astype(np.float64)
