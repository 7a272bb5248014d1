"""The model error from prior flames: zero where the fine model adds nothing, and it sets τ."""

import json

import numpy as np
import pytest

from invflame.experiments import config, runner
from invflame.experiments.model_error import PRIOR_RANGES, estimate_model_error, prior_flames
from invflame.field import Field
from invflame.geometry import VoxelGrid

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "lbfgs", "iterations": 3},
}


def test_prior_flames_are_drawn_in_their_ranges_and_repeat_with_the_seed():
    grid = VoxelGrid.poolfire(6)
    drawn = prior_flames(grid, 3, seed=4)
    assert len(drawn) == 3
    for parameters, flame in drawn:
        assert flame.grid == grid
        for key, (low, high) in PRIOR_RANGES.items():
            assert low <= parameters[key] <= high
    again = prior_flames(grid, 3, seed=4)
    assert [p for p, _ in again] == [p for p, _ in drawn]
    np.testing.assert_array_equal(again[2][1].values, drawn[2][1].values)
    assert [p for p, _ in prior_flames(grid, 3, seed=5)] != [p for p, _ in drawn]
    with pytest.raises(ValueError, match="n_flames must be a positive integer"):
        prior_flames(grid, 0, seed=0)


@pytest.fixture(scope="module")
def tiny():
    cfg = config.validate(dict(TINY, data={"rays_per_pixel": 9, "step_divisor": 1}))
    scene = runner.build_scene(cfg)
    return cfg, scene, runner.measure(cfg, scene, runner.load_truth(cfg))


def test_a_flame_constant_in_each_voxel_has_no_model_error_and_a_plume_has(tiny):
    """Same sub-rays and line-by-line step in both models: a flame uniform inside each
    reconstruction voxel renders the same on the fine grid (a homogeneous segment split in
    two), while a plume's structure inside the voxels makes a model error."""
    cfg, scene, measurement = tiny
    assert scene.rays_per_pixel == 9
    coarse = runner.load_truth(cfg).resample(scene.grid)
    fine_grid = VoxelGrid(scene.grid.lower, scene.grid.upper,
                          tuple(2 * n for n in scene.grid.shape), scene.grid.up_axis)
    blocky = Field(fine_grid, coarse.values.repeat(2, 1).repeat(2, 2).repeat(2, 3))
    plumes = prior_flames(fine_grid, 2, seed=1)
    error = estimate_model_error(cfg, scene, measurement, flames=[({"name": "blocky"}, blocky),
                                                                  *plumes])
    blocky_level, *plume_levels = error.chi2_per_value
    assert blocky_level < 1e-3  # a thousandth of the noise: float32 round-off only
    assert min(plume_levels) > 1e3 * max(blocky_level, 1e-9)
    assert error.tau == pytest.approx(1 + np.mean(error.chi2_per_value))
    assert json.loads(json.dumps(error.as_dict()))["flames"][0] == {"name": "blocky"}


def test_model_error_tau_chooses_lambda_with_the_discrepancy_principle(tmp_path):
    cfg = config.validate(dict(TINY, regularizer={
        "kind": "tikhonov", "lambda": "discrepancy", "tau": "model-error",
        "lambda_range": [1e-2, 1e2]}))
    summary = runner.run_experiment(cfg, tmp_path, progress=False)
    saved = json.loads((tmp_path / "model_error.json").read_text())
    assert len(saved["chi2_per_value"]) == 6 and saved["tau"] > 1
    choice = json.loads((tmp_path / "lambda_choice.json").read_text())
    assert choice["target"] == pytest.approx(saved["tau"] * choice["n_measurements"])
    assert summary["lambda"] == pytest.approx(choice["lam"])
    assert "tau = " in (tmp_path / "log.txt").read_text()
