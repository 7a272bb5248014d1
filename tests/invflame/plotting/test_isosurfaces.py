"""3-D isotherm figures at tiny size: the surfaces, the grid box on every panel, one panel per
field set."""

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest

from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.plotting.isosurfaces import isotherm_surface, plot_isotherms_3d


def ramp(grid: VoxelGrid) -> Field:
    """T rising linearly along x from 300 to 1800 K, no species."""
    values = np.zeros((4, *grid.shape), dtype=np.float32)
    x = grid.axes()[0]
    values[0] = (300.0 + 1500.0 * (x - x[0]) / (x[-1] - x[0]))[:, None, None]
    return Field(grid, values)


def test_isotherm_surface_lies_on_the_level_and_the_cut_removes_a_quarter():
    grid = VoxelGrid((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5), (11, 6, 8))
    field = ramp(grid)
    x = grid.axes()[0]
    at = x[0] + (1200.0 - 300.0) / 1500.0 * (x[-1] - x[0])  # where T = 1200 K: x > 0
    whole = isotherm_surface(field, 1200.0, cut=False)
    assert len(whole) > 0 and at > 0
    # a plane x = at, to the float32 rounding of T (6e-5 K over 1650 K/m: 4e-8 m)
    np.testing.assert_allclose(whole[..., 0], at, atol=1e-6)
    centres = grid.axes()
    assert whole[..., 1].min() == pytest.approx(centres[1][0])
    assert whole[..., 2].max() == pytest.approx(centres[2][-1])
    cut = isotherm_surface(field, 1200.0)  # the plane x = at > 0 loses its z < 0 half
    middle = cut.mean(axis=1)
    assert np.all(middle[:, 2] >= 0) and 0 < len(cut) < len(whole)
    assert isotherm_surface(field, 2000.0).shape == (0, 3, 3)  # outside the range: nothing
    values = np.full((4, *grid.shape), 300.0, dtype=np.float32)
    values[1:] = 0.0
    values[0, 5, 3, 3] = 900.0  # one hot voxel, between the voxels a step of 2 samples
    assert isotherm_surface(Field(grid, values), 600.0, step=2).shape == (0, 3, 3)
    assert len(isotherm_surface(Field(grid, values), 600.0, step=1, cut=False)) > 0


def test_every_panel_shows_the_whole_grid_box():
    grid = VoxelGrid((-0.5, 0.0, -0.5), (0.5, 1.0, 0.5), (11, 6, 8))
    values = np.full((4, *grid.shape), 300.0, dtype=np.float32)
    values[1:] = 0.0
    corner = values.copy()
    corner[0, :3, :2, :3] = 1200.0  # hot in one corner only
    fig = plot_isotherms_3d({"truth": ramp(grid), "corner": Field(grid, corner),
                             "cold": Field(grid, values)})
    panels = [ax for ax in fig.axes if ax.name == "3d"]
    order = (0, 2, 1)  # horizontal, horizontal, up (y)
    for ax in panels:
        limits = (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())
        for (low, high), a in zip(limits, order, strict=True):
            assert (low, high) == pytest.approx((grid.lower[a], grid.upper[a]))
    plt.close(fig)
    with pytest.raises(ValueError, match=r"field sets \['coarse'\] lie on another grid"):
        plot_isotherms_3d({"truth": ramp(grid), "coarse": ramp(VoxelGrid.cube(4))})


def test_isotherms_3d_has_one_panel_per_field_set_and_a_level_colour_bar(tmp_path, plume_fields):
    truth, estimates = plume_fields
    fig = plot_isotherms_3d({"truth": truth, **estimates}, path=tmp_path / "i.png",
                            scores={"smoothed": 0.0123}, columns=2)
    height, width, _ = matplotlib.image.imread(tmp_path / "i.png").shape
    assert width == 1600 and height > width  # 2 x 2 panels, one empty
    panels = [ax for ax in fig.axes if ax.name == "3d"]
    assert [ax.get_title() for ax in panels] == ["truth", "start", "smoothed\nMSE_T 0.0123"]
    assert all(ax.collections for ax in panels)  # the plume is hotter than 500 K
    bar = next(ax for ax in fig.axes if ax.name != "3d")
    np.testing.assert_allclose(bar.get_xticks(), np.arange(500.0, 1600.0, 100.0))
    plt.close(fig)
    with pytest.raises(ValueError, match="at least two increasing temperatures"):
        plot_isotherms_3d({"truth": truth}, levels=[900.0, 600.0])
