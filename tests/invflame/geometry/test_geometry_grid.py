"""VoxelGrid: spacing, centres, indexing, containment and validation."""

import numpy as np
import pytest

from invflame.geometry import VoxelGrid


@pytest.fixture
def grid():
    return VoxelGrid((-1.0, 0.0, 2.0), (1.0, 3.0, 2.5), (4, 6, 5))


def test_spacing_and_counts(grid):
    np.testing.assert_allclose(grid.spacing, [0.5, 0.5, 0.1])
    assert grid.n_voxels == 120
    np.testing.assert_allclose(grid.extent, [2.0, 3.0, 0.5])
    np.testing.assert_allclose(grid.centre, [0.0, 1.5, 2.25])


def test_axes_and_centres(grid):
    x, y, z = grid.axes()
    np.testing.assert_allclose(x, [-0.75, -0.25, 0.25, 0.75])
    assert y.shape == (6,) and z.shape == (5,)
    np.testing.assert_allclose(z[[0, -1]], [2.05, 2.45])
    c = grid.centres()
    assert c.shape == (4, 6, 5, 3)
    np.testing.assert_allclose(c[2, 3, 4], [x[2], y[3], z[4]])


def test_flat_index_matches_numpy_c_order(grid):
    ix, iy, iz = np.array([0, 3, 1]), np.array([5, 0, 2]), np.array([4, 1, 0])
    np.testing.assert_array_equal(
        grid.flat_index(ix, iy, iz), np.ravel_multi_index((ix, iy, iz), grid.shape)
    )
    assert grid.flat_index(1, 2, 3) == 1 * 30 + 2 * 5 + 3
    centres = grid.centres().reshape(-1, 3)
    np.testing.assert_allclose(centres[grid.flat_index(1, 2, 3)], grid.centres()[1, 2, 3])
    with pytest.raises(ValueError):
        grid.flat_index(4, 0, 0)


def test_contains(grid):
    pts = np.array([[0.0, 1.0, 2.2], [1.0, 3.0, 2.5], [1.01, 1.0, 2.2], [0.0, -0.1, 2.2]])
    np.testing.assert_array_equal(grid.contains(pts), [True, True, False, False])
    assert grid.contains(pts.reshape(2, 2, 3)).shape == (2, 2)
    with pytest.raises(ValueError, match="length 3"):
        grid.contains(np.zeros((3, 2)))


def test_corners(grid):
    c = grid.corners()
    assert c.shape == (8, 3)
    assert len({tuple(p) for p in c}) == 8
    assert np.all(grid.contains(c))
    np.testing.assert_allclose(c.min(axis=0), grid.lower)
    np.testing.assert_allclose(c.max(axis=0), grid.upper)


def test_poolfire_and_cube():
    g = VoxelGrid.poolfire()
    assert g.shape == (60, 60, 60) and g.up_axis == 1
    np.testing.assert_allclose(g.lower, [-0.5, 0.0, -0.5])
    np.testing.assert_allclose(g.upper, [0.5, 1.0, 0.5])
    np.testing.assert_allclose(g.spacing, 1 / 60)
    c = VoxelGrid.cube(8, size=2.0, centre=(1, 1, 1))
    np.testing.assert_allclose(c.lower, [0, 0, 0])
    np.testing.assert_allclose(c.upper, [2, 2, 2])
    assert c.shape == (8, 8, 8)


def test_frozen_equality_and_hash():
    a, b = VoxelGrid.poolfire(20), VoxelGrid.poolfire(20)
    assert a == b and hash(a) == hash(b)
    assert a != VoxelGrid.poolfire(21)
    assert {a: 1}[b] == 1
    with pytest.raises(AttributeError):
        a.shape = (1, 1, 1)
    with pytest.raises(ValueError):
        a.lower[0] = 5.0


@pytest.mark.parametrize(
    "lower, upper, shape, up_axis, match",
    [
        ((0, 0, 0), (1, 1, 0), (2, 2, 2), 1, "exceed"),
        ((0, 0), (1, 1), (2, 2, 2), 1, "3-vectors"),
        ((0, 0, 0), (1, 1, 1), (2, 0, 2), 1, "positive integers"),
        ((0, 0, 0), (1, 1, 1), (2, 2.5, 2), 1, "positive integers"),
        ((0, 0, 0), (1, 1, 1), (2, 2), 1, "positive integers"),
        ((0, 0, 0), (1, 1, 1), (2, 2, 2), 3, "up_axis"),
        ((0, 0, np.nan), (1, 1, 1), (2, 2, 2), 1, "finite"),
    ],
)
def test_validation(lower, upper, shape, up_axis, match):
    with pytest.raises(ValueError, match=match):
        VoxelGrid(lower, upper, shape, up_axis)
