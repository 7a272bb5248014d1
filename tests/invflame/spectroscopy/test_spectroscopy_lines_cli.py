"""The ``invflame lines plot`` subcommand and its slab radiance."""

import argparse

import numpy as np

from invflame.cli import lines as lines_cli
from invflame.spectroscopy.absorption_table import AbsorptionTable
from operators.rte.planck import planck


def test_slab_radiance_limits(table):
    x = np.array([0.1, 0.2, 0.0])
    b = planck(table.wavenumber, 1300.0)
    kappa = table.kappa(np.asarray(1300.0), x)
    thin = lines_cli.slab_radiance(table, 1300.0, x, 1e-6)
    np.testing.assert_allclose(thin, b * kappa * 1e-6, rtol=1e-4)
    thick = lines_cli.slab_radiance(table, 1300.0, x, 1e6)
    np.testing.assert_allclose(thick, b, rtol=1e-12)


def test_lines_plot_writes_png(table, tmp_path, monkeypatch):
    monkeypatch.setattr(AbsorptionTable, "default", classmethod(lambda cls: table))
    parser = argparse.ArgumentParser()
    lines_cli.add_parser(parser.add_subparsers())
    out = tmp_path / "fig" / "lines.png"
    args = parser.parse_args(["lines", "plot", "--out", str(out)])
    assert args.func(args) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
