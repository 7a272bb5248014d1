"""A configuration is checked whole before anything is written: every error at once, the files
it names read as the run reads them, the memory its arrays need, physical ranges."""

import re

import numpy as np
import pytest

from invflame.cli import main
from invflame.experiments import config, config_memory
from invflame.experiments.inputs import TEMPERATURE_RANGE
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.spectroscopy.table_inputs import DEFAULT_TEMPERATURES

SMALL = {"truth": {"grid": 8}, "rig": {"pixels": 4}}


def messages(settings: dict) -> list[str]:
    with pytest.raises(config.ConfigError) as err:
        config.validate(settings)
    return err.value.messages


def field_file(path, temperature=1000.0, **changes):
    """A small field file (the pool fire's box, 4³ voxels), its entries changed as given."""
    values = np.zeros((4, 4, 4, 4))
    values[0], values[1], values[2] = temperature, 0.1, 0.2
    Field(VoxelGrid.poolfire(4), values).save(path)
    stored = dict(np.load(path))
    stored.update(changes)
    np.savez(path, **stored)
    return str(path)


def test_every_error_is_reported_at_once():
    found = messages({"solvr": {}, "seed": -1,
                      "truth": {"grid": "big"},
                      "regularizer": {"kind": "tvv"},
                      "rig": {"rays_per_pixel": 8},
                      "spectrum": {"min": 700.0, "max": 690.0},
                      "init": {"kind": "noisy-truth"}, "data": {"source": "gone.nc"}})
    assert len(found) == 8, found
    expected = [r"unknown key 'solvr' \(did you mean 'solver'\?\); allowed: background, ",
                r"'seed' must be a non-negative integer, got -1",
                r"'truth.grid' must be an integer, got 'big'; the default is `grid = 30`",
                r"'regularizer.kind' = 'tvv' is not allowed .*allowed: 'none', 'tikhonov' or",
                r"'rig.rays_per_pixel' must be a perfect square",
                r"'init.kind' = 'noisy-truth' needs a ground truth but 'truth.source' is 'none'",
                r"'spectrum.min' must be below 'spectrum.max', got 700.0 and 690.0",
                r"'data.source' = 'gone.nc' is not an existing measurement file"]
    for pattern, message in zip(expected, found, strict=True):
        assert re.match(pattern, message), (pattern, message)


def test_a_check_reading_a_refused_key_is_left_out():
    """The default standing in for a refused key does not raise errors of its own."""
    assert messages({"spectrum": {"min": "x", "max": 600.0}}) == [
        "'spectrum.min' must be a number, got 'x'; the default is `min = 650.0` in [spectrum]"]


def test_config_and_run_print_one_line_per_error_and_write_nothing(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("seed = -1\n[rig]\npixels = 0\n[solver]\nname = 'adamm'\n")
    for command in (["config", str(path)], ["run", str(path), "--out", str(tmp_path / "out")]):
        assert main(command) == 2
        lines = capsys.readouterr().err.splitlines()
        assert len(lines) == 3
        prefix = f"invflame {command[0]}: error: {path}: "
        assert all(line.startswith(prefix) for line in lines)
        assert [line[len(prefix):].split()[0] for line in lines] == [
            "'seed'", "'rig.pixels'", "'solver.name':"]
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("changes", "words"), [
    ({}, None),
    ({"values": np.zeros((4, 4, 4, 4), np.complex64) + 1000.0},
     "stores its fields as complex numbers"),
    ({"values": np.full((4, 4, 4, 4), np.nan)}, "NaN or inf"),
    ({"values": np.full((3, 4, 4, 4), 0.1), "names": np.array(["T", "CO2", "H2O"])},
     "holds fields ('T', 'CO2', 'H2O')"),
    ({"shape": np.array([4, 4])}, "'truth.source' = "),
    ({"temperature": 3000.0}, "temperatures 3000-3000 K, outside the absorption table's "
                              "250-2500 K"),
])
def test_the_truth_file_is_read_as_the_run_reads_it(tmp_path, changes, words):
    temperature = changes.pop("temperature", 1000.0)
    source = field_file(tmp_path / "truth.npz", temperature, **changes)
    settings = {**SMALL, "truth": {**SMALL["truth"], "source": source}}
    if words is None:
        assert config.validate(settings)["truth"]["source"] == source
        return
    [message] = messages(settings)
    assert message.startswith(f"'truth.source' = {source!r}") and words in message


def test_config_refuses_a_missing_or_damaged_truth_file(tmp_path, capsys):
    damaged = tmp_path / "damaged.npz"
    damaged.write_bytes(b"not a zip file" * 10)
    for source, words in [(tmp_path / "missing.npz", "is neither 'poolfire', 'synthetic', "
                           "'none' nor an existing field file"),
                          (damaged, "is damaged or incomplete")]:
        path = tmp_path / "run.toml"
        path.write_text(f"[truth]\nsource = '{source}'\n")
        assert main(["config", str(path)]) == 2
        [line] = capsys.readouterr().err.splitlines()
        assert line.startswith(f"invflame config: error: {path}: 'truth.source' = '{source}'")
        assert words in line


def test_the_other_files_named_are_checked(tmp_path):
    garbage = tmp_path / "garbage.nc"
    garbage.write_bytes(b"\x00" * 100)
    nesr = tmp_path / "nesr.txt"
    nesr.write_text("600 1e-3\n650 1e-3\n")  # ends below the output grid
    found = messages({**SMALL, "data": {"source": str(garbage)},
                      "background": {"kind": "file", "file": str(garbage)},
                      "spectrum": {"co2_lines": str(tmp_path / "co2.par")}})
    assert [m.split(" = ")[0] for m in found] == ["'data.source'", "'background.file'",
                                                   "'spectrum.co2_lines'"]
    assert "is not an existing file" in found[2]
    [message] = messages({**SMALL, "noise": {"nesr": str(nesr)}})
    assert message.startswith(f"'noise.nesr' = {str(nesr)!r}: ") and "covers 600-650" in message


@pytest.mark.parametrize(("section", "key", "value", "words"), [
    ("truth", "grid", 100000, "'truth.grid' = 100000: the fields on the reconstruction grid "
                              "would take about 1.49e+07 GiB (4 fields x 1000000000000000 "
                              "voxels x 4 bytes), more than this machine's 4 GiB"),
    ("rig", "rays_per_pixel", 1000000, "'rig.rays_per_pixel' = 1000000, 'truth.grid' = 30: "
                                       "the voxel crossings of the reconstruction's sub-rays "
                                       "would take about 5.49e+03 GiB"),
    ("spectrum", "step", 1e-7, "'spectrum.step' = 1e-07: the absorption table of the "
                               "reconstruction would take about 7.24e+03 GiB"),
    ("instrument", "sampling", 1e-7, "'instrument.sampling' = 1e-07: the instrument's "
                                     "lineshape matrix of the reconstruction would take about "
                                     "4.12e+03 GiB"),
    ("spectrum", "max", 1e12, "'spectrum.max' = 1000000000000.0, 'spectrum.step' = 0.04: the "
                              "absorption table of the reconstruction would take about "
                              "2.41e+08 GiB"),
])
def test_arrays_larger_than_the_memory_are_refused_before_they_are_made(
        monkeypatch, section, key, value, words):
    monkeypatch.setattr(config_memory, "machine_memory", lambda: 4 * 2**30)
    found = messages({section: {key: value}})
    assert any(words in message for message in found), found
    assert all("would take" in m for m in found if "line data" not in m)


def test_the_defaults_and_the_paper_fit_a_small_machine(monkeypatch):
    monkeypatch.setattr(config_memory, "machine_memory", lambda: 2**30)
    config.validate({})
    sizes = {e.what: e.nbytes for e in config_memory.estimates(config.validate({}),
                                                                {"rig": None})}
    assert sizes["the fields on the reconstruction grid"] == 4 * 4 * 30**3


@pytest.mark.parametrize(("settings", "words"), [
    ({"spectrum": {"pressure": 1e12}}, "'spectrum.pressure' (Pa) must be in [1000, 1e+07]"),
    ({"spectrum": {"pressure": 1e-6}}, "'spectrum.pressure' (Pa) must be in [1000, 1e+07]"),
    ({"background": {"kind": "blackbody", "temperature": 1e7}},
     "'background.temperature' (K) must be in (0, 2500]"),
    ({"spectrum": {"min": 799.0, "max": 840.0}},
     "'spectrum.min'..'spectrum.max' = 799-840 cm-1 reaches past the line data: the built-in "
     "line data cover 600-800 cm-1"),
])
def test_values_outside_physical_or_tabulated_ranges_are_refused(settings, words):
    assert any(words in message for message in messages(settings))


def test_the_bounds_are_the_absorption_tables():
    assert TEMPERATURE_RANGE == (DEFAULT_TEMPERATURES[0], DEFAULT_TEMPERATURES[-1])
    assert config.SCHEMA["background"].keys["temperature"].high == TEMPERATURE_RANGE[1]
