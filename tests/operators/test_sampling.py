"""VoxelSampling: gather onto ray segments, scatter-add adjoint, JAX form."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import operators as op
from operators.sampling import VoxelSampling, sample_voxels

SHAPE = (3, 4, 5)


def voxels(seed=0, n_rays=7, n_seg=6):
    rng = np.random.default_rng(seed)
    voxel = rng.integers(0, np.prod(SHAPE), (n_rays, n_seg))
    voxel[:, -2:] = 0  # padding
    return voxel


def test_gather_picks_the_flat_c_order_voxels():
    voxel = voxels()
    fields = np.random.default_rng(1).standard_normal((4, *SHAPE))
    sampled = VoxelSampling(voxel, SHAPE)(fields)
    ix, iy, iz = np.unravel_index(voxel, SHAPE)
    np.testing.assert_array_equal(sampled, fields[:, ix, iy, iz])


@pytest.mark.parametrize("dtype, rtol", [(np.float64, 1e-13), (np.float32, 1e-5)])
def test_dot_test(dtype, rtol):
    sampling = VoxelSampling(voxels(), SHAPE, dtype=dtype)
    result = op.dottest(sampling, rtol=rtol)
    assert result.passed, result


def test_adjoint_adds_repeated_voxels():
    voxel = np.array([[5, 5, 0], [5, 2, 0]])
    sampling = VoxelSampling(voxel, SHAPE, n_fields=1)
    back = sampling.adjoint(np.ones((1, 2, 3))).reshape(-1)
    assert back[5] == 3 and back[2] == 1 and back[0] == 2 and back.sum() == 6


@pytest.mark.usefixtures("x64")
def test_jax_form_matches_and_its_vjp_is_the_adjoint():
    voxel = voxels(seed=2)
    sampling = VoxelSampling(voxel, SHAPE)
    rng = np.random.default_rng(3)
    fields, g = rng.standard_normal(sampling.dims), rng.standard_normal(sampling.dimsd)
    out, pullback = jax.vjp(lambda f: sample_voxels(f, jnp.asarray(voxel)), jnp.asarray(fields))
    np.testing.assert_array_equal(out, sampling(fields))
    np.testing.assert_allclose(pullback(jnp.asarray(g))[0], sampling.adjoint(g),
                               rtol=1e-13)


def test_bad_indices_are_reported():
    with pytest.raises(ValueError, match="voxel indices must lie in"):
        VoxelSampling(np.array([[0, 60]]), SHAPE)
    with pytest.raises(ValueError, match="integer array"):
        VoxelSampling(np.zeros((2, 2)), SHAPE)
