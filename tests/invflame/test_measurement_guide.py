"""The user guide's measurement-file page: its hand-written example makes a valid file."""

import re
import warnings
from pathlib import Path

import numpy as np

from invflame.measurement_file import read_measurement

PAGE = Path(__file__).resolve().parents[2] / "docs" / "guide" / "measurement_files.md"
SECTION = "## A minimal file, written by hand"
WINDOWS = "## Cameras of different instruments"


def example_code(heading: str = SECTION) -> list[str]:
    """The Python blocks of the page's section under ``heading`` (default: the minimal file),
    in order."""
    text = PAGE.read_text(encoding="utf-8")
    section = text.split(heading, 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)


def test_the_minimal_example_writes_a_file_the_reader_accepts(tmp_path, monkeypatch):
    blocks = example_code()
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for block in blocks:
            exec(compile(block, str(PAGE), "exec"), {})
        measured = read_measurement(tmp_path / "measured.nc")
    m = measured.measurement
    assert measured.rig.n_cameras == 4 and measured.rig.image_shapes == ((8, 8),) * 4
    assert m.data.shape == (4 * 64, 12) and measured.resolution == 8.0
    assert m.noisy and np.nanmax(m.sigma[np.isfinite(m.sigma)]) == 2e-3
    bad = np.isinf(m.sigma).all(axis=1)
    assert np.flatnonzero(bad).tolist() == [2 * 64 + 0 * 8 + 5]  # camera 2, v 0, u 5
    assert m.n_measurements == (4 * 64 - 1) * 12
    assert all(camera.principal_point == (4.0, 4.0) for camera in measured.rig.cameras)


def test_the_window_example_gives_one_camera_its_own_window(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    blocks = example_code() + example_code(WINDOWS)
    assert len(blocks) == 3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for block in blocks:
            exec(compile(block, str(PAGE), "exec"), {})
        measured = read_measurement(tmp_path / "windows.nc")
    assert measured.windows == (None, (668.0, 680.0), None, None)
    inside = (measured.wavenumber >= 668.0) & (measured.wavenumber <= 680.0)
    assert measured.measurement.n_measurements == (4 * 64 - 1) * 12 - 64 * (~inside).sum()


def test_the_page_is_in_the_guide_and_the_configuration_guide_points_to_it():
    guide = PAGE.parent
    assert "\nmeasurement_files\n" in (guide / "index.md").read_text(encoding="utf-8")
    configuration = (guide / "configuration.md").read_text(encoding="utf-8")
    assert "by you\n  ({doc}`measurement_files`)" in configuration
