"""Pixels are areas: sub-rays per pixel, their mean as the pixel's spectrum, and ray coverage."""

import numpy as np
import pytest

import operators as op
from invflame.geometry import VoxelGrid, paper_rig, ray_coverage, traverse
from invflame.geometry.camera import PinholeCamera
from invflame.scene import Scene

from .test_scene import small_table, smooth_field


def test_row_mean_is_exact_in_the_dot_test():
    mean = op.RowMean(5, 4, 3)
    x = np.arange(60.0).reshape(20, 3)
    np.testing.assert_allclose(mean(x), x.reshape(5, 4, 3).mean(axis=1))
    assert op.dottest(mean, rtol=1e-13).passed


@pytest.mark.parametrize("bad", [0, -4, 2.5, True])
def test_row_mean_rejects_bad_sizes(bad):
    with pytest.raises(ValueError, match="positive integer"):
        op.RowMean(3, bad, 2)


def test_sub_rays_tile_each_pixel_and_are_pixel_major():
    camera = PinholeCamera((0.0, 0.0, -2.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, (0.4, 0.2),
                           (4, 2))
    _, centre = camera.rays()
    _, sub = camera.rays(9)
    assert sub.shape == (8 * 9, 3)
    # the sub-rays of one pixel project inside that pixel, around its centre ray
    u, v, _ = camera.project(camera.position + sub)
    pixel_u, pixel_v = np.floor(u).reshape(8, 9), np.floor(v).reshape(8, 9)
    np.testing.assert_array_equal(pixel_u, np.tile(np.arange(4), 2)[:, None].repeat(9, 1))
    np.testing.assert_array_equal(pixel_v, np.repeat(np.arange(2), 4)[:, None].repeat(9, 1))
    # stratified: offsets 1/6, 1/2, 5/6 of a pixel along each side
    np.testing.assert_allclose(np.sort(np.unique(np.round(u[:9] % 1, 12))), [1 / 6, 0.5, 5 / 6])
    uc, vc, _ = camera.project(camera.position + centre)
    np.testing.assert_allclose(u.reshape(8, 9)[:, 4], uc, atol=1e-12)
    np.testing.assert_allclose(v.reshape(8, 9)[:, 4], vc, atol=1e-12)


@pytest.mark.parametrize("bad", [2, 0, 8, 3.0])
def test_rays_per_pixel_must_be_a_square(bad):
    camera = PinholeCamera((0.0, 0.0, -2.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, (0.4, 0.4),
                           (2, 2))
    with pytest.raises(ValueError, match="perfect square"):
        camera.rays(bad)


def test_pixel_spectrum_is_the_mean_of_its_sub_rays():
    grid = VoxelGrid.cube(5, size=1.0, centre=(0.0, 0.5, 0.0))
    rig = paper_rig(grid, n_pixels=2)
    kwargs = {"resolution": 4.0, "dtype": np.float64, "planck": "exact"}
    pixels = Scene(grid, rig, small_table(), rays_per_pixel=4, **kwargs)
    fields = smooth_field(grid)
    assert pixels.data_shape == (rig.n_rays, pixels.out_wavenumber.size)
    assert pixels.segments.n_rays == 4 * rig.n_rays
    # the same sub-rays traced one by one, as rays of their own, then averaged by hand
    per_ray = pixels.emission(pixels.sampling(fields))
    by_hand = per_ray.reshape(rig.n_rays, 4, -1).mean(axis=1) @ pixels.ils.matrix.T
    np.testing.assert_allclose(pixels.simulate(fields), by_hand, rtol=1e-12)
    np.testing.assert_allclose(pixels.operator(fields), by_hand, rtol=1e-12)
    assert op.jacobian_dottest(pixels.operator, fields, rtol=1e-10).passed


def test_sub_rays_cross_the_voxels_that_centre_rays_miss():
    grid = VoxelGrid.poolfire(12)
    rig = paper_rig(grid, n_pixels=6)  # pixel footprint ~3 voxels: centre rays leave gaps
    hot = np.zeros(grid.shape)
    hot[5:7, 2:6, 5:7] = 1500.0
    one = ray_coverage(traverse(grid, *rig.rays()), rig, hot)
    nine = ray_coverage(traverse(grid, *rig.rays(9)), rig, hot)
    assert one["voxels"] < 0.8
    assert nine["voxels"] == 1.0 and nine["common_view"] == 1.0 and nine["hot"] == 1.0
    assert ray_coverage(traverse(grid, *rig.rays(9)), rig)["hot"] is None
    with pytest.raises(ValueError, match="grid's shape"):
        ray_coverage(traverse(grid, *rig.rays()), rig, hot[:-1])


@pytest.mark.parametrize(("change", "message"), [
    (lambda f: f.__setitem__((0, 0, 0, 0), 0.0), r"temperature must be > 0 K"),
    (lambda f: f.__setitem__((0, 0, 0, 0), 100.0), r"temperature spans 100-.* outside"),
    (lambda f: f.__setitem__((0, 0, 0, 0), 5000.0), r"temperature spans .*-5000 K"),
    (lambda f: f.__setitem__((1, 0, 0, 0), -0.5), r"X_CO2 must lie in \[0, 1\]; got range \[-0.5"),
    (lambda f: f.__setitem__((slice(1, 3), 0, 0, 0), [0.1, 0.95]), "maximum sum is 1.05"),
    (lambda f: f.__setitem__((2, 0, 0, 0), np.nan), r"NaN or inf in \['H2O'\] \(1 entries\)"),
])
def test_simulate_refuses_unphysical_fields(change, message):
    grid = VoxelGrid.cube(3, size=1.0, centre=(0.0, 0.5, 0.0))
    scene = Scene(grid, paper_rig(grid, n_pixels=2), small_table(), resolution=4.0)
    fields = smooth_field(grid)
    change(fields)
    with pytest.raises(ValueError, match=message):
        scene.simulate(fields)
    with pytest.raises(ValueError, match="field values must have shape"):
        scene.simulate(np.moveaxis(smooth_field(grid), 0, -1))
