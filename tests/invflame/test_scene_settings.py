"""A scene's immutable settings, and Scene.replace: a new scene of changed settings."""

import dataclasses

import numpy as np
import pytest

from invflame.background import BlackbodyWall
from invflame.geometry import VoxelGrid, paper_rig
from invflame.scene import Scene

from .test_scene import small_table, smooth_field

GRID = VoxelGrid.cube(4, size=1.0, centre=(0.0, 0.5, 0.0))
SETTINGS = {"resolution": 4.0, "dtype": np.float64, "planck": "exact"}


@pytest.fixture(scope="module")
def scene():
    return Scene(GRID, paper_rig(GRID, n_pixels=2), small_table(), **SETTINGS)


def test_settings_are_immutable_and_keep_their_own_soot(scene):
    with pytest.raises(dataclasses.FrozenInstanceError):
        scene.settings.resolution = 2.0
    soot = np.full(GRID.shape, 1e-6)
    sooty = scene.replace(soot=soot)
    soot[:] = 0.5
    assert sooty.soot.max() == 1e-6 and not sooty.settings.soot.flags.writeable


def test_replace_gives_the_scene_built_with_the_changed_settings(scene):
    fields = smooth_field(GRID, seed=1)
    changed = {"rays_per_pixel": 4, "resolution": 2.0, "background": BlackbodyWall(500.0, 0.8)}
    built = Scene(GRID, scene.rig, scene.table, **{**SETTINGS, **changed})
    np.testing.assert_array_equal(scene.replace(**changed).operator(fields),
                                  built.operator(fields))
    np.testing.assert_array_equal(scene.replace().operator(fields), scene.operator(fields))


def test_no_cached_piece_outlives_its_settings(scene):
    fields = smooth_field(GRID, seed=2)
    assert scene.sampling.dims[0] == 4 and scene.emission.background is None  # cached now
    walled = scene.replace(background=BlackbodyWall(500.0))
    assert walled.emission.background is not None
    fifth = scene.replace(soot_input=True)
    assert fifth.sampling.dims[0] == 5 and fifth.emission.dims[0] == 5
    np.testing.assert_array_equal(scene.operator(fields), Scene(
        GRID, scene.rig, scene.table, **SETTINGS).operator(fields))


def test_replace_hands_on_only_the_pieces_whose_settings_stay(scene):
    walled = scene.replace(background=BlackbodyWall(500.0))
    assert walled.segments is scene.segments and walled.tables is scene.tables
    sooty = scene.replace(soot_input=True)
    assert sooty.segments is scene.segments and sooty.tables is not scene.tables
    finer = scene.replace(rays_per_pixel=4)
    assert finer.segments is not scene.segments and finer.tables is scene.tables


def test_replace_names_what_it_refuses(scene):
    with pytest.raises(TypeError, match=r"\['colour'\] are not settings of a scene"):
        scene.replace(colour="red")
    with pytest.raises(TypeError, match="background must be an invflame.background.Background"):
        scene.with_background("wall")
    with pytest.raises(ValueError, match="not both"):
        scene.replace(soot=np.zeros(GRID.shape), soot_input=True)
