"""The solver race's recorded reference: rows from a finished run's files, refusals of a run
that is unfinished, regularized otherwise or started from another problem."""

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import tomli_w
from solver_race_reference import first_reach, recorded_reference

from invflame.field import Field
from invflame.geometry import VoxelGrid

GRID = VoxelGrid((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (3, 3, 3))


class Problem:
    """What ``recorded_reference`` asks of a problem: its objective at ``x0``."""

    x0 = np.zeros(3)

    def __init__(self, loss):
        self.loss = loss

    def evaluate(self, x):
        return SimpleNamespace(loss=self.loss)


def write_run(path: Path, kind="tv", losses=(10.0, 4.0, 2.5), times=(3.0, 4.5, 6.0)):
    """A finished run's files: config, history, summary, start and reconstruction fields."""
    path.mkdir()
    config = {"regularizer": {"kind": kind}, "solver": {"name": "adam", "options": {"lr": 0.01}}}
    (path / "config.toml").write_text(tomli_w.dumps(config))
    rows = ["iteration,loss,misfit,regularizer,grad_norm,time"]
    rows += [f"{i},{loss},0,0,0,{t}" for i, (loss, t) in enumerate(zip(losses, times, strict=True))]
    (path / "history.csv").write_text("\n".join(rows) + "\n")
    (path / "summary.json").write_text('{"stop_reason": "max_iter: 2 iterations"}')
    for name, temperature in (("initial.npz", 1000.0), ("reconstruction.npz", 600.0)):
        values = np.full((4, *GRID.shape), 0.1, np.float32)
        values[0] = temperature
        Field(GRID, values, {"source": name}).save(path / name)
    return path


def mean_temperature(fields):
    return float(np.mean(fields[0]))


def test_the_reference_takes_the_runs_objective_times_and_end_fields(tmp_path):
    run = write_run(tmp_path / "run")
    name, recorded = recorded_reference(run, "tv", Problem(10.0), mean_temperature)
    rows = recorded["rows"]
    assert name == "adam lr=0.01 (recorded)"
    assert [row["loss"] for row in rows] == [10.0, 4.0, 2.5]
    assert [row["wall"] for row in rows] == [0.0, 1.5, 3.0]  # from the first iterate on
    assert [(row["forward"], row["vjp"], row["jvp"]) for row in rows] == [(1, 1, 0), (2, 2, 0),
                                                                           (3, 3, 0)]
    assert rows[0]["mse_t"] == pytest.approx(1000.0) and rows[-1]["mse_t"] == pytest.approx(600.0)
    assert math.isnan(rows[1]["mse_t"])
    assert recorded["stop"].startswith("max_iter") and recorded["seconds"]["wall"] == 3.0
    # an unrecorded MSE_T is never "reached", so only the end reaches the final level
    assert first_reach(rows, "mse_t", 600.0) is rows[-1]


@pytest.mark.parametrize("case, message", [
    ("unfinished", "no finished run there"),
    ("tikhonov", "regularizes with 'tikhonov'"),
    ("other start", "solved another problem"),
])
def test_a_run_of_another_problem_is_refused(tmp_path, case, message):
    run = write_run(tmp_path / "run", kind="tikhonov" if case == "tikhonov" else "tv")
    if case == "unfinished":
        (run / "reconstruction.npz").unlink()
    start = 11.0 if case == "other start" else 10.0
    with pytest.raises(SystemExit, match=message):
        recorded_reference(run, "tv", Problem(start), mean_temperature)
