"""Problem: objective, gradient through nonlinear regularizer operators, validation, pairings."""

import jax.numpy as jnp
import numpy as np
import pylops
import pytest

import operators as op
import solvers


def test_objective_is_squared_misfit_plus_weighted_regularizer(nonlinear_problem):
    p = nonlinear_problem
    x = np.linspace(-1, 1, 10)
    ev = p.evaluate(x)
    misfit = np.sum((p.forward(x) - p.data) ** 2)
    assert ev.misfit == pytest.approx(misfit, rel=1e-14)
    assert ev.regularizer == pytest.approx(np.sum(x**2), rel=1e-14)
    assert ev.loss == pytest.approx(misfit + 1e-3 * np.sum(x**2), rel=1e-14)
    assert p.objective(x) == pytest.approx(ev.loss, rel=1e-14)


def test_gradient_passes_taylor_test_with_a_nonlinear_regularizer_operator(nonlinear_forward):
    forward = nonlinear_forward(6, 12)
    # K = first difference after an elementwise network-like map (nonlinear inner operator)
    net = op.Operator.from_jax(lambda x: jnp.sin(x) + x**2, (6,), (6,), name="net")
    diff = op.aslinearoperator(pylops.FirstDerivative(6, kind="forward", edge=False))
    for g in (op.SquaredL2(scale=0.7), op.L1()):
        p = solvers.Problem(forward, np.ones(12), regularizer=(g, diff @ net), lam=0.3)
        x = np.random.default_rng(3).standard_normal(6)
        result = op.gradient_taylor_test(p.objective, lambda y, p=p: p.evaluate(y).grad, x,
                                         h0=1e-3)
        assert result.passed, str(result)


def test_regularizer_accepts_composite_and_pair(nonlinear_forward):
    forward = nonlinear_forward(4, 8)
    diff = op.aslinearoperator(pylops.FirstDerivative(4, kind="forward", edge=False))
    x = np.arange(4.0) ** 2
    for reg in (op.Composite(op.L1(), diff), (op.L1(), diff), solvers.Regularizer(op.L1(), diff)):
        p = solvers.Problem(forward, np.zeros(8), regularizer=reg)
        assert p.regularizer(x) == pytest.approx(np.abs(np.diff(x)).sum())
        assert type(p.regularizer) is op.Composite


def test_bad_inputs_give_clear_errors(nonlinear_forward):
    forward = nonlinear_forward(4, 8)
    with pytest.raises(ValueError, match=r"data has shape \(7,\).*\(8,\)"):
        solvers.Problem(forward, np.zeros(7))
    with pytest.raises(ValueError, match="lam must be"):
        solvers.Problem(forward, np.zeros(8), lam=-1)
    with pytest.raises(ValueError, match=r"data hold 2 NaN or infinite values \(first at index "
                                         r"\(3,\)\)"):
        solvers.Problem(forward, np.array([0, 0, 0, np.nan, 0, np.inf, 0, 0.0]))
    with pytest.raises(TypeError, match="linearizable must be True or False, got 'no'"):
        solvers.Problem(forward, np.zeros(8), linearizable="no")
    with pytest.raises(ValueError, match="x0 violates the bounds"):
        solvers.Problem(forward, np.zeros(8), lower=0.0, x0=-np.ones(4))
    with pytest.raises(ValueError, match="lower bound exceeds upper"):
        solvers.Problem(forward, np.zeros(8), lower=1.0, upper=0.0)
    with pytest.raises(ValueError, match="does not broadcast"):
        solvers.Problem(forward, np.zeros(8), lower=np.zeros(3))
    with pytest.raises(TypeError, match="operators.Operator"):
        solvers.Problem(lambda x: x, np.zeros(8))
    with pytest.raises(ValueError, match="no starting point"):
        solvers.solve(solvers.Problem(forward, np.zeros(8)), "gd")


def test_projection_and_projected_gradient(nonlinear_forward):
    p = solvers.Problem(nonlinear_forward(4, 8), np.zeros(8), lower=0.0, upper=[1, 2, 3, 4])
    np.testing.assert_array_equal(p.project(np.array([-1.0, 5, 2, 1])), [0, 2, 2, 1])
    x = np.array([0.0, 2.0, 1.0, 4.0])
    g = np.array([1.0, -1.0, 1.0, 1.0])
    np.testing.assert_array_equal(p.projected_gradient(x, g), [0, 0, 1, 1])


@pytest.mark.parametrize("name", ["gauss-newton", "pdhg"])
def test_second_order_and_primal_dual_solvers_refuse_a_problem_that_is_not_linearizable(
        nonlinear_problem, name):
    p = nonlinear_problem
    field = solvers.Problem(p.forward, p.data, x0=p.x0, linearizable=False)
    with pytest.raises(solvers.UnsupportedProblemError,
                       match=r"not linearizable.*First-order solvers \('adam'"):
        solvers.solve(field, name)
    solvers.solve(field, "adam", max_iter=2)  # first-order solvers accept it


def test_gauss_newton_refuses_total_variation(nonlinear_forward):
    forward = nonlinear_forward(4, 8)
    diff = op.aslinearoperator(pylops.FirstDerivative(4, kind="forward", edge=False))
    p = solvers.Problem(forward, np.zeros(8), regularizer=(op.L1(), diff), x0=np.zeros(4))
    with pytest.raises(solvers.UnsupportedProblemError, match="use 'pdhg' for total variation"):
        solvers.solve(p, "gauss-newton")


def test_stochastic_problems_only_go_to_first_order_solvers(nonlinear_problem,
                                                           stochastic_problem):
    p, sp = nonlinear_problem, stochastic_problem
    for name in ("gauss-newton", "pdhg", "lbfgs", "jaxopt-lbfgs"):
        with pytest.raises(solvers.UnsupportedProblemError, match="stochastic value_and_grad"):
            solvers.solve(sp, name)
    for name, opts in (("adam", {"lr": 0.05}), ("gd", {})):
        result = solvers.solve(sp, name, max_iter=150, **opts)
        assert np.isnan(result.history["misfit"][-1])
        assert p.objective(result.x) < 1e-2 * p.objective(p.x0), name
