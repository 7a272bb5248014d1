"""Field sets as VTK image data and NetCDF: read back value by value, names, units, grid."""

import argparse
import datetime
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import xarray as xr

from invflame import __version__
from invflame.cli import export as export_cli
from invflame.cli import main
from invflame.export import (
    FIELD_SETS,
    array_name,
    export_run,
    fields_dataset,
    read_run_fields,
    write_netcdf,
    write_vti,
)
from invflame.field import FIELD_NAMES, Field
from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume

# an anisotropic grid, off the origin, with another up axis: a swapped axis or a spacing taken
# from the wrong component shows
GRID = VoxelGrid((-0.2, 0.1, 0.05), (0.3, 0.7, 0.45), (5, 6, 4), up_axis=2)


def sample_field(seed: int) -> Field:
    rng = np.random.default_rng(seed)
    values = np.empty((4, *GRID.shape), dtype=np.float32)
    values[0] = rng.uniform(300.0, 2000.0, GRID.shape)
    values[1:] = rng.dirichlet(np.ones(4), GRID.shape)[..., :3].transpose(3, 0, 1, 2)
    return Field(GRID, values, {"source": f"sample {seed}"})


def read_vti(path) -> tuple[dict, dict[str, np.ndarray]]:
    """The image's attributes and cell arrays of a .vti with raw appended data (the VTK XML
    format: a UInt64 byte count, then the values, x fastest)."""
    raw = path.read_bytes()
    marker = raw.index(b"<AppendedData")
    start = raw.index(b"_", marker) + 1
    header = ET.fromstring(raw[:marker].decode() + "</VTKFile>")
    assert header.get("header_type") == "UInt64" and header.get("byte_order") == "LittleEndian"
    image = header.find("ImageData")
    extent = [int(v) for v in image.get("WholeExtent").split()]
    shape = tuple(extent[2 * a + 1] - extent[2 * a] for a in range(3))
    arrays = {}
    for array in image.find("Piece").find("CellData"):
        assert array.get("type") == "Float32" and array.get("format") == "appended"
        at = start + int(array.get("offset"))
        size = int(np.frombuffer(raw, "<u8", 1, at)[0])
        values = np.frombuffer(raw, "<f4", size // 4, at + 8)
        arrays[array.get("Name")] = values.reshape(shape, order="F")
    attrs = {"origin": [float(v) for v in image.get("Origin").split()],
             "spacing": [float(v) for v in image.get("Spacing").split()], "shape": shape}
    return attrs, arrays


def test_vti_holds_every_field_with_its_unit_and_the_grid_in_metres(tmp_path):
    field = sample_field(0)
    path = write_vti(field, tmp_path / "f.vti")
    attrs, arrays = read_vti(path)
    np.testing.assert_allclose(attrs["origin"], GRID.lower, rtol=1e-15)
    np.testing.assert_allclose(attrs["spacing"], GRID.spacing, rtol=1e-15)
    assert attrs["shape"] == GRID.shape
    assert list(arrays) == ["T [K]", "X_CO2 [1]", "X_H2O [1]", "X_CH4 [1]"]
    for name in FIELD_NAMES:
        np.testing.assert_array_equal(arrays[array_name(name)], field[name])
    assert [p.name for p in tmp_path.iterdir()] == ["f.vti"]  # no temporary left behind
    with pytest.raises(ValueError, match=r"end in \.vti"):
        write_vti(field, tmp_path / "f.vtk")


def test_vti_reads_back_in_vtk_at_the_voxel_centres(tmp_path):
    xml = pytest.importorskip("vtkmodules.vtkIOXML", reason="vtk is not installed")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    field = sample_field(1)
    reader = xml.vtkXMLImageDataReader()
    reader.SetFileName(str(write_vti(field, tmp_path / "f.vti")))
    reader.Update()
    image = reader.GetOutput()
    np.testing.assert_allclose(image.GetOrigin(), GRID.lower)
    np.testing.assert_allclose(image.GetSpacing(), GRID.spacing)
    assert image.GetNumberOfCells() == GRID.n_voxels
    cells = image.GetCellData()
    for name in FIELD_NAMES:
        values = vtk_to_numpy(cells.GetArray(array_name(name)))
        np.testing.assert_array_equal(values.reshape(GRID.shape, order="F"), field[name])
    # the cell VTK finds at a voxel's centre holds that voxel's value
    ix, iy, iz = 3, 1, 2
    centre = [axis[i] for axis, i in zip(GRID.axes(), (ix, iy, iz), strict=True)]
    ijk, local = [0, 0, 0], [0.0, 0.0, 0.0]
    assert image.ComputeStructuredCoordinates(centre, ijk, local) == 1
    assert ijk == [ix, iy, iz]
    np.testing.assert_allclose(local, 0.5)
    assert vtk_to_numpy(cells.GetArray("T [K]"))[image.ComputeCellId(ijk)] == field.T[ix, iy, iz]


def test_netcdf_has_cf_units_coordinates_and_values(tmp_path):
    fields = {"truth": sample_field(2), "reconstruction": sample_field(3)}
    path = write_netcdf(fields, tmp_path / "f.nc", {"protocol_start": "ambient air"})
    with xr.open_dataset(path) as ds:
        assert dict(ds.sizes) == {"x": 5, "y": 6, "z": 4, "bounds": 2}
        for a, axis in enumerate("xyz"):
            np.testing.assert_allclose(ds[axis].values, GRID.axes()[a], rtol=1e-12)
            assert ds[axis].attrs["units"] == "m"
            bounds = ds[f"{axis}_bounds"].values
            np.testing.assert_allclose(bounds.mean(axis=1), GRID.axes()[a], rtol=1e-12)
            np.testing.assert_allclose(bounds[:, 1] - bounds[:, 0], GRID.spacing[a])
        assert ds["z"].attrs["positive"] == "up" and "positive" not in ds["y"].attrs
        expected = {"T": ("K", "air_temperature"),
                    "X_CO2": ("1", "mole_fraction_of_carbon_dioxide_in_air"),
                    "X_H2O": ("1", "mole_fraction_of_water_vapor_in_air"),
                    "X_CH4": ("1", "mole_fraction_of_methane_in_air")}
        for set_name, field in fields.items():
            for field_name, (name, (units, standard)) in zip(FIELD_NAMES, expected.items(),
                                                             strict=True):
                variable = ds[f"{set_name}_{name}"]
                assert variable.dims == ("z", "y", "x") and variable.dtype == np.float32
                assert variable.attrs["units"] == units
                assert variable.attrs["standard_name"] == standard
                assert variable.attrs["field_set"] == set_name
                np.testing.assert_array_equal(variable.transpose("x", "y", "z").values,
                                              field[field_name])
        assert ds.attrs["Conventions"].startswith("CF-") and ds.attrs["up_axis"] == "z"
        assert ds.attrs["protocol_start"] == "ambient air"
        assert ds.attrs["field_sets"] == "truth reconstruction"
        assert ds.attrs["invflame_version"] and ds.attrs["date_created"]
        # a point in space selects the voxel around it
        at = ds["truth_T"].sel(x=0.11, y=0.33, z=0.2, method="nearest")
        assert float(at) == fields["truth"].T[3, 2, 1]


def test_netcdf_reads_in_vtk_with_x_y_z_where_they_belong(tmp_path):
    netcdf = pytest.importorskip("vtkmodules.vtkIONetCDF", reason="vtk is not installed")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    field = sample_field(7)
    reader = netcdf.vtkNetCDFCFReader()  # ParaView's "NetCDF CF Reader"
    # it takes the CF axes X and Y for longitude and latitude unless told they are Cartesian
    reader.SphericalCoordinatesOff()
    reader.SetFileName(str(write_netcdf({"truth": field}, tmp_path / "f.nc")))
    reader.UpdateMetaData()
    reader.SetVariableArrayStatus("truth_T", 1)
    reader.Update()
    image = reader.GetOutput()  # points at the voxel centres
    np.testing.assert_allclose(image.GetOrigin(), [axis[0] for axis in GRID.axes()])
    np.testing.assert_allclose(image.GetSpacing(), GRID.spacing)
    assert image.GetDimensions() == GRID.shape
    values = vtk_to_numpy(image.GetPointData().GetArray("truth_T"))
    np.testing.assert_array_equal(values.reshape(GRID.shape, order="F"), field.T)


def test_field_sets_on_different_grids_are_refused():
    other = synthetic_plume(VoxelGrid.cube(4))
    with pytest.raises(ValueError, match=r"'start' lies on grid \(4, 4, 4\).*Field.resample"):
        fields_dataset({"truth": sample_field(0), "start": other})
    with pytest.raises(ValueError, match="at least one field set"):
        fields_dataset({})


def write_run(folder, with_truth=True):
    folder.mkdir(parents=True)
    sets = {"truth": sample_field(4), "start": sample_field(5),
            "reconstruction": sample_field(6)}
    for name, field in sets.items():
        if name != "truth" or with_truth:
            field.save(folder / FIELD_SETS[name])
    (folder / "config.toml").write_text(
        'seed = 3\n[truth]\nsource = "synthetic"\ngrid = 5\n[regularizer]\nkind = "tv"\n'
        'lambda = 30.0\n')
    (folder / "summary.json").write_text(json.dumps(
        {"protocol": {"start": "ambient air", "noise": "none"}, "mse": {"T": 0.01}}))
    return sets


def test_export_run_writes_every_set_and_the_run_provenance(tmp_path):
    sets = write_run(tmp_path / "run")
    written = export_run(tmp_path / "run")
    assert [p.name for p in written] == ["truth.vti", "start.vti", "reconstruction.vti",
                                         "fields.nc"]
    for name, field in sets.items():
        _, arrays = read_vti(tmp_path / "run" / f"{name}.vti")
        np.testing.assert_array_equal(arrays["X_H2O [1]"], field["H2O"])
    with xr.open_dataset(tmp_path / "run" / "fields.nc") as ds:
        np.testing.assert_array_equal(ds["start_X_CO2"].values.T, sets["start"]["CO2"])
        assert ds.attrs["protocol_start"] == "ambient air"
        assert ds.attrs["config_summary"] == ("truth synthetic; grid 5; regularizer tv; "
                                              "lambda 30.0; seed 3")
        assert 'kind = "tv"' in ds.attrs["invflame_config"]
        assert json.loads(ds.attrs["mse"]) == {"T": 0.01}


def test_a_run_without_truth_exports_start_and_reconstruction(tmp_path):
    write_run(tmp_path / "run", with_truth=False)
    assert list(read_run_fields(tmp_path / "run")) == ["start", "reconstruction"]
    assert [p.name for p in export_run(tmp_path / "run", ["netcdf"])] == ["fields.nc"]
    with xr.open_dataset(tmp_path / "run" / "fields.nc") as ds:
        assert "truth_T" not in ds and "reconstruction_T" in ds
    with pytest.raises(ValueError, match=r"unknown export format\(s\) \['vtk'\]"):
        export_run(tmp_path / "run", ["vtk"])


def test_netcdf_is_read_by_its_cf_conventions(tmp_path):
    pytest.importorskip("cf_xarray", reason="cf_xarray is not installed")
    import netCDF4

    before = datetime.datetime.now(datetime.UTC).replace(microsecond=0)
    write_run(tmp_path / "run")
    (path,) = export_run(tmp_path / "run", ["netcdf"])
    with xr.open_dataset(path) as ds:
        assert ds.cf.axes == {"X": ["x"], "Y": ["y"], "Z": ["z"]}  # GRID's up axis is z
        for axis in "XYZ":
            assert ds.cf.get_bounds(axis).name == f"{axis.lower()}_bounds"
        assert "coordinates" not in ds.attrs
        written, by = ds.attrs["history"].split(": ", 1)
        assert before <= datetime.datetime.fromisoformat(written) <= datetime.datetime.now(
            datetime.UTC)
        assert by == f"written by invflame {__version__} (invflame.export)"
    with netCDF4.Dataset(path) as raw:  # the attributes as stored, before xarray decodes them
        assert "coordinates" not in raw.ncattrs()
        for name, variable in raw.variables.items():
            assert "_FillValue" not in variable.ncattrs(), name


def parse(argv):
    parser = argparse.ArgumentParser()
    export_cli.add_parser(parser.add_subparsers())
    return parser.parse_args(argv)


def test_cli_exports_a_run_or_every_run_of_a_comparison(tmp_path, capsys):
    write_run(tmp_path / "study" / "VG-TV")
    write_run(tmp_path / "study" / "NN-TV")
    args = parse(["export", str(tmp_path / "study" / "VG-TV"), "--format", "vti"])
    assert args.func(args) == 0
    assert sorted(p.name for p in (tmp_path / "study" / "VG-TV").glob("*.vti")) == [
        "reconstruction.vti", "start.vti", "truth.vti"]
    assert not (tmp_path / "study" / "VG-TV" / "fields.nc").exists()
    args = parse(["export", str(tmp_path / "study")])
    assert args.func(args) == 0
    for method in ("VG-TV", "NN-TV"):
        assert (tmp_path / "study" / method / "fields.nc").is_file()
    assert capsys.readouterr().out.count("wrote") == 3 + 8


def test_cli_names_a_folder_without_results(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    for folder, message in (("empty", "holds no reconstruction.npz, nor do its sub-folders"),
                            ("missing", "is not a folder")):
        assert main(["export", str(tmp_path / folder)]) == 2
        error = capsys.readouterr().err.strip()
        assert error.startswith("invflame export: error:") and message in error
        assert len(error.splitlines()) == 1
    with pytest.raises(FileNotFoundError, match="holds no reconstruction.npz"):
        read_run_fields(tmp_path / "empty")


def cf_findings(path, tmp_path) -> dict[str, list[str]]:
    """The IOOS compliance checker's findings on a file against CF 1.10, by priority ("high":
    errors, "medium" and "low": warnings and notes), each as its section's name."""
    from compliance_checker.runner import CheckSuite, ComplianceChecker

    CheckSuite().load_all_available_checkers()
    report = tmp_path / "cf.json"
    ComplianceChecker.run_checker(str(path), ["cf:1.10"], 0, "normal",
                                  output_filename=str(report), output_format="json")
    (result,) = json.loads(report.read_text()).values()
    return {priority: [item["name"] for item in result[f"{priority}_priorities"]
                       if item["value"][0] < item["value"][1]]
            for priority in ("high", "medium", "low")}


@pytest.mark.parametrize("up_axis", [1, 2])
def test_the_cf_checker_finds_no_error_in_fields_nc(tmp_path, up_axis):
    """CF's vertical axis Z is the grid's up axis (positive up), X and Y the horizontal ones
    as projection coordinates; the only finding is the dimension order with the y axis up,
    which stays (z, y, x) for ParaView's reader (a recommendation of CF, not a rule)."""
    pytest.importorskip("cf_xarray", reason="cf_xarray is not installed")
    grid = VoxelGrid(GRID.lower, GRID.upper, GRID.shape, up_axis=up_axis)
    path = write_netcdf({"truth": Field(grid, sample_field(1).values)}, tmp_path / "f.nc",
                        {"title": "a test field"})
    findings = cf_findings(path, tmp_path)
    assert findings == {"high": [], "medium": ["§2.4 Dimensions"] if up_axis == 1 else [],
                        "low": []}, findings
    vertical = "xyz"[up_axis]
    horizontal = [axis for axis in "xyz" if axis != vertical]
    with xr.open_dataset(path) as ds:
        assert ds.cf.axes == {"X": [horizontal[0]], "Y": [horizontal[1]], "Z": [vertical]}
        assert ds[vertical].attrs["positive"] == "up"
        assert ds.truth_T.dims == ("z", "y", "x")
