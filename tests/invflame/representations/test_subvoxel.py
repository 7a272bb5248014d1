"""The sub-voxel emission model: its defining equation, its limits and its derivatives."""

import jax.numpy as jnp
import numpy as np
import pytest

import operators
from invflame.representations.neural import NeuralCentresRepresentation
from invflame.representations.state_relation import StateRelation
from invflame.representations.subvoxel import SubvoxelEmission
from invflame.representations.voxel import VoxelRepresentation

RELATION = StateRelation([300.0, 4.2e-4, 0.01, 0.0])


def _ramp(shape=(5, 6, 7)):
    """A progress rising along x from air to near the sheet, and factors about 1.3."""
    x = np.linspace(0.0, 0.9, shape[0])[:, None, None]
    s = np.broadcast_to(x, shape) * (1.0 + 0.1 * np.random.default_rng(0).random(shape))
    return np.minimum(s, RELATION.progress_max), np.full(shape, 1.3)


def test_the_rendered_state_emits_the_mean_of_the_two_presumed_states():
    model = SubvoxelEmission(RELATION, 1.0)
    s, h = _ramp()
    rendered = model.rendered(s, h)
    a = np.minimum(np.sqrt(sum(g ** 2 for g in np.gradient(s))),
                   np.minimum(s, RELATION.progress_max - s))
    mean = 0.5 * (model.emission(s - a, h) + model.emission(s + a, h))
    np.testing.assert_allclose(model.emission(rendered, h), mean, rtol=1e-7)
    inside = (s > 0.05) & (s < RELATION.progress_max - 0.05)
    assert np.all(rendered[inside] > s[inside])  # the proxy is convex in s here


def test_a_uniform_gas_and_ambient_air_render_as_they_are():
    model = SubvoxelEmission(RELATION, 2.0)
    uniform = np.full((4, 4, 4), 0.4)
    np.testing.assert_allclose(model.rendered(uniform, np.ones_like(uniform)), uniform,
                               rtol=1e-8)
    s, h = _ramp()
    s[:, :, :3] = 0.0  # air beside gas: no spread below s = 0
    assert np.all(model.rendered(s, h)[:, :, :3] < 1e-8)


def test_numpy_and_jax_give_the_same_rendered_progress():
    model = SubvoxelEmission(RELATION, 1.0)
    s, h = _ramp()
    on_jax = model.rendered(jnp.asarray(s), jnp.asarray(h), jnp)  # float32 unless x64
    np.testing.assert_allclose(np.asarray(on_jax), model.rendered(s, h),
                               atol=8 * np.finfo(on_jax.dtype).eps)


def test_the_voxel_map_with_the_model_passes_taylor_and_dot_tests(tiny_scene64):
    relation = StateRelation([300.0, 0.0, 0.0, 0.0], factor_range=(0.3, 2.0))
    rep = VoxelRepresentation(tiny_scene64.grid, tiny_scene64.operator, state_relation=relation,
                              subvoxel=SubvoxelEmission(relation, 1.0))
    rng = np.random.default_rng(3)
    x = (rep.lower + (rep.upper - rep.lower) * rng.uniform(0.2, 0.8, rep.dims))
    assert operators.taylor_test(rep.forward, x, h0=1e-2).passed
    assert operators.jacobian_dottest(rep.forward, x).passed
    plain = VoxelRepresentation(tiny_scene64.grid, tiny_scene64.operator,
                                state_relation=relation)
    np.testing.assert_array_equal(rep.fields(x), plain.fields(x))  # reported: the mean state
    assert np.all(rep.forward(x).sum() > plain.forward(x).sum())


@pytest.mark.parametrize("spread", [0.0, -1.0, float("nan")])
def test_a_spread_that_is_not_positive_is_refused(spread):
    with pytest.raises(ValueError, match="spread must be positive"):
        SubvoxelEmission(RELATION, spread)


def test_a_network_at_the_centres_renders_through_the_model_and_reports_its_mean(
        tiny_scene64, plume):
    relation = StateRelation([300.0, 0.0, 0.0, 0.0], factor_range=(0.3, 2.0))
    kwargs = {"n_frequencies": 2, "hidden": 16, "depth": 2, "state_relation": relation}
    rep = NeuralCentresRepresentation(tiny_scene64, **kwargs,
                                      subvoxel=SubvoxelEmission(relation, 1.0))
    theta = rep.initial_parameters(plume, iterations=30, lr=3e-3, progress=False)
    assert operators.taylor_test(rep.forward, theta, h0=1e-3, seed=0).passed
    assert operators.jacobian_dottest(rep.forward, theta).passed
    plain = NeuralCentresRepresentation(tiny_scene64, **kwargs)
    np.testing.assert_allclose(rep.fields(theta), plain.fields(theta), rtol=1e-12)
    np.testing.assert_allclose(rep.forward(theta), tiny_scene64.simulate(
        rep.rendered_fields(theta)), rtol=1e-10)
    assert rep.forward(theta).sum() > plain.forward(theta).sum()
    assert rep.regularizer("tikhonov")(theta) == pytest.approx(
        plain.regularizer("tikhonov")(theta), rel=1e-12)  # on the mean state
    with pytest.raises(ValueError, match="give state_relation"):
        NeuralCentresRepresentation(tiny_scene64, subvoxel=SubvoxelEmission(relation, 1.0))
