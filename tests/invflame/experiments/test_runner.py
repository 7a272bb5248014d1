"""One reconstruction end to end on a tiny scene: outputs, metrics, resume, bad input."""

import json
import os
import re

import jax
import numpy as np
import pytest
import torch

import solvers
from invflame.experiments import comparison_table, config, reproduce, runner
from invflame.experiments.machine import describe_machine, in_words
from invflame.experiments.parameters import subvoxel_emission
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
    stages = json.loads((tmp_path / "summary.json").read_text())["stages"]
    assert list(stages) == ["inputs, tables and scene", "data", "start", "solve", "outputs"]
    assert all(seconds >= 0 for seconds in stages.values()) and stages["solve"] > 0
    assert "time by stage: inputs, tables and scene " in (tmp_path / "log.txt").read_text()


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
    with pytest.raises(config.ConfigError, match="'truth.source' = 'nope.npz' is neither "
                                                 "'poolfire', 'synthetic'"):
        tiny(truth={"grid": 8, "source": "nope.npz"})
    gone = tiny()  # a file removed after its configuration was checked
    gone["truth"]["source"] = "nope.npz"
    with pytest.raises(FileNotFoundError, match="neither 'poolfire', 'synthetic'"):
        runner.run_experiment(gone, tmp_path, progress=False)


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
    assert "| VG/TV |" in text and "Checked on this run" in text
    assert f"- VG/NR, VG/TV: {in_words(describe_machine())}" in text
    for baseline in ("*start*", "*start smoothed (σ = 1 voxel)*", "*ambient air (flat)*"):
        assert baseline in text
    assert "ground truth + 0.2 relative Gaussian noise" in text  # the paper's start, said
    table = json.loads((tmp_path / "table.json").read_text())
    assert table["protocol"] == "paper" and len(table["baselines"]) == 3
    assert all(b["kind"].startswith("no data") for b in table["baselines"])


def test_findings_are_true_of_the_rows():
    rows = [{"method": "VG/NR", "MSE_T": 0.02, "MSE_T_initial": 0.01, "converged": True,
             "hot_volume_ratio": 1.0},
            {"method": "VG/TV", "MSE_T": 0.004, "MSE_T_initial": 0.01, "converged": False,
             "hot_volume_ratio": 0.3}]
    baselines = [{"method": "ambient air (flat)", "kind": "no data", "MSE_T": 0.012}]
    text = comparison_table.findings(rows, baselines)
    assert "VG/NR beats the best no-data baseline (ambient air (flat), MSE_T 0.0120) by " \
        "0.60x: NO" in text
    assert "VG/TV beats the best no-data baseline (ambient air (flat), MSE_T 0.0120) by " \
        "3.00x: yes" in text
    assert "worse than their start: VG/NR: NO" in text
    assert "lost or distorted: VG/TV: NO" in text
    assert "stopped by the limit: VG/TV: NO" in text


def test_run_summary_says_what_made_the_result(tmp_path):
    summary = runner.run_experiment(tiny(), tmp_path, progress=False)
    made = summary["protocol"]
    assert "knows nothing of the truth" in made["start"]
    assert "fitted to the spectra" in made["start"]
    assert "state relation's progress" in made["unknowns"]
    assert "60x60x60 grid, 25 sub-rays/pixel" in made["data"] and "NESR" in made["noise"]
    assert set(summary["coverage"]) == {"voxels", "common_view", "hot"}
    assert summary["coverage"]["voxels"] == 1.0  # 3 x 3 sub-rays see every voxel
    assert summary["chi2_per_measurement"]["final"] > 0
    assert set(summary["mse_flame"]) >= {"T", "CO2", "H2O"}
    data = np.load(tmp_path / "data.npz")
    assert data["sigma"].shape == data["out_wavenumber"].shape
    assert summary["machine"] == describe_machine()  # a voxel run: torch not named
    assert f"computing on: {in_words(summary['machine'])}" in (tmp_path / "log.txt").read_text()


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


def test_discrepancy_rule_chooses_lambda_from_the_data(tmp_path):
    cfg = tiny(regularizer={"kind": "tikhonov", "lambda": "discrepancy",
                            "lambda_range": [1e-2, 1e2], "tau": 1.0},
               solver={"name": "lbfgs", "iterations": 8, "options": {}})
    summary = runner.run_experiment(cfg, tmp_path, progress=False)
    choice = json.loads((tmp_path / "lambda_choice.json").read_text())
    assert (tmp_path / "l_curve.png").is_file()
    assert choice["rule"] == "discrepancy" and len(choice["lams"]) >= 2
    assert summary["lambda"] == pytest.approx(choice["lam"])
    assert 1e-2 <= summary["lambda"] <= 1e2
    # the rule's own criterion, on its own trials: the chosen lambda passes or none did
    chi2 = np.array(choice["chi2"])
    passed = chi2 <= choice["target"]
    if choice["reached"]:
        assert passed[choice["index"]]
        assert not passed[choice["index"] + 1:].all() or choice["index"] == len(chi2) - 1
    else:
        assert not passed.any() and choice["index"] == int(np.argmin(chi2))
    assert "discrepancy principle" in summary["protocol"]["lambda"]


def test_discrepancy_needs_the_noise_weighted_scale():
    with pytest.raises(config.ConfigError, match="needs 'regularizer.scaling' = 'chi2'"):
        config.validate({"regularizer": {"lambda": "discrepancy", "scaling": "paper"}})
    with pytest.raises(config.ConfigError, match="0 < low < high"):
        config.validate({"regularizer": {"lambda_range": [1.0, 0.1]}})


def test_a_bad_solver_leaves_a_finished_run_untouched(tmp_path):
    runner.run_experiment(tiny(), tmp_path, progress=False)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    bad = {"name": "Adam", "iterations": 2, "options": {}}
    with pytest.raises(config.ConfigError, match="'solver.name': .*Did you mean 'adam'"):
        tiny(solver=bad)
    with pytest.raises(solvers.UnknownSolverError, match="Did you mean 'adam'"):
        runner.run_experiment(dict(tiny(), solver=bad), tmp_path, progress=False)
    typo = {"name": "adam", "iterations": 2, "options": {"learning_rate": 0.1}}
    with pytest.raises(config.ConfigError, match="has no option 'learning_rate'"):
        tiny(solver=typo)
    with pytest.raises(TypeError, match="has no option 'learning_rate'"):
        runner.run_experiment(dict(tiny(), solver=typo), tmp_path, progress=False)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_resume_refuses_another_configuration(tmp_path):
    runner.run_experiment(tiny(), tmp_path, progress=False)
    other = tiny(regularizer={"kind": "tv", "lambda": 2.0})
    with pytest.raises(config.ConfigError, match=r"regularizer.kind: 'tikhonov' there, 'tv' now"
                                                 r".*regularizer.lambda"):
        runner.run_experiment(other, tmp_path, resume=True, progress=False)
    assert runner.run_experiment(tiny(), tmp_path, resume=True, progress=False)["iterations"] == 6


def test_honest_rows_keep_the_tuned_lambda_on_the_state_relation_and_paper_rows_the_papers():
    for method, (kind, regularizer) in reproduce.METHODS.items():
        cfg = reproduce.method_config("quick", method, protocol="honest")
        if kind != "voxel":  # the honest networks, at the voxel centres with a feature grid
            kind = reproduce.HONEST_NETWORK["kind"]
            assert cfg["representation"]["grid_levels"] == reproduce.HONEST_NETWORK["grid_levels"]
        assert cfg["representation"]["kind"] == kind
        assert cfg["solver"]["name"] == reproduce.HONEST_SOLVERS[kind]["name"]
        assert cfg["regularizer"]["lambda"] == reproduce.HONEST_LAMBDA[kind][regularizer], method
        assert cfg["solver"]["iterations"] == reproduce.PRESETS["quick"]["honest_epochs"][method]
        assert cfg["regularizer"]["scaling"] == "chi2"
        assert cfg["representation"]["parameters"] == "state-relation"
        assert cfg["init"] == {**cfg["init"], "kind": "band-tomography", "calibrate": True}
    paper = reproduce.method_config("quick", "VG/TV", protocol="paper")
    assert paper["regularizer"]["lambda"] == 1e-3
    assert paper["representation"]["parameters"] == "fields"


def test_table_marks_the_lambdas_chosen_from_the_data():
    row = {"method": "VG/TV", "iterations": 5, "converged": True, "stopped_by": "plateau",
           "chi2_per_measurement": 2.0,
           "MSE_T": 0.01, "MSE_T_flame": 0.1, "MSE_CO2": 0.01, "MSE_H2O": 0.01,
           "hot_volume_ratio": 1.0, "MSE_T_initial": 0.02, "improvement_T": 2.0,
           "epoch_ms": 10.0, "paper_MSE_T": 0.0121, "machine": "not recorded"}
    rows = [dict(row, **{"lambda": 1.0e4, "lambda_from_data": True}),
        dict(row, method="NN/TV", **{"lambda": 30.0, "lambda_from_data": False})]
    text = comparison_table.markdown_table(rows, [], "quick", "honest", "poolfire", {})
    assert "| VG/TV | 1e+04* | 5 | plateau |" in text and "| NN/TV | 30 |" in text
    assert text.startswith("Preset `quick`, protocol `honest`, truth `poolfire`.")


def test_table_names_the_rule_that_stopped_each_run():
    assert comparison_table.stopped_by("misfit_target: misfit 3 <= 4") == "χ²/M level"
    assert comparison_table.stopped_by("rtol_loss: relative loss change <= 0.001") == "plateau"
    assert comparison_table.stopped_by("max_iter: reached 100 iterations") == "limit"
    assert comparison_table.stopped_by("scipy L-BFGS-B: CONVERGENCE: REL_REDUCTION_OF_F") \
        == "SciPy's test"
    assert comparison_table.stopped_by("callback: a callback asked to stop") == "callback"
    assert comparison_table.stopped_by(None) == "not recorded"


def test_table_names_the_machines_of_its_epoch_times():
    summary = {"config": {"regularizer": {"lambda": 1e-3}}, "lambda": 1e-3, "iterations": 4,
               "converged": False, "chi2_per_measurement": {"final": 1.0},
               "mse": {"T": 0.01, "CO2": 0.01, "H2O": 0.01}, "mse_flame": {"T": 0.1},
               "hot_volume_ratio": 1.0, "mse_initial": {"T": 0.02, "CO2": 0.02, "H2O": 0.02},
               "seconds_per_epoch": 0.5, "parameter_memory_mb": 3.5}
    gpu = {"processor": "a processor, 16 cores", "jax": "gpu: a GPU", "torch": None,
           "versions": {}}
    rows = comparison_table.table_rows({"VG/NR": dict(summary, machine=gpu),
                                 "VG/TV": dict(summary, machine=gpu),
                                 "VG/Tikh.": summary})  # written before runs recorded it
    assert [r["machine"] for r in rows] == [in_words(gpu), in_words(gpu), "not recorded"]
    text = comparison_table.markdown_table(rows, [], "paper", "paper", "poolfire", {})
    assert ("Epoch times measured on:\n"
            "- VG/NR, VG/TV: JAX on gpu: a GPU; processor a processor, 16 cores\n"
            "- VG/Tikh.: not recorded\n") in text


def test_the_machine_is_this_process_s():
    machine = describe_machine()
    assert machine["jax"].split(":")[0] == jax.default_backend()
    usable = (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
              else os.cpu_count())
    assert int(re.fullmatch(r".+, (\d+) cores?", machine["processor"]).group(1)) == usable
    assert machine["torch"] is None
    assert machine["versions"]["jax"] == jax.__version__
    assert describe_machine(uses_torch=True)["torch"] == str(torch.get_default_device())
    assert "torch on cpu" in in_words(dict(machine, torch="cpu"))
    assert "torch" not in in_words(machine)


def test_tv_smoothing_reaches_the_voxel_problem_and_is_refused_where_it_means_nothing(tmp_path):
    cfg = tiny(regularizer={"kind": "tv", "lambda": 1e5, "tv_smoothing": 0.1},
               solver={"name": "lbfgs", "iterations": 4, "options": {}})
    scene = runner.build_scene(cfg)
    problem = runner.make_representation(cfg, scene).problem(
        np.zeros(scene.data_shape, np.float32), regularizer="tv")
    assert problem.regularizer.functional.smoothing == 0.1
    summary = runner.run_experiment(cfg, tmp_path, progress=False)
    assert summary["loss"]["final"] < summary["loss"]["initial"]
    with pytest.raises(config.ConfigError, match="set kind = 'tv' or tv_smoothing = 0"):
        tiny(regularizer={"kind": "tikhonov", "tv_smoothing": 0.1})
    with pytest.raises(config.ConfigError, match="needs 'representation.kind' = 'voxel'"):
        tiny(regularizer={"kind": "tv", "tv_smoothing": 0.1},
             representation={"kind": "neural-field"})


def test_a_configuration_naming_only_the_truth_is_the_honest_studys_voxel_tikhonov():
    """`invflame run` without [init], [solver], [regularizer], [representation] runs what the
    study runs as VG/Tikh. (the sizes apart: the quick preset shrinks the cameras and the
    line-by-line step)."""
    given = config.validate({"truth": {"source": "poolfire"}})
    study = reproduce.method_config("quick", "VG/Tikh.", protocol="honest")
    for sizes in ("rig", "spectrum"):
        study[sizes] = {**study[sizes], **{k: given[sizes][k] for k in ("pixels", "step")
                                          if k in given[sizes]}}
    assert given == study


def test_stop_chi2_ends_the_solve_at_the_first_iterate_within_the_level(tmp_path):
    free = runner.run_experiment(tiny(), tmp_path / "free", progress=False)
    chi2 = np.loadtxt(tmp_path / "free" / "history.csv", delimiter=",", skiprows=1,
                      usecols=2) / np.load(tmp_path / "free" / "data.npz")["measured"].size
    assert free["iterations"] == 6
    first = next(k for k in range(1, 6) if chi2[k] < chi2[:k].min())  # a new lowest misfit
    level = 0.5 * (chi2[first] + chi2[:first].min())  # the first iterate at or below it
    summary = runner.run_experiment(tiny(solver={**TINY["solver"], "stop_chi2": level}),
                                    tmp_path / "stopped", progress=False)
    assert summary["iterations"] == first and summary["converged"]
    assert summary["stop_reason"].startswith("misfit_target:")
    with pytest.raises(config.ConfigError, match="'solver.stop_chi2' = 2.0 stops at a noise-"):
        tiny(solver={**TINY["solver"], "stop_chi2": 2.0}, regularizer={"scaling": "paper"})
    with pytest.raises(config.ConfigError, match="these data have no noise σ"):
        runner.run_experiment(tiny(solver={**TINY["solver"], "stop_chi2": 2.0},
                                   noise={"kind": "none"}), tmp_path / "free", progress=False)


def test_a_subvoxel_model_renders_what_the_summary_scores_on_voxels_and_centres(tmp_path):
    cfg = tiny(representation={"subvoxel_spread": 1.0},
               solver={"name": "lbfgs", "iterations": 3, "options": {}})
    summary = runner.run_experiment(cfg, tmp_path, progress=False)
    data = np.load(tmp_path / "data.npz")
    chi2 = np.mean(((data["simulated"] - data["measured"]) / data["sigma"]) ** 2)
    assert summary["chi2_per_measurement"]["final"] == pytest.approx(chi2, rel=1e-6)
    mean_state = runner.build_scene(cfg).simulate(
        Field.load(tmp_path / "reconstruction.npz").values)
    assert data["simulated"].sum() > mean_state.sum()  # rendered above the reported mean
    centres = tiny(representation={"subvoxel_spread": 1.0, "kind": "neural-centres"})
    assert subvoxel_emission(centres, runner.build_scene(centres)).spread == 1.0
    for representation in ({"kind": "neural-field"}, {"parameters": "fields"}):
        off = tiny(representation={"subvoxel_spread": 1.0, **representation})
        assert subvoxel_emission(off, runner.build_scene(off)) is None  # rays, free fields
