"""D_x, D_y, D_z, Gradient and the regularizers built on them."""

import jax
import numpy as np
import pytest

import operators as op
from operators.derivatives import ForwardDifferences
from operators.pylops_import import pylops

DIMS = (2, 5, 4, 3)  # non-cubic on purpose
SPACING = (0.1, 0.25, 0.5)


@pytest.mark.parametrize("name", ["D_x", "D_y", "D_z", "Gradient"])
def test_dot_tests_in_float64(name):
    result = op.dottest(getattr(op, name)(DIMS, SPACING), rtol=1e-10)
    assert result.passed, str(result)


def test_forward_differences_with_zero_last_difference():
    f = np.random.default_rng(0).standard_normal(DIMS)
    G = op.Gradient(DIMS, SPACING)
    g = G(f)
    assert g.shape == (3, *DIMS)
    np.testing.assert_allclose(g[0, :, :-1], np.diff(f, axis=1) / 0.1, rtol=1e-12)
    np.testing.assert_allclose(g[1, :, :, :-1], np.diff(f, axis=2) / 0.25, rtol=1e-12)
    np.testing.assert_allclose(g[2, :, :, :, :-1], np.diff(f, axis=3) / 0.5, rtol=1e-12)
    assert not g[0, :, -1].any() and not g[1, :, :, -1].any() and not g[2, ..., -1].any()


@pytest.mark.parametrize("axes", ["xyz", "zx", "y"])
def test_the_differences_are_pylops_forward_first_derivatives(axes):
    rng = np.random.default_rng(1)
    f, w = rng.standard_normal(DIMS), rng.standard_normal((len(axes), *DIMS))
    ours = ForwardDifferences(DIMS, axes, SPACING)
    theirs = [pylops.FirstDerivative(DIMS, axis=i + 1, sampling=SPACING[i], kind="forward",
                                     edge=False) for i in map("xyz".index, axes)]
    np.testing.assert_allclose(ours(f), np.stack([d @ f.ravel() for d in theirs]).reshape(
        w.shape), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ours.adjoint(w), sum(d.H @ wi.ravel() for d, wi in zip(
        theirs, w, strict=True)).reshape(DIMS), rtol=1e-12, atol=1e-12)


def test_float32_fields_stay_float32_and_values_sum_in_float64():
    f = np.random.default_rng(2).standard_normal(DIMS).astype(np.float32)
    G = op.Gradient(DIMS, SPACING, np.float32)
    assert G(f).dtype == np.float32 and G.adjoint(G(f)).dtype == np.float32
    g = G(f)
    assert op.L1()(g) == pytest.approx(np.abs(g.astype(np.float64)).sum(), rel=1e-12)
    assert op.SquaredL2()(g) == pytest.approx(np.sum(g.astype(np.float64) ** 2), rel=1e-6)


def test_linear_ramp_has_constant_gradient():
    x = np.arange(DIMS[1]) * SPACING[0]
    f = np.broadcast_to(3.0 * x[None, :, None, None], DIMS).copy()
    g = op.D_x(DIMS, SPACING)(f)
    np.testing.assert_allclose(g[:, :-1], 3.0, rtol=1e-12)


def test_regularizer_values_and_gradients():
    rng = np.random.default_rng(3)
    f = rng.standard_normal(DIMS)
    G = op.Gradient(DIMS, SPACING)
    tik = op.tikhonov(DIMS, SPACING)
    tv = op.total_variation(DIMS, SPACING)
    assert tik(f) == pytest.approx(sum(np.mean(d**2) for d in G(f)), rel=1e-12)
    assert tv(f) == pytest.approx(sum(np.mean(np.abs(d)) for d in G(f)), rel=1e-12)
    assert op.gradient_taylor_test(tik, tik.grad, f).passed
    # TV is differentiable away from zero differences, which random fields avoid
    result = op.gradient_taylor_test(tv, tv.grad, f, h0=1e-4)
    assert abs(result.rate0 - 1) < 0.1


def test_l1_prox_and_dual_prox_satisfy_moreau():
    l1 = op.L1(scale=0.3)
    y = np.linspace(-2, 2, 11)
    sigma = 0.7
    np.testing.assert_allclose(l1.prox_dual(y, sigma),
                               y - sigma * l1.prox(y / sigma, 1 / sigma), atol=1e-14)
    assert np.abs(l1.prox_dual(y, sigma)).max() <= 0.3


def test_huber_smoothed_l1_value_gradient_and_proximal_maps():
    eps, c = 0.2, 0.3
    huber = op.L1(scale=c, smoothing=eps)
    x = np.array([-1.0, -0.2, -0.05, 0.0, 0.1, 0.5])
    expected = c * np.where(np.abs(x) <= eps, x**2 / (2 * eps), np.abs(x) - eps / 2)
    assert huber(x) == pytest.approx(expected.sum(), rel=1e-14)
    # below the exact L1 by at most c * eps / 2 per entry
    assert 0 <= op.L1(scale=c)(x) - huber(x) <= c * x.size * eps / 2
    # differentiable everywhere, also at 0 where the exact L1 has its kinks
    z = np.random.default_rng(4).standard_normal(20) * 0.1
    z[:5] = 0.0
    assert op.gradient_taylor_test(huber, huber.grad, z).passed
    # prox: the minimizer of c h(z) + (z - x)^2 / (2 tau), checked by brute force per entry
    tau = 0.4
    grid = np.linspace(-2, 2, 400001)
    for xi in x:
        brute = grid[np.argmin(c * np.where(np.abs(grid) <= eps, grid**2 / (2 * eps),
                                            np.abs(grid) - eps / 2) + (grid - xi) ** 2 / (2 * tau))]
        assert huber.prox(np.array([xi]), tau)[0] == pytest.approx(brute, abs=2e-5)
    y, sigma = np.linspace(-2, 2, 11), 0.7
    np.testing.assert_allclose(huber.prox_dual(y, sigma),
                               y - sigma * huber.prox(y / sigma, 1 / sigma), atol=1e-14)
    with pytest.raises(ValueError, match="smoothing must be"):
        op.L1(smoothing=-1.0)


def test_smoothed_total_variation_is_differentiable_on_a_flat_field():
    f = np.zeros(DIMS)
    f[0, 2:, 1:, :] = 1.0  # flat regions, one step
    tv = op.total_variation(DIMS, SPACING, smoothing=0.05)
    assert tv(f) < op.total_variation(DIMS, SPACING)(f)
    direction = np.random.default_rng(5).standard_normal(DIMS)
    # steps below the smoothing's reach (h |D v| < 0.05), where the remainder is quadratic
    assert op.gradient_taylor_test(tv, tv.grad, f, direction, h0=1e-3).passed


def test_bad_dims_and_spacing():
    with pytest.raises(ValueError, match="n_fields, nx, ny, nz"):
        op.D_x((5, 4, 3))
    with pytest.raises(ValueError, match="spacing"):
        op.Gradient(DIMS, (0.1, -1, 1))
    with pytest.raises(ValueError, match="axis"):
        op.derivative(DIMS, "w")
    with pytest.raises(ValueError, match="each at most once"):
        ForwardDifferences(DIMS, "xx")
    with pytest.raises(ValueError, match="one direction"):
        ForwardDifferences(DIMS, "xy", stacked=False)


@pytest.mark.parametrize("axes, stacked", [("xyz", True), ("zx", True), ("y", False)])
def test_the_jax_map_gives_the_numpy_differences(axes, stacked):
    differences = ForwardDifferences(DIMS, axes, SPACING, stacked=stacked)
    f = np.random.default_rng(6).standard_normal(DIMS)
    jax_map = differences.jax_map()
    with op.precision(np.float64):
        traced = np.asarray(jax.jit(jax_map.function)(jax_map.args, f))
    np.testing.assert_allclose(traced, differences(f), rtol=1e-14, atol=1e-14)
    assert jax_map.check is None
