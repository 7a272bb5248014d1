"""Partition sums, line parameters, Planck's law and line-by-line cross-sections."""

import dataclasses

import numpy as np
import pytest
from scipy import constants, integrate

from invflame.spectroscopy.cross_section import (
    cross_section,
    default_wavenumber,
    grid_step,
)
from invflame.spectroscopy.isotopologues import molar_mass
from invflame.spectroscopy.line_parameters import (
    C2,
    doppler_hwhm,
    line_intensity,
    lorentz_hwhm,
    pressure_shift,
)
from invflame.spectroscopy.linelist import LineList, read_par
from invflame.spectroscopy.partition import hapi_module, partition_function
from operators.rte.planck import planck

ATM = 101325.0


@pytest.fixture(scope="module")
def h2o(h2o_par):
    return read_par(h2o_par)


def one_line(nu=690.0, s296=1e-20, gamma_air=0.07, gamma_self=0.09, n_air=0.7, e_lower=500.0,
             delta_air=-0.002, molecule=2, isotopologue=1) -> LineList:
    return LineList(
        molecule=[molecule], isotopologue=[isotopologue], nu=[nu], S296=[s296], A=[1.0],
        gamma_air=[gamma_air], gamma_self=[gamma_self], E_lower=[e_lower], n_air=[n_air],
        delta_air=[delta_air], V_upper=[""], V_lower=[""], Q_upper=[""], Q_lower=[""],
        g_upper=[1.0], g_lower=[1.0],
    )


def test_partition_function_matches_hapi_and_rejects_out_of_range():
    hapi = hapi_module()
    temperatures = np.array([250.0, 296.0, 777.7, 1500.0, 2500.0])
    for molecule, isotopologue in [(1, 1), (2, 1), (1, 4)]:
        expected = np.array(hapi.partitionSum(molecule, isotopologue, temperatures.tolist()))
        np.testing.assert_allclose(
            partition_function(molecule, isotopologue, temperatures), expected, rtol=1e-6
        )
    with pytest.raises(ValueError, match="outside the TIPS range"):
        partition_function(6, 1, 3000.0)  # CH4 tabulated to 2500 K


def test_line_intensity_formula():
    line = one_line()
    np.testing.assert_allclose(line_intensity(line, 296.0), line.S296, rtol=1e-12)
    t = 1234.0
    q = partition_function(2, 1, [296.0, t])
    expected = (
        1e-20 * q[0] / q[1] * np.exp(-C2 * 500.0 / t) / np.exp(-C2 * 500.0 / 296.0)
        * (1 - np.exp(-C2 * 690.0 / t)) / (1 - np.exp(-C2 * 690.0 / 296.0))
    )
    np.testing.assert_allclose(line_intensity(line, t), [expected], rtol=1e-12)
    assert abs(C2 - 1.4387769) < 1e-6


def test_widths_and_shift():
    line = one_line()
    t, p_self = 1000.0, 0.1 * ATM
    expected = (296.0 / t) ** 0.7 * (0.07 * 0.9 + 0.09 * 0.1)
    np.testing.assert_allclose(lorentz_hwhm(line, t, ATM, p_self), [expected], rtol=1e-12)
    np.testing.assert_allclose(pressure_shift(line, 2 * ATM), [-0.004], rtol=1e-12)
    # no self shift in the record: the air shift weighted by the air's partial pressure
    np.testing.assert_allclose(pressure_shift(line, 2 * ATM, 0.5 * ATM), [-0.003], rtol=1e-12)
    # CO2 at 296 K, 690 cm-1: nu/c sqrt(2 ln2 kT/m) with m = 43.98983 u
    mass = 43.98983 * constants.atomic_mass
    expected_d = 690.0 * np.sqrt(2 * np.log(2) * constants.k * 296.0 / mass) / constants.c
    np.testing.assert_allclose(doppler_hwhm(line, 296.0), [expected_d], rtol=1e-6)
    assert 6.0e-4 < expected_d < 6.6e-4
    with pytest.raises(ValueError, match="self_pressure"):
        lorentz_hwhm(line, t, ATM, 2 * ATM)
    with pytest.raises(KeyError, match="no molar mass"):
        molar_mass([7], [1])


def test_planck_value_and_stefan_boltzmann():
    # c1 eta^3 / (exp(c2 eta / T) - 1) with the radiance constants in cm units (CODATA 2018:
    # 2hc^2 = 1.191042972e-8 W m-2 sr-1 (cm-1)-4, hc/k = 1.438776877 cm K)
    expected = 1.191042972e-8 * 700.0**3 / np.expm1(1.438776877 * 700.0 / 1000.0)
    np.testing.assert_allclose(planck(700.0, 1000.0), expected, rtol=1e-8)
    assert abs(expected - 2.35087) < 1e-4
    total, _ = integrate.quad(lambda eta: planck(eta, 1000.0), 1.0, 30000.0, limit=200)
    np.testing.assert_allclose(total, constants.sigma * 1000.0**4 / np.pi, rtol=1e-5)
    assert planck(np.ones((2, 3)), np.ones((2, 1)) * 300).shape == (2, 3)
    with pytest.raises(ValueError, match="positive"):
        planck(700.0, 0.0)


def test_default_grid():
    grid = default_wavenumber()
    assert grid.size == 1876 and grid[0] == 650.0 and abs(grid[-1] - 725.0) < 1e-9
    assert abs(grid_step(grid) - 0.04) < 1e-12
    with pytest.raises(ValueError, match="uniform"):
        grid_step(np.array([650.0, 650.04, 650.1]))


@pytest.mark.parametrize(
    ("temperature", "pressure"), [(250.0, ATM), (2500.0, ATM), (1000.0, 1000.0)]
)
def test_bin_averaging_conserves_line_area(temperature, pressure):
    """A line narrower than the grid step keeps its area (up to the 25 cm-1 cutoff)."""
    grid = default_wavenumber()
    for centre in (690.0, 690.013, 690.02):  # on a bin centre, off centre, on a bin edge
        line = one_line(nu=centre)
        sigma = cross_section(line, grid, temperature, pressure)
        gamma = lorentz_hwhm(line, temperature, pressure)[0]
        inside = 2 / np.pi * np.arctan(25.0 / gamma)
        area = sigma.sum() * grid_step(grid)
        np.testing.assert_allclose(area, line_intensity(line, temperature)[0] * inside, rtol=1e-4)
        # the peak is where the (shifted) line is
        shifted = centre + pressure_shift(line, pressure)[0]
        assert abs(grid[np.argmax(sigma)] - shifted) <= 0.02 + 1e-9


def test_cutoff_and_lines_outside_the_grid():
    grid = default_wavenumber()
    outside = one_line(nu=640.0, delta_air=0.0)  # 10 cm-1 below the grid: wing only
    sigma = cross_section(outside, grid, 1000.0)
    reaches = grid <= 640.0 + 25.0 + 0.02
    assert np.all(sigma[reaches] > 0) and np.all(sigma[~reaches] == 0)
    gamma = lorentz_hwhm(outside, 1000.0, ATM)[0]
    s = line_intensity(outside, 1000.0)[0]
    k = 100  # 14 cm-1 from the line: the Lorentz wing value
    np.testing.assert_allclose(
        sigma[k], s * gamma / (np.pi * ((grid[k] - 640.0) ** 2 + gamma**2)), rtol=1e-9
    )
    far = one_line(nu=600.0)
    assert not cross_section(far, grid, 1000.0).any()


def test_cross_section_is_additive_over_lines(h2o):
    grid = default_wavenumber()
    a, b = h2o.select(slice(0, 800)), h2o.select(slice(800, None))
    total = cross_section(h2o, grid, 900.0, self_fraction=0.2)
    np.testing.assert_allclose(
        total,
        cross_section(a, grid, 900.0, self_fraction=0.2)
        + cross_section(b, grid, 900.0, self_fraction=0.2),
        rtol=1e-10, atol=1e-35,
    )
    assert total.shape == grid.shape and np.all(total > 0)
    with pytest.raises(ValueError, match="self_fraction"):
        cross_section(h2o, grid, 900.0, self_fraction=1.5)
    narrower = dataclasses.replace(h2o, gamma_self=h2o.gamma_air)
    assert not np.allclose(
        cross_section(narrower, grid, 900.0, self_fraction=0.2), total, rtol=1e-3, atol=0
    )
