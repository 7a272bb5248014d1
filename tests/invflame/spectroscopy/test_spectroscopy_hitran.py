"""fetch_hitran, with HAPI's download replaced by a local file."""

from pathlib import Path

import numpy as np
import pytest

from invflame.spectroscopy.hitran import fetch_hitran
from invflame.spectroscopy.linelist import read_par
from invflame.spectroscopy.partition import hapi_module


def test_fetch_hitran_reads_what_hapi_writes(h2o_par, monkeypatch):
    source = h2o_par
    hapi = hapi_module()
    calls = []

    def fake_fetch(table, molecule, isotopologue, nu_min, nu_max):
        calls.append((table, molecule, isotopologue, nu_min, nu_max))
        folder = Path(hapi.VARIABLES["BACKEND_DATABASE_NAME"])
        lines = source.read_text().splitlines(keepends=True)
        kept = [
            line for line in lines
            if int(line[2]) == isotopologue and nu_min <= float(line[3:15]) <= nu_max
        ]
        (folder / f"{table}.data").write_text("".join(kept))

    monkeypatch.setattr(hapi, "fetch", fake_fetch)
    lines = fetch_hitran("H2O", 650.0, 725.0, isotopologues=(1, 2))
    assert [c[1:] for c in calls] == [(1, 1, 650.0, 725.0), (1, 2, 650.0, 725.0)]
    expected = read_par(source, nu_range=(650.0, 725.0))
    expected = expected.select(np.isin(expected.isotopologue, [1, 2]))
    assert len(lines) == len(expected) > 0
    np.testing.assert_array_equal(np.sort(lines.nu), np.sort(expected.nu))
    assert not (Path(hapi.VARIABLES["BACKEND_DATABASE_NAME"]).exists()), "temp folder removed"


def test_fetch_hitran_rejects_bad_arguments():
    with pytest.raises(ValueError, match="unknown molecule"):
        fetch_hitran("N2O", 650.0, 725.0)
    with pytest.raises(ValueError, match="nu_min < nu_max"):
        fetch_hitran("CO2", 725.0, 650.0)
