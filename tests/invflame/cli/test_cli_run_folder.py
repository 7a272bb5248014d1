"""``invflame run --out``: no folder's files are replaced unless asked (``--resume``,
``--overwrite``); ``invflame plot`` and ``export`` name what a folder lacks or what is damaged."""

import json

import numpy as np
import pytest

from invflame.cli import main
from invflame.experiments import config, runner
from invflame.experiments.run_folder import INCOMPLETE, LOCK
from invflame.geometry import VoxelGrid
from invflame.phantoms import make_phantom

from ..experiments.test_config_checks import field_file

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "adam", "iterations": 2, "options": {"lr": 0.01}},
}


def write_config(path, **changes):
    path.write_text(config.dumps(config.validate({**TINY, **changes})))
    return str(path)


def finished_run(folder):
    """A folder as a finished run leaves it (what the refusals look at), with its contents."""
    folder.mkdir(parents=True)
    files = {"summary.json": json.dumps({"iterations": 7}), "fingerprint.json": "{}",
             "config.toml": "seed = 7\n", "log.txt": "the first run\n",
             "checkpoint.npz": "weights", "reconstruction.npz": "fields"}
    for name, text in files.items():
        (folder / name).write_text(text)
    return files


def contents(folder):
    return {p.name: p.read_text() for p in sorted(folder.iterdir())}


def one_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err


def test_a_finished_run_is_not_replaced_without_resume_or_overwrite(tmp_path, capsys):
    files = finished_run(tmp_path / "run")
    other = write_config(tmp_path / "other.toml", seed=11)
    assert main(["run", other, "--out", str(tmp_path / "run"), "--quiet"]) == 2
    assert one_error(capsys) == (
        f"invflame run: error: output folder {tmp_path / 'run'} holds a finished run "
        "(summary.json): continue it with --resume, replace its results with --overwrite, or "
        "choose another --out\n")
    assert contents(tmp_path / "run") == files


def test_an_unfinished_run_is_not_replaced_either(tmp_path, capsys):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / INCOMPLETE).write_text("partial\n")
    (tmp_path / "run" / "checkpoint.npz").write_text("iteration 500 of 2000")
    before = contents(tmp_path / "run")
    assert main(["run", write_config(tmp_path / "c.toml"), "--out", str(tmp_path / "run")]) == 2
    assert "holds an unfinished run: continue it with --resume" in one_error(capsys)
    assert contents(tmp_path / "run") == before


def test_a_folder_of_other_files_is_refused(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("log.txt", "data.npz", "truth.npz", "config.toml"):
        (mine / name).write_text(f"my own {name}\n")
    before = contents(mine)
    for flags in ([], ["--resume"]):
        assert main(["run", write_config(tmp_path / "c.toml"), "--out", str(mine), *flags]) == 2
        assert (f"output folder {mine} holds files that no run wrote (config.toml, data.npz, "
                "log.txt, truth.npz): choose another --out (a new or empty folder), or "
                "--overwrite") in one_error(capsys)
        assert contents(mine) == before  # not even a lock


def test_an_empty_out_is_refused_before_anything_is_written(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = write_config(tmp_path / "c.toml")
    with pytest.raises(SystemExit) as exit_info:
        main(["run", cfg, "--out", ""])
    assert exit_info.value.code == 2
    assert "argument --out: an empty path would write into the current folder" in \
        capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]


def test_resume_and_overwrite_exclude_each_other(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["run", "c.toml", "--out", str(tmp_path), "--resume", "--overwrite"])
    assert exit_info.value.code == 2
    assert "argument --overwrite: not allowed with argument --resume" in capsys.readouterr().err


def test_overwrite_keeps_the_results_when_the_truth_cannot_load(tmp_path, capsys):
    files = finished_run(tmp_path / "run")
    torn = tmp_path / "truth.npz"
    make_phantom("synthetic", grid=VoxelGrid.poolfire(8)).save(torn)
    cfg = write_config(tmp_path / "c.toml", truth={"grid": 8, "source": str(torn)})
    torn.write_bytes(b"PK\x03\x04 torn")  # torn after the configuration was written
    assert main(["run", cfg, "--out", str(tmp_path / "run"), "--overwrite", "--quiet"]) == 2
    assert f"'truth.source' = '{torn}': field file {torn} is damaged or incomplete" in \
        one_error(capsys)
    kept = contents(tmp_path / "run")
    assert {name: kept[name] for name in files} == files and LOCK not in kept


def test_overwrite_replaces_a_finished_run(tmp_path, capsys):
    finished_run(tmp_path / "run")
    cfg = write_config(tmp_path / "c.toml")
    assert main(["run", cfg, "--out", str(tmp_path / "run"), "--overwrite", "--quiet"]) == 0
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["iterations"] == 2
    assert "the first run" not in (tmp_path / "run" / "log.txt").read_text()
    assert not (tmp_path / "run" / INCOMPLETE).exists()


@pytest.mark.parametrize("command", ["plot", "export"])
def test_plot_and_export_name_a_folder_without_a_finished_run(tmp_path, capsys, command):
    wanted = "summary.json" if command == "plot" else "reconstruction.npz"
    (tmp_path / "a file").write_text("")
    (tmp_path / "empty").mkdir()
    (tmp_path / "cut").mkdir()
    (tmp_path / "cut" / INCOMPLETE).write_text("partial\n")
    for name, message in [
        ("missing", "is not a folder: give the output folder of 'invflame run'"),
        ("a file", "is not a folder"),
        ("empty", f"holds no {wanted}, nor do its sub-folders: no finished run\n"),
        ("cut", f"holds no {wanted}, nor do its sub-folders: no finished run (it holds an "
                "unfinished run: continue it with invflame run --resume)"),
    ]:
        assert main([command, str(tmp_path / name)]) == 2
        err = one_error(capsys)
        assert err.startswith(f"invflame {command}: error: {tmp_path / name} ") and message in err


@pytest.mark.parametrize("command", ["plot", "export"])
@pytest.mark.parametrize(("name", "content", "message"), [
    ("data.npz", b"PK\x03\x04 torn", "output {path} is damaged or incomplete"),
    ("history.csv", b"iteration,loss\n", "{path} is damaged or incomplete (expected a header "
                                         "row, then rows of as many values)"),
    ("config.toml", b"seed = = 3\n", "{path} is damaged or incomplete (Invalid value"),
    ("summary.json", b'{"mse": ', "{path} is damaged or incomplete (not valid JSON"),
])
def test_plot_and_export_name_a_damaged_file(tmp_path, capsys, command, name, content,
                                             message):
    run = tmp_path / "run"
    run.mkdir()
    np.savez(run / "reconstruction.npz", values=np.zeros(3))
    (run / "summary.json").write_text("{}")
    (run / name).write_bytes(content)
    assert main([command, str(run)]) == 2
    err = one_error(capsys)
    assert err.startswith(f"invflame {command}: error: ")
    assert message.format(path=run / name) in err
    assert "invflame run --overwrite --out" in err or name == "summary.json"


@pytest.mark.parametrize("command", ["plot", "export"])
def test_plot_and_export_name_a_truth_of_reordered_fields(tmp_path, capsys, command):
    run = tmp_path / "run"
    run.mkdir()
    field_file(run / "reconstruction.npz")
    field_file(run / "truth.npz", names=np.array(["CO2", "T", "H2O", "CH4"]))
    (run / "summary.json").write_text("{}")
    assert main([command, str(run)]) == 2
    assert one_error(capsys).startswith(
        f"invflame {command}: error: {run / 'truth.npz'} holds fields ('CO2', 'T', 'H2O', "
        "'CH4'); expected ('T', 'CO2', 'H2O', 'CH4')")


def test_a_quiet_run_builds_its_table_without_a_bar(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path / "cache"))  # built, not loaded
    runner.build_scene(config.validate(TINY), progress=False)
    assert capsys.readouterr().err == ""
    assert [p.suffix for p in (tmp_path / "cache").iterdir()] == [".npz"]
