"""Pixels are areas: a pixel's spectrum is the mean of its sub-rays; fields are checked
before they are simulated."""

import numpy as np
import pytest

import operators as op
from invflame.geometry import VoxelGrid, paper_rig
from invflame.scene import Scene

from .test_scene import small_table, smooth_field


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
