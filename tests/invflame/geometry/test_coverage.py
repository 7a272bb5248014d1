"""Ray coverage of a grid: sub-rays per pixel reach the voxels that centre rays miss."""

import numpy as np
import pytest

from invflame.geometry import VoxelGrid, paper_rig, ray_coverage, traverse


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
