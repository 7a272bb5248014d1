"""Synthetic measurements: no inverse crime, FTIR noise, and the noise-weighted misfit."""

import warnings

import numpy as np
import pytest

from invflame.errors import InputDataError
from invflame.experiments import config
from invflame.experiments.measurement import (
    add_noise,
    noise_sigma,
    read_nesr,
    simulate_measurement,
    synthesis_scene,
)
from invflame.experiments.metrics import flame_mse, normalized_mse, smoothed
from invflame.field import Field
from invflame.geometry import VoxelGrid, paper_rig
from invflame.representations.voxel import VoxelRepresentation
from invflame.representations.whitening import noise_weights
from invflame.scene import Scene

from ..test_scene import small_table, smooth_field


@pytest.fixture(scope="module")
def scenes():
    grid = VoxelGrid.cube(4, size=1.0, centre=(0.0, 0.5, 0.0))
    fine = VoxelGrid.cube(8, size=1.0, centre=(0.0, 0.5, 0.0))
    scene = Scene(grid, paper_rig(grid, n_pixels=3), small_table(24), resolution=4.0,
                  dtype=np.float64, rays_per_pixel=4)
    truth = Field(fine, smooth_field(fine))
    synthesis = synthesis_scene(scene, truth, small_table(48), rays_per_pixel=9)
    return scene, synthesis, truth


def test_synthesis_scene_is_finer_than_the_reconstruction(scenes):
    scene, synthesis, truth = scenes
    assert synthesis.grid == truth.grid and synthesis.grid.shape == (8, 8, 8)
    assert synthesis.rays_per_pixel == 9 and synthesis.step < scene.step
    np.testing.assert_array_equal(synthesis.out_wavenumber, scene.out_wavenumber)
    assert synthesis.data_shape == scene.data_shape
    # the reconstruction's own model on the resampled truth does not reproduce the data
    clean = synthesis.simulate(truth.values)
    crime = scene.simulate(truth.resample(scene.grid).values)
    assert np.abs(clean - crime).max() > 1e-3 * np.abs(clean).max()


def test_noise_weighted_misfit_of_the_truth_is_about_one_per_value(scenes):
    _, synthesis, truth = scenes
    measurement = simulate_measurement(synthesis, truth, {"kind": "nesr", "nesr": 2e-3},
                                       seed=3)
    clean = synthesis.simulate(truth.values)
    m = measurement.n_measurements
    chi2 = np.sum(((clean - measurement.data) / measurement.sigma) ** 2)
    # chi2 of M standard normals: mean M, standard deviation sqrt(2M)
    assert abs(chi2 - m) < 5 * np.sqrt(2 * m)
    assert measurement.noisy and measurement.provenance["peak_snr"] > 1
    # the voxel problem weighs its misfit the same way
    rep = VoxelRepresentation(synthesis.grid, synthesis.operator)
    problem = rep.problem(measurement.data, sigma=measurement.sigma)
    x = rep.initial_parameters(truth.values)
    np.testing.assert_allclose(problem.evaluate(x).misfit, chi2, rtol=1e-6)


def test_noise_free_data_have_unit_weights(scenes):
    _, synthesis, truth = scenes
    measurement = simulate_measurement(synthesis, truth, {"kind": "none"}, seed=0)
    assert not measurement.noisy
    np.testing.assert_array_equal(measurement.sigma, 1.0)
    np.testing.assert_array_equal(measurement.data, synthesis.simulate(truth.values))


def test_noise_kinds_give_sigma_per_wavenumber(tmp_path):
    clean = np.array([[0.0, 2.0, -4.0], [1.0, 1.0, 1.0]])
    eta = np.array([660.0, 670.0, 680.0])
    np.testing.assert_allclose(noise_sigma({"kind": "snr", "snr": 8.0}, clean, eta), 0.5)
    np.testing.assert_allclose(noise_sigma({"kind": "nesr", "nesr": 1e-3}, clean, eta), 1e-3)
    assert noise_sigma({"kind": "none"}, clean, eta) is None
    table = tmp_path / "nesr.txt"
    table.write_text("# wavenumber NESR\n650 1e-3\n700 3e-3\n")
    np.testing.assert_allclose(
        noise_sigma({"kind": "nesr", "nesr": str(table)}, clean, eta), [1.4e-3, 1.8e-3, 2.2e-3])
    noisy = add_noise(np.zeros((20000, 3)), [1.0, 2.0, 3.0], seed=0)
    np.testing.assert_allclose(noisy.std(axis=0), [1.0, 2.0, 3.0], rtol=0.03)
    with pytest.raises(ValueError, match="finite and positive"):
        add_noise(np.zeros((2, 3)), [1.0, 0.0, 1.0], seed=0)


@pytest.mark.parametrize(("text", "message"), [
    ("", "need at least 2 rows of 'wavenumber NESR' .*; got 0 rows"),
    ("650 1e-3\n", "need at least 2 rows .*; got 1 rows of 2 columns"),
    ("650 1e-3 5\n700 1e-3 5\n", "got 2 rows of 3 columns"),
    ("650 1e-3\n640 2e-3\n", "data row 2 \\(640 0.002\\) holds a wavenumber not above the row "
                           "before"),
    ("650 1e-3\n700 -1\n", "data row 2 \\(700 -1\\) holds an NESR that is not positive"),
    ("# cm-1 NESR\n650 nan\n700 1e-3\n", "data row 1 \\(650 nan\\) holds a value that is not a "
                                        "finite number"),
    ("650 1e-3\n675 2e-3\n", "covers 650-675"),
    ("650 abc\n700 1\n", "cannot be read as UTF-8 rows of 'wavenumber NESR'"),
    (b"\xff\xfe6\x005\x000\x00", "cannot be read as UTF-8 rows"),
], ids=["empty", "one row", "three columns", "decreasing", "negative", "NaN", "short",
        "text", "UTF-16"])
def test_bad_nesr_files_are_named(tmp_path, text, message):
    path = tmp_path / "nesr.txt"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's note on an empty file is not a second message
        with pytest.raises(InputDataError, match=message) as err:
            read_nesr(path, [660.0, 690.0])
    assert str(err.value).startswith(f"{path}: ")
    with pytest.raises(FileNotFoundError, match="noise.nesr file not found"):
        read_nesr(tmp_path / "missing.txt", [660.0])


def test_sigma_must_broadcast_and_be_positive():
    assert noise_weights(None, (2, 3)) is None
    np.testing.assert_allclose(noise_weights([1.0, 2.0, 4.0], (2, 3))[1], [1.0, 0.5, 0.25])
    with pytest.raises(ValueError, match="does not broadcast"):
        noise_weights([1.0, 2.0], (2, 3))
    with pytest.raises(ValueError, match="finite and positive"):
        noise_weights([1.0, 0.0, 1.0], (2, 3))


def test_flame_mse_scores_only_where_there_is_flame():
    truth = np.zeros((4, 4, 4, 4))
    truth[0] = 300.0
    truth[0, 1, 1, 1] = 1300.0  # one hot voxel; range 1000 K
    truth[1:] = np.linspace(0, 1, 64).reshape(4, 4, 4)
    flat = truth.copy()
    flat[0, 1, 1, 1] = 300.0  # the flame lost: ambient everywhere
    assert normalized_mse(truth, flat)["T"] == pytest.approx(1 / 64)
    assert flame_mse(truth, flat)["T"] == pytest.approx(1.0)  # the one flame voxel, all wrong
    ghost = truth.copy()
    ghost[0, 3, 3, 3] = 800.0  # a flame where there is none counts too
    assert flame_mse(truth, ghost)["T"] == pytest.approx(0.5**2 / 2)
    assert flame_mse(flat, flat) == {}


def test_smoothing_keeps_a_flat_field_and_spreads_a_peak():
    fields = np.ones((2, 5, 5, 5))
    np.testing.assert_allclose(smoothed(fields), 1.0)
    fields[1, 2, 2, 2] = 2.0
    out = smoothed(fields)
    assert out[1, 2, 2, 2] < 2.0 and out[1, 1, 2, 2] > 1.0
    assert out[1].sum() == pytest.approx(fields[1].sum())


def test_config_accepts_the_new_sections():
    cfg = config.validate({"noise": {"kind": "snr", "snr": 50.0}, "data": {"inverse_crime": True},
                           "regularizer": {"lambda": "discrepancy"}})
    assert cfg["rig"]["rays_per_pixel"] == 9 and cfg["init"]["kind"] == "band-tomography"
    with pytest.raises(config.ConfigError, match="'noise.kind' = 'gaussian'"):
        config.validate({"noise": {"kind": "gaussian"}})
