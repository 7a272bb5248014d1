"""One reconstruction end to end on a tiny scene: outputs, metrics, resume, bad input."""

import json

import numpy as np
import pytest

from invflame.experiments import config, reproduce, runner
from invflame.field import Field

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "adam", "iterations": 6, "options": {"lr": 0.01}},
}


def tiny(**sections):
    settings = {**TINY, **sections}
    return config.validate(settings)


def test_run_writes_every_output_and_lowers_the_loss(tmp_path):
    summary = runner.run_experiment(tiny(regularizer={"kind": "tv"}), tmp_path, progress=False)
    for name in ("config.toml", "summary.json", "history.csv", "truth.npz", "initial.npz",
                 "reconstruction.npz", "data.npz", "checkpoint.npz", "log.txt"):
        assert (tmp_path / name).is_file(), name
    assert summary["loss"]["final"] < summary["loss"]["initial"]
    assert set(summary["mse"]) >= {"T", "CO2", "H2O"}
    assert json.loads((tmp_path / "summary.json").read_text())["iterations"] == 6
    recon = Field.load(tmp_path / "reconstruction.npz")
    assert recon.values.shape == (4, 8, 8, 8)
    assert config.load(tmp_path / "config.toml") == tiny(regularizer={"kind": "tv"})


def test_interrupted_run_resumes_to_the_same_result(tmp_path):
    cfg = tiny()
    full = runner.run_experiment(cfg, tmp_path / "full", progress=False)
    short = dict(cfg, solver=dict(cfg["solver"], iterations=3))
    runner.run_experiment(short, tmp_path / "cut", progress=False)
    (tmp_path / "cut" / "summary.json").unlink()  # as if killed after the checkpoint
    resumed = runner.run_experiment(cfg, tmp_path / "cut", resume=True, progress=False)
    assert resumed["iterations"] == full["iterations"]
    a = np.load(tmp_path / "full" / "reconstruction.npz")["values"]
    b = np.load(tmp_path / "cut" / "reconstruction.npz")["values"]
    np.testing.assert_allclose(a, b, rtol=1e-6)


def test_unknown_truth_file_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="neither 'poolfire', 'synthetic'"):
        runner.run_experiment(tiny(truth={"grid": 8, "source": "nope.npz"}), tmp_path,
                              progress=False)


def test_reproduce_writes_table_and_figures(tmp_path, monkeypatch):
    monkeypatch.setitem(reproduce.PRESETS, "tiny", {
        "truth": {"grid": 8}, "rig": {"pixels": 4},
        "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1}, "epochs": 3})
    rows = reproduce.reproduce("tiny", tmp_path, progress=False,
                               methods=["VG/NR", "VG/TV"])
    assert [r["method"] for r in rows] == ["VG/NR", "VG/TV"]
    assert rows[0]["paper_MSE_T"] == 0.0295
    for name in ("table.md", "table.csv", "table.json", "cutaways.png", "loss_curves.png",
                 "spectrum_image.png"):
        assert (tmp_path / name).is_file(), name
    text = (tmp_path / "table.md").read_text()
    assert "| VG/TV |" in text and "qualitative findings" in text


@pytest.mark.parametrize(("solver", "regularizer"), [("gauss-newton", "tikhonov"),
                                                      ("pdhg", "tv")])
def test_forward_mode_solvers_run_through_the_runner(tmp_path, solver, regularizer):
    cfg = tiny(solver={"name": solver, "iterations": 2, "options": {"inner_iter": 5}},
               regularizer={"kind": regularizer})
    summary = runner.run_experiment(cfg, tmp_path, progress=False)
    assert summary["loss"]["final"] < summary["loss"]["initial"]


@pytest.mark.parametrize("kind", ["neural", "neural-centres"])
def test_neural_representations_run_through_the_runner(tmp_path, kind):
    cfg = tiny(representation={"kind": kind, "hidden": 16, "layers": 2, "coarse_samples": 8,
                               "fine_samples": 8, "rays_per_batch": 32,
                               "pretrain_iterations": 20},
               solver={"name": "adam", "iterations": 3, "options": {"lr": 1e-3}})
    summary = runner.run_experiment(cfg, tmp_path, progress=False)
    assert np.isfinite(summary["loss"]["final"])
    assert summary["parameter_memory_mb"] > 0
    assert Field.load(tmp_path / "reconstruction.npz").values.shape == (4, 8, 8, 8)
