"""Scene: the voxel forward map, composed and fused, on a small grid with a small table."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import operators as op
from invflame.geometry import VoxelGrid, paper_rig
from invflame.scene import Scene
from invflame.spectroscopy.absorption_table import AbsorptionTable


def small_table(n_eta=48):
    """CO2 and H2O with a few T-dependent Lorentzian lines, CH4 transparent (cm²/molecule)."""
    wavenumber = np.linspace(650.0, 668.8, n_eta)
    temperatures = np.array([250.0, 600.0, 1100.0, 1700.0, 2500.0])
    sigma = np.zeros((temperatures.size, 3, n_eta))
    for s, centres in enumerate([(655.0, 661.0), (658.0, 666.0)]):
        for i, c in enumerate(centres):
            strength = 1e-19 * np.exp(-(300.0 + 900.0 * i) * (1 / temperatures - 1 / 1000.0))
            sigma[:, s] += strength[:, None] / (1.0 + ((wavenumber - c) / 1.2) ** 2)
    return AbsorptionTable(("CO2", "H2O", "CH4"), wavenumber, 101325.0, temperatures, sigma,
                           (0.1, 0.2, 0.0))


def smooth_field(grid, seed=0):
    """A hot, CO2/H2O-rich blob in cool air: (4, nx, ny, nz)."""
    x, y, z = np.meshgrid(*grid.axes(), indexing="ij")
    centre = grid.centre + np.random.default_rng(seed).uniform(-0.1, 0.1, 3)
    r2 = ((x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2) / 0.3**2
    blob = np.exp(-r2)
    return np.stack([300.0 + 1400.0 * blob, 0.09 * blob, 0.18 * blob + 0.01, 0.0 * blob])


def physical_direction(fields, seed=5):
    """A Taylor-test direction along which ``fields + h·direction`` stays physical for h ≤ 1:
    T moves by up to 30 K, each mole or volume fraction by up to half its own value (the scene
    operator refuses negative fractions)."""
    shape = np.random.default_rng(seed).uniform(-1.0, 1.0, fields.shape)
    return np.concatenate([30.0 * shape[:1], 0.5 * fields[1:] * shape[1:]])


@pytest.fixture(scope="module")
def scene64():
    grid = VoxelGrid.cube(5, size=1.0, centre=(0.0, 0.5, 0.0))
    return Scene(grid, paper_rig(grid, n_pixels=3), small_table(), resolution=4.0,
                 dtype=np.float64, planck="exact")


def test_shapes_and_attributes(scene64):
    assert scene64.field_shape == (4, 5, 5, 5)
    assert scene64.n_rays == 4 * 9
    assert scene64.data_shape == (36, scene64.out_wavenumber.size)
    assert scene64.operator.dims == scene64.field_shape
    assert scene64.operator.dimsd == scene64.data_shape
    assert scene64.step == pytest.approx(0.4)
    assert scene64.pressure == 101325.0


def test_fused_forward_equals_the_composed_operator(scene64):
    fields = smooth_field(scene64.grid)
    composed = scene64.operator(fields)
    np.testing.assert_allclose(scene64.simulate(fields), composed, rtol=1e-13)
    assert composed.max() > 0.01  # W/(m2 sr cm-1): the blob is seen


def test_the_pieces_share_the_scene_tables_and_give_its_map(scene64):
    fields = smooth_field(scene64.grid, seed=4)
    assert scene64.emission.tables is scene64.tables
    by_pieces = scene64.ils(scene64.emission(scene64.sampling(fields)))
    np.testing.assert_allclose(scene64.operator(fields), by_pieces, rtol=1e-12)


@pytest.mark.usefixtures("x64")
def test_fused_gradient_equals_the_operator_vjp(scene64):
    fields = smooth_field(scene64.grid, seed=1)
    w = np.random.default_rng(2).standard_normal(scene64.data_shape)
    grad = jax.grad(lambda f: jnp.sum(jnp.asarray(w) * scene64.forward(f)))(jnp.asarray(fields))
    np.testing.assert_allclose(grad, scene64.operator.vjp(fields, w), rtol=1e-11,
                               atol=1e-13 * np.abs(grad).max())


def test_a_float64_scene_as_a_jax_function_needs_64_bit_mode(scene64):
    """Outside JAX's 64-bit mode its forward would round to float32: refused, saying how."""
    with pytest.raises(ValueError, match=r"this scene is float64.*operators.precision"):
        scene64.forward(smooth_field(scene64.grid))


def test_voxel_forward_map_dot_and_taylor_tests(scene64):
    fields = smooth_field(scene64.grid, seed=3)
    dot = op.jacobian_dottest(scene64.operator, fields, rtol=1e-12)
    assert dot.passed, dot
    taylor = op.taylor_test(scene64.operator, fields, physical_direction(fields), h0=1.0)
    assert taylor.passed, taylor


def test_float32_scene_matches_float64():
    grid = VoxelGrid.cube(5, size=1.0, centre=(0.0, 0.5, 0.0))
    rig = paper_rig(grid, n_pixels=3)
    fields = smooth_field(grid)
    g32 = Scene(grid, rig, small_table(), resolution=4.0).simulate(fields)
    g64 = Scene(grid, rig, small_table(), resolution=4.0, dtype=np.float64).simulate(fields)
    assert g32.dtype == np.float32
    np.testing.assert_allclose(g32, g64, rtol=2e-5, atol=1e-6 * g64.max())


def test_window_selects_part_of_the_table_and_bad_windows_fail():
    grid = VoxelGrid.cube(3)
    rig = paper_rig(grid, n_pixels=2)
    scene = Scene(grid, rig, small_table(), resolution=2.0, window=(652.0, 664.0))
    assert scene.wavenumber[0] >= 652.0 and scene.wavenumber[-1] <= 664.0
    with pytest.raises(ValueError, match="window"):
        Scene(grid, rig, small_table(), window=(700.0, 710.0))
    with pytest.raises(TypeError, match="VoxelGrid"):
        Scene("grid", rig, small_table())
