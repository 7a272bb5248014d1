"""``invflame run`` reports a solver that diverged, in its summary and on the terminal."""

import json

from invflame.cli import main
from invflame.experiments import config

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "adam", "iterations": 6, "options": {"lr": 1e30}},
    # mean states: the first step at this rate raises the loss past the divergence rule's 1000×
    # (through the sub-voxel model it rises 908× at the first step and past 1000× at the next)
    "representation": {"subvoxel_spread": 0.0},
}


def test_adam_with_a_huge_learning_rate_is_reported_as_diverged(tmp_path, capsys):
    path = tmp_path / "run.toml"
    path.write_text(config.dumps(config.validate(TINY)))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["diverged"] and not summary["converged"] and summary["iterations"] == 0
    assert summary["stop_reason"].startswith("diverged: the loss rose from ")
    assert summary["loss"]["final"] == summary["loss"]["initial"]  # the start is kept
    assert capsys.readouterr().out.startswith("the solver stopped (diverged: the loss rose")
