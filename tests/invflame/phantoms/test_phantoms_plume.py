"""Synthetic McCaffrey plume and the methane-air composition behind it."""

import numpy as np
import pytest

from invflame.geometry import VoxelGrid
from invflame.phantoms import synthetic_plume
from invflame.phantoms.composition import (
    MOLAR_MASS,
    Z_STOICHIOMETRIC,
    burke_schumann_methane,
    mass_to_mole_fractions,
)
from invflame.phantoms.plume import mccaffrey_centreline_rise


def test_stoichiometric_products_are_co2_2h2o_7p52n2():
    temperature, mass = burke_schumann_methane(Z_STOICHIOMETRIC, 1500.0, 300.0)
    x = mass_to_mole_fractions(mass, MOLAR_MASS)
    assert temperature == pytest.approx(1800.0)
    assert x["CO2"] == pytest.approx(1 / 10.52, rel=1e-4)
    assert x["H2O"] == pytest.approx(2 / 10.52, rel=1e-4)
    assert x["N2"] == pytest.approx(7.52 / 10.52, rel=1e-4)
    assert x["CH4"] == pytest.approx(0.0, abs=1e-12)
    assert x["O2"] == pytest.approx(0.0, abs=1e-4)
    assert Z_STOICHIOMETRIC == pytest.approx(0.0552, abs=2e-4)


def test_burke_schumann_limits_and_mass_balance():
    z = np.linspace(0, 1, 101)
    temperature, mass = burke_schumann_methane(z, 1500.0, 300.0)
    np.testing.assert_allclose(sum(mass.values()), 1.0, atol=1e-5)
    assert temperature[0] == temperature[-1] == 300.0  # pure air, pure fuel
    assert mass["CH4"][-1] == pytest.approx(1.0)
    assert mass["O2"][0] == pytest.approx(0.2329, abs=1e-3)
    assert np.all(mass["CH4"][z <= Z_STOICHIOMETRIC] == 0)
    assert np.all(mass["O2"][z > Z_STOICHIOMETRIC + 1e-9] < 1e-12)


def test_mccaffrey_regions_and_values():
    q = 13.0
    q25 = q**0.4
    rise = mccaffrey_centreline_rise(np.array([0.04, 0.14, 0.5]) * q25, q, 300.0)
    g = 9.81
    expected = [
        300 * (6.8 / (0.9 * np.sqrt(2 * g))) ** 2,
        300 * (1.9 / (0.9 * np.sqrt(2 * g))) ** 2 / 0.14,
        300 * (1.1 / (0.9 * np.sqrt(2 * g))) ** 2 * 0.5 ** (-5 / 3),
    ]
    np.testing.assert_allclose(rise, expected, rtol=1e-12)
    assert 850 < rise[0] < 880  # the classic ~ 870 K flame excess at 300 K ambient
    heights = np.linspace(0.01, 1.0, 200)
    assert np.all(np.diff(mccaffrey_centreline_rise(heights, q, 300.0)) <= 0)


def test_plume_is_physical_and_peaks_on_axis():
    grid = VoxelGrid.poolfire(30)
    field = synthetic_plume(grid)
    assert field.grid == grid
    assert field.T.min() == pytest.approx(300.0)
    flame = mccaffrey_centreline_rise(0.0, 13.0, 300.0)
    assert field.T.max() <= 300.0 + flame + 1e-3
    assert field.T.max() > 300.0 + 0.9 * flame
    assert 0.09 < field.X("CO2").max() <= 1 / 10.52 + 1e-6  # stoichiometric products at most
    assert field.X("CH4").max() > 0.5  # fuel-rich core above the pool
    # hottest column on the axis; cools with radius and (above the flame) with height
    t = field.T
    assert np.all(t[14:16, 20, 14:16] > t[5, 20, 14:16].max())
    assert t[15, 25, 15] < t[15, 15, 15]
    # CH4 only near the pool
    iy = np.nonzero(field.X("CH4").max(axis=(0, 2)) > 1e-3)[0]
    assert grid.axes()[1][iy.max()] < 0.25


def test_sheet_rise_keeps_the_mean_temperature_and_scales_the_gas_toward_air():
    grid = VoxelGrid.poolfire(16)
    flame = float(mccaffrey_centreline_rise(0.0, 13.0, 300.0))
    own, sheet = synthetic_plume(grid), synthetic_plume(grid, sheet_rise=1950.0)
    np.testing.assert_array_equal(sheet.T, own.T)
    hot = (own.X("CO2") > 0.01) & (own.X("CH4") == 0)  # burnt lean gas
    # mole fractions of CO2 + H2O per kelvin of rise: those of the sheet's stoichiometric
    # state (3 mol in 10.52), 1950 K or the flame's own rise above ambient; mole fractions are
    # not linear in the mass fractions the states are mixed by, hence 10 %
    for field, rise in ((sheet, 1950.0), (own, flame)):
        per_kelvin = (field.X("CO2") + field.X("H2O"))[hot] / (field.T[hot] - 300.0)
        np.testing.assert_allclose(per_kelvin, 3 / 10.52 / rise, rtol=0.1)
    assert 0 < sheet.X("CH4").max() < own.X("CH4").max()  # the fuel core diluted by air too
    assert sheet.metadata["sheet_rise_K"] == 1950.0
    assert own.metadata["sheet_rise_K"] == pytest.approx(flame)
    with pytest.raises(ValueError, match="at least the continuous flame"):
        synthetic_plume(grid, sheet_rise=500.0)


def test_resolution_consistency():
    coarse = synthetic_plume(VoxelGrid.poolfire(20))
    fine = synthetic_plume(VoxelGrid.poolfire(40)).resample(VoxelGrid.poolfire(20))
    rel = np.abs(fine.T - coarse.T) / coarse.T
    assert np.median(rel) < 1e-3 and rel.max() < 0.2


def test_perturbation_is_seeded():
    grid = VoxelGrid.poolfire(16)
    a = synthetic_plume(grid, perturbation=0.2, seed=1)
    b = synthetic_plume(grid, perturbation=0.2, seed=1)
    c = synthetic_plume(grid, perturbation=0.2, seed=2)
    smooth = synthetic_plume(grid)
    np.testing.assert_array_equal(a.values, b.values)
    assert not np.allclose(a.values, c.values)
    assert not np.allclose(a.values, smooth.values)
    assert a.metadata["seed"] == 1
    with pytest.raises(ValueError, match="explicit seed"):
        synthetic_plume(grid, perturbation=0.2)
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        synthetic_plume(grid, perturbation=1.5, seed=0)


def test_x_up_grid_puts_the_plume_along_x():
    grid = VoxelGrid((0.0, -0.5, -0.5), (1.0, 0.5, 0.5), (20, 10, 10), up_axis=0)
    field = synthetic_plume(grid)
    column = field.T[:, 4:6, 4:6].mean(axis=(1, 2))
    assert column[2] > column[-1] > 300.0
