"""Data-driven start: band tomography, the state relation, and the start from data alone."""

from types import SimpleNamespace

import numpy as np
import pytest

from invflame.experiments import data_start as ds
from invflame.experiments.initialization import ambient
from invflame.experiments.metrics import hot_volume_ratio, normalized_mse
from invflame.geometry import VoxelGrid, paper_rig, traverse
from invflame.phantoms import make_phantom
from invflame.phantoms.composition import Z_STOICHIOMETRIC
from invflame.scene import Scene
from invflame.spectroscopy.absorption_table import AbsorptionTable, default_linelists

DRY_AIR = np.array([300.0, 0.0, 0.0, 0.0])  # the phantoms' ambient air


@pytest.fixture(scope="module")
def table():
    wavenumber = 660.0 + 0.2 * np.arange(201)  # 660-700 cm-1
    return AbsorptionTable.cached(default_linelists(wavenumber), wavenumber=wavenumber,
                                  progress=False)


@pytest.fixture(scope="module")
def scene(table):
    grid = VoxelGrid.poolfire(12)
    return Scene(grid, paper_rig(grid, n_pixels=8), table, rays_per_pixel=4)


def planar_rays(grid, n_angles=24, n_offsets=16):
    """Parallel rays at many angles in the plane z = centre of a one-voxel-thick grid."""
    centre = grid.centre
    origins, directions = [], []
    for angle in np.linspace(0.0, np.pi, n_angles, endpoint=False):
        d = np.array([np.cos(angle), np.sin(angle), 0.0])
        normal = np.array([-d[1], d[0], 0.0])
        for s in np.linspace(-0.6, 0.6, n_offsets):
            origins.append(centre - 2.0 * d + s * normal)
            directions.append(d)
    return traverse(grid, np.array(origins), np.array(directions))


def blob(grid):
    x, y, _ = np.meshgrid(*grid.axes(), indexing="ij")
    return 100.0 * np.exp(-((x - 0.55) ** 2 + (y - 0.45) ** 2) / 0.05)  # W/(m3 sr)


def test_linear_solve_recovers_a_known_emission_from_exact_band_data():
    grid = VoxelGrid((0.0, 0.0, 0.0), (1.0, 1.0, 0.1), (8, 8, 1))
    lengths = planar_rays(grid).to_csr()
    emission = blob(grid)
    result = ds.band_tomography(lengths, lengths @ emission.ravel(), grid, smoothing=1e-9)
    assert result.choice is None and result.smoothing == 1e-9
    np.testing.assert_allclose(result.emission, emission, atol=1e-3 * emission.max())


def test_discrepancy_principle_fits_noisy_band_data_to_the_noise():
    grid = VoxelGrid((0.0, 0.0, 0.0), (1.0, 1.0, 0.1), (8, 8, 1))
    lengths = planar_rays(grid).to_csr()
    emission = blob(grid)
    exact = lengths @ emission.ravel()
    sigma = 0.01 * exact.max()
    band = exact + sigma * np.random.default_rng(0).standard_normal(exact.size)
    result = ds.band_tomography(lengths, band, grid, sigma_band=sigma)
    assert result.choice.reached
    assert result.chi2 <= exact.size  # tau = 1
    assert ds.SMOOTHING_RANGE[1] < result.smoothing < ds.SMOOTHING_RANGE[0]
    assert np.all(result.emission >= 0)
    error = np.linalg.norm(result.emission - emission) / np.linalg.norm(emission)
    assert error < 0.1


def test_pixel_path_lengths_average_the_sub_rays(scene):
    lengths = ds.pixel_path_lengths(scene)
    sub = scene.segments.to_csr().toarray()
    assert lengths.shape == (scene.n_rays, scene.grid.n_voxels)
    np.testing.assert_allclose(lengths.toarray(), sub.reshape(scene.n_rays, 4, -1).mean(axis=1))
    one_ray = SimpleNamespace(segments=scene.segments)  # a scene without sub-rays
    np.testing.assert_allclose(ds.pixel_path_lengths(one_ray).toarray(), sub)
    with pytest.raises(ValueError, match="not a multiple"):
        ds.pixel_path_lengths(SimpleNamespace(segments=scene.segments, rays_per_pixel=7))


def test_lean_branch_runs_from_ambient_air_to_stoichiometric_products():
    z, states = ds.lean_branch(1500.0, DRY_AIR, n_points=9)
    assert z[0] == 0.0 and z[-1] == pytest.approx(Z_STOICHIOMETRIC)
    np.testing.assert_allclose(states[:, 0], DRY_AIR, atol=1e-12)
    # CH4 + 2 (O2 + 3.76 N2) -> CO2 + 2 H2O + 7.52 N2: 10.52 moles of products
    np.testing.assert_allclose(states[:, -1], [1800.0, 1 / 10.52, 2 / 10.52, 0.0], rtol=1e-3)
    assert np.all(np.diff(states[:3]) > 0)
    _, humid = ds.lean_branch(1500.0, n_points=9)
    np.testing.assert_allclose(humid[:, 0], ds.AMBIENT, atol=1e-12)  # humid air at Z = 0
    assert np.all(humid[1:].sum(axis=0) < 1)


def test_band_integral_is_the_line_integral_of_the_emission_density_when_thin(scene):
    """Dilute hot gas is optically thin: band radiance = path-length matrix @ density."""
    x, y, z = np.meshgrid(*scene.grid.axes(), indexing="ij")
    shape = np.exp(-(x**2 + (y - 0.3) ** 2 + z**2) / 0.04)
    fields = np.stack([300.0 + 1200.0 * shape, 1e-4 * shape, 2e-4 * shape, 0.0 * shape])
    weights = ds.channel_weights(scene)
    band = scene.simulate(fields) @ weights
    density = ds.channel_emission(scene, fields.reshape(4, -1)) @ weights
    predicted = ds.pixel_path_lengths(scene) @ density
    assert band.max() > 0
    np.testing.assert_allclose(band, predicted, rtol=0.02, atol=1e-3 * band.max())


def test_thin_channels_keep_fewer_channels_for_thicker_flames(scene):
    _, states = ds.lean_branch(1500.0, DRY_AIR)
    assert ds.thin_channels(scene, 0.0, states).all()  # no flame seen
    kept = [ds.thin_channels(scene, peak, states) for peak in (1.0, 10.0, 100.0, 1000.0)]
    for thinner, thicker in zip(kept, kept[1:], strict=False):
        assert np.all(thinner >= thicker)
    assert kept[-1].sum() < kept[0].sum()
    assert kept[-1].any()


@pytest.mark.parametrize("noise_known", [True, False])
def test_start_from_synthetic_flame_data_beats_ambient_air(scene, noise_known):
    truth = make_phantom("synthetic", grid=scene.grid).values.astype(np.float64)
    clean = np.asarray(scene.simulate(truth), np.float64)
    sigma = 1e-3 * clean.max()
    data = clean + sigma * np.random.default_rng(1).standard_normal(clean.shape)
    start = ds.band_tomography_start(scene, data, sigma if noise_known else None,
                                     ambient=DRY_AIR)
    assert start.shape == scene.field_shape
    assert np.all((start[0] >= 300.0) & (start[0] <= 300.0 + ds.DEFAULT_TEMPERATURE_RISE_ST))
    assert np.all((start[1:] >= 0) & (start[1:].sum(axis=0) <= 1))
    error = normalized_mse(truth, start)["T"]
    baseline = normalized_mse(truth, ambient(scene.grid.shape))["T"]
    assert error < 0.5 * baseline
    assert 0.3 < hot_volume_ratio(truth, start) < 3.0


def test_a_scene_without_flame_gives_ambient_air(scene):
    air = np.broadcast_to(DRY_AIR.reshape(4, 1, 1, 1), scene.field_shape)
    start = ds.band_tomography_start(scene, scene.simulate(air), smoothing=1e-3,
                                     ambient=DRY_AIR)
    np.testing.assert_allclose(start, air, atol=1e-6)


@pytest.mark.parametrize(("change", "message"), [
    (lambda scene: {"data": np.zeros((3, 3))}, "data must have the scene's shape"),
    (lambda scene: {"sigma": np.ones(5)}, "does not broadcast"),
    (lambda scene: {"sigma": -1.0}, "must be finite and positive"),
    (lambda scene: {"channels": np.ones(3, bool)}, "boolean mask of shape"),
    (lambda scene: {"channels": np.zeros(scene.out_wavenumber.size, bool)},
     "selects no output wavenumber"),
    (lambda scene: {"temperature_rise_st": -10.0}, "temperature_rise_st must be positive"),
    (lambda scene: {"ambient": (300.0, 0.5, 0.6, 0.0)}, "ambient must be"),
    (lambda scene: {"smoothing": -1.0}, "smoothing must be"),
])
def test_bad_input_is_a_clear_error(scene, change, message):
    kwargs = {"data": np.zeros(scene.data_shape), "sigma": 1e-3, **change(scene)}
    data = kwargs.pop("data")
    with pytest.raises(ValueError, match=message):
        ds.band_tomography_start(scene, data, **kwargs)


def test_bad_tomography_and_state_input_are_clear_errors(scene):
    grid = VoxelGrid((0.0, 0.0, 0.0), (1.0, 1.0, 0.1), (8, 8, 1))
    lengths = planar_rays(grid).to_csr()
    with pytest.raises(ValueError, match="columns, the grid"):
        ds.band_tomography(lengths, np.zeros(lengths.shape[0]), scene.grid)
    with pytest.raises(ValueError, match="band must be"):
        ds.band_tomography(lengths, np.zeros(3), grid)
    with pytest.raises(ValueError, match="states must have shape"):
        ds.channel_emission(scene, np.zeros((3, 5)))
    with pytest.raises(ValueError, match="min_ratio"):
        ds.thin_channels(scene, 1.0, ds.lean_branch()[1], min_ratio=1.5)


def test_masked_pixels_and_wavenumbers_are_left_out(scene):
    """A masked value does not reach the start: garbage there gives the same start, which
    still beats ambient air; a mask that leaves no pixel whole is refused."""
    truth = make_phantom("synthetic", grid=scene.grid).values.astype(np.float64)
    clean = np.asarray(scene.simulate(truth), np.float64)
    noise = 1e-3 * clean.max()
    data = clean + noise * np.random.default_rng(2).standard_normal(clean.shape)
    sigma = np.full(data.shape, noise)
    sigma[::7] = np.inf  # bad pixels
    sigma[:, 3] = np.inf  # a bad wavenumber
    sigma[5, 10] = np.inf  # one bad value
    start = ds.band_tomography_start(scene, data, sigma, ambient=DRY_AIR)
    garbage = np.where(np.isfinite(sigma), data, 1e3)
    np.testing.assert_array_equal(ds.band_tomography_start(scene, garbage, sigma,
                                                           ambient=DRY_AIR), start)
    error = normalized_mse(truth, start)["T"]
    assert error < 0.5 * normalized_mse(truth, ambient(scene.grid.shape))["T"]
    unknown_noise = ds.band_tomography_start(scene, garbage, ambient=DRY_AIR,
                                             measured=np.isfinite(sigma))
    assert normalized_mse(truth, unknown_noise)["T"] < 0.5 * normalized_mse(
        truth, ambient(scene.grid.shape))["T"]
    sigma[:, ::2] = np.inf
    sigma[::2, 1::2] = np.inf
    sigma[1::2, 1::2] = np.inf
    with pytest.raises(ValueError, match="no pixel measured in every channel"):
        ds.band_tomography_start(scene, data, sigma, ambient=DRY_AIR)
