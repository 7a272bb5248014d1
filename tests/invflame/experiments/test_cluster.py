"""Many runs on a Dask cluster: sweeps and the comparison, failures reported, results kept."""

import argparse
import csv
import json

import pytest

from invflame.cli import reproduce as reproduce_cli
from invflame.cli import sweep
from invflame.experiments import config, reproduce
from invflame.experiments.cluster import FAILURES, Job, dask_client, run_jobs

BASE = """
[truth]
grid = 8
source = "synthetic"
[rig]
pixels = 4
[spectrum]
min = 660.0
max = 690.0
step = 0.1
[solver]
name = "adam"
iterations = 3
options = { lr = 0.01 }
"""


def command(module, argv):
    parser = argparse.ArgumentParser(prog="invflame")
    module.add_parser(parser.add_subparsers())
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.fixture(scope="module")
def client():
    """Two worker threads in this process (in-process transport, no network)."""
    with dask_client(workers=2, processes=False) as connected:
        yield connected


def test_param_values_are_toml_or_text():
    assert sweep.parse_param("regularizer.lambda=1e-4, 1e-3") == (
        "regularizer.lambda", [("1e-4", 1e-4), ("1e-3", 1e-3)])
    assert sweep.parse_param("solver.name=adam,gd")[1] == [("adam", "adam"), ("gd", "gd")]
    key, values = sweep.parse_param("solver.options.betas=[0.9, 0.99],[0.5, 0.9]")
    assert key == "solver.options.betas" and [v for _, v in values] == [[0.9, 0.99], [0.5, 0.9]]
    for bad in ("regularizer.lambda", "=1,2", "seed=1,,2"):
        with pytest.raises(ValueError, match="--param"):
            sweep.parse_param(bad)


def test_combinations_are_the_grid_with_clear_errors():
    base = config.validate({})
    combos = sweep.combinations(base, [sweep.parse_param("regularizer.lambda=1e-4,1e-2"),
                                       sweep.parse_param("solver.name=adam,gd,lbfgs")])
    assert len(combos) == 6 and len({c["name"] for c in combos}) == 6
    assert combos[5]["config"]["regularizer"]["lambda"] == 1e-2
    assert combos[5]["config"]["solver"]["name"] == "lbfgs"
    assert combos[0]["name"] == "000_regularizer.lambda=1e-4_solver.name=adam"
    with pytest.raises(config.ConfigError, match="regularizer.lamda=1.*did you mean 'lambda'"):
        sweep.combinations(base, [sweep.parse_param("regularizer.lamda=1,2")])
    with pytest.raises(ValueError, match="one --param only"):
        sweep.combinations(base, [sweep.parse_param("seed=1"), sweep.parse_param("seed=2")])
    with pytest.raises(ValueError, match="'seed' is a value"):
        sweep.combinations(base, [sweep.parse_param("seed.x=1")])


def test_dask_client_needs_one_of_workers_or_scheduler():
    with pytest.raises(ValueError, match="either workers"), dask_client():
        pass
    with pytest.raises(ValueError, match="at least 1"), dask_client(workers=0):
        pass


def test_sweep_keeps_results_and_reports_a_failing_run(client, tmp_path, capsys):
    base = tmp_path / "base.toml"
    base.write_text(BASE)
    out = tmp_path / "sweep"
    code = command(sweep, ["sweep", str(base), "--param",
                           "noise.kind=snr,none",  # 'discrepancy' refuses noise-free data
                           "--param", "regularizer.lambda=discrepancy", "--out", str(out),
                           "--scheduler", client.scheduler.address, "--quiet"])
    assert code == 1
    assert "FAILED noise.kind=none" in capsys.readouterr().err
    with open(out / "summary.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["status"] for r in rows] == ["ok", "failed"]
    good, bad = (out / r["run"] for r in rows)
    assert (good / "summary.json").is_file() and (good / "reconstruction.npz").is_file()
    assert float(rows[0]["MSE_T"]) > 0 and rows[0]["error"] == ""
    assert "needs data with a noise σ" in rows[1]["error"]
    assert rows[1]["attempts"] == "2"  # the default retry ran, and failed again
    assert (bad / FAILURES).read_text().count("--- attempt failed") == 2
    assert "| failed |" in (out / "summary.md").read_text()
    assert json.loads((out / "sweep.json").read_text())["params"]["regularizer.lambda"] == [
        "discrepancy"]


def test_run_jobs_resume_returns_finished_runs(client, tmp_path):
    base = tmp_path / "base.toml"
    base.write_text(BASE)
    cfg = config.load(base)
    jobs = [Job("a", cfg, tmp_path / "a")]
    first = run_jobs(client, jobs, progress=False)
    again = run_jobs(client, jobs, resume=True, progress=False)
    assert first[0].ok and again[0].summary == first[0].summary
    assert first[0].attempts == 1


def test_reproduce_on_two_local_worker_processes(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(reproduce.PRESETS, "tiny", {
        "truth": {"grid": 8}, "rig": {"pixels": 4},
        "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1}, "epochs": 3})
    code = command(reproduce_cli, ["reproduce", "--preset", "tiny", "--methods", "VG/NR",
                                   "VG/TV", "--out", str(tmp_path), "--workers", "2",
                                   "--quiet"])
    assert code == 0, capsys.readouterr().err
    for folder in ("VG-NR", "VG-TV"):
        assert (tmp_path / folder / "summary.json").is_file()
    rows = json.loads((tmp_path / "table.json").read_text())["rows"]
    assert [r["method"] for r in rows] == ["VG/NR", "VG/TV"]
    assert (tmp_path / "table.md").is_file() and (tmp_path / "cutaways.png").is_file()
