"""Cutaway figures of fields and the `phantom plot` command."""

import argparse

import numpy as np
import pytest

from invflame.cli import phantom
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume
from invflame.plotting.fields import mid_plane, plot_fields


def test_mid_plane_averages_the_two_central_layers():
    volume = np.arange(4 * 3 * 2, dtype=float).reshape(4, 3, 2)
    np.testing.assert_array_equal(mid_plane(volume, 0), volume[1:3].mean(axis=0))
    np.testing.assert_array_equal(mid_plane(volume, 1), volume[:, 1, :])


def test_side_by_side_figure_shares_colour_scales(tmp_path):
    truth = synthetic_plume(VoxelGrid.poolfire(16))
    other = synthetic_plume(VoxelGrid.poolfire(16), perturbation=0.3, seed=0)
    fig = plot_fields([truth, other], labels=["truth", "perturbed"], path=tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 10_000
    axes = np.array(fig.axes[:16]).reshape(4, 4)
    for row in axes:
        limits = {ax.images[0].get_clim() for ax in row}
        assert len(limits) == 1  # one colour scale per row
    t_lo, t_hi = axes[0, 0].images[0].get_clim()
    assert t_hi == pytest.approx(max(truth.T.max(), other.T.max()))
    assert axes[0, 0].collections, "isotherms drawn"
    with pytest.raises(ValueError, match="one per field"):
        plot_fields([truth], labels=["a", "b"])


def test_cli_plot_and_write(tmp_path, capsys):
    parser = argparse.ArgumentParser()
    phantom.add_parser(parser.add_subparsers())
    out = tmp_path / "s.npz"
    args = parser.parse_args(["phantom", "write", "synthetic", "--n", "12", "--out", str(out)])
    assert args.func(args) == 0
    png = tmp_path / "s.png"
    args = parser.parse_args(["phantom", "plot", str(out), "--out", str(png)])
    assert args.func(args) == 0 and png.stat().st_size > 10_000
    sheet = tmp_path / "sheet.npz"
    args = parser.parse_args(["phantom", "write", "synthetic", "--n", "12", "--sheet-rise",
                              "1950", "--out", str(sheet)])
    assert args.func(args) == 0 and Field.load(sheet).metadata["sheet_rise_K"] == 1950.0
    for name, rise, message in (("synthetic", "500", "at least the continuous flame's"),
                                ("poolfire", "1950", "apply to 'synthetic', not poolfire")):
        args = parser.parse_args(["phantom", "write", name, "--sheet-rise", rise,
                                  "--out", str(tmp_path / "no.npz")])
        with pytest.raises(SystemExit, match=message):
            args.func(args)
    assert not (tmp_path / "no.npz").exists()
    args = parser.parse_args(["phantom", "info", "nonexistent.npz"])
    with pytest.raises(SystemExit, match="neither a field file nor a phantom name"):
        args.func(args)
