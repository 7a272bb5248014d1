"""The ``co2`` subcommand: ``write`` produces a readable .par file."""

import argparse

from invflame.cli import co2, main
from invflame.spectroscopy.linelist import read_par


def _parse(argv):
    parser = argparse.ArgumentParser(prog="invflame")
    co2.add_parser(parser.add_subparsers(dest="command", required=True))
    return parser.parse_args(argv)


def test_write_produces_par_file(tmp_path, capsys):
    path = tmp_path / "co2.par"
    args = _parse(["co2", "write", str(path), "--nu-min", "667", "--nu-max", "668"])
    assert args.func(args) == 0
    lines = read_par(path)
    assert len(lines) > 20 and lines.nu.min() >= 667 and lines.nu.max() <= 668
    assert "wrote" in capsys.readouterr().out


def test_validate_reports_missing_reference(tmp_path, capsys):
    missing = tmp_path / "missing.par"
    assert main(["co2", "validate", "--reference", str(missing)]) == 2
    assert f"reference line file not found: {missing} (pass --reference PATH)" in \
        capsys.readouterr().err
