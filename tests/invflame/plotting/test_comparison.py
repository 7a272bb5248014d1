"""Comparison grids and error maps at tiny size: layout, scales, values."""

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest

from invflame.experiments.metrics import normalized_mse
from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume
from invflame.plotting.comparison import plot_comparison, plot_errors
from invflame.plotting.fields import vertical_planes, vertical_section


def image_panels(fig):
    return [ax for ax in fig.axes if ax.images and ax.get_label() != "<colorbar>"]


def test_comparison_grid_rows_columns_scales_and_scores(tmp_path, plume_fields):
    truth, estimates = plume_fields
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
    shown, normal = vertical_planes(truth.grid)[1]
    np.testing.assert_array_equal(panels[1, 3].images[0].get_array(),
                                  vertical_section(estimates["start"]["CO2"], shown, normal, 1))
    assert panels[0, 0].collections, "isotherms on the temperature panels"
    assert panels[0, 0].get_ylabel().startswith("ground truth")
    plt.close(fig)


def test_error_maps_show_estimate_minus_truth_on_a_symmetric_scale(tmp_path, plume_fields):
    truth, estimates = plume_fields
    fig = plot_errors(truth, estimates, path=tmp_path / "e.png")
    assert matplotlib.image.imread(tmp_path / "e.png").shape[1] == 1600
    panels = np.array(image_panels(fig)).reshape(2, 6)
    for ax in panels.ravel():
        low, high = ax.images[0].get_clim()
        assert low == -high and high > 0
    shown, normal = vertical_planes(truth.grid)[0]
    np.testing.assert_allclose(
        panels[1, 0].images[0].get_array(),
        vertical_section(estimates["smoothed"].T - truth.T, shown, normal, 1), rtol=1e-6)
    assert panels[0, 0].get_title() == "T [K], x–y plane"  # no scores given: no MSE
    plt.close(fig)


def test_figures_refuse_estimates_on_another_grid(plume_fields):
    truth, _ = plume_fields
    other = synthetic_plume(VoxelGrid.poolfire(8))
    with pytest.raises(ValueError, match=r"'coarse' lies on grid \(8, 8, 8\)"):
        plot_comparison(truth, {"coarse": other})
    with pytest.raises(ValueError, match="at least one estimate"):
        plot_errors(truth, {})
    with pytest.raises(ValueError, match=r"unknown quantities \['NO'\]"):
        plot_comparison(truth, {"a": truth}, quantities=("T", "NO"))
