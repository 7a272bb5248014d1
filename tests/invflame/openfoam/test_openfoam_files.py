"""Malformed and tutorial-style OpenFOAM files: what is read and what each error names."""

import gzip
import re

import numpy as np
import pytest

from invflame.openfoam import read_case, read_internal_field
from invflame.openfoam.foamfile import FoamFormatError, read_foam
from invflame.openfoam.mesh import cell_centres


def replace_internal_field(path, new_entry: str) -> None:
    """Rewrite the ``internalField ...;`` entry of an ascii field file."""
    text = path.read_text()
    start = text.index("internalField")
    path.write_text(text[:start] + new_entry + text[text.index(";", start) + 1 :])


def test_missing_field_file_is_named(tiny_case):
    case, _ = tiny_case()
    (case / "0.5" / "T").unlink()
    with pytest.raises(FileNotFoundError, match=r"0\.5/T \(nor T\.gz\)"):
        read_case(case, 0.5)


def test_field_of_wrong_length_is_named_with_both_counts(tiny_case):
    case, expected = tiny_case()
    values = " ".join(repr(v) for v in expected["T"][:-1].tolist())
    replace_internal_field(case / "0.5" / "T",
                           f"internalField nonuniform List<scalar> 23({values});")
    with pytest.raises(FoamFormatError, match=r"0\.5/T: internalField holds 23 values, not 24"):
        read_case(case, 0.5)


def test_vector_field_where_a_scalar_is_read_is_named(tiny_case):
    case, expected = tiny_case()
    rows = " ".join(f"({x} {y} {z})" for x, y, z in expected["centres"])
    replace_internal_field(case / "0.5" / "CO2",
                           f"internalField nonuniform List<vector> 24({rows});")
    with pytest.raises(FoamFormatError, match=r"0\.5/CO2: internalField holds 3-component"):
        read_case(case, 0.5)


@pytest.mark.parametrize("entry", ["", "internalField uniform hot;",
                                   "internalField nonuniform List<scalar> 2(1 2 3);"])
def test_file_without_numeric_internal_field_is_named(tiny_case, entry):
    case, _ = tiny_case()
    path = case / "0.5" / "T"
    replace_internal_field(path, entry)
    with pytest.raises(FoamFormatError, match=re.escape(f"{path}: no internalField of numbers")):
        read_internal_field(path)


def test_unparsable_file_names_file_line_and_column(tmp_path):
    path = tmp_path / "T"
    path.write_text("FoamFile\n{\n    format ascii;\n}\ninternalField uniform ((;\n")
    with pytest.raises(FoamFormatError, match=re.escape(f"{path}: ") + r".*line 5, column"):
        read_foam(path)


def test_uniform_integer_field_is_a_float_and_repeats_over_the_cells(tmp_path):
    path = tmp_path / "CH4.gz"
    path.write_bytes(gzip.compress(b"dimensions [0 0 0 0 0 0 0];\ninternalField uniform 0;\n"))
    value = read_internal_field(tmp_path / "CH4")
    assert isinstance(value, float) and value == 0.0
    np.testing.assert_array_equal(read_internal_field(path, 5), np.zeros(5))


def test_ascii_face_compact_list_gives_the_same_centres(tiny_case):
    """OpenFOAM may write ascii faces as a faceCompactList (offsets, then labels)."""
    case, expected = tiny_case()
    mesh = case / "constant" / "polyMesh"
    faces = read_foam(mesh / "faces")
    offsets = np.cumsum([0] + [len(f) for f in faces])
    labels = np.concatenate(faces)
    text = (mesh / "faces").read_text()
    header = text[: text.index("FoamFile")] + text[text.index("FoamFile") : text.index("}") + 1]
    body = "".join(f"{len(a)}\n(\n" + "\n".join(map(str, a)) + "\n)\n" for a in (offsets, labels))
    (mesh / "faces").write_text(header.replace("faceList", "faceCompactList") + "\n" + body)
    assert isinstance(read_foam(mesh / "faces"), tuple)
    np.testing.assert_allclose(cell_centres(case), expected["centres"], rtol=0, atol=1e-15)


def test_tutorial_style_dictionaries_and_absent_species(tiny_case):
    """Species list beside a reactions dictionary, thermo entries with several sub-dictionaries,
    a thermophysicalProperties that names the files, the build from the solver log; a case
    without CH4 has zero CH4 and says so."""
    case, expected = tiny_case()
    constant = case / "constant"
    (case / "0.5" / "CH4").unlink()
    (constant / "reactions").write_text(
        'species\n(\n    O2 H2O CO2 N2\n);\n\nreactions\n{\n    oxidation\n    {\n'
        '        type     irreversibleinfiniteReaction;\n'
        '        reaction "CO + 0.5O2 = CO2";\n    }\n}\n'
    )
    weights = {"O2": 31.9988, "H2O": 18.0153, "CO2": 44.01, "N2": 28.0134}
    (constant / "thermo.compressibleGas").write_text("".join(
        f"{s}\n{{\n    specie\n    {{\n        molWeight   {w};\n    }}\n"
        "    thermodynamics\n    {\n        Tlow 200;\n"
        "        highCpCoeffs ( 3.7 0.0006 -1.3e-07 1.8e-11 -1.1e-15 -1234 3.2 );\n    }\n"
        "    transport\n    {\n        As 1.67212e-06;\n        Ts 170.672;\n    }\n}\n"
        for s, w in weights.items()
    ))
    (constant / "thermophysicalProperties").write_text(
        "thermoType\n{\n    type hePsiThermo;\n    mixture singleStepReactingMixture;\n}\n"
        'inertSpecie N2;\nfuel CH4;\nfoamChemistryFile "<constant>/reactions";\n'
        'foamChemistryThermoFile "<constant>/thermo.compressibleGas";\n'
    )
    (case / "log.fireFoam").write_text("/* banner */\nBuild  : 1912 OPENFOAM=1912\nExec   : x\n")
    field = read_case(case, 0.5)
    assert field.metadata["species"] == ["O2", "H2O", "CO2", "N2"]
    assert field.metadata["molar_masses_g_per_mol"] == weights
    assert field.metadata["absent_species"] == ["CH4"]
    assert field.metadata["version"] == "1912 OPENFOAM=1912"
    moles = {s: expected[s] / w for s, w in weights.items()}
    total = sum(moles.values())
    for s in ("CO2", "H2O"):
        # fields are stored in float32
        np.testing.assert_allclose(field.X(s).reshape(-1), moles[s] / total, rtol=1e-6)
    np.testing.assert_array_equal(field.X("CH4"), 0.0)


def test_species_without_molar_mass_is_named(tiny_case):
    case, _ = tiny_case()
    reactions = case / "constant" / "reactions"
    reactions.write_text(reactions.read_text().replace("N2", "XY9"))
    (case / "0.5" / "N2").rename(case / "0.5" / "XY9")
    with pytest.raises(FoamFormatError, match="no molWeight for species 'XY9'"):
        read_case(case, 0.5)
