"""``invflame uncertainty``: σ per voxel of a tiny finished run, and clear refusals."""

import json

import numpy as np
import pytest
import xarray as xr

from invflame.cli import main
from invflame.experiments import config, runner

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "adam", "iterations": 4, "options": {"lr": 0.01}},
}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A tiny finished voxel run (state relation, Tikhonov, noisy data) with a truth."""
    folder = tmp_path_factory.mktemp("run")
    runner.run_experiment(config.validate(TINY), folder, progress=False)
    return folder


def test_writes_sigma_the_figures_and_the_calibration(finished, capsys):
    assert main(["uncertainty", str(finished), "--rank", "8", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert f"wrote {finished / 'uncertainty.nc'}" in out and "T, all voxels (512)" in out
    for name in ("uncertainty.nc", "uncertainty.png", "uncertainty_z.png", "uncertainty.json"):
        assert (finished / name).is_file(), name
    with xr.open_dataset(finished / "uncertainty.nc") as dataset:
        sigma_t = dataset["sigma_T"]
        assert sigma_t.attrs["units"] == "K"
        assert sigma_t.attrs["standard_name"] == "air_temperature standard_error"
        assert sigma_t.dims == ("z", "y", "x") and sigma_t.shape == (8, 8, 8)
        assert np.all(np.isfinite(sigma_t)) and float(sigma_t.min()) > 0
        assert {"sigma_X_CO2", "sigma_X_H2O", "reconstruction_T", "truth_T"} <= set(dataset)
    report = json.loads((finished / "uncertainty.json").read_text())
    assert report["settings"]["rank"] == 8 and len(report["eigenvalues"]) == 8
    assert report["prior"]["regularizer"] == "tikhonov" and report["prior"]["weight"] > 0
    shares = report["calibration"]["T"]["all"]
    assert shares["voxels"] == 512 and 0 <= shares["within_1sigma"] <= shares["within_2sigma"]
    assert not (finished / "INCOMPLETE").exists() and not (finished / ".lock").exists()


def test_a_folder_without_a_finished_run_is_refused_with_exit_2(tmp_path, capsys):
    assert main(["uncertainty", str(tmp_path / "missing")]) == 2
    assert "is not a folder" in capsys.readouterr().err
    assert main(["uncertainty", str(tmp_path)]) == 2
    assert "holds no summary.json" in capsys.readouterr().err


def test_a_run_whose_objective_is_no_posterior_is_refused(finished, tmp_path, capsys):
    copy = tmp_path / "paper"
    copy.mkdir()
    for path in finished.iterdir():
        (copy / path.name).write_bytes(path.read_bytes())
    text = (copy / "config.toml").read_text().replace('scaling = "chi2"', 'scaling = "paper"')
    (copy / "config.toml").write_text(text)
    assert main(["uncertainty", str(copy), "--quiet"]) == 2
    assert "regularizer.scaling = 'paper' weighs the misfit without the noise" in \
        capsys.readouterr().err
