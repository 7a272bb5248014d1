"""Bad input on the command line: a bad configuration, argument or file is refused before
anything is computed, with exit status 2, no traceback and one ``error:`` line naming the key,
argument or file, and no file that was there before is changed; ``config.validate`` raises
naming the key."""

import errno
import os
import tomllib

import numpy as np
import pytest

from invflame.cli import main
from invflame.errors import ConfigError
from invflame.experiments import config, runner
from invflame.experiments.config import NON_NEGATIVE, POSITIVE
from invflame.experiments.run_folder import INCOMPLETE, LOCK
from invflame.spectroscopy.absorption_table import AbsorptionTable

from ..experiments.test_config_checks import field_file

SECTIONS = {"truth": ['source = "synthetic"', "grid = 8"], "rig": ["pixels = 4"],
            "spectrum": ["min = 660.0", "max = 700.0", "step = 0.1"],
            "solver": ['name = "adam"', "iterations = 3"]}
"""A tiny valid configuration by section: 8³ grid, 4×4 pixels, 660–700 cm⁻¹, 3 iterations."""


def configuration(section: str = "", lines: str = "") -> str:
    """The tiny configuration as TOML text with ``lines`` (``key = value`` each, or any text)
    set in ``[section]``, replacing the lines of the same keys there, or at the top when
    ``section`` is empty."""
    sections = {name: list(body) for name, body in SECTIONS.items()}
    if section:
        keys = {line.split("=")[0].strip() for line in lines.splitlines()}
        sections[section] = lines.splitlines() + [
            line for line in sections.get(section, []) if line.split("=")[0].strip() not in keys]
    tables = [f"[{name}]\n" + "\n".join(body) for name, body in sections.items()]
    return "\n".join(([lines] if lines and not section else []) + tables) + "\n"


BASE = configuration()
"""The tiny configuration as TOML text."""

CHECKED = ([(f"{s}.{k} = {v}", s, f"{k} = {v}", (f"{s}.{k}",))
            for s, k in sorted(POSITIVE) for v in ("0", "-1")]
           + [(f"{s}.{k} = -1", s, f"{k} = -1", (f"{s}.{k}",)) for s, k in sorted(NON_NEGATIVE)])
"""Every key that must be positive, at 0 and -1, and every one that must be non-negative."""

SPECIAL = [
    ("seed = -3", "", "seed = -3", ("seed",)),
    ("seed = 1.5", "", "seed = 1.5", ("seed",)),
    ("lr as a string", "solver", 'options = { lr = "0.01" }', ("solver.options.lr",)),
    ("max_iter in options", "solver", "options = { max_iter = 5 }",
     ("solver.options.max_iter",)),
    ("unknown solver option", "solver", "options = { learning_rate = 0.1 }",
     ("solver.options",)),
    ("negative lr", "solver", "options = { lr = -0.1 }", ("solver.options",)),
    ("unknown solver", "solver", 'name = "adamm"', ("solver.name",)),
    ("spectrum.step = 100", "spectrum", "step = 100", ("spectrum.step",)),
    ("spectrum.step = nan", "spectrum", "step = nan", ("spectrum.step",)),
    ("spectrum.max = inf", "spectrum", "max = inf", ("spectrum.max",)),
    ("instrument.sampling = 1000", "instrument", "sampling = 1000", ("instrument.sampling",)),
    ("window narrower than 2 resolutions", "instrument", "resolution = 30.0",
     ("instrument.resolution", "spectrum.min")),
    ("cameras inside the grid", "rig", "distance = 0.1", ("rig.distance",)),
    ("init.noise = 5", "init", 'kind = "noisy-truth"\nnoise = 5', ("init.noise",)),
    ("window with no lines", "spectrum", "min = 900.0\nmax = 940.0",
     ("spectrum.min", "spectrum.max")),
    ("truth.grid = 1", "truth", "grid = 1", ("truth.grid",)),
    ("truth.grid = 2", "truth", "grid = 2", ("truth.grid",)),
    ("truth.source missing file", "truth", 'source = "nowhere.npz"',
     ("truth.source", "nowhere.npz")),
    ("unknown section", "", "[solvr]\nname = 'gd'", ("solvr",)),
    ("unknown key", "rig", "pixel = 4", ("rig.pixel",)),
    ("grid as a string", "truth", 'grid = "big"', ("truth.grid",)),
    ("bad regularizer", "regularizer", 'kind = "tvv"', ("regularizer.kind",)),
    ("bad lambda word", "regularizer", 'lambda = "auto"', ("regularizer.lambda",)),
    ("negative lambda", "regularizer", "lambda = -1.0", ("regularizer.lambda",)),
    ("lambda_range reversed", "regularizer", "lambda_range = [10.0, 1.0]",
     ("regularizer.lambda_range",)),
    ("tau below 1", "regularizer", "tau = 0.5", ("regularizer.tau",)),
    ("discrepancy with paper scaling", "regularizer",
     'lambda = "discrepancy"\nscaling = "paper"', ("regularizer.scaling",)),
    ("ambient too hot", "init", "ambient = [900.0, 0.0, 0.0, 0.0]", ("init.ambient",)),
    ("ambient below the tables", "init", "ambient = [200.0, 0.0, 0.0, 0.0]",
     ("init.ambient", "250 K")),
    ("ambient too short", "init", "ambient = [300.0]", ("init.ambient",)),
    ("rays_per_pixel not square", "rig", "rays_per_pixel = 8", ("rig.rays_per_pixel",)),
    ("nesr negative", "noise", "nesr = -1e-3", ("noise.nesr",)),
    ("nesr file missing", "noise", 'nesr = "no_such_nesr.txt"',
     ("noise.nesr", "no_such_nesr.txt")),
    ("bad noise kind", "noise", 'kind = "gaussian"', ("noise.kind",)),
    ("bad representation", "representation", 'kind = "mlp"', ("representation.kind",)),
    ("inverse_crime as string", "data", 'inverse_crime = "yes"', ("data.inverse_crime",)),
    ("section as value", "", "truth = 3", ("truth", "bad.toml")),
    ("spectrum min above max", "spectrum", "min = 710.0", ("spectrum.min",)),
]
"""Other bad values: ``(case, section, lines, names)``; the message names one of ``names``."""



@pytest.fixture
def refused(tmp_path, capsys):
    """``refused(argv, names, files=None, keep=())`` writes ``files`` (path under ``tmp_path``
    → text or bytes), runs ``invflame`` with ``argv`` and checks that it refuses the input
    clearly: exit status 2, no traceback, one ``error:`` line on stderr naming one of ``names``
    (a key, argument or file), and the files ``keep`` unchanged. ``{work}`` in ``argv`` and
    ``names`` stands for ``tmp_path``."""
    def check(argv, names, files=None, keep=()):
        for name, content in (files or {}).items():
            path = tmp_path / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                path.write_bytes(content)
            else:
                path.write_text(content)
        before = {name: (tmp_path / name).read_bytes() for name in keep}
        try:
            status = main([word.format(work=tmp_path) for word in argv])
        except SystemExit as stop:  # argparse's usage errors
            status = stop.code
        err = capsys.readouterr().err
        errors = [line for line in err.splitlines() if "error:" in line]
        assert status == 2 and "Traceback" not in err, f"exit status {status}: {err}"
        assert len(errors) == 1, err
        assert any(name.format(work=tmp_path) in errors[0] for name in names), err
        assert {name: (tmp_path / name).read_bytes() for name in keep} == before
    return check


def test_the_tiny_configuration_is_valid():
    config.validate(tomllib.loads(configuration()))


@pytest.mark.parametrize(("section", "lines", "names"),
                         [case[1:] for case in CHECKED + SPECIAL],
                         ids=[case[0] for case in CHECKED + SPECIAL])
def test_a_bad_value_is_refused_naming_its_key(refused, section, lines, names):
    refused(["run", "{work}/bad.toml", "--out", "{work}/out", "--quiet"], names,
            files={"bad.toml": configuration(section, lines)})


@pytest.mark.parametrize(("argv", "names", "files"), [
    (["run", "{work}/m.toml"], ("m.toml",), {"m.toml": "[solver\n"}),
    (["run", "{work}/u.toml"], ("u.toml",), {"u.toml": BASE.encode("utf-16")}),
    (["run", "{work}/g.toml"], ("g.toml",), {"g.toml": bytes(range(256))}),
    (["run", "{work}"], ("configuration", "{work}"), {}),
    (["simulate", "{work}/none.toml"], ("none.toml",), {}),
], ids=["malformed TOML", "UTF-16 configuration", "binary garbage configuration",
        "configuration is a folder", "missing configuration"])
def test_an_unreadable_configuration_file_is_named(refused, argv, names, files):
    refused([*argv, "--out", "{work}/out"], names, files=files)


@pytest.mark.parametrize(("settings", "match"), [
    ({"seed": -3}, "seed"),
    ({"truth": {"grid": 8.5}}, "truth.grid"),
    ({"solver": {"options": 3}}, "solver.options"),
], ids=["seed -3", "grid as float", "options not a table"])
def test_validate_names_the_bad_key(settings, match):
    with pytest.raises(ConfigError, match=match):
        config.validate(settings)


OLD = "results of another day\n"
"""What a file that must survive holds."""

CASES = {
    "--out is a file": (["run", "{work}/base.toml", "--out", "{work}/file"], ("--out",),
                        {"base.toml": BASE, "file": OLD}, ("file",)),
    "--out under a file": (["simulate", "{work}/base.toml", "--out", "{work}/file/sub"],
                           ("--out",), {"base.toml": BASE, "file": OLD}, ("file",)),
    "study --out is a file": (["study", "--out", "{work}/file"], ("--out",), {"file": OLD},
                              ("file",)),
    "reproduce --out under a file": (["reproduce", "--out", "{work}/file/x"], ("--out",),
                                     {"file": OLD}, ("file",)),
    "sweep --out is a file": (["sweep", "{work}/base.toml", "--param", "seed=1,2", "--out",
                               "{work}/file"], ("--out",), {"base.toml": BASE, "file": OLD},
                              ("file",)),
    "sweep unknown key": (["sweep", "{work}/base.toml", "--param", "solver.lrr=1,2", "--out",
                           "{work}/s"], ("solver.lrr",), {"base.toml": BASE}, ()),
    "sweep without values": (["sweep", "{work}/base.toml", "--param", "seed=", "--out",
                              "{work}/s"], ("seed", "--param"), {"base.toml": BASE}, ()),
    "sweep bad value": (["sweep", "{work}/base.toml", "--param", "truth.grid=-1,8", "--out",
                         "{work}/s"], ("truth.grid",), {"base.toml": BASE}, ()),
    "study unknown preset": (["study", "--preset", "huge", "--out", "{work}/s"], ("--preset",),
                             {}, ()),
    "study truth missing": (["study", "--truth", "{work}/none.npz", "--out", "{work}/s"],
                            ("none.npz",), {}, ()),
    "study truth garbage": (["study", "--truth", "{work}/bad.npz", "--out", "{work}/s"],
                            ("bad.npz",), {"bad.npz": b"garbage" * 50}, ()),
    "plot of an empty folder": (["plot", "{work}"], ("{work}",), {}, ()),
    "plot of a missing folder": (["plot", "{work}/none"], ("{work}/none",), {}, ()),
    "export of an empty folder": (["export", "{work}"], ("{work}",), {}, ()),
    "lines plot --out DIR": (["lines", "plot", "--out", "{work}"], ("--out",), {}, ()),
    "lines plot --x-co2 -0.5": (["lines", "plot", "--out", "{work}/l.png", "--x-co2", "-0.5"],
                                ("--x-co2",), {}, ()),
    "lines plot --x-h2o 2": (["lines", "plot", "--out", "{work}/l.png", "--x-h2o", "2"],
                             ("--x-h2o",), {}, ()),
    "lines plot --length -1": (["lines", "plot", "--out", "{work}/l.png", "--length", "-1"],
                               ("--length",), {}, ()),
    "lines plot --resolution 0": (["lines", "plot", "--out", "{work}/l.png", "--resolution",
                                   "0"], ("--resolution",), {}, ()),
    "lines plot --temperatures -5": (["lines", "plot", "--out", "{work}/l.png",
                                      "--temperatures", "-5"], ("--temperatures",), {}, ()),
    "co2 write outside the band": (["co2", "write", "{work}/co2.par", "--nu-min", "2000",
                                    "--nu-max", "2100"], ("--nu-min", "co2.par"), {}, ()),
    "co2 write over a file outside the band": (["co2", "write", "{work}/old.par", "--nu-min",
                                                "2000", "--nu-max", "2100"], ("old.par",),
                                               {"old.par": OLD}, ("old.par",)),
    "co2 write reversed window": (["co2", "write", "{work}/co2.par", "--nu-min", "700",
                                   "--nu-max", "650"], ("--nu-min",), {}, ()),
    "co2 validate missing reference": (["co2", "validate", "--reference", "{work}/none.par"],
                                       ("none.par",), {}, ()),
    "co2 validate garbage reference": (["co2", "validate", "--reference", "{work}/bad.par"],
                                       ("bad.par",), {"bad.par": "not a record\n"}, ()),
    "phantom write unknown name": (["phantom", "write", "candle", "--out", "{work}/p.npz"],
                                   ("candle", "phantom"), {}, ()),
    "phantom write --n 0": (["phantom", "write", "synthetic", "--n", "0", "--out",
                             "{work}/p.npz"], ("--n", " n "), {}, ()),
    "phantom write --perturbation 5": (["phantom", "write", "synthetic", "--seed", "1",
                                        "--perturbation", "5", "--out", "{work}/p.npz"],
                                       ("--perturbation", "perturbation"), {}, ()),
    "phantom info of garbage": (["phantom", "info", "{work}/bad.npz"], ("bad.npz",),
                                {"bad.npz": b""}, ()),
    "phantom from-openfoam missing case": (["phantom", "from-openfoam", "{work}/nocase",
                                            "--time", "0.9", "--out", "{work}/f.npz"],
                                           ("nocase",), {}, ()),
    "run into a folder another process writes": (
        ["run", "{work}/base.toml", "--out", "{work}/out"], ("{work}/out", "process"),
        {"base.toml": BASE, "out/.lock": f"{os.getppid()}\n"}, ("out/.lock",)),
    "run --resume of another configuration": (
        ["run", "{work}/other.toml", "--out", "{work}/done", "--resume"], ("config", "seed"),
        {"other.toml": "seed = 7\n" + BASE, "done/config.toml": "seed = 0\n" + BASE},
        ("done/config.toml",)),
}
"""Case → ``(argv, names, files, keep)``: ``{work}`` is the test's folder, the message names
one of ``names``, ``files`` are written first and those of ``keep`` must survive unchanged."""

@pytest.mark.parametrize(("argv", "names", "files", "keep"), [
    pytest.param(*case, id=name) for name, case in CASES.items()])
def test_a_bad_command_line_is_refused_naming_what_is_wrong(refused, argv, names, files, keep):
    refused(argv, names, files, keep)


@pytest.mark.parametrize(("arguments", "names"), [
    (["--x-co2", "0.7", "--x-h2o", "0.7"], ("--x-co2",)),
    (["--slab-temperature", "9000"], ("--slab-temperature",)),
], ids=["fractions sum above 1", "slab outside the table"])
def test_lines_plot_refuses_a_slab_the_table_cannot_give(refused, monkeypatch, table, arguments,
                                                         names):
    monkeypatch.setattr(AbsorptionTable, "default", classmethod(lambda cls: table))
    refused(["lines", "plot", "--out", "{work}/l.png", *arguments], names)


TRUTHS = {
    "truth at 100 K": ({"temperature": 100.0}, "holds temperatures 100-100 K, outside"),
    "truth at 5000 K": ({"temperature": 5000.0}, "holds temperatures 5000-5000 K, outside"),
    "truth of reordered names": ({"names": np.array(["CO2", "T", "H2O", "CH4"])},
                                 "holds fields ('CO2', 'T', 'H2O', 'CH4')"),
    "truth metadata not JSON": ({"metadata": np.array("{oops")},
                                "entry 'metadata' is not JSON"),
    "truth of another shape": ({"values": np.zeros((4, 3, 4, 4))},
                               "field values must have shape (4, 4, 4, 4)"),
}
"""Case → ``(changes of the field file t.npz, words of the message)``."""


@pytest.mark.parametrize(("changes", "words"), TRUTHS.values(), ids=TRUTHS.keys())
def test_a_bad_truth_file_is_refused_before_a_folder_is_made(refused, tmp_path, monkeypatch,
                                                            changes, words):
    monkeypatch.chdir(tmp_path)
    field_file(tmp_path / "t.npz", **changes)
    files = {"c.toml": configuration("truth", 'source = "t.npz"')}
    for argv in (["config", "c.toml"], ["run", "c.toml", "--out", "out", "--quiet"]):
        refused(argv, [f"'truth.source' = 't.npz'{between}{words}"
                       for between in (" ", ": t.npz ", ": t.npz: ")], files)
    assert not (tmp_path / "out").exists()
    if "outside" not in words:  # a field, but not for the absorption table
        refused(["phantom", "info", "t.npz"], (f"t.npz {words}", f"t.npz: {words}"))


@pytest.mark.parametrize("out", ["link", "link/run"])
def test_out_through_a_link_to_nothing_is_refused(refused, tmp_path, out):
    (tmp_path / "link").symlink_to(tmp_path / "gone")
    refused(["run", "{work}/base.toml", "--out", "{work}/" + out],
            (f"is a link to {tmp_path / 'gone'}, which does not exist",), {"base.toml": BASE})
    assert not (tmp_path / "gone").exists()


def test_out_in_a_folder_this_user_may_not_write_in_is_refused(refused, tmp_path, monkeypatch):
    (tmp_path / "locked").mkdir()
    access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode: path != tmp_path / "locked"
                        and access(path, mode))  # as chmod 555 does for all but root
    refused(["run", "{work}/base.toml", "--out", "{work}/locked/run"],
            ("lies under {work}/locked, which is a folder this user may not write in",),
            {"base.toml": BASE})
    assert list((tmp_path / "locked").iterdir()) == []


def test_a_folder_the_system_refuses_to_create_is_named(refused, tmp_path, monkeypatch):
    mkdir = os.mkdir

    def refuse(path, *args, **kwargs):
        if str(path).startswith(str(tmp_path / "out")):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
        mkdir(path, *args, **kwargs)

    monkeypatch.setattr(os, "mkdir", refuse)
    refused(["run", "{work}/base.toml", "--out", "{work}/out", "--quiet"],
            ("output folder {work}/out cannot be created (Permission denied)",),
            {"base.toml": BASE})


def test_a_disk_that_fills_up_during_a_run_is_named_and_the_folder_marked(refused, tmp_path,
                                                                         monkeypatch):
    def full(path, **arrays):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(runner, "write_npz", full)  # data.npz, written after the solver
    refused(["run", "{work}/base.toml", "--out", "{work}/out", "--quiet"],
            ("{work}/out/data.npz: No space left on device: free space on its disk",),
            {"base.toml": BASE})
    left = {p.name for p in (tmp_path / "out").iterdir()}
    assert INCOMPLETE in left and LOCK not in left and "reconstruction.npz" in left
