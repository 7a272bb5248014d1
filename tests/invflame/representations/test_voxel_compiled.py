"""The voxel problem's compiled objective against the operators' own methods, on a scene."""

import numpy as np
import pytest

from invflame.representations.voxel import VoxelRepresentation


def problem_on(scene, plume, regularizer, sigma=None, tv_smoothing=0.0):
    rep = VoxelRepresentation(scene.grid, scene.operator, tv_smoothing=tv_smoothing)
    data = scene.simulate(plume)
    start = plume.copy()
    start[0] = 0.9 * plume[0] + 60.0  # not the truth: a non-zero misfit
    return rep.problem(data, regularizer, lam=1e-2, sigma=sigma,
                       x0=rep.initial_parameters(start))


@pytest.mark.parametrize("regularizer", ["none", "tikhonov", "tv"])
def test_float64_compiled_objective_is_the_operators(tiny_scene64, plume, regularizer):
    problem = problem_on(tiny_scene64, plume, regularizer, sigma=1e-3)
    assert problem.compiled is not None
    compiled = problem.evaluate(problem.x0)
    operators = problem.evaluate(problem.x0, jacobians=True)
    assert compiled.misfit > 0
    for part in ("loss", "misfit", "regularizer"):
        np.testing.assert_allclose(getattr(compiled, part), getattr(operators, part),
                                   rtol=1e-12)
    np.testing.assert_allclose(compiled.grad, operators.grad, rtol=1e-9,
                               atol=1e-12 * np.abs(operators.grad).max())


@pytest.mark.parametrize("regularizer", ["tikhonov", "tv"])
def test_float32_compiled_objective_agrees_to_float32_round_off(tiny_scene, plume, regularizer):
    """(TV smoothed: exact TV's subgradient jumps at 0, and XLA flushes subnormal differences
    to 0 where NumPy keeps them.)"""
    problem = problem_on(tiny_scene, plume, regularizer, tv_smoothing=1.0)
    compiled = problem.evaluate(problem.x0)
    operators = problem.evaluate(problem.x0, jacobians=True)
    assert abs(compiled.loss - operators.loss) <= 1e-6 * operators.loss
    assert compiled.grad.dtype == np.float32
    difference = np.linalg.norm(compiled.grad - operators.grad)
    assert difference <= 1e-5 * np.linalg.norm(operators.grad)


def test_a_temperature_outside_the_tables_is_refused_as_by_the_operators(tiny_scene64, plume):
    problem = problem_on(tiny_scene64, plume, "tikhonov")
    x = problem.x0.copy()
    x[0, 4, 4, 4] *= 10  # T far above the tables' last node
    messages = []
    for jacobians in (False, True):
        with pytest.raises(ValueError, match="temperature") as error:
            problem.evaluate(x, jacobians=jacobians)
        messages.append(str(error.value))
    assert messages[0] == messages[1]
