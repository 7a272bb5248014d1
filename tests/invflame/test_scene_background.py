"""A scene in front of a background: the forward map with a wall or measured spectra per camera."""

from pathlib import Path

import numpy as np
import pytest

import operators as op
from invflame.background import BlackbodyWall, MeasuredBackground
from invflame.background_file import background_from_config, read_background, write_background
from invflame.errors import InputDataError
from invflame.geometry import VoxelGrid, paper_rig
from invflame.measurement import Measurement
from invflame.measurement_file import MeasurementFile, write_measurement
from invflame.scene import Scene
from operators.rte.planck import planck

from .test_scene import physical_direction, small_table, smooth_field

GRID = VoxelGrid.cube(5, size=1.0, centre=(0.0, 0.5, 0.0))


def per_camera(wavenumber, n_cameras=4):
    """Four different smooth backgrounds, W/(m2 sr cm-1)."""
    return np.array([e * planck(wavenumber, t) for e, t in
                     zip((0.9, 0.6, 0.8, 0.3), (500.0, 700.0, 350.0, 900.0), strict=True)])


@pytest.fixture(scope="module")
def plain():
    return Scene(GRID, paper_rig(GRID, n_pixels=3), small_table(), resolution=4.0,
                 dtype=np.float64, planck="exact")


@pytest.fixture(scope="module")
def walled(plain):
    wavenumber = np.linspace(640.0, 680.0, 41)
    return plain.with_background(MeasuredBackground(wavenumber, per_camera(wavenumber)))


def test_a_background_adds_its_transmitted_radiance_per_camera(plain, walled):
    """Through empty air (no absorber) every pixel sees its camera's background through the
    instrument; through the flame less of it."""
    air = np.stack([np.full(GRID.shape, 300.0), *np.zeros((3, *GRID.shape))])
    seen = walled.operator(air)
    expected = walled.ils(np.repeat(walled.background.on_grid(walled.wavenumber, 4), 9, axis=0))
    np.testing.assert_allclose(seen, expected, rtol=1e-12)
    assert np.all(plain.operator(air) == 0)
    fields = smooth_field(GRID)
    flame_only, with_wall = plain.operator(fields), walled.operator(fields)
    assert np.all(with_wall - flame_only <= expected * (1 + 1e-12))
    assert np.all(with_wall - flame_only > 0)


def test_the_pieces_give_the_scene_map_with_background(walled):
    fields = smooth_field(GRID, seed=4)
    by_pieces = walled.ils(walled.emission(walled.sampling(fields)))
    np.testing.assert_allclose(walled.operator(fields), by_pieces, rtol=1e-12)


def test_forward_map_with_background_dot_and_taylor_tests(walled):
    fields = smooth_field(GRID, seed=3)
    dot = op.jacobian_dottest(walled.operator, fields, rtol=1e-10)
    assert dot.passed, dot
    taylor = op.taylor_test(walled.operator, fields, physical_direction(fields), h0=1.0)
    assert taylor.passed, taylor
    assert taylor.rate1 > 1.9  # the linearization remainder falls as h^2


def test_blackbody_wall_and_its_configuration():
    wall = background_from_config({"kind": "blackbody", "temperature": 600.0,
                                   "emissivity": 0.7, "file": ""})
    eta = np.array([660.0, 700.0])
    np.testing.assert_allclose(wall.on_grid(eta, 2), 0.7 * planck(eta, 600.0)[None].repeat(2, 0))
    assert background_from_config({"kind": "none", "temperature": 300.0, "emissivity": 1.0,
                                   "file": ""}) is None
    with pytest.raises(ValueError, match="emissivity must lie in"):
        BlackbodyWall(600.0, 1.5)
    with pytest.raises(ValueError, match="temperature must be positive"):
        BlackbodyWall(-1.0)


def test_background_file_round_trip_and_bad_files(tmp_path):
    eta = np.linspace(650.0, 700.0, 11)
    written = MeasuredBackground(eta, per_camera(eta))
    back = read_background(write_background(written, tmp_path / "bg.nc"))
    np.testing.assert_array_equal(back.radiance, written.radiance)
    np.testing.assert_array_equal(back.wavenumber, eta)
    with pytest.raises(ValueError, match="holds 4 spectra but the rig has 3 cameras"):
        back.on_grid(eta, 3)
    (tmp_path / "junk.nc").write_text("not netcdf")
    with pytest.raises(InputDataError, match="junk.nc: not a NetCDF background file"):
        read_background(tmp_path / "junk.nc")
    with pytest.raises(ValueError, match="must be finite and >= 0"):
        MeasuredBackground(eta, -per_camera(eta))


def test_a_flameless_measurement_file_is_a_background(plain, tmp_path):
    """A frame without the flame, written as a measurement file, read back as the per-camera
    mean of its (here identical) pixels' spectra."""
    wall = plain.with_background(BlackbodyWall(700.0, 0.5))
    air = np.stack([np.full(GRID.shape, 300.0), *np.zeros((3, *GRID.shape))])
    frame = wall.simulate(air)
    measured = MeasurementFile(Measurement(frame, np.full(frame.shape[1], 1e-3), True, {}),
                               wall.rig, wall.out_wavenumber, wall.resolution)
    background = read_background(write_measurement(measured, tmp_path / "frame.nc"))
    np.testing.assert_allclose(background.radiance, frame[::9], rtol=1e-12)
    np.testing.assert_array_equal(background.wavenumber, wall.out_wavenumber)


def test_a_flameless_frame_with_camera_windows_holds_each_camera_at_its_window_edges(
        plain, tmp_path):
    """A camera with its own window: its background is the frame's mean inside the window and
    its nearest measured value outside it (never zero or NaN); the other cameras are the
    frame's mean everywhere."""
    wall = plain.with_background(BlackbodyWall(700.0, 0.5))
    air = np.stack([np.full(GRID.shape, 300.0), *np.zeros((3, *GRID.shape))])
    frame = wall.simulate(air)
    eta = wall.out_wavenumber
    window = (float(eta[len(eta) // 3]), float(eta[2 * len(eta) // 3]))
    inside = (eta >= window[0]) & (eta <= window[1])
    sigma = np.full(frame.shape, 1e-3)
    sigma[:9, ~inside] = np.inf  # camera 0 (9 pixels) measures its window only
    measured = MeasurementFile(Measurement(np.where(np.isfinite(sigma), frame, np.nan), sigma,
                                           True, {}),
                               wall.rig, eta, wall.resolution,
                               windows=(window,) + (None,) * (wall.rig.n_cameras - 1))
    background = read_background(write_measurement(measured, tmp_path / "frame.nc"))
    first = frame[0]
    expected = np.interp(eta, eta[inside], first[inside])
    np.testing.assert_allclose(background.radiance[0], expected, rtol=1e-12)
    assert not np.allclose(expected[~inside], first[~inside])  # the wall's spectrum changes
    np.testing.assert_allclose(background.radiance[1:], frame[9::9], rtol=1e-12)


def test_a_flameless_frame_with_a_camera_that_measures_nothing_is_refused(plain, tmp_path):
    wall = plain.with_background(BlackbodyWall(700.0, 0.5))
    air = np.stack([np.full(GRID.shape, 300.0), *np.zeros((3, *GRID.shape))])
    frame = wall.simulate(air)
    sigma = np.full(frame.shape, 1e-3)
    sigma[9:18] = np.inf  # every pixel of camera 1 bad
    measured = MeasurementFile(Measurement(frame, sigma, True, {}), wall.rig,
                               wall.out_wavenumber, wall.resolution)
    with pytest.raises(InputDataError, match=r"frame\.nc: camera 1 measures no value"):
        read_background(write_measurement(measured, tmp_path / "frame.nc"))


def test_background_and_soot_on_two_devices_equal_one_device(script_report):
    """The sharded map splits the sub-rays' cameras with the rays and replicates the
    backgrounds and the soot (run in a fresh process with two forced CPU devices)."""
    check = Path(__file__).resolve().parent / "sharded_background_check.py"
    result = script_report(check, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    assert result["devices"] == 2
    assert result["forward"] < 1e-12 and result["vjp"] < 1e-12, result
