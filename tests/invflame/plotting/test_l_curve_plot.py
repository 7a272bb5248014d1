"""The L-curve figure of a choice of lambda: a PNG with the chosen point marked in red."""

import numpy as np
import pytest
from matplotlib.image import imread

import solvers
from invflame.plotting.parameter_choice import plot_l_curve

M = 60  # measurements


def red_pixels(path):
    image = imread(path)
    return int(np.sum((image[..., 0] > 0.9) & (image[..., 1] < 0.15) & (image[..., 2] < 0.15)))


def l_curve_choice():
    """An L-shaped sweep: chi2 grows and Phi falls with lambda, bending near lambda = 1."""
    lams = 10.0 ** np.arange(-4, 5.0)
    return solvers.l_curve(lams, M * (1 + lams), 1 + 1 / lams, n_measurements=M)


def discrepancy_choice():
    """chi2 = M (0.5 + lambda): the discrepancy level 1.5 M is met at lambda = 1."""
    return solvers.discrepancy_principle(lambda lam: (None, M * (0.5 + lam), 1 / (1 + lam)), M,
                                         lam_max=1e4, lam_min=1e-4, tau=1.5)


@pytest.mark.parametrize("make", [l_curve_choice, discrepancy_choice])
def test_the_plot_marks_the_chosen_point(tmp_path, make):
    path = plot_l_curve(make(), tmp_path / "figs" / "l_curve.png", phi_label="mean square [1]")
    assert path == tmp_path / "figs" / "l_curve.png"
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert red_pixels(path) > 50
    assert [p.name for p in path.parent.iterdir()] == ["l_curve.png"]  # no temporary left
