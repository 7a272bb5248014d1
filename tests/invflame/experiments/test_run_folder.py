"""Run folders: one writer at a time, partial outputs marked, damaged outputs named."""

import errno
import logging
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from invflame.atomic_files import CorruptFileError
from invflame.errors import ConfigError, GeometryError, InputDataError, OutputError
from invflame.experiments import config, run_folder, runner, summaries
from invflame.experiments.run_folder import INCOMPLETE, LOCK, RunLock
from invflame.field import Field
from invflame.geometry import CameraRig, VoxelGrid
from invflame.geometry.camera import PinholeCamera
from invflame.phantoms import make_phantom

TINY = {
    "truth": {"grid": 8, "source": "synthetic"},
    "rig": {"pixels": 4},
    "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
    "solver": {"name": "adam", "iterations": 3, "options": {"lr": 0.01}},
}


def dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_a_second_writer_is_refused_with_the_holders_pid(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK).write_text(f"{holder.pid}\n")
        with pytest.raises(OutputError, match=f"run folder {tmp_path} is being written by "
                                              f"process {holder.pid}"), RunLock(tmp_path):
            pass
        assert (tmp_path / LOCK).read_text() == f"{holder.pid}\n"  # not taken from it
    finally:
        holder.kill()
        holder.wait()


def test_a_stale_lock_is_taken_over_with_a_warning(tmp_path, caplog):
    pid = dead_pid()
    (tmp_path / LOCK).write_text(f"{pid}\n")
    with caplog.at_level(logging.WARNING), RunLock(tmp_path) as lock:
        pid_text, host, started, _ = (tmp_path / LOCK).read_text().split("\n")
        assert (pid_text, host) == (str(os.getpid()), socket.gethostname())
        assert started == run_folder._started(os.getpid())
        assert (tmp_path / INCOMPLETE).is_file()
        lock.complete()
    assert [r.getMessage() for r in caplog.records] == [
        f"taking over the lock {tmp_path / LOCK} of process {pid}, which no longer runs"]
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="no /proc start times")
def test_a_full_disk_on_taking_the_lock_leaves_no_lock(tmp_path, monkeypatch):
    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)  # INCOMPLETE, the first file written whole
    with pytest.raises(OSError, match="No space left on device") as err, RunLock(tmp_path):
        pass
    assert err.value.filename == str(tmp_path / INCOMPLETE)
    assert list(tmp_path.iterdir()) == []


def test_a_lock_whose_process_id_was_reused_is_taken_over(tmp_path, caplog):
    started = run_folder._started(os.getpid())
    assert started.isdigit()
    pid = os.getpid()  # alive, but started at another time than the lock records
    (tmp_path / LOCK).write_text(f"{pid}\n{socket.gethostname()}\n{int(started) + 1}\n")
    with caplog.at_level(logging.WARNING), RunLock(tmp_path):
        assert (tmp_path / LOCK).read_text().split("\n")[2] == started
    assert [r.getMessage() for r in caplog.records] == [
        f"taking over the lock {tmp_path / LOCK} of process {pid}, which no longer runs"]


def test_a_lock_of_another_host_is_never_taken_over(tmp_path):
    (tmp_path / LOCK).write_text(f"{dead_pid()}\nanother-host.example\n")
    with pytest.raises(OutputError, match="on host another-host.example .*remove the lock if "
                                          "that process is gone"), RunLock(tmp_path):
        pass


def test_a_lock_held_by_this_run_refuses_a_nested_writer(tmp_path):
    with RunLock(tmp_path), pytest.raises(OutputError, match="being written by process"), \
            RunLock(tmp_path):
        pass
    assert not (tmp_path / LOCK).exists()


def test_a_crashed_run_leaves_its_folder_marked_incomplete(tmp_path, monkeypatch):
    cfg = config.validate(TINY)

    def crash(*args, **kwargs):
        raise KeyboardInterrupt("killed while scoring")

    monkeypatch.setattr(summaries, "field_scores", crash)
    with pytest.raises(KeyboardInterrupt):
        runner.run_experiment(cfg, tmp_path, progress=False)
    assert (tmp_path / INCOMPLETE).is_file() and not (tmp_path / "summary.json").exists()
    assert not (tmp_path / LOCK).exists()
    assert (tmp_path / "reconstruction.npz").is_file()  # partial outputs stay, marked
    monkeypatch.undo()
    summary = runner.run_experiment(cfg, tmp_path, resume=True, progress=False)
    assert summary["iterations"] == 3
    assert not (tmp_path / INCOMPLETE).exists() and not (tmp_path / LOCK).exists()


@pytest.mark.parametrize("damage", [b"", b"PK\x03\x04 torn", None])
def test_a_damaged_field_file_is_named(tmp_path, damage):
    path = tmp_path / "truth.npz"
    Field(VoxelGrid.poolfire(4), make_phantom("synthetic").resample(VoxelGrid.poolfire(4))
          .values).save(path)
    cfg = config.validate({**TINY, "truth": {"grid": 8, "source": str(path)}})
    whole = path.read_bytes()
    path.write_bytes(whole[: len(whole) // 2] if damage is None else damage)
    with pytest.raises(CorruptFileError, match=f"field file {path} is damaged or incomplete"):
        Field.load(path)
    with pytest.raises(InputDataError, match=f"'truth.source' = '{path}': field file {path}"):
        runner.load_truth(cfg)
    with pytest.raises(ConfigError, match=f"'truth.source' = '{path}': field file {path}"):
        config.validate(cfg)


def test_cameras_inside_the_grid_are_a_geometry_error():
    from invflame.geometry import paper_rig

    with pytest.raises(GeometryError, match="camera distance 0.3 m puts the cameras inside the "
                                            "grid \\(it reaches 0.5 m"):
        paper_rig(VoxelGrid.poolfire(4), distance=0.3)


def test_a_plain_npy_is_not_a_field_file(tmp_path):
    np.save(tmp_path / "a.npy", np.ones((4, 2, 2, 2)))
    with pytest.raises(CorruptFileError, match="a single .npy array, not an .npz archive"):
        Field.load(tmp_path / "a.npy")


def test_a_rig_that_misses_the_grid_is_a_geometry_error():
    from invflame.scene import Scene
    from invflame.spectroscopy.absorption_table import AbsorptionTable

    wavenumber = np.linspace(650.0, 690.0, 41)
    table = AbsorptionTable(("CO2", "H2O", "CH4"), wavenumber, 101325.0, [300.0, 1000.0, 2000.0],
                            np.full((3, 3, 41), 1e-20), (0.1, 0.2, 0.0))
    grid = VoxelGrid.poolfire(4)
    away = PinholeCamera(grid.centre + [3.0, 0.0, 0.0], grid.centre + [6.0, 0.0, 0.0],
                         [0.0, 1.0, 0.0], 0.5, (0.1, 0.1), (2, 2))
    with pytest.raises(GeometryError, match="no ray of the 1 camera\\(s\\) crosses the grid"):
        Scene(grid, CameraRig((away,)), table)


def test_a_refused_resume_leaves_a_finished_run_finished(tmp_path):
    (tmp_path / "summary.json").write_text("{}\n")
    with pytest.raises(ValueError, match="refused"), RunLock(tmp_path):
        assert (tmp_path / INCOMPLETE).is_file()  # while it is written
        raise ValueError("refused: the configuration changed")
    assert not (tmp_path / INCOMPLETE).exists() and not (tmp_path / LOCK).exists()


@pytest.mark.parametrize("change", ["rewritten", "removed"])
def test_a_finished_run_changed_by_a_failed_resume_is_marked_incomplete(tmp_path, change):
    summary = tmp_path / "summary.json"
    summary.write_text("{}\n")
    with pytest.raises(KeyboardInterrupt), RunLock(tmp_path):
        if change == "removed":
            summary.unlink()
        else:
            summary.write_text('{"iterations": 5}\n')
        raise KeyboardInterrupt
    assert (tmp_path / INCOMPLETE).is_file()
