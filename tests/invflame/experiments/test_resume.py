"""Resume refuses a run folder whose truth, data or code changed; --force continues and says so."""

import json

import numpy as np
import pytest

import solvers
from invflame.cli import main
from invflame.experiments import config, runner
from invflame.experiments.run_folder import CHECKPOINT
from solvers.checkpoint import save_checkpoint

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "adam", "iterations": 6, "options": {"lr": 0.01}},
}


def test_fingerprint_hashes_the_contents_and_describes_the_solver_options():
    class Truth:
        values = np.zeros((4, 2, 2, 2))

    class Data:
        data, sigma = np.ones((3, 5)), np.full((3, 5), 1e-3)

    cfg = config.validate(TINY)
    first = runner.run_fingerprint(cfg, Truth, Data)
    assert first["solver options"].startswith("solvers.adam.AdamOptions(lr: float = 0.001")
    assert runner.run_fingerprint(cfg, Truth, Data) == first
    Data.data = Data.data.copy()
    Data.data[1, 2] = np.nextafter(1.0, 2.0)  # one value, one unit in the last place
    second = runner.run_fingerprint(cfg, Truth, Data)
    assert second["data sha256"] != first["data sha256"]
    assert second["truth sha256"] == first["truth sha256"]
    assert runner.run_fingerprint(cfg, None, Data)["truth sha256"] is None


def test_resume_refuses_a_run_whose_fingerprint_is_gone(tmp_path):
    cfg = config.validate(dict(TINY, solver=dict(TINY["solver"], iterations=3)))
    runner.run_experiment(cfg, tmp_path, progress=False)
    (tmp_path / "fingerprint.json").unlink()
    with pytest.raises(config.ConfigError, match="fingerprint.json is missing, so the truth, "
                                                 "data and code cannot be compared"):
        runner.run_experiment(cfg, tmp_path, resume=True, progress=False)
    assert runner.run_experiment(cfg, tmp_path, resume=True, progress=False,
                                 force=True)["iterations"] == 3


def test_resume_refuses_changed_data_and_code_and_force_records_them(tmp_path, capsys):
    cfg = config.validate(dict(TINY, solver=dict(TINY["solver"], iterations=3)))
    runner.run_experiment(cfg, tmp_path, progress=False)
    (tmp_path / "summary.json").unlink()  # as if killed after its last checkpoint
    saved = json.loads((tmp_path / "fingerprint.json").read_text())
    assert set(saved) == {"truth sha256", "data sha256", "invflame version", "solver options"}
    tampered = dict(saved, **{"data sha256": "0" * 64, "invflame version": "0.0.1"})
    (tmp_path / "fingerprint.json").write_text(json.dumps(tampered))
    longer = config.validate(TINY)

    with pytest.raises(config.ConfigError) as err:
        runner.run_experiment(longer, tmp_path, resume=True, progress=False)
    message = str(err.value)
    assert f"data sha256: '{'0' * 64}' there, '{saved['data sha256']}' now" in message
    assert f"invflame version: '0.0.1' there, '{saved['invflame version']}' now" in message
    assert "truth sha256" not in message and "--force" in message

    (tmp_path / "run.toml").write_text(config.dumps(longer))
    assert main(["run", str(tmp_path / "run.toml"), "--out", str(tmp_path), "--force",
                 "--quiet"]) == 2
    assert "--force only applies to --resume" in capsys.readouterr().err
    assert main(["run", str(tmp_path / "run.toml"), "--out", str(tmp_path), "--resume",
                 "--force", "--quiet"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["iterations"] == 6
    resumed = summary["resumed"]
    assert resumed["from_iteration"] == 3 and resumed["exact"] and resumed["forced"]
    assert [c.split(":")[0] for c in resumed["changed"]] == ["data sha256", "invflame version"]
    log = (tmp_path / "log.txt").read_text()
    assert "resumed with --force although what defines the run changed: data sha256" in log
    assert json.loads((tmp_path / "fingerprint.json").read_text()) == saved  # the run's own now


def test_the_summary_says_whether_a_run_was_resumed_exactly(tmp_path):
    """The summary of a resumed run says from which iteration it continued and whether the
    continuation is the uninterrupted run's: L-BFGS-B's checkpoint holds its memory, one
    without it (an older checkpoint) restarts the memory; a run done in one go says it was
    not resumed."""
    lbfgs = {"name": "lbfgs", "iterations": 6, "options": {"pgtol": 0.0, "ftol": 0.0}}
    cfg = config.validate(dict(TINY, solver=lbfgs))
    runner.run_experiment(config.validate(dict(TINY, solver=dict(lbfgs, iterations=3))),
                          tmp_path, progress=False)
    assert json.loads((tmp_path / "summary.json").read_text())["resumed"] is None
    (tmp_path / "summary.json").unlink()
    checkpoint = tmp_path / CHECKPOINT
    saved = solvers.load_checkpoint(checkpoint)
    summary = runner.run_experiment(cfg, tmp_path, resume=True, progress=False)
    assert summary["resumed"] == {"from_iteration": 3, "exact": True, "forced": False,
                                  "changed": []}

    save_checkpoint(checkpoint, saved.meta, saved.x, saved.grad, {})
    (tmp_path / "summary.json").unlink()
    with pytest.warns(RuntimeWarning, match="L-BFGS memory restarted"):
        summary = runner.run_experiment(cfg, tmp_path, resume=True, progress=False)
    assert summary["resumed"]["exact"] is False
    assert summary["iterations"] > 3


def test_resume_of_a_finished_run_checks_truth_and_code_not_only_the_configuration(tmp_path):
    cfg = config.validate(dict(TINY, solver=dict(TINY["solver"], iterations=2)))
    finished = runner.run_experiment(cfg, tmp_path, progress=False)
    assert runner.run_experiment(cfg, tmp_path, resume=True, progress=False) == finished
    saved = json.loads((tmp_path / "fingerprint.json").read_text())
    tampered = dict(saved, **{"truth sha256": "0" * 64, "invflame version": "0.0.1"})
    (tmp_path / "fingerprint.json").write_text(json.dumps(tampered))
    with pytest.raises(config.ConfigError) as err:
        runner.run_experiment(cfg, tmp_path, resume=True, progress=False)
    message = str(err.value)
    assert f"truth sha256: '{'0' * 64}' there, '{saved['truth sha256']}' now" in message
    assert "invflame version: '0.0.1' there" in message
    assert "data sha256" not in message  # simulated data follow from what is checked
    forced = runner.run_experiment(cfg, tmp_path, resume=True, progress=False, force=True)
    assert forced == finished


def test_resume_continues_a_finished_run_to_a_raised_limit(tmp_path):
    """A run that stopped at its limit continues to a higher one where it stopped, as the
    uninterrupted run of that length would; the same limit returns it as it is."""
    short = config.validate(dict(TINY, solver=dict(TINY["solver"], iterations=3)))
    runner.run_experiment(short, tmp_path / "cut", progress=False)
    assert runner.run_experiment(short, tmp_path / "cut", resume=True,
                                 progress=False)["resumed"] is None
    continued = runner.run_experiment(config.validate(TINY), tmp_path / "cut", resume=True,
                                      progress=False)
    assert continued["iterations"] == 6 and continued["resumed"]["from_iteration"] == 3
    whole = runner.run_experiment(config.validate(TINY), tmp_path / "whole", progress=False)
    assert continued["loss"]["final"] == pytest.approx(whole["loss"]["final"], rel=1e-5)


def test_resume_refuses_a_limit_below_the_iterations_done(tmp_path):
    runner.run_experiment(config.validate(TINY), tmp_path, progress=False)
    lower = config.validate(dict(TINY, solver=dict(TINY["solver"], iterations=4)))
    refusal = (r"cannot resume .*: it has done 6 epochs, but 'solver.iterations' = 4 now stops "
               r"it before them: set solver.iterations to at least 6")
    with pytest.raises(config.ConfigError, match=refusal):  # finished
        runner.run_experiment(lower, tmp_path, resume=True, progress=False)
    (tmp_path / "summary.json").unlink()  # as if killed after its last checkpoint
    with pytest.raises(config.ConfigError, match=refusal):
        runner.run_experiment(lower, tmp_path, resume=True, progress=False)
    assert not (tmp_path / "summary.json").exists()


def another_grid(meta, x):
    return dict(meta, dims=[2, 10, 10, 10]), np.zeros((2, 10, 10, 10), x.dtype)


def another_solver(meta, x):
    return dict(meta, solver="gd"), x


def no_iteration(meta, x):
    return {key: value for key, value in meta.items() if key != "iteration"}, x


def test_resume_names_a_checkpoint_of_another_run(tmp_path, capsys):
    """A checkpoint copied from a run of another grid or solver, or one whose header lacks its
    iteration: one error line naming it, exit status 2, the folder's files kept."""
    path = tmp_path / "run.toml"
    path.write_text(config.dumps(config.validate(dict(TINY, solver=dict(TINY["solver"],
                                                                         iterations=2)))))
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    (tmp_path / "run" / "summary.json").unlink()  # as if killed after its last checkpoint
    saved = solvers.load_checkpoint(tmp_path / "run" / CHECKPOINT)
    for change, words in [
        (another_grid, "holds parameters of shape (2, 10, 10, 10), the problem's are "
                       "(2, 8, 8, 8): it belongs to another run; start this one again "
                       "(invflame run --overwrite --out "),
        (another_solver, "was written by solver 'gd', not 'adam': it belongs to another run"),
        (no_iteration, "lacks the header entries ['iteration']; delete it"),
    ]:
        meta, x = change(saved.meta, saved.x)
        save_checkpoint(tmp_path / "run" / CHECKPOINT, meta, x, saved.grad, saved.state)
        before = (tmp_path / "run" / CHECKPOINT).read_bytes()
        assert main(["run", str(path), "--out", str(tmp_path / "run"), "--resume",
                     "--quiet"]) == 2
        [line] = capsys.readouterr().err.splitlines()
        assert line.startswith(f"invflame run: error: checkpoint {tmp_path / 'run' / CHECKPOINT}")
        assert words in line
        assert (tmp_path / "run" / CHECKPOINT).read_bytes() == before
