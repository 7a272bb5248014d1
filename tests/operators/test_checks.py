"""The public checks: dot tests and Taylor tests report, pass and fail as they should."""

import jax.numpy as jnp
import numpy as np
import pylops

import operators as op
from operators import JaxOperator

RNG = np.random.default_rng(2)
M = RNG.standard_normal((6, 4))


class WrongJvp(JaxOperator):
    """The right forward with a deliberately wrong directional derivative."""

    def _jvp(self, x, v):
        return super()._jvp(x, v) * 1.01


def composed(cls=JaxOperator):
    inner = op.aslinearoperator(pylops.MatrixMult(M), name="M")
    return cls(lambda y: jnp.exp(0.3 * y) * jnp.sin(y), (6,), (6,), name="g") @ inner


def test_taylor_rates_one_and_two_on_a_composed_nonlinear_operator():
    F = composed()
    result = op.taylor_test(F, RNG.standard_normal(4))
    assert result.passed
    assert abs(result.rate0 - 1) < 0.05 and abs(result.rate1 - 2) < 0.05
    assert "PASS" in str(result)


def test_taylor_test_fails_for_a_wrong_jvp():
    result = op.taylor_test(composed(WrongJvp), RNG.standard_normal(4))
    assert not result.passed
    assert abs(result.rate1 - 1) < 0.1
    assert "FAIL" in str(result)


def test_taylor_test_of_a_linear_map_is_exact():
    result = op.taylor_test(op.aslinearoperator(pylops.MatrixMult(M)), RNG.standard_normal(4))
    assert result.exact and result.passed


def test_gradient_taylor_test_for_a_scalar_objective():
    A = RNG.standard_normal((5, 5))

    def fun(x):
        return float(np.sum(np.cos(A @ x)))

    def grad(x):
        return -A.T @ np.sin(A @ x)

    x = RNG.standard_normal(5)
    assert op.gradient_taylor_test(fun, grad, x).passed
    assert not op.gradient_taylor_test(fun, lambda y: 1.05 * grad(y), x).passed


def test_dottest_detects_a_wrong_adjoint():
    class Broken(op.LinearOperator):
        def _forward(self, x):
            return M @ x

        def _adjoint(self, y):
            return 0.5 * M.T @ y

    bad = op.dottest(Broken((4,), (6,)))
    assert not bad.passed and bad.relative_error > 0.1
    assert "FAIL" in str(bad)
    assert not op.jacobian_dottest(composed() + composed(WrongJvp), RNG.standard_normal(4)).passed
