"""Bad input on the command line: a message naming what was wrong, exit status 2, no traceback."""

import pytest

from invflame.cli import main
from invflame.errors import ConfigError
from invflame.spectroscopy.absorption_table import AbsorptionTable


def test_an_error_prints_its_message_and_exits_2(tmp_path, capsys):
    config = tmp_path / "bad.toml"
    config.write_text("seed = -3\n")
    assert main(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"invflame run: error: {config}: 'seed' must be a non-negative")
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()  # refused before the output folder is touched
    with pytest.raises(ConfigError, match="'seed' must be a non-negative integer"):
        main(["--debug", "run", str(config), "--out", str(tmp_path / "out")])


def test_a_missing_configuration_is_named(tmp_path, capsys):
    assert main(["simulate", str(tmp_path / "none.toml"), "--out", str(tmp_path)]) == 2
    assert f"configuration file not found: {tmp_path / 'none.toml'}" in capsys.readouterr().err


@pytest.mark.parametrize("command", [["run", "c.toml"], ["simulate", "c.toml"],
                                     ["study", "--preset", "quick"],
                                     ["sweep", "c.toml", "--param", "seed=1,2"]])
@pytest.mark.parametrize(("out", "message"), [("file", "is a file"),
                                              ("file/sub", "lies under the file")])
def test_out_that_is_a_file_or_under_one_is_refused(tmp_path, capsys, command, out, message):
    (tmp_path / "file").write_text("results of another day\n")
    with pytest.raises(SystemExit) as exit_info:
        main([*command, "--out", str(tmp_path / out)])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --out: output folder {tmp_path / out} {message}" in err
    assert (tmp_path / "file").read_text() == "results of another day\n"


@pytest.mark.parametrize(("arguments", "message"), [
    (["--x-co2", "-0.5"], "argument --x-co2: a mole fraction must be in [0, 1], got -0.5"),
    (["--x-h2o", "nan"], "argument --x-h2o: expected a finite number, got 'nan'"),
    (["--length", "0"], "argument --length: must be positive, got 0"),
    (["--temperatures", "300", "abc"], "argument --temperatures: expected a number, got 'abc'"),
])
def test_lines_plot_refuses_unphysical_slabs(tmp_path, capsys, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["lines", "plot", "--out", str(tmp_path / "l.png"), *arguments])
    assert exit_info.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "l.png").exists()


def test_lines_plot_checks_the_mixture_and_temperatures_against_the_table(
        tmp_path, capsys, monkeypatch, table):
    monkeypatch.setattr(AbsorptionTable, "default", classmethod(lambda cls: table))
    out = str(tmp_path / "l.png")
    assert main(["lines", "plot", "--out", out, "--x-co2", "0.6", "--x-h2o", "0.6"]) == 2
    assert "--x-co2 0.6 plus --x-h2o 0.6 exceed 1" in capsys.readouterr().err
    assert main(["lines", "plot", "--out", out, "--slab-temperature", "5000"]) == 2
    assert "--slab-temperature 5000 K lies outside the absorption table's 250-1600 K" in \
        capsys.readouterr().err


def test_lines_plot_out_names_the_file_it_writes(tmp_path, capsys, monkeypatch, table):
    monkeypatch.setattr(AbsorptionTable, "default", classmethod(lambda cls: table))
    with pytest.raises(SystemExit):
        main(["lines", "plot", "--out", str(tmp_path)])
    assert f"{tmp_path} is a folder: give a file name, e.g. {tmp_path / 'lines.png'}" in \
        capsys.readouterr().err
    assert main(["lines", "plot", "--out", str(tmp_path / "lines")]) == 0
    assert capsys.readouterr().out == f"wrote {tmp_path / 'lines.png'}\n"
    assert (tmp_path / "lines.png").read_bytes()[:4] == b"\x89PNG"
    assert not (tmp_path / "lines").exists()


def test_co2_write_outside_the_band_leaves_no_file(tmp_path, capsys):
    path = tmp_path / "co2.par"
    assert main(["co2", "write", str(path), "--nu-min", "2000", "--nu-max", "2100"]) == 2
    assert "no generated CO2 line in 2000-2100 cm-1" in capsys.readouterr().err
    assert not path.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("arguments", "message"), [
    (["--n", "0"], "argument --n: must be a positive integer, got 0"),
    (["--seed", "1", "--perturbation", "5"], "argument --perturbation: must lie in [0, 1), got 5"),
])
def test_phantom_write_refuses_bad_sizes(tmp_path, capsys, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["phantom", "write", "synthetic", "--out", str(tmp_path / "p.npz"), *arguments])
    assert exit_info.value.code == 2 and message in capsys.readouterr().err


@pytest.mark.parametrize("content", [b"", b"garbage" * 50])
def test_a_damaged_field_file_is_named_without_a_traceback(tmp_path, capsys, content):
    path = tmp_path / "field.npz"
    path.write_bytes(content)
    assert main(["phantom", "info", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"invflame phantom: error: field file {path} is damaged or incomplete")
    assert "Traceback" not in err
