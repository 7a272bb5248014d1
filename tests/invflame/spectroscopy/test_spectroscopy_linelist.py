"""LineList and the HITRAN 160-character reader/writer."""

from dataclasses import fields

import numpy as np
import pytest

from invflame.errors import InputDataError
from invflame.spectroscopy.linelist import LineList, read_par, write_par


def assert_same_lines(a: LineList, b: LineList):
    assert len(a) == len(b)
    for f in fields(LineList):
        np.testing.assert_array_equal(getattr(a, f.name), getattr(b, f.name), err_msg=f.name)


@pytest.fixture(scope="module")
def h2o(h2o_par):
    return read_par(h2o_par)


def test_read_h2o_file(h2o):
    assert len(h2o) == 1650
    assert set(h2o.molecule.tolist()) == {1}
    assert set(h2o.isotopologue.tolist()) == {1, 2, 3, 4}
    # first record of the file, read field by field
    assert h2o.nu[0] == 600.023928
    assert h2o.S296[0] == 1.208e-28
    assert h2o.gamma_air[0] == 0.0288
    assert h2o.delta_air[0] == 0.0
    assert h2o.E_lower[0] == 3812.9592
    assert h2o.isotopologue[0] == 3
    assert h2o.V_upper[0] == "         -2-2-2"
    assert (h2o.g_upper[0], h2o.g_lower[0]) == (198.0, 186.0)
    assert h2o.delta_air[1] == -0.0016


def test_round_trip_keeps_every_field(h2o, h2o_par, tmp_path):
    out = tmp_path / "copy.par"
    write_par(h2o, out)
    assert_same_lines(read_par(out), h2o)
    # columns the LineList holds are written byte for byte as in the original
    original = (h2o_par).read_text().splitlines()
    written = out.read_text().splitlines()
    assert all(len(line) == 160 for line in written)
    assert [line[:127] + line[146:] for line in written] == [
        line[:127] + line[146:] for line in original
    ]


def test_write_is_atomic_and_rejects_values_that_do_not_fit(h2o, tmp_path):
    out = tmp_path / "lines.par"
    write_par(h2o.select(slice(0, 5)), out)
    before = out.read_bytes()
    bad = LineList.concatenate([h2o.select([0]), h2o.select([1])])
    bad.gamma_air[1] = 12.5  # does not fit F5.4
    with pytest.raises(ValueError, match="gamma_air"):
        write_par(bad, out)
    assert out.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["lines.par"]


def test_window_filter_in_reader_matches_window_method(h2o, h2o_par):
    windowed = read_par(h2o_par, nu_range=(650.0, 725.0))
    assert len(windowed) == 628
    assert windowed.nu.min() >= 650.0 and windowed.nu.max() <= 725.0
    assert_same_lines(windowed, h2o.window(650.0, 725.0))


@pytest.mark.parametrize("chunk_lines", [1, 7, 1649, 1650, 1651])
def test_chunk_boundaries_do_not_change_the_result(h2o, h2o_par, chunk_lines):
    lines = read_par(h2o_par, nu_range=(690.0, 700.0), chunk_lines=chunk_lines)
    assert_same_lines(lines, h2o.window(690.0, 700.0))


def test_malformed_record_names_file_line_and_field(h2o_par, tmp_path):
    records = h2o_par.read_text().splitlines()[:10]
    bad_number = records[6][:3] + "   abc.defgh" + records[6][15:]
    short = records[8][:150]
    path = tmp_path / "bad.par"
    path.write_text("\n".join(records[:6] + [bad_number] + records[7:]) + "\n")
    with pytest.raises(ValueError, match=r"bad\.par: line 7: field nu"):
        read_par(path, chunk_lines=4)
    path.write_text("\n".join(records[:8] + [short] + records[9:]) + "\n")
    with pytest.raises(ValueError, match=r"line 9: record has 150 characters"):
        read_par(path)
    bad_iso = records[2][:2] + "x" + records[2][3:]
    path.write_text("\n".join(records[:2] + [bad_iso]) + "\n")
    with pytest.raises(ValueError, match=r"line 3: isotopologue"):
        read_par(path)


def test_isotopologue_codes_above_nine(h2o, tmp_path):
    lines = h2o.select([0, 1, 2])
    lines.isotopologue[:] = [10, 11, 12]
    path = tmp_path / "iso.par"
    write_par(lines, path)
    assert [line[2] for line in path.read_text().splitlines()] == ["0", "A", "B"]
    np.testing.assert_array_equal(read_par(path).isotopologue, [10, 11, 12])


def test_missing_file_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="line list file not found"):
        read_par(tmp_path / "nope.par")


def test_linelist_validates_lengths_and_concatenates(h2o):
    arrays = {f.name: getattr(h2o, f.name)[:3] for f in fields(LineList)}
    arrays["nu"] = arrays["nu"][:2]
    with pytest.raises(ValueError, match="same length"):
        LineList(**arrays)
    parts = [h2o.select(slice(0, 10)), h2o.select(slice(10, 25))]
    assert_same_lines(LineList.concatenate(parts), h2o.select(slice(0, 25)))
    assert len(LineList.concatenate([])) == 0
    with pytest.raises(ValueError, match="nu_min <= nu_max"):
        h2o.window(700.0, 650.0)


@pytest.mark.parametrize(("field", "columns", "text", "shown"), [
    ("S296", (16, 25), "-1.000E-20", "-1e-20"),
    ("S296", (16, 25), "       nan", "nan"),
    ("gamma_air", (36, 40), "-.070", "-0.07"),
    ("nu", (4, 15), "         inf", "inf"),
])
def test_unphysical_values_are_refused_with_their_line(h2o_par, tmp_path, field,
                                                       columns, text, shown):
    source = h2o_par.read_text().splitlines()[:5]
    first, last = columns
    source[3] = source[3][: first - 1] + text + source[3][last:]
    path = tmp_path / "bad.par"
    path.write_text("\n".join(source) + "\n")
    with pytest.raises(InputDataError, match=f"{path}: line 4: field {field} \\(columns "
                                             f"{first}-{last}\\) must be a finite number.*"
                                             f"got {shown}"):
        read_par(path)
