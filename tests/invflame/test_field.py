"""Field: validation, accessors, .npz round trip and resampling."""

import numpy as np
import pytest

from invflame.field import FIELD_NAMES, Field, hot_extent, resample_values
from invflame.geometry import VoxelGrid


def random_values(grid, seed=0):
    rng = np.random.default_rng(seed)
    t = rng.uniform(300, 1800, grid.shape)
    x = rng.dirichlet([1, 1, 1, 2], size=grid.shape)[..., :3]  # leave room for the rest
    return np.concatenate([t[None], np.moveaxis(x, -1, 0)]).astype(np.float32)


@pytest.fixture
def grid():
    return VoxelGrid((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5), (4, 6, 2))


def test_accessors_and_names(grid):
    values = random_values(grid)
    field = Field(grid, values, {"source": "test"})
    assert Field.names == FIELD_NAMES == ("T", "CO2", "H2O", "CH4")
    assert field.values.dtype == np.float32
    np.testing.assert_array_equal(field.T, values[0])
    np.testing.assert_array_equal(field.X("H2O"), values[2])
    np.testing.assert_array_equal(field["CH4"], values[3])
    with pytest.raises(KeyError, match="unknown species 'CO'"):
        field.X("CO")
    with pytest.raises(ValueError):
        field.values[0, 0, 0, 0] = 1.0  # read-only


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda v: v[:, :-1], "must have shape"),
        (lambda v: v.__setitem__((1, 0, 0, 0), np.nan) or v, r"NaN or inf in \['CO2'\]"),
        (lambda v: v.__setitem__((0, 1, 1, 1), 0.0) or v, "temperature must be > 0 K"),
        (lambda v: v.__setitem__((3, 0, 0, 0), -0.1) or v, "X_CH4 must lie in"),
        (lambda v: v.__setitem__((2, 0, 0, 0), 1.5) or v, "X_H2O must lie in"),
        (lambda v: v.__setitem__((slice(1, 4), 0, 0, 0), 0.5) or v, "sum to at most 1"),
    ],
)
def test_invalid_values_are_refused_with_reason(grid, change, message):
    values = change(random_values(grid))
    with pytest.raises(ValueError, match=message):
        Field(grid, values)


def test_save_load_round_trip_is_atomic_and_validated(grid, tmp_path):
    field = Field(grid, random_values(grid), {"source": "test", "time": 0.9})
    path = field.save(tmp_path / "sub" / "f.npz")
    assert sorted(p.name for p in path.parent.iterdir()) == ["f.npz"]  # no temporary left
    loaded = Field.load(path)
    assert loaded.grid == grid
    np.testing.assert_array_equal(loaded.values, field.values)
    assert loaded.metadata == {"source": "test", "time": 0.9}
    with np.load(path) as data:
        np.testing.assert_allclose(data["spacing"], grid.spacing)
        assert int(data["up_axis"]) == 1

    bad = dict(np.load(path))
    bad["values"] = bad["values"].copy()
    bad["values"][0, 0, 0, 0] = -5.0
    np.savez(tmp_path / "bad.npz", **bad)
    with pytest.raises(ValueError, match="bad.npz: temperature must be > 0 K"):
        Field.load(tmp_path / "bad.npz")
    np.savez(tmp_path / "other.npz", values=bad["values"])
    with pytest.raises(ValueError, match="missing"):
        Field.load(tmp_path / "other.npz")


def test_block_average_with_uniform_temperature_is_the_block_mean():
    fine = VoxelGrid.poolfire(12)
    values = random_values(fine, seed=1)
    values[0] = 1000.0
    coarse = VoxelGrid.poolfire(4)
    out = resample_values(values, fine, coarse)
    block = values.reshape(4, 4, 3, 4, 3, 4, 3).mean(axis=(2, 4, 6))
    np.testing.assert_allclose(out, block, rtol=1e-5)


def test_resampling_conserves_moles_of_each_species():
    """Σ V c X_s and Σ V c (c = 1/T up to p/R) agree between grids, integer factor or not."""
    fine = VoxelGrid.poolfire(12)
    values = random_values(fine, seed=2).astype(np.float64)

    def moles(a, g):
        return np.prod(g.spacing) * np.array([np.sum(1 / a[0])] + [np.sum(x / a[0]) for x in a[1:]])

    reference = moles(values, fine)
    for coarse in (VoxelGrid.poolfire(4), VoxelGrid.poolfire(5)):
        out = resample_values(values, fine, coarse).astype(np.float64)
        np.testing.assert_allclose(moles(out, coarse), reference, rtol=1e-5)


def test_resample_general_overlap_and_refinement(grid):
    field = Field(grid, random_values(grid, seed=3))
    sub = VoxelGrid((-0.25, 0.5, -0.5), (0.25, 1.0, 0.5), (2, 3, 2))
    out = field.resample(sub)
    np.testing.assert_allclose(out.values, field.values[:, 1:3, 3:6, :], rtol=1e-6)
    fine = field.resample(VoxelGrid((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5), (8, 12, 4)))
    np.testing.assert_allclose(fine.values[:, ::2, ::2, ::2], field.values, rtol=1e-6)
    assert fine.metadata["resampled_from"] == [4, 6, 2]
    assert field.resample(grid) is field  # its own grid: nothing to average
    with pytest.raises(ValueError, match="must lie inside the source box"):
        field.resample(VoxelGrid.cube(4, size=2.0))


def test_hot_extent_bounds_the_hot_voxels(grid):
    values = random_values(grid)
    values[0] = 300.0
    values[0, 1, 2:4, 0] = 900.0
    lo, hi = hot_extent(Field(grid, values), 500.0)
    axes = grid.axes()
    np.testing.assert_allclose(lo, [axes[0][1], axes[1][2], axes[2][0]])
    np.testing.assert_allclose(hi, [axes[0][1], axes[1][3], axes[2][0]])
    assert hot_extent(Field(grid, values), 1000.0) == (None, None)
