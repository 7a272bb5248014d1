"""A rig of unequal cameras, one with a spectral window of its own, from the command line:
simulate, run with and without a ground truth, plot and export."""

import json

import numpy as np
import pytest

from invflame.cli import main
from invflame.experiments import figures
from invflame.geometry import CameraRig, PinholeCamera, VoxelGrid, paper_rig
from invflame.geometry.rig_file import write_rig
from invflame.measurement_file import read_measurement

PIXELS = ((6, 5), (4, 4), (5, 5))
"""(columns, rows) of each camera."""

WINDOW = (670.0, 678.0)
"""The first camera's own window, cm⁻¹; the others measure every channel, 668-682 cm⁻¹."""

SETTINGS = """
seed = 0
[rig]
file = "rig.toml"
rays_per_pixel = 1
[spectrum]
min = 660.0
max = 690.0
step = 0.1
[init]
kind = "ambient"
[representation]
parameters = "fields"
[solver]
name = "adam"
iterations = 2
options = { lr = 0.01 }
"""
"""What the simulation and both runs share: tiny, so that each command takes seconds."""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The rig file and the configurations: the experiment (a synthetic truth rendered on the
    reconstruction's 6³ grid) and the run from its measurement file alone."""
    root = tmp_path_factory.mktemp("windows")
    cameras = [PinholeCamera(c.position, c.look_at, c.up, c.focal_length, c.sensor_size, pixels)
               for c, pixels in zip(paper_rig(VoxelGrid.poolfire(6), n_pixels=5).cameras,
                                    PIXELS, strict=False)]
    write_rig(CameraRig(cameras), root / "rig.toml", [{"window": list(WINDOW)}, {}, {}])
    (root / "experiment.toml").write_text(SETTINGS + """
[truth]
source = "synthetic"
grid = 6
[data]
inverse_crime = true
""")
    (root / "blind.toml").write_text(SETTINGS + """
[truth]
grid = 6
[data]
source = "m.nc"
[instrument]
margin = 0  # the file's data were simulated on this window: model it alike
""")
    return root


def test_unequal_cameras_with_their_own_windows_run_end_to_end(folder, monkeypatch, capsys):
    monkeypatch.chdir(folder)
    assert main(["simulate", "experiment.toml", "--out", "m.nc"]) == 0
    measured = read_measurement("m.nc")
    assert measured.rig.image_shapes == ((5, 6), (4, 4), (5, 5))
    assert measured.windows == (WINDOW, None, None)
    wavenumber = measured.wavenumber
    inside = (wavenumber >= WINDOW[0]) & (wavenumber <= WINDOW[1])
    counts = measured.measurement.measured.sum(axis=1)
    assert set(counts[:30]) == {inside.sum()} and set(counts[30:]) == {wavenumber.size}
    assert np.all(measured.measurement.data[:30, ~inside] == 0)

    assert main(["run", "experiment.toml", "--out", "scored", "--quiet"]) == 0
    assert main(["run", "blind.toml", "--out", "blind", "--quiet"]) == 0
    scored, blind = (json.loads((folder / run / "summary.json").read_text())
                     for run in ("scored", "blind"))
    assert "mse" in scored and "mse" not in blind
    assert blind["chi2_per_measurement"] == pytest.approx(scored["chi2_per_measurement"],
                                                          rel=1e-6)
    assert blind["measured_instrument"]["windows"] == [list(WINDOW), None, None]
    saved = np.load(folder / "scored" / "data.npz")
    np.testing.assert_array_equal(np.isfinite(saved["sigma"]), measured.measurement.measured)

    closed = []
    monkeypatch.setattr(figures.plt, "close", closed.append)
    capsys.readouterr()
    for run in ("scored", "blind"):
        assert main(["plot", run]) == 0
        assert main(["export", run]) == 0
        spectrum = closed[-1].axes[0]  # the spectrum panel of spectrum_image.png
        first = spectrum.lines[0].get_xydata()  # camera 1's brightest pixel, measured
        shown = first[np.isfinite(first[:, 1]), 0]
        np.testing.assert_array_equal(shown, wavenumber[inside])
        assert spectrum.get_title().startswith("brightest pixel of each camera")
    printed = capsys.readouterr().out
    for name in ("scored/cutaways.png", "scored/spectrum_image.png", "blind/spectrum_image.png",
                 "blind/loss_curves.png", "scored/fields.nc", "blind/reconstruction.vti"):
        assert f"wrote {name}" in printed
    assert "blind/cutaways.png" not in printed  # no ground truth to compare with
