"""A spectral window per camera: read from rig and measurement files, simulated, kept out of
the misfit, written back, and refused where it cannot be measured."""

import numpy as np
import pytest
import xarray as xr

import operators as op
from invflame.errors import InputDataError
from invflame.experiments import data_start
from invflame.experiments.measurement import simulate_measurement
from invflame.field import Field
from invflame.geometry import CameraRig, PinholeCamera, VoxelGrid, paper_rig
from invflame.geometry.rig_file import check_instrument, parse_rig, read_rig, write_rig
from invflame.measurement import Measurement, channel_mask, check_windows
from invflame.measurement_file import MeasurementFile, read_measurement, write_measurement
from invflame.representations.whitening import whitened

CAMERA = {"position": [2.0, 0.5, 0.0], "look_at": [0.0, 0.5, 0.0], "up": [0.0, 1.0, 0.0],
          "focal_length": 0.5, "sensor_size": [0.4, 0.3], "pixels": [5, 3]}
WAVENUMBER = np.array([661.3, 663.0, 667.9, 668.4, 675.0, 690.2])  # irregular, cm-1
NESR = {"kind": "nesr", "nesr": 1e-3, "snr": 100.0}


def unequal_rig() -> CameraRig:
    """Two cameras: 3 columns × 2 rows, then 2 × 4."""
    cameras = paper_rig(VoxelGrid.poolfire(8), n_pixels=3).cameras[:2]
    return CameraRig([PinholeCamera(c.position, c.look_at, c.up, c.focal_length, c.sensor_size,
                                    pixels)
                      for c, pixels in zip(cameras, ((3, 2), (2, 4)), strict=True)])


def test_a_rig_file_gives_each_camera_its_own_window(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text("\n".join(
        "[[cameras]]\n" + "\n".join(f"{k} = {v}" for k, v in CAMERA.items())
        + f"\nresolution = 8.0\n{window}\n"
        for window in ("window = [668.0, 682.0]", "", "window = [660, 690]")))
    spec = read_rig(path)
    assert spec.windows == ((668.0, 682.0), None, (660.0, 690.0))
    assert spec.instrument == {"resolution": 8.0} and spec.source == str(path)
    again = read_rig(write_rig(spec.rig, tmp_path / "again.toml",
                               [{"window": list(w)} if w else {} for w in spec.windows]))
    assert again.windows == spec.windows
    # one lineshape for all cameras: their resolutions may not differ
    with pytest.raises(InputDataError, match="camera 1: 'resolution' = 4.0 differs from camera "
                                             "0's 8.0; .* \\(the spectral window may differ"):
        parse_rig([{**CAMERA, "resolution": 8.0}, {**CAMERA, "resolution": 4.0}], "rig.toml")


@pytest.fixture(scope="module")
def windowed(tiny_scene, plume):
    """Noisy data of the tiny scene's two cameras, the first measuring 670-690 cm-1 only, and
    the same data of cameras measuring everything."""
    truth = Field(tiny_scene.grid, plume)
    scene = tiny_scene.replace(camera_windows=((670.0, 690.0), None))
    return (simulate_measurement(scene, truth, NESR, seed=3),
            simulate_measurement(tiny_scene, truth, NESR, seed=3), scene)


def test_a_camera_measures_only_inside_its_window(windowed):
    measurement, everything, scene = windowed
    eta = scene.out_wavenumber
    inside = (eta >= 670.0) & (eta <= 690.0)
    first = slice(0, scene.rig.cameras[0].n_rays)
    assert 0 < inside.sum() < eta.size
    np.testing.assert_array_equal(scene.measured_channels[first], np.broadcast_to(
        inside, (36, eta.size)))
    assert np.all(measurement.data[first][:, ~inside] == 0)  # nothing drawn there is kept
    assert np.all(np.isinf(measurement.sigma[first][:, ~inside]))
    kept = measurement.measured
    np.testing.assert_array_equal(measurement.data[kept], everything.data[kept])
    assert measurement.n_measurements == everything.n_measurements - 36 * (~inside).sum()
    assert measurement.provenance["camera_windows_cm-1"] == [[670.0, 690.0], None]


@pytest.mark.parametrize("weighting", ["noise", "unweighted"])
def test_values_outside_a_camera_s_window_do_not_change_the_misfit(windowed, weighting):
    measurement = windowed[0]
    sigma = measurement.sigma if weighting == "noise" else measurement.unweighted_sigma
    forward = op.Diagonal(np.ones(measurement.data.shape))  # the model's spectra: ``model``
    model = np.random.default_rng(1).uniform(0.0, 0.05, measurement.data.shape)

    def misfit(data):
        weighted, target = whitened(forward, data, sigma)
        return float(np.sum((weighted(model) - target) ** 2))

    changed = np.where(measurement.measured, measurement.data, 1e3)
    assert misfit(changed) == misfit(measurement.data) > 0
    assert np.isfinite(misfit(measurement.data))


def test_every_camera_gives_rows_to_the_start_from_the_data(windowed, monkeypatch):
    measurement, _, scene = windowed
    rows, solve = [], data_start.band_tomography

    def counted(lengths, band, *args):
        rows.append(band.size)
        return solve(lengths, band, *args)

    monkeypatch.setattr(data_start, "band_tomography", counted)
    data_start.band_tomography_start(scene, measurement.data, measurement.sigma,
                                     measured=measurement.measured)
    assert rows == [scene.n_rays]  # the band: channels inside every camera's window


@pytest.mark.parametrize("noisy", [True, False])
def test_a_measurement_file_round_trips_windows_and_unequal_cameras(tmp_path, noisy):
    rig, windows = unequal_rig(), ((663.0, 669.0), None)
    rng = np.random.default_rng(0)
    data = rng.uniform(0.0, 0.05, (rig.n_rays, WAVENUMBER.size)).astype(np.float32)
    sigma = np.linspace(1e-3, 2e-3, WAVENUMBER.size) if noisy else np.ones(WAVENUMBER.size)
    measurement = Measurement(data, sigma, noisy, {"made": "by hand"}).restricted(
        channel_mask(rig, windows, WAVENUMBER))
    written = MeasurementFile(measurement, rig, WAVENUMBER, 8.0, windows=windows)
    back = read_measurement(write_measurement(written, tmp_path / "m.nc"), rig=rig)
    assert back.windows == windows and back.rig.image_shapes == ((2, 3), (4, 2))
    np.testing.assert_array_equal(back.measurement.data, measurement.data)
    np.testing.assert_array_equal(back.measurement.sigma, measurement.sigma)
    with xr.open_dataset(tmp_path / "m.nc", engine="netcdf4") as ds:
        np.testing.assert_array_equal(ds["window"].values, [[663.0, 669.0], [np.nan, np.nan]])
        assert ds["window"].attrs["units"] == "cm-1"
        assert ds["pixels"].values.tolist() == [[3, 2], [2, 4]]
        radiance = ds["radiance"].values  # (camera, v, u, wavenumber) of 4 x 3 pixels
        assert radiance.shape == (2, 4, 3, WAVENUMBER.size)
        assert np.isnan(radiance[0, :2, :, [0, 4, 5]]).all()  # outside camera 0's window
        assert np.isfinite(radiance[0, :2, :, 1:4]).all()
        assert np.isnan(radiance[0, 2:]).all() and np.isnan(radiance[1, :, 2:]).all()  # padding
    narrowed = read_measurement(tmp_path / "m.nc", rig=rig, rig_source="rig.toml",
                                windows=((665.0, 700.0), (660.0, 668.0)))
    assert narrowed.windows == ((665.0, 669.0), (660.0, 668.0))
    assert narrowed.measurement.n_measurements == 6 * 2 + 8 * 3


def _window_file(tmp_path, window):
    rig = unequal_rig()
    data = np.full((rig.n_rays, WAVENUMBER.size), 0.01, np.float32)
    path = write_measurement(MeasurementFile(Measurement(data, np.full(6, 1e-3), True, {}), rig,
                                             WAVENUMBER, 8.0), tmp_path / "m.nc")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        edited = ds.load().assign(window=(("camera", "bound"), [[np.nan, np.nan], window],
                                          {"units": "cm-1"}))
    path.unlink()
    edited.to_netcdf(path, engine="netcdf4")
    return path


@pytest.mark.parametrize(("refuse", "message"), [
    (lambda tmp: parse_rig([CAMERA, {**CAMERA, "window": [682.0, 668.0]}], "rig.toml"),
     "rig.toml: camera 1: 'window' must be \\[min, max\\] in cm-1 with 0 < min < max"),
    (lambda tmp: check_instrument(parse_rig([CAMERA, {**CAMERA, "window": [650.0, 700.0]}],
                                            "rig.toml"), 8.0, (660.0, 690.0), "[spectrum]"),
     "rig.toml: camera 1: 'window' = 650-700 cm-1 reaches outside the window 660-690 cm-1"),
    (lambda tmp: check_windows((None, (660.0, 665.0)), np.arange(668.0, 683.0, 2.0),
                               "rig.toml", "simulated"),
     "rig.toml: camera 1: 'window' = 660-665 cm-1 holds none of the 8 simulated channels "
     "668-682 cm-1"),
    (lambda tmp: read_measurement(_window_file(tmp, [700.0, 720.0])),
     "m.nc: camera 1: 'window' = 700-720 cm-1 holds none of the 6 measured channels "
     "661.3-690.2 cm-1"),
    (lambda tmp: read_measurement(_window_file(tmp, [669.0, 669.0])),
     "m.nc: camera 1: 'window' must be \\[min, max\\] in cm-1 with 0 < min < max"),
    (lambda tmp: read_measurement(_window_file(tmp, [660.0, 664.0]), rig=unequal_rig(),
                                  rig_source="rig.toml", windows=(None, (666.0, 680.0))),
     "rig.toml: camera 1: 'window' = 666-680 cm-1 does not overlap the measurement file"),
])
def test_a_window_that_cannot_be_measured_is_refused_in_one_line(tmp_path, refuse, message):
    with pytest.raises(InputDataError, match=message) as err:
        refuse(tmp_path)
    assert "\n" not in str(err.value)


def test_a_scene_needs_one_window_or_none_per_camera(tiny_scene):
    assert tiny_scene.camera_windows is None and tiny_scene.measured_channels.all()
    with pytest.raises(ValueError, match="one \\(min, max\\) window in cm-1 with min < max, or "
                                         "None, for each of the 2 cameras"):
        tiny_scene.replace(camera_windows=((670.0, 690.0),))
