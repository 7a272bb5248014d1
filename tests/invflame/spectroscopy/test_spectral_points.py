"""Spectral points: sub-bin means, the plan of points per bin, and an absorption table that
holds them, through the emission kernel."""

import numpy as np
import pytest
from scipy import constants

from invflame.spectroscopy.absorption_table import AbsorptionTable
from invflame.spectroscopy.spectral_points import fine_grid, plan_points, points_of
from operators.base import precision
from operators.rte.kernel import emission_radiance
from operators.rte.planck import planck

ATM = 101325.0
GRID = 690.0 + 0.04 * np.arange(251)  # 690-700 cm-1
NODES = [300.0, 800.0, 1500.0, 2200.0]


@pytest.fixture(scope="module")
def pointed(h2o):
    """H2O on 690-700 cm-1, its cross-section on self-fraction nodes, up to 8 points per bin."""
    return AbsorptionTable.build({"H2O": h2o}, wavenumber=GRID, temperatures=NODES,
                                 self_fraction={"H2O": (0.0, 0.1, 1.0)})


def test_fine_grid_and_sub_bin_means():
    grid = np.array([700.0, 700.04, 700.08])
    fine = fine_grid(grid, 4)
    np.testing.assert_allclose(fine[:4], 700.0 + 0.01 * np.array([-1.5, -0.5, 0.5, 1.5]))
    values = np.arange(12.0)
    np.testing.assert_allclose(points_of(values, [1, 1, 1], 4), [1.5, 5.5, 9.5])
    np.testing.assert_allclose(points_of(values, [4, 4, 4], 4), values)
    np.testing.assert_allclose(points_of(values, [2, 1, 4], 4), [0.5, 2.5, 5.5, 8, 9, 10, 11])


def test_the_plan_splits_the_bins_of_a_saturated_line_and_keeps_its_budget():
    """A toy window: one bin with a strong line in one of its 8 sub-bins, weak absorption
    elsewhere. The plan refines that bin only, and meets its budget for the reference."""
    wavenumber = 700.0 + 0.04 * np.arange(50)
    fine = np.full((1, 3, 400), 1e-22)  # (T, columns CO2 H2O CH4, fine sub-bins), cm²
    fine[0, 0, 10 * 8 + 3] = 1e-18
    fine[0, 2] = 0.0
    nodes = ((0.0,), (0.0,), (0.0,))
    reference = {"T": 1500.0, "CO2": 0.1, "length": 1.0}
    plan = plan_points(wavenumber, np.array([1500.0]), fine, ("CO2", "H2O", "CH4"), nodes, ATM,
                       budget=1e-3, references=[reference])
    assert plan[10] > 1 and np.all(np.delete(plan, 10) == 1)
    tau = 0.1 * ATM / (constants.k * 1500.0) * 1e-4 * fine[0, 0] * 1.0
    exact = np.exp(-tau).reshape(50, 8).mean(axis=1)
    chosen = np.exp(-points_of(tau, plan, 8)) / np.repeat(plan, plan)
    mean = np.add.reduceat(chosen, np.cumsum(plan) - plan)
    b = planck(wavenumber, 1500.0)
    first_window = slice(0, 25)  # 1 cm-1 at 0.04 cm-1
    error = np.sum((b * np.abs(mean - exact))[first_window])
    assert error <= 1e-3 * np.sum((b * (1 - exact))[first_window])
    # one optical depth for the whole bin would not have met it
    coarse = np.exp(-tau.reshape(50, 8).mean(axis=1))
    assert np.sum((b * np.abs(coarse - exact))[first_window]) > error
    loose = plan_points(wavenumber, np.array([1500.0]), fine, ("CO2", "H2O", "CH4"), nodes,
                        ATM, budget=10.0, references=[reference])
    assert np.all(loose == 1)


def test_a_table_with_points_bins_what_the_kernel_solves_at_each_point(pointed):
    assert pointed.points_per_bin.max() > 1 and pointed.sigma.shape[-1] == \
        pointed.points_per_bin.sum()
    assert np.all(np.diff(pointed.points) > 0)
    assert pointed.take_bins(slice(None, None, 5)).bin_width == pointed.bin_width
    temperature, x, length = 1500.0, 0.1, 0.3  # on a T node and a fraction node
    with precision(np.float64):
        tables = pointed.kernel_tables(dtype=np.float64, planck="exact")
        fields = np.array([temperature, 0.0, x, 0.0]).reshape(4, 1, 1)
        ours = np.asarray(emission_radiance(tables, fields, np.array([[length]])))[0]
    sigma = pointed.sigma[2, pointed.columns(1)][1]  # H2O at x = 0.1, 1500 K, per point
    kappa = x * ATM / (constants.k * temperature) * sigma * 1e-4
    per_point = planck(pointed.points, temperature) * -np.expm1(-kappa * length)
    np.testing.assert_allclose(ours, pointed.bin_average(per_point), rtol=1e-10)
    # the bins' cross-sections are the means over their points
    np.testing.assert_allclose(
        pointed.cross_sections(np.array(temperature), np.array([0.0, x, 0.0]))[1],
        pointed.bin_average(sigma), rtol=1e-10)


def test_one_point_per_bin_is_the_bin_mean(h2o, pointed):
    plain = AbsorptionTable.build({"H2O": h2o}, wavenumber=GRID, temperatures=NODES,
                                  self_fraction={"H2O": (0.0, 0.1, 1.0)}, subdivision=1)
    assert np.all(plain.points_per_bin == 1)
    # the same bin means from eight times finer sub-bins: the line areas agree (the wings'
    # midpoint rule errs by ~h²/d², a few 1e-4 of a wing, cross_section's notes), and bin by
    # bin within 1 % where the cross-section is not negligible
    means, direct = pointed.bin_average(pointed.sigma)[:, 2:5], plain.sigma[:, 2:5]  # H2O
    np.testing.assert_allclose(means.sum(-1), direct.sum(-1), rtol=5e-4)
    seen = direct > 1e-2 * direct.max(axis=-1, keepdims=True)
    np.testing.assert_allclose(means[seen], direct[seen], rtol=0.01)
    with pytest.raises(ValueError, match="power of two"):
        AbsorptionTable.build({"H2O": h2o}, wavenumber=GRID, temperatures=NODES, subdivision=3)


def test_save_and_load_keep_the_points(pointed, tmp_path):
    pointed.save(tmp_path / "t.npz")
    loaded = AbsorptionTable.load(tmp_path / "t.npz")
    np.testing.assert_array_equal(loaded.points_per_bin, pointed.points_per_bin)
    np.testing.assert_array_equal(loaded.sigma, pointed.sigma)
    assert loaded.self_fraction == pointed.self_fraction
    assert loaded.bin_width == pointed.bin_width


def test_radiance_stays_between_zero_and_the_hottest_blackbody():
    """The default forward model (float32, local broadening, spectral points) on random rays
    through gas of any temperature in the table and mole fractions up to 0.6, including the
    interpolation nodes and beyond: 0 <= I <= B(the ray's hottest T), at every bin."""
    table = AbsorptionTable.default(progress=False)
    rng = np.random.default_rng(4)
    n_rays, n_seg = 64, 12
    fields = np.zeros((4, n_rays, n_seg))
    fields[0] = rng.uniform(table.temperatures[0], table.temperatures[-1], (n_rays, n_seg))
    fields[1:3] = rng.uniform(0.0, 0.6, (2, n_rays, n_seg))
    fields[2, :8] = np.array(table.self_fraction[1][:8])[:, None]  # on H2O's nodes
    lengths = rng.uniform(0.0, 0.2, (n_rays, n_seg))
    radiance = np.asarray(emission_radiance(table.kernel_tables(), fields, lengths))
    hottest = planck(table.wavenumber, fields[0].max(axis=1)[:, None])
    assert radiance.min() >= 0.0
    assert np.all(radiance <= hottest * (1 + 1e-5))
