"""Experiment configuration: defaults, round trip, and errors that name the bad key."""

import numpy as np
import pytest

from invflame.experiments import config
from invflame.experiments.metrics import normalized_mse, psnr


def test_defaults_and_partial_override(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text('[solver]\nname = "gd"\noptions = { step = 0.5 }\n[regularizer]\n'
                    'kind = "tv"\n')
    cfg = config.load(path)
    assert cfg["solver"]["name"] == "gd" and cfg["solver"]["options"] == {"step": 0.5}
    assert cfg["regularizer"] == {"kind": "tv", "lambda": 30.0, "scaling": "chi2",
                                  "lambda_range": [1e-3, 1e2], "tau": 1.0, "tv_smoothing": 0.0}
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
        ("seed = -3\n", r"'seed' must be a non-negative integer, got -3"),
        ("[solver]\nname = 'adam'\noptions = { lr = '0.01' }\n",
         r"'solver.options.lr' must be a number, got '0.01' \(write lr = 0.01 without quotes"),
        ("[solver]\noptions = { max_iter = 5 }\n",
         r"'solver.options.max_iter' clashes with 'solver.iterations'"),
        ("[solver]\nname = 'adam'\noptions = { lr = -1.0 }\n",
         r"'solver.options' = \{'lr': -1.0\}: .*lr"),
        ("[solver]\nname = 'adamm'\n", r"'solver.name': .*Did you mean 'adam'"),
        ("[spectrum]\nstep = 100\n", r"'spectrum.step' = 100.0 cm-1 must be at most half of "
                                     r"'instrument.resolution' = 8.0"),
        ("[instrument]\nsampling = 1000\n", r"'instrument.sampling' = 1000.0 cm-1 leaves 1 "
                                            r"output point"),
        ("[spectrum]\nmin = 660.0\nmax = 670.0\n",
         r"narrower than twice the resolution 8 cm-1"),
        ("[rig]\ndistance = 0.3\n",
         r"'rig.distance' = 0.3: camera distance 0.3 m puts the cameras inside the grid"),
        ("[init]\nnoise = 5\n", r"'init.noise' .* must be in \[0, 1\] .*got 5.0"),
        ("[spectrum]\nmin = 900.0\nmax = 940.0\n",
         r"'spectrum.min'..'spectrum.max' = 900-940 cm-1 holds no absorption line"),
        ("[truth]\ngrid = 1\n", r"'truth.grid' must be at least 4 voxels per axis .*got 1"),
        ("[spectrum]\nmax = nan\n", r"'spectrum.max' must be a finite number, got nan"),
        ("[noise]\nnesr = 'no_such_nesr.txt'\n",
         r"'noise.nesr' = 'no_such_nesr.txt' is neither a number nor an existing file"),
        ("[rig]\ndistance = 0\n", r"'rig.distance' \(m\) must be a positive number, got 0.0; "
                                r"the default is `distance = 1.5` in \[rig\]$"),
        ("[regularizer]\ntau = 0\n",
         r"'regularizer.tau' must be positive: at least 1 or 'model-error', got 0.0"),
        ("[regularizer]\nlambda = 'discrepncy'\n",
         r"'regularizer.lambda' = 'discrepncy' is not allowed \(did you mean 'discrepancy'\?\); "
         r"allowed: a non-negative number or 'discrepancy'"),
        ("[regularizer]\nlambda_range = [1e-3, inf]\n",
         r"'regularizer.lambda_range' must be finite numbers, got \[0.001, inf\]"),
        ("[data]\ninverse_crime = 1\n", r"'data.inverse_crime' must be true or false, got 1"),
        ("[representation]\ndevice = 'gpu'\n", r"'representation.device' must be 'auto', "
                                              r"'cpu', 'cuda' or 'cuda:N' .*got 'gpu'"),
        ("[init]\nnoise = -0.1\n", r"'init.noise' \(fraction of each field's range\) must be in "
                                 r"\[0, 1\] \(the paper's 0.2\), got -0.1"),
    ],
)
def test_errors_name_the_bad_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(config.ConfigError, match=message):
        config.load(path)


def test_a_utf16_file_is_named(tmp_path):
    path = tmp_path / "utf16.toml"
    path.write_bytes("seed = 1\n".encode("utf-16"))
    with pytest.raises(config.ConfigError, match=r"utf16.toml: not UTF-8 text"):
        config.load(path)


def test_a_utf8_file_with_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes("seed = 3\n".encode("utf-8-sig"))  # as some Windows editors save it
    assert config.load(path)["seed"] == 3


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


def test_the_networks_device_resolves_here_or_says_what_is_missing():
    import jax
    import torch

    from invflame.experiments.parameters import torch_device

    on_gpu = jax.default_backend() == "gpu" and torch.cuda.is_available()
    assert torch_device("auto") == ("cuda" if on_gpu else "cpu")
    assert torch_device("cpu") == "cpu"
    if not on_gpu:
        with pytest.raises(ValueError, match=r"representation.device = 'cuda:1', but here torch "
                                             r".* both need the GPU .* or set device = 'auto'"):
            torch_device("cuda:1")
