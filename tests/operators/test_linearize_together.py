"""Operators after one inner factor, linearized together: the factor once, the same derivatives."""

import jax.numpy as jnp
import numpy as np
import pylops
import pytest
import torch

import operators as op
import solvers

RNG = np.random.default_rng(3)
W = RNG.standard_normal((8, 5))


class CountingInner:
    """A torch map (5,) -> (2, 4) that counts its evaluations."""

    def __init__(self):
        self.calls = 0
        self.op = op.Operator.from_torch(self, (5,), (2, 4), name="P")

    def __call__(self, x):
        self.calls += 1
        return torch.sin(torch.as_tensor(W) @ x).reshape(2, 4) + 0.1 * (x**2).sum()


def matrix(shape, name):
    return op.aslinearoperator(pylops.MatrixMult(RNG.standard_normal(shape)), name=name)


def outer_maps():
    """A nonlinear data-like map (8,) -> (7,) and a linear regularizer-like one (8,) -> (3,)."""
    g = op.Operator.from_jax(lambda u: jnp.tanh(u) + 0.3 * u**2, (8,), (8,), name="g")
    return matrix((7, 8), "A") @ g, matrix((3, 8), "B") @ op.Diagonal(RNG.uniform(1, 2, 8))


def test_the_shared_inner_factor_is_evaluated_once_and_the_derivatives_are_the_chain_rules():
    inner = CountingInner()
    a, b = outer_maps()
    f, k = a @ inner.op, b @ inner.op
    x, v = RNG.standard_normal(5), RNG.standard_normal(5)
    wf, wk = RNG.standard_normal(7), RNG.standard_normal(3)
    separate = (2.0 * f.vjp(x, wf) + 0.3 * k.vjp(x, wk), f.jvp(x, v), k.jvp(x, v), f(x), k(x))

    inner.calls = 0
    (jf, jk), pull = op.linearize_together([f, k], x)
    gradient = pull([wf, wk], [2.0, 0.3])
    assert inner.calls == 1  # once for both values and the pullback of both terms
    np.testing.assert_allclose(gradient, separate[0], rtol=1e-12)
    np.testing.assert_allclose(jf @ v, separate[1], rtol=1e-12)
    np.testing.assert_allclose(jk @ v, separate[2], rtol=1e-12)
    np.testing.assert_allclose(jf.value, separate[3], rtol=1e-12)
    np.testing.assert_allclose(jk.value, separate[4], rtol=1e-12)
    np.testing.assert_allclose(pull([wf, None], [0.5, 1.0]), 0.5 * f.vjp(x, wf), rtol=1e-12)
    assert op.dottest(jf).passed and op.dottest(jk).passed


def test_operators_without_a_common_factor_are_linearized_each_on_its_own():
    first, second = CountingInner(), CountingInner()
    a, b = outer_maps()
    f, k = a @ first.op, b @ second.op
    x, wf, wk = RNG.standard_normal(5), RNG.standard_normal(7), RNG.standard_normal(3)
    expected = f.vjp(x, wf) + k.vjp(x, wk)
    first.calls = second.calls = 0
    (jf, jk), pull = op.linearize_together([f, k], x)
    np.testing.assert_allclose(pull([wf, wk], [1.0, 1.0]), expected, rtol=1e-12)
    assert first.calls == second.calls == 1
    np.testing.assert_allclose(jf.value, f(x), rtol=1e-12)


def test_a_single_operator_is_linearized_whole(monkeypatch):
    inner = CountingInner()
    a, _ = outer_maps()
    f = a @ inner.op
    whole, calls = f.linearize, []
    monkeypatch.setattr(f, "linearize", lambda x: calls.append(x) or whole(x))
    x = RNG.standard_normal(5)
    (jf,), _ = op.linearize_together([f], x)
    assert len(calls) == 1
    np.testing.assert_array_equal(jf.value, whole(x).value)


@pytest.mark.parametrize("lam", [0.0, 0.7])
def test_a_problem_with_data_and_regularizer_after_one_inner_map_evaluates_it_once(lam):
    inner = CountingInner()
    a, b = outer_maps()
    data = RNG.standard_normal(7)
    problem = solvers.Problem(a @ inner.op, data,
                              regularizer=solvers.Regularizer(op.SquaredL2(), b @ inner.op),
                              lam=lam)
    x = RNG.standard_normal(5)
    f, k = problem.forward, problem.regularizer.op
    residual = f(x) - data
    expected = 2.0 * f.vjp(x, residual) + lam * k.vjp(x, problem.regularizer.functional.grad(k(x)))

    inner.calls = 0
    evaluation = problem.evaluate(x)
    gradient = evaluation.grad
    assert inner.calls == 1
    assert evaluation.misfit == pytest.approx(float(residual @ residual), rel=1e-12)
    np.testing.assert_allclose(gradient, expected, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("regularized", [False, True])
def test_a_problem_whose_maps_share_nothing_keeps_the_gradient_of_its_terms_to_the_bit(
        regularized):
    """Without a shared factor (a voxel grid's problem, or no regularizer) the gradient is
    2 J_Fᵀ r + λ J_Kᵀ ∇g computed term by term, in that order."""
    first, second = CountingInner(), CountingInner()
    a, b = outer_maps()
    data = RNG.standard_normal(7)
    regularizer = solvers.Regularizer(op.SquaredL2(), b @ second.op) if regularized else None
    problem = solvers.Problem(a @ first.op, data, regularizer=regularizer, lam=0.7)
    x = RNG.standard_normal(5)
    expected = 2.0 * problem.forward.linearize(x).adjoint(problem.forward(x) - data)
    if regularized:
        k = problem.regularizer.op
        expected = expected + 0.7 * k.linearize(x).adjoint(
            problem.regularizer.functional.grad(k(x)))
    np.testing.assert_array_equal(problem.evaluate(x).grad, expected)


class CountingMatrix(op.LinearOperator):
    """A matrix (5,) -> (8,) that counts its products and adjoint products."""

    def __init__(self):
        super().__init__((5,), (8,), name="P")
        self.products = self.adjoints = 0

    def _forward(self, x):
        self.products += 1
        return W @ x

    def _adjoint(self, y):
        self.adjoints += 1
        return W.T @ y


def test_a_stack_of_linear_blocks_after_one_factor_applies_it_once():
    inner = CountingMatrix()
    a, b = matrix((7, 8), "A"), matrix((3, 8), "B")
    d = RNG.uniform(1, 2, 8)
    blocks = [a @ inner, 0.5 * (b @ op.Diagonal(d) @ inner)]
    stack = op.vstack(blocks)
    x, y = RNG.standard_normal(5), RNG.standard_normal(10)
    expected = np.concatenate([a @ (W @ x), 0.5 * (b @ (d * (W @ x)))])

    inner.products = inner.adjoints = 0
    np.testing.assert_allclose(stack @ x, expected, rtol=1e-12)
    transposed = stack.adjoint(y)
    assert (inner.products, inner.adjoints) == (1, 1)
    np.testing.assert_allclose(transposed, blocks[0].adjoint(y[:7]) + blocks[1].adjoint(y[7:]),
                               rtol=1e-12)
    assert op.dottest(stack).passed


def test_a_stack_of_blocks_without_a_common_factor_applies_each_block():
    first, second = CountingMatrix(), CountingMatrix()
    stack = op.vstack([matrix((7, 8), "A") @ first, matrix((3, 8), "B") @ second])
    stack @ RNG.standard_normal(5)
    stack.adjoint(RNG.standard_normal(10))
    assert (first.products, first.adjoints, second.products, second.adjoints) == (1, 1, 1, 1)


def test_the_gauss_newton_stack_of_maps_after_one_inner_map_linearizes_it_once_per_product():
    """Solvers stack the Jacobians of one evaluation (solvers.gauss_newton.stacked_jacobian):
    the inner map's Jacobian-vector product runs once per product of the stack."""
    from solvers.gauss_newton import stacked_jacobian

    inner = CountingInner()
    a, b = outer_maps()
    problem = solvers.Problem(a @ inner.op, RNG.standard_normal(7),
                              regularizer=solvers.Regularizer(op.SquaredL2(), b @ inner.op),
                              lam=0.7)
    x, v, y = RNG.standard_normal(5), RNG.standard_normal(5), RNG.standard_normal(10)
    stack, _ = stacked_jacobian(problem, problem.evaluate(x))
    f, k = problem.forward, problem.regularizer.op
    weight = np.sqrt(0.7 * problem.regularizer.functional.scale)

    inner.calls = 0
    product = stack @ v
    assert inner.calls == 1  # torch's forward-mode product runs the map once
    np.testing.assert_allclose(product, np.concatenate([f.jvp(x, v), weight * k.jvp(x, v)]),
                               rtol=1e-12)
    np.testing.assert_allclose(stack.adjoint(y), f.vjp(x, y[:7]) + weight * k.vjp(x, y[7:]),
                               rtol=1e-12)
    assert op.dottest(stack).passed
