"""Fixtures of the spectroscopy tests: the shared HITRAN H2O lines of the default window."""

import pytest

from invflame.spectroscopy.linelist import read_par


@pytest.fixture(scope="session")
def h2o(shared_linedata):
    """HITRAN2012 H2O lines of 664–726 cm⁻¹: those whose wings (25 cm⁻¹) reach 690–700 cm⁻¹."""
    return read_par(shared_linedata / "H2O_HITRAN2012_600-800.par", nu_range=(664.0, 726.0))
