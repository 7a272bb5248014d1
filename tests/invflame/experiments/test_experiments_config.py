"""Experiment configuration: defaults, round trip, and errors that name the bad key."""

import numpy as np
import pytest

from invflame.experiments import config
from invflame.experiments.metrics import normalized_mse, psnr


def test_defaults_and_partial_override(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text('[solver]\nname = "gd"\noptions = { max_step = 0.5 }\n[regularizer]\n'
                    'kind = "tv"\n')
    cfg = config.load(path)
    assert cfg["solver"]["name"] == "gd" and cfg["solver"]["options"] == {"max_step": 0.5}
    assert cfg["regularizer"] == {"kind": "tv", "lambda": 1e-3, "scaling": "chi2",
                                  "lambda_range": [1e-3, 1e2], "tau": 1.0}
    assert cfg["rig"]["focal_length"] == 0.59
    path.write_text(config.dumps(cfg))
    assert config.load(path) == cfg


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[solvr]\nname = 'gd'\n", r"unknown key 'solvr' \(did you mean 'solver'\?\)"),
        ("[regularizer]\nkind = 'tvv'\n", r"'regularizer.kind' = 'tvv' is not allowed.*tikhonov"),
        ("[truth]\ngrid = -3\n", r"'truth.grid' must be positive"),
        ("[truth]\ngrid = 'big'\n", r"'truth.grid' must be an integer"),
        ("[spectrum]\nmin = 800.0\n", r"'spectrum.min' must be below"),
        ("[solver\n", r"malformed TOML"),
        ("[init]\nambient = [300.0, 0.5, 0.6, 0.0]\n", r"'init.ambient' must be"),
        ("[init]\nambient = [300.0, 0.0]\n", r"'init.ambient' must be a list of 4 numbers"),
        ("[rig]\nrays_per_pixel = 8\n", r"'rig.rays_per_pixel' must be a perfect square"),
    ],
)
def test_errors_name_the_bad_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(config.ConfigError, match=message):
        config.load(path)


def test_missing_file():
    with pytest.raises(FileNotFoundError, match="configuration file not found"):
        config.load("/nonexistent/run.toml")


def test_normalized_mse_uses_the_truth_range():
    truth = np.zeros((4, 2, 2, 2))
    truth[0] = [[[300, 500], [700, 900]], [[300, 500], [700, 900]]]
    truth[1, 0] = 0.1
    estimate = truth.copy()
    estimate[0] += 60.0  # 10 % of the 600 K range everywhere
    mse = normalized_mse(truth, estimate)
    assert mse["T"] == pytest.approx(0.01)
    assert mse["CO2"] == 0.0
    assert "H2O" not in mse  # constant in the truth: no range to normalize by
    assert psnr(truth, estimate)["T"] == pytest.approx(20.0)
    with pytest.raises(ValueError, match="differ in shape"):
        normalized_mse(truth, estimate[:3])


def test_hot_volume_ratio_flags_a_lost_flame():
    from invflame.experiments.metrics import hot_volume_ratio

    truth = np.full((4, 4, 4, 4), 300.0)
    truth[0, 1:3, 1:3, 1:3] = 1200.0
    assert hot_volume_ratio(truth, truth) == 1.0
    assert hot_volume_ratio(truth, np.full_like(truth, 300.0)) == 0.0
    with pytest.raises(ValueError, match="no voxel above"):
        hot_volume_ratio(np.full_like(truth, 300.0), truth)
