"""A small absorption table for the command-line tests (CO2 and H2O lines of the shared data)."""

import pytest

from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.linelist import read_par


@pytest.fixture(scope="module")
def table(shared_linedata):
    linelists = {
        "CO2": read_par(shared_linedata / "CO2_HITRAN_691.4-692.7_validation.par"),
        "H2O": read_par(shared_linedata / "H2O_HITRAN2012_600-800.par", nu_range=(624, 751)),
    }
    return AbsorptionTable.build(linelists, temperatures=[250.0, 800.0, 1600.0])
