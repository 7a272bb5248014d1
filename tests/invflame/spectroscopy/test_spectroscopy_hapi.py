"""Acceptance: cross-sections against HAPI's absorptionCoefficient_Voigt on the same H2O lines.

HAPI evaluates the Voigt profile at points; it is run on 16 points per 0.04 cm⁻¹ bin (every
0.0025 cm⁻¹, fine enough for the narrowest lines, HWHM ≈ 0.005 cm⁻¹) and averaged per bin, with
the same 25 cm⁻¹ absolute line cutoff, over the full 650–725 cm⁻¹ grid. Measured: at most
0.58 % difference on the spectrum smoothed to 1 cm⁻¹, 0.04 % on the band integral.

HAPI applies the air shift only to the air part of the mixture (it has no self shift); the
self-broadened comparison therefore uses lines with zero shift.
"""

import contextlib
import dataclasses
import io
import json

import numpy as np
import pytest

from invflame.spectroscopy.cross_section import cross_section, default_wavenumber
from invflame.spectroscopy.linelist import read_par, write_par
from invflame.spectroscopy.partition import hapi_module
from invflame.spectroscopy.table_accuracy import smooth

SUBSAMPLES = 16


@pytest.fixture(scope="module")
def hapi_case(h2o_par, tmp_path_factory):
    """HAPI with two local tables: the H2O lines as they are, and the same without shifts."""
    hapi = hapi_module()
    folder = tmp_path_factory.mktemp("hapi")
    lines = read_par(h2o_par)
    unshifted = dataclasses.replace(lines, delta_air=np.zeros(len(lines)))
    for name, table in [("h2o", lines), ("h2o_unshifted", unshifted)]:
        write_par(table, folder / f"{name}.data")
        header = dict(hapi.HITRAN_DEFAULT_HEADER, table_name=name)
        (folder / f"{name}.header").write_text(json.dumps(header))
    with contextlib.redirect_stdout(io.StringIO()):
        hapi.db_begin(str(folder))
    return hapi, {"h2o": lines, "h2o_unshifted": unshifted}


def hapi_bin_averaged(hapi, table, grid, temperature, self_fraction):
    step = grid[1] - grid[0]
    offsets = ((np.arange(SUBSAMPLES) + 0.5) / SUBSAMPLES - 0.5) * step
    fine = (grid[:, None] + offsets).ravel()
    diluent = {"air": 1.0 - self_fraction}
    if self_fraction:
        diluent["self"] = self_fraction
    with contextlib.redirect_stdout(io.StringIO()):
        _, coefficient = hapi.absorptionCoefficient_Voigt(
            SourceTables=table, WavenumberGrid=fine, Environment={"T": temperature, "p": 1.0},
            Diluent=diluent, WavenumberWing=25.0, WavenumberWingHW=0.0, HITRAN_units=True,
        )
    return coefficient.reshape(grid.size, SUBSAMPLES).mean(axis=1)


@pytest.mark.parametrize(
    ("table", "temperature", "self_fraction"),
    [("h2o", 500.0, 0.0), ("h2o", 1000.0, 0.0), ("h2o", 1500.0, 0.0),
     ("h2o_unshifted", 1000.0, 0.2)],
)
def test_cross_section_matches_hapi(hapi_case, table, temperature, self_fraction):
    hapi, lines = hapi_case
    grid = default_wavenumber()
    reference = hapi_bin_averaged(hapi, table, grid, temperature, self_fraction)
    ours = cross_section(lines[table], grid, temperature, self_fraction=self_fraction)
    step = grid[1] - grid[0]
    smoothed_difference = np.abs(smooth(ours, step) / smooth(reference, step) - 1).max()
    band_difference = abs(ours.sum() / reference.sum() - 1)
    assert smoothed_difference <= 0.01, smoothed_difference
    assert band_difference <= 0.005, band_difference
