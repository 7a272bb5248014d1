"""OpenFOAM input that cannot be used: the command line names the file, exit status 2; binary
meshes with 64-bit labels read as those with 32-bit ones."""

import numpy as np
import pytest

from invflame.cli import main
from invflame.openfoam import read_case
from invflame.openfoam.foamfile import FoamFormatError, read_foam, read_labels


@pytest.mark.parametrize("compress", [False, True])
def test_binary_mesh_with_64_bit_labels_reads_as_with_32_bit_ones(tiny_case, compress):
    narrow, expected = tiny_case(fmt="binary", compress=compress)
    wide, _ = tiny_case(fmt="binary", compress=compress, label_bits=64)
    owner = wide / "constant" / "polyMesh" / "owner"
    assert read_foam(owner).dtype.kind == "f"  # foamlib: 8-byte items read as float64
    assert read_labels(owner).dtype == np.int64
    np.testing.assert_array_equal(read_labels(owner),
                                  read_labels(narrow / "constant" / "polyMesh" / "owner"))
    field = read_case(wide, 0.5)
    assert field.grid.shape == expected["shape"]
    np.testing.assert_allclose(field.T.reshape(-1), expected["T"], rtol=1e-6)
    np.testing.assert_array_equal(field.values, read_case(narrow, 0.5).values)


def test_labels_of_the_wrong_size_are_named(tiny_case):
    case, _ = tiny_case(fmt="binary", label_bits=64)
    faces = case / "constant" / "polyMesh" / "faces"
    faces.write_bytes(faces.read_bytes().replace(b"label=64", b"label=32"))
    with pytest.raises(FoamFormatError, match=f"{faces}: not a list of mesh labels"):
        read_case(case, 0.5)


def from_openfoam(case, tmp_path, capsys) -> str:
    """Run ``invflame phantom from-openfoam``; return its one line on stderr (exit status 2)."""
    out = tmp_path / "field.npz"
    assert main(["phantom", "from-openfoam", str(case), "--time", "0.5", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and not out.exists()
    return err


def test_cli_names_a_graded_mesh(tiny_case, tmp_path, capsys):
    graded = (np.array([0.0, 0.1, 0.3, 0.6]), np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    case, _ = tiny_case(edges=graded)
    err = from_openfoam(case, tmp_path, capsys)
    assert err.startswith(f"invflame phantom: error: {case / 'constant' / 'polyMesh'}: mesh is "
                          "not a uniform grid along x")


@pytest.mark.parametrize("fmt", ["ascii", "binary"])
@pytest.mark.parametrize("kept", [0.5, 0.8, 0.9])
def test_cli_names_a_field_file_cut_short(tiny_case, tmp_path, capsys, fmt, kept):
    """An ascii list cut short is refused at once (foamlib's parser would search for minutes)."""
    case, _ = tiny_case(fmt=fmt)
    path = case / "0.5" / "T"
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * kept)])
    err = from_openfoam(case, tmp_path, capsys)
    assert err.startswith(f"invflame phantom: error: {path}: ")


@pytest.mark.parametrize("name", ["points", "faces", "owner"])
def test_cli_names_a_mesh_file_cut_short(tiny_case, tmp_path, capsys, name):
    case, _ = tiny_case()
    path = case / "constant" / "polyMesh" / name
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * 0.7)])
    err = from_openfoam(case, tmp_path, capsys)
    assert err.startswith(f"invflame phantom: error: {path}: the '(' at line ")
    assert "is never closed: the file is cut short" in err
