"""A scene with a known soot field, and the synthetic plume's soot layer."""

import numpy as np
import pytest

import operators as op
from invflame.geometry import VoxelGrid, paper_rig
from invflame.phantoms import synthetic_plume
from invflame.phantoms.plume import plume_soot
from invflame.scene import Scene
from operators.sampling import VoxelSampling

from .test_scene import physical_direction, small_table, smooth_field

GRID = VoxelGrid.cube(5, size=1.0, centre=(0.0, 0.5, 0.0))
RIG = paper_rig(GRID, n_pixels=3)


def sooty(soot):
    return Scene(GRID, RIG, small_table(), resolution=4.0, dtype=np.float64, planck="exact",
                 soot=soot)


@pytest.fixture(scope="module")
def soot():
    return 2e-6 * np.exp(-((np.indices(GRID.shape) - 2.0) ** 2).sum(axis=0) / 2.0)


def test_soot_emits_and_absorbs_beside_the_gas(soot):
    fields = smooth_field(GRID)
    gas_only = sooty(None).operator(fields)
    np.testing.assert_allclose(sooty(np.zeros(GRID.shape)).operator(fields), gas_only,
                               rtol=1e-13)
    change = sooty(soot).operator(fields) - gas_only
    assert np.abs(change).max() > 1e-2 * gas_only.max()  # ppm of soot is seen


def test_the_pieces_give_the_scene_map_with_soot(soot):
    scene = sooty(soot)
    fields = smooth_field(GRID, seed=2)
    sampling = VoxelSampling(scene.segments.voxel, GRID.shape, 5, dtype=np.float64)
    on_segments = sampling(np.concatenate([fields, soot[None]]))
    assert scene.emission.dims[0] == 5
    np.testing.assert_allclose(scene.ils(scene.emission(on_segments)), scene.operator(fields),
                               rtol=1e-12)


def test_forward_map_with_known_soot_dot_and_taylor_tests(soot):
    scene = sooty(soot)
    fields = smooth_field(GRID, seed=3)
    dot = op.jacobian_dottest(scene.operator, fields, rtol=1e-10)
    assert dot.passed, dot
    taylor = op.taylor_test(scene.operator, fields, physical_direction(fields), h0=1.0)
    assert taylor.passed, taylor
    assert taylor.rate1 > 1.9


def test_bad_soot_fields_are_named():
    with pytest.raises(ValueError, match=r"soot must be a volume fraction per voxel of shape"):
        sooty(np.zeros((4, 4, 4)))
    with pytest.raises(ValueError, match=r"soot volume fraction must lie in \[0, 1\)"):
        sooty(np.full(GRID.shape, -1e-6))


def test_plume_soot_sits_in_the_hot_fuel_and_is_scaled_to_its_peak():
    plume = synthetic_plume(VoxelGrid.poolfire(16))
    soot = plume_soot(plume, 1e-6)
    assert soot.max() == pytest.approx(1e-6) and soot.min() >= 0
    hot_fuel = plume.values[3] * (plume.values[0] - plume.values[0].min())
    assert np.all(soot[hot_fuel == 0] == 0)
    assert np.unravel_index(np.argmax(soot), soot.shape) == np.unravel_index(
        np.argmax(hot_fuel), soot.shape)
    with pytest.raises(ValueError, match="peak_volume_fraction"):
        plume_soot(plume, 1.5)


def test_with_soot_equals_a_scene_built_with_it(soot):
    fields = smooth_field(GRID, seed=6)
    np.testing.assert_array_equal(sooty(None).with_soot(soot).operator(fields),
                                  sooty(soot).operator(fields))
    np.testing.assert_array_equal(sooty(soot).with_soot(None).operator(fields),
                                  sooty(None).operator(fields))


def test_soot_as_an_input_field_gives_the_known_soot_map(soot):
    """Soot as the fifth input field: the map of the fields and that soot equals the map of
    the fields with that soot known."""
    scene = Scene(GRID, RIG, small_table(), resolution=4.0, dtype=np.float64, planck="exact",
                  soot_input=True)
    assert scene.field_shape == (5, *GRID.shape) and scene.soot is None
    fields = smooth_field(GRID, seed=4)
    np.testing.assert_allclose(scene.operator(np.concatenate([fields, soot[None]])),
                               sooty(soot).operator(fields), rtol=1e-12)
    assert sooty(None).with_soot(None, soot_input=True).field_shape == scene.field_shape
    assert scene.with_soot(None).field_shape == (4, *GRID.shape)
    with pytest.raises(ValueError, match=r"field values must have shape \(5, 5, 5, 5\)"):
        scene.simulate(fields)
    with pytest.raises(ValueError, match=r"not both"):
        sooty(soot).with_soot(soot, soot_input=True)


def test_forward_map_with_soot_as_input_dot_and_taylor_tests(soot):
    """Exact derivatives of the five-field map, the soot volume fraction included (float64)."""
    scene = sooty(None).with_soot(None, soot_input=True)
    fields = np.concatenate([smooth_field(GRID, seed=6), soot[None]])
    dot = op.jacobian_dottest(scene.operator, fields, rtol=1e-10)
    assert dot.passed, dot
    # the steps x + h·direction, h ≤ 1, stay physical: T ± 30 K, each X and f_v within ±50 %
    shape = np.random.default_rng(7).uniform(-1.0, 1.0, fields.shape)
    direction = np.concatenate([30.0 * shape[:1], 0.5 * fields[1:] * shape[1:]])
    taylor = op.taylor_test(scene.operator, fields, direction, h0=1.0)
    assert taylor.passed, taylor
    assert taylor.rate1 > 1.9
    only_soot = np.zeros_like(fields)
    only_soot[4] = direction[4]
    taylor = op.taylor_test(scene.operator, fields, only_soot, h0=1.0)
    assert taylor.passed and taylor.rate1 > 1.9, taylor
