"""Fixtures of the spectroscopy tests: the packaged HITRAN H2O lines of the default window."""

import pytest

from invflame.spectroscopy.linelist import read_par


@pytest.fixture(scope="session")
def h2o(h2o_par):
    """HITRAN2012 H2O lines of 664–726 cm⁻¹: those whose wings (25 cm⁻¹) reach 690–700 cm⁻¹."""
    return read_par(h2o_par, nu_range=(664.0, 726.0))
