"""Reading a tiny generated OpenFOAM case onto a regular grid."""

import argparse
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from invflame.cli import phantom
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.openfoam import read_case, read_internal_field, time_directory
from invflame.openfoam.foamfile import FoamFormatError
from invflame.openfoam.mesh import cell_centres, grid_from_centres, mesh_box

TUTORIAL = Path(
    "/usr/share/doc/openfoam-examples/examples/combustion/fireFoam/LES/smallPoolFire3D"
)

MOLAR = {"O2": 32.0, "H2O": 18.0, "CH4": 16.0, "CO2": 44.0, "N2": 28.0}


def expected_mole_fractions(expected):
    moles = {s: expected[s] / w for s, w in MOLAR.items()}
    total = sum(moles.values())
    return {s: m / total for s, m in moles.items()}


@pytest.mark.parametrize(
    "fmt, compress, with_centres",
    [("ascii", False, False), ("ascii", True, True), ("binary", False, True),
     ("binary", True, False)],
)
def test_read_case_maps_cells_and_converts_to_mole_fractions(tiny_case, fmt, compress,
                                                              with_centres):
    case, expected = tiny_case(fmt=fmt, compress=compress, with_centres=with_centres)
    field = read_case(case, 0.5)
    shape = expected["shape"]
    assert field.grid.shape == shape
    np.testing.assert_allclose(field.grid.lower, [-0.3, 0.0, -0.1], atol=1e-12)
    np.testing.assert_allclose(field.grid.upper, [0.3, 1.0, 0.1], atol=1e-12)
    assert field.grid.up_axis == 1
    np.testing.assert_allclose(field.grid.centres().reshape(-1, 3), expected["centres"], atol=1e-12)
    np.testing.assert_allclose(field.T.reshape(-1), expected["T"], rtol=1e-6)
    x = expected_mole_fractions(expected)
    for s in ("CO2", "H2O", "CH4"):
        np.testing.assert_allclose(field.X(s).reshape(-1), x[s], rtol=1e-5, atol=1e-8)
    assert field.metadata["solver"] == "fireFoam"
    assert field.metadata["version"] == "v1912"
    assert field.metadata["time"] == 0.5
    assert field.metadata["molar_masses_g_per_mol"] == MOLAR


def test_mole_fractions_use_all_species(tiny_case):
    """Doubling N2 molar mass (a species not in the field) changes X_CO2: all Y_i/W_i count."""
    case, expected = tiny_case()
    thermo = case / "constant" / "thermo.compressibleGas"
    thermo.write_text(thermo.read_text().replace("28.0", "56.0"))
    field = read_case(case, "0.5")
    moles = {s: expected[s] / (56.0 if s == "N2" else w) for s, w in MOLAR.items()}
    x_co2 = moles["CO2"] / sum(moles.values())
    np.testing.assert_allclose(field.X("CO2").reshape(-1), x_co2, rtol=1e-5)


def test_uniform_internal_field_is_broadcast(tiny_case):
    case, expected = tiny_case()
    o2 = case / "0.5" / "O2"
    text = o2.read_text()
    start = text.index("internalField")
    end = text.index(";", start)
    o2.write_text(text[:start] + "internalField   uniform 0.15" + text[end:])
    assert read_internal_field(o2) == 0.15
    field = read_case(case, 0.5)
    x = expected_mole_fractions(expected)
    np.testing.assert_allclose(field.X("H2O").reshape(-1), x["H2O"], rtol=1e-5)


def test_non_uniform_mesh_is_refused_with_reason(tiny_case):
    graded = (np.array([0.0, 0.1, 0.3, 0.6]), np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    case, _ = tiny_case(edges=graded)
    with pytest.raises(ValueError, match="not a uniform grid along x"):
        read_case(case, 0.5)


def test_missing_time_lists_times_and_hints_reconstruct(tiny_case):
    case, _ = tiny_case()
    with pytest.raises(FileNotFoundError, match=r"times present: \[0\.5\]"):
        time_directory(case, 0.9)
    (case / "processor0" / "0.9").mkdir(parents=True)
    with pytest.raises(FileNotFoundError, match="reconstructPar"):
        read_case(case, 0.9)


def test_missing_species_file_is_reported(tiny_case):
    case, _ = tiny_case()
    (case / "0.5" / "N2").unlink()
    with pytest.raises(FileNotFoundError, match=r"\['N2'\]"):
        read_case(case, 0.5)


def test_truncated_binary_list_is_a_format_error(tiny_case):
    case, _ = tiny_case(fmt="binary")
    path = case / "0.5" / "T"
    data = path.read_bytes()
    path.write_bytes(data.replace(b"internalField   nonuniform List<scalar> 24",
                                  b"internalField   nonuniform List<scalar> 23"))
    with pytest.raises(FoamFormatError, match="does not end where expected"):
        read_internal_field(path)


def test_cli_from_openfoam_writes_a_field(tiny_case, tmp_path, capsys):
    case, expected = tiny_case()
    parser = argparse.ArgumentParser()
    phantom.add_parser(parser.add_subparsers())
    out = tmp_path / "out" / "tiny.npz"
    args = parser.parse_args(["phantom", "from-openfoam", str(case), "--time", "0.5",
                              "--out", str(out)])
    assert args.func(args) == 0
    field = Field.load(out)
    np.testing.assert_allclose(field.T.reshape(-1), expected["T"], rtol=1e-6)
    assert "T > 500 K" in capsys.readouterr().out


def test_real_tutorial_mesh_if_installed(tmp_path):
    """With Debian's openfoam-examples: blockMesh's binary mesh of the pool fire maps to 60³."""
    blockmesh = shutil.which("blockMesh")
    if blockmesh is None or not TUTORIAL.is_dir():
        pytest.skip("OpenFOAM (apt-get install openfoam openfoam-examples) not installed")
    case = tmp_path / "pool"
    shutil.copytree(TUTORIAL, case)
    env = {**os.environ, "WM_PROJECT_DIR": os.environ.get("WM_PROJECT_DIR", "/usr/share/openfoam")}
    subprocess.run([blockmesh], cwd=case, check=True, capture_output=True, env=env)
    grid, flat = grid_from_centres(cell_centres(case), 1, mesh_box(case))
    assert grid == VoxelGrid.poolfire(60)
    assert len(np.unique(flat)) == 216000
