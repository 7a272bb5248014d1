"""Measurement files as a laboratory writes them: optional variables, refused masks,
wavenumbers and resolutions, and warnings about radiance no flame emits."""

import warnings

import numpy as np
import pytest

from invflame.errors import InputDataError
from invflame.geometry import VoxelGrid, paper_rig
from invflame.measurement import Measurement
from invflame.measurement_checks import HOTTEST_FLAME, MeasurementWarning
from invflame.measurement_file import MeasurementFile, read_measurement, write_measurement
from operators.rte.planck import planck

from .test_measurement_file import rewrite

RIG = paper_rig(VoxelGrid.poolfire(8), n_pixels=3)
WAVENUMBER = np.linspace(660.0, 690.0, 7)  # cm-1
NESR = 1e-3  # W/(m2 sr cm-1)


def write(tmp_path, data=None, noisy=True, change=None):
    """A measurement file of ``data`` (default: a plausible flame) with NESR noise or none,
    edited by ``change`` (a function of the dataset)."""
    if data is None:
        data = np.random.default_rng(0).uniform(0.0, 3.0, (RIG.n_rays, WAVENUMBER.size))
    sigma = np.full(WAVENUMBER.size, NESR if noisy else 1.0)
    measured = MeasurementFile(Measurement(data, sigma, noisy, {}), RIG, WAVENUMBER, 8.0)
    path = write_measurement(measured, tmp_path / "m.nc")
    return path if change is None else rewrite(path, change)


def read_quietly(path):
    """Read a file, failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return read_measurement(path)


def camera_values(value, camera=1):
    data = np.random.default_rng(0).uniform(0.0, 3.0, (RIG.n_rays, WAVENUMBER.size))
    pixels = slice(camera * 9, (camera + 1) * 9)
    data[pixels] = value(data[pixels])
    return data


def test_masks_and_principal_points_are_optional(tmp_path):
    path = write(tmp_path, change=lambda ds: ds.drop_vars(["bad_pixel", "bad_wavenumber",
                                                           "principal_point"]))
    measured = read_quietly(path)
    assert np.all(np.isfinite(measured.measurement.sigma))
    assert measured.measurement.n_measurements == RIG.n_rays * WAVENUMBER.size
    assert all(camera.principal_point == (1.5, 1.5) for camera in measured.rig.cameras)
    same = read_measurement(path, rig=RIG)  # the sensor's centre is the paper rig's
    assert same.rig.n_cameras == 4


def _flags(name, value, dims=None):
    def change(ds):
        dims_ = ds[name].dims if dims is None else dims
        return ds.assign({name: (dims_, value(ds[name].values) if callable(value) else value)})
    return change


@pytest.mark.parametrize(("change", "message"), [
    (_flags("bad_pixel", 7, ()),
     "variable 'bad_pixel' must be a flag per pixel, 1 to leave it out and 0 to keep it, over "
     "\\('camera', 'v', 'u'\\) \\(shape \\(4, 3, 3\\)\\); it has dimensions \\(\\) \\(shape "
     "\\(\\)\\), the single value 7"),
    (_flags("bad_pixel", lambda v: np.where(np.arange(v.size).reshape(v.shape) == 5, 7, v)),
     "variable 'bad_pixel' must be a flag per pixel.*; it holds 1 other values, the first 7 at "
     "index \\(0, 1, 2\\): flag each pixel to leave out with 1 rather than give its index"),
    (_flags("bad_pixel", np.array([3, 40]), ("index",)),
     "variable 'bad_pixel' must be a flag per pixel.*it has dimensions \\('index',\\) "
     "\\(shape \\(2,\\)\\)"),
    (_flags("bad_pixel", np.zeros((4, 3)), ("camera", "v")),
     "variable 'bad_pixel' must be .*it has dimensions \\('camera', 'v'\\) \\(shape \\(4, 3\\)"),
    (_flags("bad_wavenumber", lambda v: v - 1),
     "variable 'bad_wavenumber' must be a flag per wavenumber.*over \\('wavenumber',\\) "
     "\\(shape \\(7,\\)\\); it holds 7 other values, the first -1"),
    (_flags("bad_pixel", lambda v: np.ones_like(v)),
     "variable 'bad_pixel' leaves out every pixel \\(36\\): no data are left"),
    (_flags("bad_wavenumber", lambda v: np.ones_like(v)),
     "variable 'bad_wavenumber' leaves out every wavenumber \\(7\\)"),
    (lambda ds: ds.assign_coords(wavenumber=-ds["wavenumber"]),
     "variable 'wavenumber' holds 7 values that are not positive, the first -660: "
     "wavenumbers are positive, in cm-1"),
    (lambda ds: ds.assign_attrs(resolution=1e6),
     "global attribute 'resolution' = 1e\\+06 cm-1 is coarser than the measured band "
     "660-690 cm-1"),
    (lambda ds: ds.assign_attrs(resolution=-8.0),
     "global attribute 'resolution' must be a positive number in cm-1, got -8.0"),
])
def test_bad_masks_wavenumbers_and_resolutions_are_refused(tmp_path, change, message):
    path = write(tmp_path, change=change)
    with pytest.raises(InputDataError, match=message) as err:
        read_measurement(path)
    assert str(err.value).startswith(f"{path}: ")


def test_one_wavenumber_takes_a_resolution_finer_than_itself(tmp_path):
    path = write(tmp_path, change=lambda ds: ds.isel(wavenumber=[3]))
    assert read_quietly(path).wavenumber.tolist() == [675.0]
    coarse = write(tmp_path, change=lambda ds: ds.isel(wavenumber=[3]).assign_attrs(
        resolution=1e3))
    with pytest.raises(InputDataError, match="coarser than the measured band 675-675 cm-1"):
        read_measurement(coarse)


@pytest.mark.parametrize("noisy", [True, False])
def test_a_plausible_flame_and_pure_noise_raise_no_warning(tmp_path, noisy):
    read_quietly(write(tmp_path, noisy=noisy))
    noise = np.random.default_rng(3).normal(0.0, NESR, (RIG.n_rays, WAVENUMBER.size))
    read_quietly(write(tmp_path, data=noise, noisy=noisy))  # a dark scene, half negative


@pytest.mark.parametrize(("data", "noisy", "message"), [
    (camera_values(lambda v: np.full_like(v, -1.0)), False,
     "camera 1: its radiance is negative on the whole \\(mean -1 W/\\(m2 sr cm-1\\), 100% of "
     "the values below zero\\); emitted radiance is never negative: check the sign of the "
     "spectra and the background subtraction"),
    (camera_values(lambda v: NESR * (np.random.default_rng(1).standard_normal(v.shape) - 1000)),
     True, "camera 1: its radiance is negative"),
    (camera_values(lambda v: -v), True, "camera 1: its radiance is negative"),
    (camera_values(lambda v: v * 1e4), True,
     "camera 1: 6[0-9] of its 63 values exceed the radiance of a black body at 3500 K .*: "
     "'radiance' must be in W/\\(m2 sr cm-1\\) \\(1 W/\\(cm2 sr cm-1\\) = 1e4 W/\\(m2 sr "
     "cm-1\\)\\)"),
    (camera_values(lambda v: np.where(np.arange(v.size).reshape(v.shape) == 10, 1e30, v)),
     True, "camera 1: 1 value beyond the radiance of a black body at 3500 K, the first 1e\\+30 "
           "W/\\(m2 sr cm-1\\) at v 0, u 1, wavenumber 675 cm-1: spikes, saturated or dead "
           "pixels; flag them in 'bad_pixel' or 'bad_wavenumber'"),
])
def test_implausible_radiance_is_named_with_its_camera_and_cause(tmp_path, data, noisy,
                                                                 message):
    path = write(tmp_path, data=data, noisy=noisy)
    with pytest.warns(MeasurementWarning, match=message) as caught:
        read_measurement(path)
    assert all(str(w.message).startswith(f"{path}: camera 1: ") for w in caught)


def test_values_in_masked_pixels_are_not_looked_at(tmp_path):
    data = camera_values(lambda v: np.full_like(v, -1.0))
    path = write(tmp_path, data=data, change=_flags(
        "bad_pixel", lambda v: np.where(np.arange(v.size).reshape(v.shape) // 9 == 1, 1, v)))
    read_quietly(path)


def test_the_bound_is_the_black_body_at_the_hottest_flame():
    bound = planck(WAVENUMBER, HOTTEST_FLAME)
    assert np.all((bound > 10.0) & (bound < 13.0))  # W/(m2 sr cm-1) near 675 cm-1
