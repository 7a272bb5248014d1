"""Audit: bad and hostile inputs across the command line and the Python API.

Runs every case of :func:`cases` (tiny sizes: 8³ grids, 4×4 pixels, 660–700 cm⁻¹) in this
process and sorts its outcome into

- **clear error**: refused, with a message (no traceback) that names the expected key, file or
  argument;
- **unclear error**: a traceback (an exception the command line does not explain), or a message
  that names none of them;
- **silent garbage**: accepted, with no error;
- **data loss**: a file that was there before the case is changed or gone.

Prints one line per case that is not a clear error, then the totals::

    INVFLAME_CACHE=/tmp/audit-cache python benchmarks/bad_inputs.py [--verbose]

The first run builds two small absorption tables (some seconds); the cases then take a few
seconds each at most (a case that passes its checks is stopped after ``LIMIT`` seconds and
counted as silent garbage).
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import os
import re
import signal
import sys
import tempfile
import tomllib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

LIMIT = 60
"""Seconds a case may run before it counts as accepted (silent garbage)."""

BASE = """\
[truth]
source = "synthetic"
grid = 8
[rig]
pixels = 4
[spectrum]
min = 660.0
max = 700.0
step = 0.1
[solver]
name = "adam"
iterations = 3
"""

OUTCOMES = ("clear error", "unclear error", "silent garbage", "data loss")


@dataclass
class Case:
    """One bad input.

    Attributes
    ----------
    name : str
        What is wrong.
    run : callable
        ``run(work)`` in a fresh folder ``work``: a CLI case returns ``main``'s exit status,
        an API case raises or returns.
    names : tuple of str
        A clear message names at least one of these (key, argument, file).
    keep : tuple of str
        Files under ``work`` that must survive unchanged (created by ``setup``).
    setup : callable, optional
        ``setup(work)`` before the case.
    """

    name: str
    run: object
    names: tuple
    keep: tuple = ()
    setup: object = None
    kind: str = field(default="api")


def _config(work: Path, text: str, name: str = "bad.toml") -> Path:
    path = work / name
    path.write_text(text)
    return path


def _with(section: str, lines: str) -> str:
    """The base configuration with ``lines`` (``key = value``) set in ``[section]`` (or at the
    top): replacing the base's line of the same key, or added."""
    if not section:
        return lines + "\n" + BASE
    text = BASE if f"[{section}]" in BASE else BASE + f"[{section}]\n"
    for line in lines.split("\n"):
        key = line.split("=")[0].strip()
        text = re.sub(rf"^{re.escape(key)} = .*\n", "", text, flags=re.M) if \
            f"[{section}]" in BASE else text
        text = text.replace(f"[{section}]\n", f"[{section}]\n{line}\n")
    return text


def cli(name, argv, names, keep=(), setup=None) -> Case:
    """A command-line case: ``argv`` may hold ``{work}``."""
    from invflame.cli import main

    def run(work):
        return main([a.format(work=work) for a in argv])
    return Case(name, run, names, keep, setup, kind="cli")


def config_case(name, section, line, names) -> Case:
    """``invflame run`` of the base configuration with one bad line."""
    from invflame.cli import main

    def run(work):
        return main(["run", str(_config(work, _with(section, line))), "--out",
                     str(work / "out"), "--quiet"])
    return Case(name, run, names, kind="cli")


def _sentinel(path_name: str, text: str = "results of another day\n"):
    def setup(work):
        path = work / path_name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return setup


def config_cases() -> list[Case]:
    """Bad values of every checked key of a configuration."""
    from invflame.experiments.config import NON_NEGATIVE, POSITIVE

    out = []
    for section, key in sorted(POSITIVE):
        key_name = f"{section}.{key}"
        for value in ("0", "-1"):
            out.append(config_case(f"{key_name} = {value}", section, f"{key} = {value}",
                                   (key_name,)))
    for section, key in sorted(NON_NEGATIVE):
        out.append(config_case(f"{section}.{key} = -1", section, f"{key} = -1",
                               (f"{section}.{key}",)))
    special = [
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
        ("instrument.sampling = 1000", "instrument", "sampling = 1000",
         ("instrument.sampling",)),
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
    out += [config_case(*case) for case in special]
    out.append(cli("malformed TOML", ["run", "{work}/m.toml", "--out", "{work}/out"],
                   ("m.toml",), setup=lambda w: _config(w, "[solver\n", "m.toml")))
    out.append(cli("UTF-16 configuration", ["run", "{work}/u.toml", "--out", "{work}/out"],
                   ("u.toml",),
                   setup=lambda w: (w / "u.toml").write_bytes(BASE.encode("utf-16"))))
    out.append(cli("binary garbage configuration", ["run", "{work}/g.toml", "--out",
                                                    "{work}/out"], ("g.toml",),
                   setup=lambda w: (w / "g.toml").write_bytes(bytes(range(256)))))
    out.append(cli("configuration is a folder", ["run", "{work}", "--out", "{work}/out"],
                   ("configuration", "{work}")))
    out.append(cli("missing configuration", ["simulate", "{work}/none.toml"],
                   ("none.toml",)))
    return out


def _base(work):
    return _config(work, BASE, "base.toml")


def command_cases() -> list[Case]:
    """Bad command lines beyond the configuration."""
    base = ["{work}/base.toml"]
    return [
        cli("--out is a file", ["run", *base, "--out", "{work}/file"], ("--out",),
            keep=("file",), setup=lambda w: (_base(w), _sentinel("file")(w))),
        cli("--out under a file", ["simulate", *base, "--out", "{work}/file/sub"], ("--out",),
            keep=("file",), setup=lambda w: (_base(w), _sentinel("file")(w))),
        cli("study --out is a file", ["study", "--out", "{work}/file"], ("--out",),
            keep=("file",), setup=_sentinel("file")),
        cli("reproduce --out under a file", ["reproduce", "--out", "{work}/file/x"],
            ("--out",), keep=("file",), setup=_sentinel("file")),
        cli("sweep --out is a file", ["sweep", *base, "--param", "seed=1,2", "--out",
                                      "{work}/file"], ("--out",), keep=("file",),
            setup=lambda w: (_base(w), _sentinel("file")(w))),
        cli("sweep unknown key", ["sweep", *base, "--param", "solver.lrr=1,2", "--out",
                                  "{work}/s"], ("solver.lrr",), setup=_base),
        cli("sweep without values", ["sweep", *base, "--param", "seed=", "--out",
                                     "{work}/s"], ("seed", "--param"), setup=_base),
        cli("sweep bad value", ["sweep", *base, "--param", "truth.grid=-1,8", "--out",
                                "{work}/s"], ("truth.grid",), setup=_base),
        cli("study unknown preset", ["study", "--preset", "huge", "--out", "{work}/s"],
            ("--preset",)),
        cli("study truth missing", ["study", "--truth", "{work}/none.npz", "--out",
                                    "{work}/s"], ("none.npz",)),
        cli("study truth garbage", ["study", "--truth", "{work}/bad.npz", "--out", "{work}/s"],
            ("bad.npz",), setup=lambda w: (w / "bad.npz").write_bytes(b"garbage" * 50)),
        cli("plot of an empty folder", ["plot", "{work}"], ("{work}",)),
        cli("plot of a missing folder", ["plot", "{work}/none"], ("{work}/none",)),
        cli("export of an empty folder", ["export", "{work}"], ("{work}",)),
        cli("lines plot --out DIR", ["lines", "plot", "--out", "{work}"], ("--out",)),
        cli("lines plot --x-co2 -0.5", ["lines", "plot", "--out", "{work}/l.png", "--x-co2",
                                        "-0.5"], ("--x-co2",)),
        cli("lines plot --x-h2o 2", ["lines", "plot", "--out", "{work}/l.png", "--x-h2o", "2"],
            ("--x-h2o",)),
        cli("lines plot --length -1", ["lines", "plot", "--out", "{work}/l.png", "--length",
                                       "-1"], ("--length",)),
        cli("lines plot --resolution 0", ["lines", "plot", "--out", "{work}/l.png",
                                          "--resolution", "0"], ("--resolution",)),
        cli("lines plot --temperatures -5", ["lines", "plot", "--out", "{work}/l.png",
                                             "--temperatures", "-5"], ("--temperatures",)),
        cli("lines plot --slab-temperature 9000", ["lines", "plot", "--out", "{work}/l.png",
                                                   "--slab-temperature", "9000"],
            ("--slab-temperature",)),
        cli("lines plot fractions sum above 1", ["lines", "plot", "--out", "{work}/l.png",
                                                 "--x-co2", "0.7", "--x-h2o", "0.7"],
            ("--x-co2",)),
        cli("co2 write outside the band", ["co2", "write", "{work}/co2.par", "--nu-min",
                                           "2000", "--nu-max", "2100"], ("--nu-min",
                                                                         "co2.par")),
        cli("co2 write over a file outside the band", ["co2", "write", "{work}/old.par",
                                                       "--nu-min", "2000", "--nu-max", "2100"],
            ("old.par",), keep=("old.par",), setup=_sentinel("old.par")),
        cli("co2 write reversed window", ["co2", "write", "{work}/co2.par", "--nu-min", "700",
                                          "--nu-max", "650"], ("--nu-min",)),
        cli("co2 validate missing reference", ["co2", "validate", "--reference",
                                               "{work}/none.par"], ("none.par",)),
        cli("co2 validate garbage reference", ["co2", "validate", "--reference",
                                               "{work}/bad.par"], ("bad.par",),
            setup=lambda w: (w / "bad.par").write_text("not a record\n")),
        cli("phantom write unknown name", ["phantom", "write", "candle", "--out",
                                           "{work}/p.npz"], ("candle", "phantom")),
        cli("phantom write --n 0", ["phantom", "write", "synthetic", "--n", "0", "--out",
                                    "{work}/p.npz"], ("--n", " n ")),
        cli("phantom write --perturbation 5", ["phantom", "write", "synthetic", "--seed", "1",
                                               "--perturbation", "5", "--out", "{work}/p.npz"],
            ("--perturbation", "perturbation")),
        cli("phantom info of garbage", ["phantom", "info", "{work}/bad.npz"], ("bad.npz",),
            setup=lambda w: (w / "bad.npz").write_bytes(b"")),
        cli("phantom from-openfoam missing case", ["phantom", "from-openfoam",
                                                   "{work}/nocase", "--time", "0.9",
                                                   "--out", "{work}/f.npz"],
            ("nocase",)),
        cli("run into a folder another process writes", ["run", *base, "--out", "{work}/out"],
            ("{work}/out", "process"), keep=("out/.lock",),
            setup=lambda w: (_base(w), _sentinel("out/.lock", f"{os.getppid()}\n")(w))),
        cli("run --resume of another configuration",
            ["run", "{work}/other.toml", "--out", "{work}/done", "--resume"],
            ("config", "seed"), keep=("done/config.toml",),
            setup=lambda w: (_config(w, "seed = 7\n" + BASE, "other.toml"),
                             _sentinel("done/config.toml", "seed = 0\n" + BASE)(w))),
    ]


def _expect_raise(function, *args, **kwargs):
    def run(work):
        return function(*args, **kwargs)
    return run


def api_cases() -> list[Case]:
    """Bad input through the Python API."""
    import solvers
    from invflame.atomic_files import write_npz
    from invflame.experiments import config, runner
    from invflame.experiments.initialization import noisy_truth
    from invflame.experiments.run_folder import LOCK, RunLock
    from invflame.field import Field
    from invflame.geometry import CameraRig, VoxelGrid, paper_rig
    from invflame.geometry.camera import PinholeCamera
    from invflame.phantoms import make_phantom
    from invflame.scene import Scene
    from invflame.spectroscopy.absorption_table import AbsorptionTable
    from invflame.spectroscopy.linelist import read_par
    from solvers.checkpoint import load_checkpoint

    tiny = config.validate(tomllib.loads(BASE))
    grid = VoxelGrid.poolfire(8)
    table = runner.absorption_table(tiny)
    scene = Scene(grid, paper_rig(grid, n_pixels=2), table)
    good = np.stack([np.full(grid.shape, 1000.0), np.full(grid.shape, 0.1),
                     np.full(grid.shape, 0.2), np.zeros(grid.shape)])
    record = Path(__file__).resolve().parents[1].joinpath(
        "invflame", "data", "H2O_HITRAN2012_600-800.par").read_text().splitlines()[0]

    def fields(**change):
        values = good.copy()
        for index, value in change.items():
            values[int(index[1:])] = value
        return values

    def par(work, text):
        (work / "l.par").write_text(text)
        return read_par(work / "l.par")

    def edit(columns, text):
        first, last = columns
        return record[: first - 1] + text + record[last:] + "\n"

    def problem(data):
        import operators as op
        return solvers.Problem(op.aslinearoperator(np.eye(3)), data, x0=np.zeros(3))

    def damaged(work, name, content):
        path = work / name
        path.write_bytes(content)
        return path

    def field_file(work):
        Field(grid, good).save(work / "f.npz")
        whole = (work / "f.npz").read_bytes()
        return damaged(work, "f.npz", whole[: len(whole) // 3])

    def checkpoint_file(work, content):
        return load_checkpoint(damaged(work, "checkpoint.npz", content))

    def locked(work):
        (work / LOCK).write_text(f"{os.getppid()}\n")
        with RunLock(work):
            pass

    away = PinholeCamera(grid.centre + [3.0, 0.0, 0.0], grid.centre + [6.0, 0.0, 0.0],
                         [0.0, 1.0, 0.0], 0.5, (0.1, 0.1), (2, 2))
    cases = [
        Case("simulate T = 5000 K", lambda w: scene.simulate(fields(f0=5000.0)),
             ("T", "temperature")),
        Case("simulate X_CO2 = -0.1", lambda w: scene.simulate(fields(f1=-0.1)), ("CO2",)),
        Case("simulate sum X > 1", lambda w: scene.simulate(fields(f1=0.6, f2=0.6)),
             ("sum", "mole fraction")),
        Case("simulate NaN T", lambda w: scene.simulate(fields(f0=np.nan)), ("NaN", "T")),
        Case("simulate wrong shape", lambda w: scene.simulate(good[:3]), ("shape",)),
        Case("operator T = 0 K", lambda w: scene.operator(fields(f0=0.0)), ("temperature",)),
        Case("operator T = 5000 K", lambda w: scene.operator(fields(f0=5000.0)),
             ("temperature", "table")),
        Case("operator X_CO2 = -0.5", lambda w: scene.operator(fields(f1=-0.5)), ("CO2",)),
        Case("operator fields last", lambda w: scene.operator(np.moveaxis(good, 0, -1)),
             ("shape",)),
        Case("jvp at T = -300 K", lambda w: scene.operator.jvp(fields(f0=-300.0), good),
             ("temperature",)),
        Case("vjp at NaN T", lambda w: scene.operator.vjp(
            fields(f0=np.nan), np.zeros(scene.operator.dimsd)), ("NaN", "T")),
        Case("linearize at X_H2O = 1.5", lambda w: scene.operator.linearize(fields(f2=1.5)),
             ("H2O",)),
        Case("EmissionRTE at T = 5000 K", lambda w: scene.emission(
            scene.sampling(good) * np.array([5.0, 1, 1, 1])[:, None, None]),
            ("temperature", "5000")),
        Case("EmissionRTE X_CO2 = -0.5", lambda w: scene.emission(
            scene.sampling(good) - np.array([0, 0.6, 0, 0])[:, None, None]),
            ("mole fraction", "negative")),
        Case("rig that misses the grid", lambda w: Scene(grid, CameraRig((away,)), table),
             ("grid", "camera")),
        Case("paper_rig inside the grid", lambda w: paper_rig(grid, distance=0.2),
             ("distance",)),
        Case("Problem NaN data", lambda w: problem(np.array([1.0, np.nan, 0.0])), ("NaN",)),
        Case("Problem inf data", lambda w: problem(np.array([1.0, np.inf, 0.0])),
             ("infinite", "inf")),
        Case("unknown solver", lambda w: solvers.get("adamm"), ("adamm",)),
        Case("solver option typo", lambda w: solvers.get("adam")(lrr=0.1), ("lrr",)),
        Case("solver lr as text", lambda w: solvers.get("adam")(lr="0.1"), ("lr",)),
        Case("solver negative seed", lambda w: solvers.solve(problem(np.ones(3)), "gd",
                                                             seed=-1), ("seed",)),
        Case("config.validate seed -3", lambda w: config.validate({"seed": -3}), ("seed",)),
        Case("config.validate grid as float", lambda w: config.validate({"truth": {"grid":
                                                                                  8.5}}),
             ("truth.grid",)),
        Case("config.validate options not a table",
             lambda w: config.validate({"solver": {"options": 3}}), ("solver.options",)),
        Case("read_par missing file", lambda w: read_par(w / "none.par"), ("none.par",)),
        Case("read_par short record", lambda w: par(w, record[:100] + "\n"), ("l.par",)),
        Case("read_par negative intensity", lambda w: par(w, edit((16, 25), "-1.000E-20")),
             ("line 1", "S296")),
        Case("read_par NaN intensity", lambda w: par(w, edit((16, 25), "       nan")),
             ("line 1", "S296")),
        Case("read_par negative width", lambda w: par(w, edit((36, 40), "-.070")),
             ("gamma_air",)),
        Case("read_par bad isotopologue", lambda w: par(w, edit((3, 3), "#")),
             ("isotopologue",)),
        Case("read_par text in a number", lambda w: par(w, edit((4, 15), "  abc.defghi")),
             ("line 1", "nu")),
        Case("read_par binary garbage", lambda w: ((w / "l.par").write_bytes(
            bytes(range(256)) * 2), read_par(w / "l.par")), ("l.par",)),
        Case("Field.load empty", lambda w: Field.load(damaged(w, "f.npz", b"")), ("f.npz",)),
        Case("Field.load truncated", lambda w: Field.load(field_file(w)), ("f.npz",)),
        Case("Field.load of a plain array", lambda w: (np.save(w / "a.npy", good),
                                                       Field.load(w / "a.npy")), ("a.npy",)),
        Case("Field.load of another npz", lambda w: (write_npz(w / "o.npz", x=np.ones(3)),
                                                     Field.load(w / "o.npz")), ("o.npz",)),
        Case("truth.source truncated", lambda w: (field_file(w), runner.load_truth(
            config.validate({"truth": {"source": str(w / "f.npz"), "grid": 8}}))), ("f.npz",)),
        Case("checkpoint empty", lambda w: checkpoint_file(w, b""), ("checkpoint.npz",)),
        Case("checkpoint garbage", lambda w: checkpoint_file(w, b"x" * 500),
             ("checkpoint.npz",)),
        Case("checkpoint torn zip", lambda w: checkpoint_file(w, b"PK\x03\x04" + b"\0" * 80),
             ("checkpoint.npz",)),
        Case("absorption table empty", lambda w: AbsorptionTable.load(damaged(w, "t.npz",
                                                                              b"")), ("t.npz",)),
        Case("absorption table without lines", lambda w: AbsorptionTable.build(
            {"H2O": par(w, record + "\n")}, wavenumber=900.0 + 0.1 * np.arange(11),
            temperatures=[300.0, 1000.0]), ("900",)),
        Case("noisy_truth negative noise", lambda w: noisy_truth(good, -1.0, 0), ("noise",)),
        Case("unknown phantom", lambda w: make_phantom("candle"), ("candle",)),
        Case("run folder locked by a live process", locked, ("process",), keep=(LOCK,),
             setup=lambda w: (w / LOCK).write_text(f"{os.getppid()}\n")),
        Case("write under a file", lambda w: write_npz(w / "file" / "x.npz", a=np.ones(2)),
             ("file",), keep=("file",), setup=_sentinel("file")),
        Case("VoxelGrid upper below lower", lambda w: VoxelGrid((0, 0, 0), (-1, 1, 1),
                                                                (4, 4, 4)), ("upper", "lower")),
        Case("VoxelGrid zero cells", lambda w: VoxelGrid((0, 0, 0), (1, 1, 1), (0, 4, 4)),
             ("shape",)),
        Case("camera looking along up", lambda w: PinholeCamera(
            [0.0, 5.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5, (0.1, 0.1), (2, 2)),
             ("up",)),
    ]
    return cases


def cases() -> list[Case]:
    """Every case of the audit."""
    return config_cases() + command_cases() + api_cases()


class _Timeout(BaseException):
    pass


def _on_alarm(signum, frame):
    raise _Timeout


def _digest(path: Path) -> str | None:
    return hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None


def classify(case: Case, work: Path) -> tuple[str, str]:
    """Run one case in ``work``; returns (outcome, message)."""
    if case.setup is not None:
        case.setup(work)
    before = {name: _digest(work / name) for name in case.keep}
    err, out = io.StringIO(), io.StringIO()
    names = tuple(n.format(work=work) for n in case.names)
    raised, text = None, ""
    signal.alarm(LIMIT)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            status = case.run(work)
    except SystemExit as stop:  # argparse's usage error, or SystemExit(message)
        status = stop.code
        text = stop.code if isinstance(stop.code, str) else err.getvalue() + out.getvalue()
    except _Timeout:
        status, text = 0, f"still running after {LIMIT} s"
    except Exception as exc:  # noqa: BLE001 - every exception is an outcome here
        raised, text = exc, f"{type(exc).__name__}: {exc}"
    finally:
        signal.alarm(0)
    after = {name: _digest(work / name) for name in case.keep}
    if after != before:
        return "data loss", f"changed: {[n for n in case.keep if after[n] != before[n]]}"
    if case.kind == "cli":
        if raised is not None:
            return "unclear error", "traceback: " + text
        if not status:
            return "silent garbage", text or "exit status 0"
        text = text or err.getvalue() + out.getvalue()
    elif raised is None:
        return "silent garbage", text or "returned without an error"
    if "Traceback" in text or not any(n in text for n in names):
        return "unclear error", text.strip().splitlines()[-1] if text.strip() else "(empty)"
    return "clear error", text.strip().splitlines()[-1]


def main(argv=None) -> int:
    """Run the audit; prints non-clear outcomes and the totals."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--verbose", action="store_true", help="print every case")
    args = parser.parse_args(argv)
    os.environ.setdefault("INVFLAME_CACHE", str(Path(tempfile.gettempdir()) / "invflame-audit"))
    signal.signal(signal.SIGALRM, _on_alarm)
    totals = Counter()
    all_cases = cases()
    for case in all_cases:
        with tempfile.TemporaryDirectory() as work:
            outcome, message = classify(case, Path(work))
        totals[outcome] += 1
        if args.verbose or outcome != "clear error":
            print(f"[{outcome}] {case.kind} {case.name}: {message[:300]}", flush=True)
    print(f"\n{len(all_cases)} cases: " + ", ".join(f"{totals[o]} {o}" for o in OUTCOMES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
