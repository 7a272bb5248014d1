"""The state relation as a parameterization: its states, inverse, bounds and derivatives."""

import numpy as np
import pytest
import torch

import operators
from invflame.experiments.data_start import lean_branch
from invflame.representations.neural.network import FieldNetwork
from invflame.representations.state_relation import StateRelation
from invflame.representations.voxel import VoxelRepresentation

HUMID = [300.0, 4.2e-4, 0.01, 0.0]


def test_the_states_at_factor_one_are_the_lean_branch_of_the_start():
    mixture, states = lean_branch(1500.0, HUMID, 33)
    relation = StateRelation(HUMID, 1500.0)
    s = np.linspace(0.0, 1.0, 33)
    np.testing.assert_allclose(np.stack(relation.states(s)), states, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(relation.mixture_fraction(s), mixture, rtol=1e-12)


def test_no_temperature_without_products_whatever_the_factor():
    relation = StateRelation(HUMID)
    t, co2, h2o, ch4 = relation.states(np.zeros(3), np.array([0.3, 1.0, 2.0]))
    np.testing.assert_array_equal(t, 300.0)
    np.testing.assert_allclose([co2, h2o, ch4], np.array(HUMID[1:])[:, None] * np.ones(3),
                               rtol=1e-12)


def test_the_factor_scales_the_temperature_rise_and_leaves_the_gas():
    relation = StateRelation(HUMID)
    s = np.array([0.1, 0.4, 0.7])
    one, two = np.stack(relation.states(s, 1.0)), np.stack(relation.states(s, 2.0))
    np.testing.assert_allclose(two[0] - 300.0, 2.0 * (one[0] - 300.0), rtol=1e-12)
    np.testing.assert_array_equal(two[1:], one[1:])


def test_invert_recovers_states_inside_the_bounds_and_clips_outside():
    relation = StateRelation(HUMID, factor_range=(0.5, 1.8))
    s = np.array([[0.0, 0.05, 0.3], [0.6, 0.7, 0.2]])
    h = np.array([[1.0, 0.7, 1.7], [1.2, 0.5, 1.8]])
    found_s, found_h = relation.invert(np.stack(relation.states(s, h)))
    np.testing.assert_allclose(found_s, s, atol=1e-6)
    np.testing.assert_allclose(found_h, h, atol=1e-4)
    hot = np.stack(relation.states(np.array([0.2]), np.array([3.0])))
    assert relation.invert(hot)[1] == pytest.approx(1.8)


def test_the_progress_bound_keeps_every_state_below_the_hottest_temperature():
    relation = StateRelation(HUMID, factor_range=(0.3, 2.0), temperature_max=2500.0)
    assert 0.5 < relation.progress_max < 1.0
    hottest = relation.states(np.array(relation.progress_max), 2.0)[0]
    assert 2400.0 < hottest <= 2500.0
    assert StateRelation(HUMID, factor_range=(0.3, 1.0)).progress_max == 1.0


@pytest.mark.parametrize("bad, match", [
    ({"ambient": [300.0, 0.6, 0.5, 0.0]}, "ambient"),
    ({"temperature_rise_st": -1.0}, "temperature_rise_st"),
    ({"factor_range": (1.5, 1.0)}, "factor_range"),
    ({"temperature_max": 250.0}, "temperature_max"),
])
def test_bad_arguments_are_named(bad, match):
    arguments = {"ambient": HUMID, **bad}
    with pytest.raises(ValueError, match=match):
        StateRelation(**arguments)


def _state_representation(scene, soot=False):
    relation = StateRelation([300.0, 0.0, 0.0, 0.0], factor_range=(0.3, 2.0))
    forward = scene.with_soot(None, soot_input=True).operator if soot else scene.operator
    return VoxelRepresentation(scene.grid, forward, state_relation=relation), relation


def _interior_point(rep, seed=0):
    rng = np.random.default_rng(seed)
    low, high = rep.lower, rep.upper
    return (low + (high - low) * rng.uniform(0.2, 0.8, rep.dims)).astype(rep.forward.dtype)


def test_the_voxel_map_through_the_relation_passes_taylor_and_dot_tests(tiny_scene64):
    rep, _ = _state_representation(tiny_scene64)
    x = _interior_point(rep)
    assert rep.dims == (2, *tiny_scene64.grid.shape)
    assert operators.taylor_test(rep.forward, x, h0=1e-2).passed
    assert operators.jacobian_dottest(rep.forward, x).passed


def test_the_objective_gradient_through_the_relation_passes_a_taylor_test(tiny_scene64, plume):
    rep, _ = _state_representation(tiny_scene64)
    problem = rep.problem(tiny_scene64.simulate(plume), "tv", lam=1e-2, sigma=1e-3,
                          x0=rep.initial_parameters(plume))
    x = _interior_point(rep, seed=1)
    evaluation = problem.evaluate(x)
    result = operators.gradient_taylor_test(lambda y: problem.evaluate(y).loss,
                                            evaluation.grad, x, h0=1e-3)
    assert result.passed, result


def test_parameters_of_relation_states_give_those_states_back(tiny_scene64):
    rep, relation = _state_representation(tiny_scene64)
    x = _interior_point(rep)
    fields = rep.fields(x)
    np.testing.assert_allclose(rep.fields(rep.initial_parameters(fields)), fields,
                               rtol=1e-5, atol=1e-8)
    with pytest.raises(ValueError, match="fields must have shape"):
        rep.initial_parameters(fields[:3])


def test_soot_rides_along_as_a_third_parameter_field(tiny_scene64, plume):
    rep, _ = _state_representation(tiny_scene64, soot=True)
    assert rep.dims == (3, *tiny_scene64.grid.shape)
    fields = np.concatenate([plume, np.full((1, *plume.shape[1:]), 2e-6)])
    x = rep.initial_parameters(fields)
    np.testing.assert_allclose(rep.fields(x)[4], 2e-6)
    assert operators.jacobian_dottest(rep.forward, _interior_point(rep)).passed


def test_a_network_through_the_relation_starts_as_ambient_air_and_stays_on_it(tiny_scene):
    relation = StateRelation([300.0, 0.0, 0.0, 0.0])
    network = FieldNetwork.for_scene(tiny_scene, n_frequencies=2, hidden=8, depth=2,
                                     state_relation=relation)
    points = torch.rand(50, 3) * torch.tensor(tiny_scene.grid.extent, dtype=torch.float32) \
        + torch.tensor(tiny_scene.grid.lower, dtype=torch.float32)
    fields = network(points).detach().numpy().astype(np.float64)
    assert fields.shape == (4, 50)
    assert np.all(np.abs(fields[0] - 300.0) < 10.0) and np.all(fields[1] < 2e-3)
    s, h = relation.invert(fields)
    np.testing.assert_allclose(np.stack(relation.states(s, h)), fields, rtol=1e-4, atol=1e-6)
