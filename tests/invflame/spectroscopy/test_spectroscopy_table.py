"""AbsorptionTable: construction, cache, spline accuracy, κ and Planck-mean κ."""

import numpy as np
import pytest
from scipy import constants

from invflame.errors import InputDataError
from invflame.spectroscopy.absorption_table import AbsorptionTable, default_linelists
from invflame.spectroscopy.cross_section import cross_section
from invflame.spectroscopy.linelist import LineList, read_par, write_par
from invflame.spectroscopy.table_accuracy import spline_error
from operators.rte.planck import planck

ATM = 101325.0
GRID = 690.0 + 0.04 * np.arange(251)  # 690-700 cm-1, small and fast
NODES = [300.0, 600.0, 1000.0, 1500.0]


@pytest.fixture(scope="module")
def small(h2o):
    """Fixed self-broadening fractions, one point per bin: one column per species."""
    return AbsorptionTable.build({"H2O": h2o}, wavenumber=GRID, temperatures=NODES,
                                 self_fraction={"CO2": 0.1, "H2O": 0.2}, subdivision=1)


@pytest.fixture(scope="module")
def default_table(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("INVFLAME_CACHE", str(tmp_path_factory.mktemp("cache")))
        yield AbsorptionTable.default(progress=False)


def test_build_layout_nodes_and_zero_species(small, h2o):
    assert small.species == ("CO2", "H2O", "CH4")
    assert small.sigma.shape == (4, 3, GRID.size)
    assert not small.sigma[:, 0].any() and not small.sigma[:, 2].any()  # no lines: zero
    np.testing.assert_allclose(
        small.sigma[2, 1], cross_section(h2o, GRID, 1000.0, ATM, 0.2), rtol=1e-12
    )
    # the spline passes through the nodes and has the documented shape
    np.testing.assert_allclose(small.spline(np.array(NODES)), small.sigma, rtol=1e-9, atol=0)
    assert small.cross_sections(np.full((2, 5), 700.0), np.zeros((3, 2, 5))).shape == \
        (2, 5, 3, GRID.size)
    assert small.spline.coef.shape == (4, 3, 3, GRID.size)
    assert small.self_fraction == ((0.1,), (0.2,), (0.0,))
    tables = small.kernel_tables()
    assert tables.fraction_nodes == ((0.2,),) and tables.species == (1,)  # H2O alone absorbs
    assert tables.n_points == tables.n_eta == GRID.size
    with pytest.raises(ValueError, match="not in species"):
        AbsorptionTable.build({"N2O": h2o}, wavenumber=GRID, temperatures=NODES)


def test_save_load_and_cache(small, h2o, tmp_path, monkeypatch):
    small.save(tmp_path / "t.npz")
    loaded = AbsorptionTable.load(tmp_path / "t.npz")
    np.testing.assert_array_equal(loaded.sigma, small.sigma)
    assert loaded.species == small.species and loaded.pressure == small.pressure
    assert loaded.self_fraction == small.self_fraction

    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path / "cache"))
    args = {"wavenumber": GRID, "temperatures": NODES, "progress": False}
    first = AbsorptionTable.cached({"H2O": h2o}, **args)
    assert len(list((tmp_path / "cache").glob("absorption-*.npz"))) == 1

    def no_build(*_, **__):
        raise AssertionError("should have loaded from the cache")

    monkeypatch.setattr(AbsorptionTable, "build", no_build)
    np.testing.assert_array_equal(AbsorptionTable.cached({"H2O": h2o}, **args).sigma, first.sigma)
    with pytest.raises(AssertionError, match="cache"):  # other inputs, other key: rebuilds
        AbsorptionTable.cached({"H2O": h2o.select(slice(1, None))}, **args)
    with pytest.raises(AssertionError, match="cache"):
        AbsorptionTable.cached({"H2O": h2o}, pressure=0.5 * ATM, **args)


def test_kappa_and_planck_mean(small):
    t = np.array([[400.0, 800.0], [1200.0, 1500.0]])
    x = np.zeros((3, 2, 2))
    x[1] = 0.2
    kappa = small.kappa(t, x)
    assert kappa.shape == (2, 2, GRID.size)
    sigma_h2o = small.spline(np.array(800.0))[1]
    expected = 0.2 * ATM / (constants.k * 800.0) * sigma_h2o * 1e-4
    np.testing.assert_allclose(kappa[0, 1], expected, rtol=1e-12)
    mean = small.planck_mean_kappa(t, x)
    b = planck(GRID, 1200.0)
    np.testing.assert_allclose(mean[1, 0], np.sum(b * kappa[1, 0]) / np.sum(b), rtol=1e-12)
    assert mean.shape == (2, 2) and np.all(mean > 0)
    with pytest.raises(ValueError, match="outside the table range"):
        small.kappa(np.array(200.0), np.array([0.1, 0.1, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        small.kappa(t, np.zeros((2, 2, 3)))
    with pytest.raises(ValueError, match="build a table at that pressure"):
        small.kappa(t, x, pressure=2 * ATM)


def test_default_table(default_table, monkeypatch):
    table = default_table
    assert table.species == ("CO2", "H2O", "CH4")
    assert table.wavenumber.size == 1876 and table.pressure == ATM
    assert table.temperatures[0] == 250.0 and table.temperatures[-1] == 2500.0
    assert table.self_fraction[2] == (0.0,) and not table.sigma[:, table.columns(2)].any()
    assert np.all(table.sigma[:, :table.columns(2).start] > 0)  # CO2 and H2O, every node
    assert 1.3 < table.points_per_bin.mean() < 2.0  # spectral points where lines saturate
    # CO2 ν2 Q branch at 667.4 cm-1 dominates the window at 300 K
    air = np.array([0.0004, 0.01, 0.0])
    peak = table.wavenumber[np.argmax(table.cross_sections(np.array(300.0), air)[0])]
    assert abs(peak - 667.4) < 0.5
    # hot gas: Planck-mean κ of 10 % CO2 + 20 % H2O at 1500 K is of order 1 m-1
    mean = table.planck_mean_kappa(np.array(1500.0), np.array([0.1, 0.2, 0.0]))
    assert 0.1 < mean < 10.0
    # loading the cached default is fast and needs no build
    monkeypatch.setattr(AbsorptionTable, "build", None)
    np.testing.assert_array_equal(AbsorptionTable.default(progress=False).sigma, table.sigma)


def test_default_spline_error_below_half_percent(default_table):
    """Off-node spline error on spectra smoothed to 1 cm-1, at the intervals where it peaks."""
    nodes = default_table.temperatures
    intervals = [0, 1, 13, len(nodes) - 3, len(nodes) - 2]
    midpoints = 0.5 * (nodes[intervals] + nodes[[i + 1 for i in intervals]])
    errors = spline_error(default_table, default_linelists(), midpoints)
    assert errors[:, :2].min() > 0
    assert errors.max() <= 0.005, errors



def test_a_users_line_files_replace_the_built_in_lists(h2o, shared_linedata, tmp_path):
    """A HITRAN CO2 file stands in for the generated list, its other molecules left out; a file
    without the species near the grid is refused, naming it."""
    mixed = tmp_path / "mixed.par"
    co2 = read_par(shared_linedata / "CO2_HITRAN_691.4-692.7_validation.par")
    write_par(LineList.concatenate([co2, h2o.window(691.0, 693.0)]), mixed)
    grid = 690.0 + 0.04 * np.arange(101)
    lines = default_linelists(grid, {"CO2": mixed, "H2O": ""})
    assert len(lines["CO2"]) == len(co2) and set(lines["CO2"].molecule) == {2}
    np.testing.assert_array_equal(lines["H2O"].nu, default_linelists(grid)["H2O"].nu)
    with pytest.raises(InputDataError, match="holds no H2O line"):
        default_linelists(650.0 + 0.04 * np.arange(101), {"H2O": shared_linedata
                                                        / "CO2_HITRAN_691.4-692.7_validation.par"})
    with pytest.raises(ValueError, match="only CO2 and H2O"):
        default_linelists(grid, {"N2O": mixed})
