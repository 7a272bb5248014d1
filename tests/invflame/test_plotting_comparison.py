"""Comparison grids, error maps and 3-D isotherm figures at tiny size: layout, scales, values."""

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest

from invflame.experiments.figures import field_figures, run_fields
from invflame.experiments.metrics import normalized_mse, smoothed
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume
from invflame.plotting.comparison import plot_comparison, plot_errors
from invflame.plotting.fields import vertical_planes, vertical_section
from invflame.plotting.isosurfaces import isotherm_surface, plot_isotherms_3d, shown_box

GRID = VoxelGrid.poolfire(10)


@pytest.fixture(scope="module")
def fields():
    truth = synthetic_plume(GRID)
    return truth, {"start": synthetic_plume(GRID, perturbation=0.3, seed=0),
                   "smoothed": Field(GRID, smoothed(truth.values, 1.0))}


def image_panels(fig):
    return [ax for ax in fig.axes if ax.images and ax.get_label() != "<colorbar>"]


def test_comparison_grid_rows_columns_scales_and_scores(tmp_path, fields):
    truth, estimates = fields
    scores = {k: normalized_mse(truth.values, f.values) for k, f in estimates.items()}
    fig = plot_comparison(truth, estimates, scores, path=tmp_path / "c.png")
    height, width, _ = matplotlib.image.imread(tmp_path / "c.png").shape
    assert width == 1600 and height > 600
    panels = np.array(image_panels(fig)).reshape(3, 6)  # truth + 2 estimates x (3 fields x 2)
    assert len(fig.axes) == 18 + 3  # one colour bar per quantity
    for q, name in enumerate(("T", "CO2", "H2O")):
        for ax in panels[:, 2 * q:2 * q + 2].ravel():  # one scale per quantity: the truth's
            assert ax.images[0].get_clim() == pytest.approx(
                (truth[name].min(), truth[name].max()))
        assert panels[2, 2 * q].get_title() == f"MSE {scores['smoothed'][name]:.4f}"
        assert "x–y plane" in panels[0, 2 * q].get_title()
        assert "z–y plane" in panels[0, 2 * q + 1].get_title()
    # the panel shows the mid-plane of its row's field, vertical axis up
    shown, normal = vertical_planes(GRID)[1]
    np.testing.assert_array_equal(panels[1, 3].images[0].get_array(),
                                  vertical_section(estimates["start"]["CO2"], shown, normal, 1))
    assert panels[0, 0].collections, "isotherms on the temperature panels"
    assert panels[0, 0].get_ylabel().startswith("ground truth")
    plt.close(fig)


def test_error_maps_show_estimate_minus_truth_on_a_symmetric_scale(tmp_path, fields):
    truth, estimates = fields
    fig = plot_errors(truth, estimates, path=tmp_path / "e.png")
    assert matplotlib.image.imread(tmp_path / "e.png").shape[1] == 1600
    panels = np.array(image_panels(fig)).reshape(2, 6)
    for ax in panels.ravel():
        low, high = ax.images[0].get_clim()
        assert low == -high and high > 0
    shown, normal = vertical_planes(GRID)[0]
    np.testing.assert_allclose(
        panels[1, 0].images[0].get_array(),
        vertical_section(estimates["smoothed"].T - truth.T, shown, normal, 1), rtol=1e-6)
    assert panels[0, 0].get_title() == "T [K], x–y plane"  # no scores given: no MSE
    plt.close(fig)


def test_figures_refuse_estimates_on_another_grid(fields):
    truth, _ = fields
    other = synthetic_plume(VoxelGrid.poolfire(8))
    with pytest.raises(ValueError, match=r"'coarse' lies on grid \(8, 8, 8\)"):
        plot_comparison(truth, {"coarse": other})
    with pytest.raises(ValueError, match="at least one estimate"):
        plot_errors(truth, {})
    with pytest.raises(ValueError, match=r"unknown quantities \['NO'\]"):
        plot_comparison(truth, {"a": truth}, quantities=("T", "NO"))


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


def test_shown_box_covers_the_hot_voxels_with_a_margin():
    grid = VoxelGrid.cube(10)
    values = np.zeros((4, 10, 10, 10), dtype=np.float32)
    values[0] = 300.0
    values[0, 4:6, 2:5, 5] = 900.0
    field = Field(grid, values)
    lower, upper = shown_box([field], 500.0, margin=1)
    np.testing.assert_allclose(lower, grid.lower + grid.spacing * [3, 1, 4])
    np.testing.assert_allclose(upper, grid.lower + grid.spacing * [7, 6, 7])
    cold = Field(grid, np.where(values > 0, 300.0, 0.0).astype(np.float32))
    lower, upper = shown_box([cold], 500.0)
    np.testing.assert_array_equal(lower, grid.lower)
    np.testing.assert_array_equal(upper, grid.upper)


def test_isotherms_3d_has_one_panel_per_field_set_and_a_level_colour_bar(tmp_path, fields):
    truth, estimates = fields
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


def test_field_figures_of_run_folders(tmp_path, fields):
    truth, estimates = fields
    for method in ("VG-TV", "NN-TV"):
        folder = tmp_path / method
        folder.mkdir()
        truth.save(folder / "truth.npz")
        estimates["start"].save(folder / "initial.npz")
        estimates["smoothed"].save(folder / "reconstruction.npz")
    loaded_truth, loaded = run_fields({m: tmp_path / m for m in ("VG-TV", "NN-TV")})
    assert list(loaded) == ["start", "VG-TV", "NN-TV"]
    np.testing.assert_array_equal(loaded_truth.values, truth.values)
    written = field_figures(tmp_path, loaded_truth, loaded)
    assert [p.name for p in written] == ["cutaways.png", "errors.png", "isotherms_3d.png"]
    rows = {p.name: matplotlib.image.imread(p).shape for p in written}
    assert all(shape[1] == 1600 for shape in rows.values())
    # four rows of cutaways (truth, start, two methods) against three rows of errors
    assert rows["cutaways.png"][0] > rows["errors.png"][0]
