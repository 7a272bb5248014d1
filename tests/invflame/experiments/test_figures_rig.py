"""The figures of a run whose rig is not four square cameras: three cameras of unequal pixels."""

import json

import matplotlib.image
import numpy as np
import pytest

from invflame.experiments import config, figures
from invflame.experiments.config_text import dumps
from invflame.geometry import paper_rig
from invflame.geometry.rig_file import rig_records

PIXELS = ([6, 5], [4, 4], [5, 5])
"""(columns, rows) of each camera."""


@pytest.fixture
def run_folder(tmp_path, plume_fields):
    """A finished run's folder on the 10³ pool-fire grid, seen by three unequal cameras."""
    truth, estimates = plume_fields
    cameras = rig_records(paper_rig(truth.grid, n_pixels=5))[:3]
    for record, pixels in zip(cameras, PIXELS, strict=True):
        record["pixels"] = pixels
        del record["principal_point"]  # the image centre
    cfg = config.validate({"truth": {"grid": 10, "source": "synthetic"},
                           "rig": {"cameras": cameras}})
    folder = tmp_path / "VG-TV"
    folder.mkdir()
    (folder / "config.toml").write_text(dumps(cfg))
    truth.save(folder / "truth.npz")
    estimates["start"].save(folder / "initial.npz")
    estimates["smoothed"].save(folder / "reconstruction.npz")
    n_rays = sum(u * v for u, v in PIXELS)
    measured = np.random.default_rng(1).random((n_rays, 6))
    np.savez(folder / "data.npz", measured=measured, simulated=0.8 * measured,
             sigma=np.full(6, 1e-3), out_wavenumber=np.linspace(660.0, 690.0, 6))
    rows = ["iteration,loss,misfit,regularizer,grad_norm,time"]
    rows += [f"{i},{10.0 / (i + 1)},{8.0 / (i + 1)},0.1,1.0,{0.5 * i}" for i in range(5)]
    (folder / "history.csv").write_text("\n".join(rows) + "\n")
    (folder / "summary.json").write_text(json.dumps({"iterations": 4, "epochs": 4.0,
                                                      "config": cfg}))
    return folder


def test_the_run_s_rig_comes_from_its_configuration(run_folder):
    rig = figures.run_rig(run_folder)
    assert rig.image_shapes == ((5, 6), (4, 4), (5, 5))  # (rows, columns)


def test_every_figure_of_a_rig_of_unequal_cameras_is_drawn(run_folder, tmp_path, monkeypatch):
    closed = []
    monkeypatch.setattr(figures.plt, "close", closed.append)
    out = tmp_path / "figures"
    written = figures.comparison_figures(out, {"VG/TV": run_folder})
    assert [p.name for p in written] == ["cutaways.png", "errors.png", "isotherms_3d.png",
                                         "loss_curves.png", "spectrum_image.png"]
    for path in written:
        assert matplotlib.image.imread(path).size > 0
    spectrum = closed[-1]
    images = [ax.images[0].get_array().shape for ax in spectrum.axes if ax.images]
    assert images == [(5, 6), (4, 4), (5, 5)] * 2  # every camera, measured and simulated
    titles = [ax.get_title() for ax in spectrum.axes if ax.images]
    assert titles[:3] == ["camera 1 (6×5 px)\nmeasured", "camera 2 (4×4 px)\nmeasured",
                          "camera 3 (5×5 px)\nmeasured"]
    assert closed[-2].axes[1].get_ylabel() == figures.MISFIT_LABELS[True]
