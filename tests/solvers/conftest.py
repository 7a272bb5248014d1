"""Small problems shared by the solver tests."""

import jax.numpy as jnp
import numpy as np
import pylops
import pytest

import operators as op
import solvers


def _nonlinear_forward(n_params=10, n_data=30, seed=0):
    a = np.random.default_rng(seed).standard_normal((n_data, n_params)) / 3

    def forward(x):
        y = jnp.asarray(a, x.dtype) @ x  # the matrix in the operator's dtype (float64)
        return jnp.tanh(y) + 0.1 * y

    return op.Operator.from_jax(forward, (n_params,), (n_data,), name="tanh(Ax)")


class NumpyTanh(op.Operator):
    """F(x) = tanh(Ax) + 0.1 Ax in NumPy with hand-written derivatives (fast for long runs)."""

    def __init__(self, a):
        super().__init__(a.shape[1], a.shape[0], name="numpy tanh(Ax)")
        self.a = np.asarray(a)

    def _forward(self, x):
        z = self.a @ x
        return np.tanh(z) + 0.1 * z

    def _slope(self, x):
        return 1.1 - np.tanh(self.a @ x) ** 2

    def _jvp(self, x, v):
        return self._slope(x) * (self.a @ v)

    def _vjp(self, x, w):
        return self.a.T @ (self._slope(x) * w)


@pytest.fixture
def numpy_forward():
    """The operator of ``nonlinear_forward`` (default sizes) in NumPy."""
    return NumpyTanh(np.random.default_rng(0).standard_normal((30, 10)) / 3)


@pytest.fixture
def nonlinear_forward():
    """Factory ``(n_params, n_data, seed) -> F`` with F(x) = tanh(Ax) + 0.1 Ax."""
    return _nonlinear_forward


@pytest.fixture
def nonlinear_problem():
    """Nonlinear least squares with a small Tikhonov term, starting at zero."""
    forward = _nonlinear_forward()
    truth = 0.5 * np.random.default_rng(1).standard_normal(10)
    reg = solvers.Regularizer(op.SquaredL2(), op.aslinearoperator(pylops.Identity(10)))
    return solvers.Problem(forward, forward(truth), regularizer=reg, lam=1e-3,
                           x0=np.zeros(10), name="tanh")


@pytest.fixture
def stochastic_problem(nonlinear_problem):
    """The nonlinear problem with a random half of the data rows per iteration."""
    p = nonlinear_problem
    rows = p.forward.dimsd[0]

    def minibatch(x, iteration, rng):
        pick = rng.choice(rows, size=rows // 2, replace=False)
        jac = p.forward.linearize(x)
        r = np.zeros(rows)
        r[pick] = (jac.value - p.data)[pick]
        return float(r @ r), 2 * jac.adjoint(r)

    return solvers.Problem(p.forward, p.data, x0=p.x0, value_and_grad=minibatch)


@pytest.fixture
def tikhonov_problem():
    """Linear least squares with a first-difference Tikhonov term and its closed-form minimizer.

    Returns the problem and x* = (AᵀA + λ DᵀD)⁻¹ Aᵀ d.
    """
    rng = np.random.default_rng(2)
    n, m, lam = 8, 20, 0.5
    a = rng.standard_normal((m, n)) / np.sqrt(m) + np.eye(m, n)
    d = rng.standard_normal(m)
    forward = op.aslinearoperator(pylops.MatrixMult(a), name="A")
    diff = op.aslinearoperator(pylops.FirstDerivative(n, kind="forward", edge=False), name="D")
    dmat = diff.todense()
    x_star = np.linalg.solve(a.T @ a + lam * dmat.T @ dmat, a.T @ d)
    problem = solvers.Problem(forward, d, regularizer=op.Composite(op.SquaredL2(), diff),
                              lam=lam, x0=np.zeros(n), name="tikhonov")
    return problem, x_star
