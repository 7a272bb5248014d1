"""Measurement files: round trips value by value, masks in the data term, malformed files."""

import numpy as np
import pytest
import xarray as xr

import operators as op
from invflame.errors import InputDataError
from invflame.geometry import CameraRig, VoxelGrid, paper_rig
from invflame.geometry.rig_file import rig_records
from invflame.measurement import Measurement
from invflame.measurement_file import MeasurementFile, read_measurement, write_measurement
from invflame.representations.whitening import whitened

RIG = paper_rig(VoxelGrid.poolfire(8), n_pixels=3)
WAVENUMBER = np.array([661.3, 663.0, 667.9, 668.4, 675.0, 690.2])  # irregular, cm-1


def measured(sigma, noisy=True, seed=0) -> MeasurementFile:
    rng = np.random.default_rng(seed)
    data = rng.uniform(0.0, 0.05, (RIG.n_rays, WAVENUMBER.size)).astype(np.float32)
    data[np.isinf(np.broadcast_to(sigma, data.shape))] = 0.0  # masked values hold 0
    provenance = {"instrument": "test", "grid": [8, 8, 8], "noise": {"kind": "nesr"}}
    return MeasurementFile(Measurement(data, sigma, noisy, provenance), RIG, WAVENUMBER, 8.0)


def masked_sigma():
    sigma = np.full((RIG.n_rays, WAVENUMBER.size), 1e-3) * np.linspace(1, 2, WAVENUMBER.size)
    sigma[[3, 17]] = np.inf  # two bad pixels
    sigma[:, 4] = np.inf  # a bad wavenumber
    return sigma


def assert_same(a: MeasurementFile, b: MeasurementFile):
    assert a.measurement.data.dtype == b.measurement.data.dtype
    np.testing.assert_array_equal(a.measurement.data, b.measurement.data)
    np.testing.assert_array_equal(a.measurement.sigma, b.measurement.sigma)
    assert a.measurement.noisy == b.measurement.noisy
    assert a.measurement.provenance == b.measurement.provenance
    np.testing.assert_array_equal(a.wavenumber, b.wavenumber)
    assert (a.resolution, a.apodization) == (b.resolution, b.apodization)
    assert rig_records(a.rig) == rig_records(b.rig)


@pytest.mark.parametrize("case", ["nesr", "per-value with masks", "noise-free",
                                  "bad wavenumber only"])
def test_write_then_read_gives_the_same_measurement_and_rig(tmp_path, case):
    sigma = {"nesr": np.linspace(1e-3, 2e-3, WAVENUMBER.size),
             "per-value with masks": masked_sigma(),
             "noise-free": np.ones(WAVENUMBER.size),
             "bad wavenumber only": np.where(np.arange(6) == 2, np.inf, 1e-3)}[case]
    original = measured(sigma, noisy=case != "noise-free")
    path = write_measurement(original, tmp_path / "m.nc")
    back = read_measurement(path, rig=RIG)
    assert_same(back, original)
    assert all(np.array_equal(x, y) for x, y in zip(back.rig.rays(9), RIG.rays(9), strict=True))


def test_masked_values_drop_out_of_the_data_term(tmp_path):
    back = read_measurement(write_measurement(measured(masked_sigma()), tmp_path / "m.nc"))
    m = back.measurement
    assert m.n_measurements == (RIG.n_rays - 2) * (WAVENUMBER.size - 1)
    forward = op.Diagonal(np.ones(m.data.shape))  # the model's spectra are ``model`` itself
    model = np.random.default_rng(1).uniform(0.0, 0.05, m.data.shape)
    weighted, target = whitened(forward, m.data, m.sigma)
    misfit = np.sum((weighted(model) - target) ** 2)
    keep = np.isfinite(m.sigma)
    expected = np.sum(((model - m.data) / m.sigma)[keep] ** 2)
    assert misfit == pytest.approx(expected, rel=1e-12)
    changed = m.data.copy()
    changed[~keep] = 1e3  # whatever a bad value holds, it does not count
    assert np.sum((weighted(model) - whitened(forward, changed, m.sigma)[1]) ** 2) == \
        pytest.approx(misfit, rel=1e-12)


def test_the_file_holds_radiance_on_its_dimensions_with_units(tmp_path):
    path = write_measurement(measured(masked_sigma()), tmp_path / "m.nc")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        assert ds["radiance"].dims == ("camera", "v", "u", "wavenumber")
        assert ds["radiance"].attrs["units"] == "W/(m2 sr cm-1)"
        assert ds["wavenumber"].attrs["units"] == "cm-1"
        assert int(ds["bad_pixel"].sum()) == 2 and int(ds["bad_wavenumber"].sum()) == 1
        assert np.isnan(ds["radiance"].values[0, 1, 0]).all()  # pixel 3 = camera 0, v 1, u 0
        assert ds.attrs["apodization"] == "triangular" and ds.attrs["resolution"] == 8.0


def rewrite(path, change):
    """Replace the measurement file at ``path`` by ``change`` of its dataset."""
    with xr.open_dataset(path, engine="netcdf4") as ds:
        edited = change(ds.load())
    path.unlink()
    edited.to_netcdf(path, engine="netcdf4")
    return path


def _set_radiance_nan(ds):
    values = ds["radiance"].values.copy()
    values[1, 2, 0, 3] = np.nan
    return ds.assign(radiance=(ds["radiance"].dims, values, ds["radiance"].attrs))


def _set_units(name, units):
    def change(ds):
        ds[name].attrs["units"] = units
        return ds
    return change


def _drop_wavenumber_order(ds):
    w = ds["wavenumber"].values.copy()
    w[2], w[3] = w[3], w[2]
    return ds.assign_coords(wavenumber=("wavenumber", w, ds["wavenumber"].attrs))


@pytest.mark.parametrize(("change", "message"), [
    (lambda ds: ds.drop_vars("radiance"), "missing variable 'radiance'"),
    (lambda ds: ds.drop_vars("focal_length"), "missing variable 'focal_length'"),
    (lambda ds: ds.drop_vars("nesr"), "missing variable 'nesr'"),
    (_set_units("radiance", "W/(cm2 sr cm-1)"), "variable 'radiance' has units "
                                                "'W/\\(cm2 sr cm-1\\)', expected"),
    (_set_units("wavenumber", "um"), "variable 'wavenumber' has units 'um'"),
    (_set_units("position", "mm"), "variable 'position' has units 'mm'"),
    (lambda ds: ds.assign(radiance=ds["radiance"].transpose("camera", "u", "v", "wavenumber")),
     "variable 'radiance' has dimensions \\('camera', 'u', 'v', 'wavenumber'\\)"),
    (_set_radiance_nan, "variable 'radiance' holds 1 NaN or infinite values outside the mask, "
                        "the first at camera 1, v 2, u 0, wavenumber 668.4 cm-1"),
    (_drop_wavenumber_order, "variable 'wavenumber' must be strictly monotone"),
    (lambda ds: ds.assign(nesr=ds["nesr"] * -1), "variable 'nesr' must be positive"),
    (lambda ds: ds.assign_attrs(apodization="boxcar"), "'apodization' = 'boxcar' is not "
                                                       "modelled"),
    (lambda ds: ds.assign_attrs(noise="gaussian"), "'noise' = 'gaussian'"),
    (lambda ds: ds.assign(focal_length=ds["focal_length"] * -1), "camera 0: 'focal_length' "
                                                                "must be a positive number"),
])
def test_malformed_files_name_the_variable_and_the_file(tmp_path, change, message):
    path = rewrite(write_measurement(measured(np.full(6, 1e-3)), tmp_path / "m.nc"), change)
    with pytest.raises(InputDataError, match=message) as err:
        read_measurement(path)
    assert str(path) in str(err.value)


def test_a_missing_attribute_and_a_file_that_is_not_netcdf(tmp_path):
    path = rewrite(write_measurement(measured(np.full(6, 1e-3)), tmp_path / "m.nc"),
                    lambda ds: ds.drop_attrs(deep=False))
    with pytest.raises(InputDataError, match="missing global attribute 'noise'"):
        read_measurement(path)
    text = tmp_path / "text.nc"
    text.write_text("not netcdf")
    with pytest.raises(InputDataError, match=f"{text}: not a NetCDF measurement file"):
        read_measurement(text)
    with pytest.raises(FileNotFoundError, match="measurement file not found"):
        read_measurement(tmp_path / "missing.nc")


def test_data_from_other_cameras_are_refused(tmp_path):
    path = write_measurement(measured(np.full(6, 1e-3)), tmp_path / "m.nc")
    three = CameraRig(RIG.cameras[:3])
    with pytest.raises(InputDataError, match="'radiance' holds 4 camera\\(s\\) .* rig.toml has 3"):
        read_measurement(path, rig=three, rig_source="rig.toml")
    moved = paper_rig(VoxelGrid.poolfire(8), n_pixels=3, distance=1.6)
    with pytest.raises(InputDataError, match="variable 'position' of camera 0 is .* but rig.toml"):
        read_measurement(path, rig=moved, rig_source="rig.toml")
    bigger = paper_rig(VoxelGrid.poolfire(8), n_pixels=4)
    with pytest.raises(InputDataError, match="image shape \\(3, 3\\)"):
        read_measurement(path, rig=bigger, rig_source="rig.toml")


def test_a_failed_write_keeps_the_previous_file(tmp_path):
    path = write_measurement(measured(np.full(6, 1e-3)), tmp_path / "m.nc")
    before = path.read_bytes()
    scattered = np.full((RIG.n_rays, WAVENUMBER.size), 1e-3)
    scattered[5, 1] = np.inf  # one bad value, neither a whole pixel nor a whole wavenumber
    with pytest.raises(ValueError, match="whole pixels or whole wavenumbers"):
        write_measurement(measured(scattered), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["m.nc"]
