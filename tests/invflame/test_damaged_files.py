"""Damaged, foreign or locked files read or written through the Python API: line lists, field
files, checkpoints, absorption tables, run folders; each raises naming the file or the field
that is wrong, and a file that was there is left as it was."""

import errno
import json
import os
from importlib import resources

import numpy as np
import pytest

from invflame.atomic_files import write_npz, write_text
from invflame.errors import InputDataError
from invflame.experiments import config, runner
from invflame.experiments.run_folder import LOCK, RunLock
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume
from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.linelist import read_par
from solvers.checkpoint import HEADER, load_checkpoint, read_run, save_checkpoint

RECORD = (resources.files("invflame") / "data" / "H2O_HITRAN2012_600-800.par").read_text(
    ).splitlines()[0]
"""One valid 160-character HITRAN record."""

GRID = VoxelGrid.poolfire(8)


def edited(first: int, last: int, text: str) -> str:
    """:data:`RECORD` with its columns ``first``..``last`` (1-based) replaced by ``text``."""
    return RECORD[: first - 1] + text + RECORD[last:] + "\n"


def par_file(work, content):
    """Read ``content`` (text or bytes) as the line list ``l.par``."""
    path = work / "l.par"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return read_par(path)


def written(work, name, content: bytes):
    """The file ``name`` in ``work`` holding ``content``."""
    path = work / name
    path.write_bytes(content)
    return path


def truncated_field(work):
    """A field file cut to its first third."""
    synthetic_plume(GRID).save(work / "f.npz")
    whole = (work / "f.npz").read_bytes()
    return written(work, "f.npz", whole[: len(whole) // 3])


@pytest.mark.parametrize(("content", "match"), [
    (RECORD[:100] + "\n", "l.par"),
    (edited(16, 25, "-1.000E-20"), "line 1|S296"),
    (edited(16, 25, "       nan"), "line 1|S296"),
    (edited(36, 40, "-.070"), "gamma_air"),
    (edited(3, 3, "#"), "isotopologue"),
    (edited(4, 15, "  abc.defghi"), "line 1|nu"),
    (bytes(range(256)) * 2, "l.par"),
], ids=["short record", "negative intensity", "NaN intensity", "negative width",
        "bad isotopologue", "text in a number", "binary garbage"])
def test_a_bad_line_record_is_named(tmp_path, content, match):
    with pytest.raises(Exception, match=match):
        par_file(tmp_path, content)


def test_a_missing_line_list_is_named(tmp_path):
    with pytest.raises(Exception, match="none.par"):
        read_par(tmp_path / "none.par")


def field_file(work, **changes):
    """The synthetic plume on :data:`GRID` saved as ``f.npz``, its entries changed as given."""
    path = synthetic_plume(GRID).save(work / "f.npz")
    stored = dict(np.load(path))
    stored.update(changes)
    np.savez(path, **stored)
    return path


@pytest.mark.parametrize(("changes", "match"), [
    ({"names": np.array(["CO2", "T", "H2O", "CH4"])},
     r"holds fields \('CO2', 'T', 'H2O', 'CH4'\); expected \('T', 'CO2', 'H2O', 'CH4'\)"),
    ({"metadata": np.array("{not json")}, "entry 'metadata' is not JSON"),
    ({"values": np.zeros((4, 3, 8, 8))}, r"field values must have shape \(4, 8, 8, 8\)"),
    ({"shape": np.array([8, 8])}, "shape must be three positive integers"),
    ({"values": np.full((4, 8, 8, 8), np.nan)}, "NaN or inf"),
], ids=["reordered names", "metadata not JSON", "values of another shape", "2-D grid",
        "NaN"])
def test_a_field_file_of_bad_content_is_named(tmp_path, changes, match):
    path = field_file(tmp_path, **changes)
    with pytest.raises(InputDataError, match=match) as err:
        Field.load(path)
    assert str(err.value).startswith(str(path))


def checkpoint_without(work, key):
    """A run's checkpoint whose header lacks ``key``."""
    meta = {entry: 0 for entry in HEADER if entry != key}
    return save_checkpoint(work / "checkpoint.npz", meta, np.zeros(3), None, {})


CASES = {
    "Field.load empty": (lambda w: Field.load(written(w, "f.npz", b"")), "f.npz"),
    "Field.load truncated": (lambda w: Field.load(truncated_field(w)), "f.npz"),
    "Field.load of a plain array": (lambda w: (np.save(w / "a.npy", np.ones(3)),
                                               Field.load(w / "a.npy")), "a.npy"),
    "Field.load of another npz": (lambda w: (write_npz(w / "o.npz", x=np.ones(3)),
                                             Field.load(w / "o.npz")), "o.npz"),
    "truth.source truncated": (lambda w: runner.load_truth(config.validate(
        {"truth": {"source": str(truncated_field(w)), "grid": 8}})), "f.npz"),
    "checkpoint empty": (lambda w: load_checkpoint(written(w, "checkpoint.npz", b"")),
                         "checkpoint.npz"),
    "checkpoint garbage": (lambda w: load_checkpoint(written(w, "checkpoint.npz", b"x" * 500)),
                           "checkpoint.npz"),
    "checkpoint torn zip": (lambda w: load_checkpoint(
        written(w, "checkpoint.npz", b"PK\x03\x04" + b"\0" * 80)), "checkpoint.npz"),
    "absorption table empty": (lambda w: AbsorptionTable.load(written(w, "t.npz", b"")),
                               "t.npz"),
    "absorption table without lines": (lambda w: AbsorptionTable.build(
        {"H2O": par_file(w, RECORD + "\n")}, wavenumber=900.0 + 0.1 * np.arange(11),
        temperatures=[300.0, 1000.0]), "900"),
    "checkpoint without its iteration": (lambda w: read_run(checkpoint_without(w, "iteration")),
                                         r"checkpoint .*checkpoint.npz lacks the header "
                                         r"entries \['iteration'\]; delete it"),
}
"""Case → ``(call, match)``: ``call(folder)`` must raise a message that ``match`` finds."""


@pytest.mark.parametrize(("call", "match"), CASES.values(), ids=CASES.keys())
def test_a_damaged_or_foreign_file_is_named(tmp_path, call, match):
    with pytest.raises(Exception, match=match):
        call(tmp_path)


def test_a_run_folder_locked_by_a_live_process_is_refused_and_kept(tmp_path):
    lock = tmp_path / LOCK
    lock.write_text(f"{os.getppid()}\n")  # the process that started the tests: alive
    with pytest.raises(Exception, match="process"), RunLock(tmp_path):
        pass
    assert lock.read_text() == f"{os.getppid()}\n"


def test_writing_under_a_file_is_refused_and_the_file_kept(tmp_path):
    (tmp_path / "file").write_text("results of another day\n")
    with pytest.raises(Exception, match="file"):
        write_npz(tmp_path / "file" / "x.npz", a=np.ones(2))
    assert (tmp_path / "file").read_text() == "results of another day\n"


def test_a_full_disk_is_named_with_the_file_and_the_file_kept(tmp_path, monkeypatch):
    """A disk that fills up while a file is written (found at the flush to disk)."""
    path = write_text(tmp_path / "summary.json", json.dumps({"kept": True}))

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OSError, match="No space left on device") as err:
        write_text(path, "{}")
    assert err.value.errno == errno.ENOSPC and err.value.filename == str(path)
    assert json.loads(path.read_text()) == {"kept": True}
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left
