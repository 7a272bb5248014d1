"""Operator algebra: chain rule, sums, scaling, stacks, framework adapters."""

import jax
import jax.numpy as jnp
import numpy as np
import pylops
import pytest
import torch

import operators as op

RNG = np.random.default_rng(1)
M = RNG.standard_normal((7, 5))
N = RNG.standard_normal((5, 4))


def matrix(a, name):
    return op.aslinearoperator(pylops.MatrixMult(a), name=name)


def jax_nonlinear(n):
    return op.Operator.from_jax(lambda x: jnp.tanh(x) + 0.3 * x**2, (n,), (n,), name="g")


def test_composition_of_linear_operators_is_linear_and_pylops_compatible():
    A, B = matrix(M, "A"), matrix(N, "B")
    AB = A @ B
    assert AB.linear and isinstance(AB, pylops.LinearOperator)
    x = RNG.standard_normal(4)
    np.testing.assert_allclose(AB(x), M @ N @ x, rtol=1e-13)
    np.testing.assert_allclose(AB @ x, M @ N @ x, rtol=1e-13)
    y = RNG.standard_normal(7)
    np.testing.assert_allclose(AB.H @ y, N.T @ M.T @ y, rtol=1e-13)
    assert op.dottest(AB).passed
    assert pylops.utils.dottest(AB, 7, 4, rtol=1e-10)


def test_sum_scale_negation_and_difference():
    A, B = matrix(M, "A"), matrix(M[::-1], "B")
    x = RNG.standard_normal(5)
    np.testing.assert_allclose((A + B)(x), (M + M[::-1]) @ x, rtol=1e-13)
    np.testing.assert_allclose((2.5 * A)(x), 2.5 * M @ x, rtol=1e-13)
    np.testing.assert_allclose((A * 2.5)(x), 2.5 * M @ x, rtol=1e-13)
    np.testing.assert_allclose((A - B)(x), (M - M[::-1]) @ x, rtol=1e-13)
    np.testing.assert_allclose((-A)(x), -M @ x, rtol=1e-13)
    for combo in (A + B, 2.5 * A, A - B):
        assert combo.linear and op.dottest(combo).passed


@pytest.mark.usefixtures("x64")
def test_chain_rule_matches_jax_on_the_same_function():
    """A mixed JAX/torch/linear composition has the derivatives JAX finds for the same map."""
    A = matrix(M, "A")
    g = jax_nonlinear(7)
    t = op.Operator.from_torch(lambda x: torch.sin(x) * x, (7,), (7,), name="t")
    F = A.H @ (t @ g @ A) + 0.5 * (A.H @ A)
    Mj = jnp.asarray(M)

    def reference(x):
        y = Mj @ x
        h = jnp.tanh(y) + 0.3 * y**2
        return Mj.T @ (jnp.sin(h) * h) + 0.5 * Mj.T @ y

    x, v, w = RNG.standard_normal(5), RNG.standard_normal(5), RNG.standard_normal(5)
    np.testing.assert_allclose(F(x), reference(x), rtol=1e-12)
    np.testing.assert_allclose(F.jvp(x, v), jax.jvp(reference, (x,), (v,))[1], rtol=1e-12)
    np.testing.assert_allclose(F.vjp(x, w), jax.vjp(reference, x)[1](w)[0], rtol=1e-12)
    J = F.linearize(x)
    np.testing.assert_allclose(J.value, reference(x), rtol=1e-12)
    np.testing.assert_allclose(J @ v, jax.jvp(reference, (x,), (v,))[1], rtol=1e-12)
    np.testing.assert_allclose(J.H @ w, jax.vjp(reference, x)[1](w)[0], rtol=1e-12)
    assert op.dottest(J).passed
    assert op.jacobian_dottest(F, x).passed


def test_stacks_and_block_diagonal():
    A, B = matrix(M, "A"), matrix(M[:, ::-1], "B")
    S = op.vstack([A, B])
    assert S.dimsd == (2, 7) and S.linear
    x = RNG.standard_normal(5)
    np.testing.assert_allclose(S(x), np.stack([M @ x, M[:, ::-1] @ x]), rtol=1e-13)
    D = op.block_diag([A, B])
    assert D.dims == (2, 5) and D.dimsd == (2, 7)
    xx = RNG.standard_normal((2, 5))
    np.testing.assert_allclose(D(xx), np.stack([M @ xx[0], M[:, ::-1] @ xx[1]]), rtol=1e-13)
    C = op.block_diag([A, matrix(N, "N")])
    assert C.dims == (9,) and C.dimsd == (12,)
    for lin in (S, D, C):
        assert op.dottest(lin).passed
    nonlinear = op.vstack([jax_nonlinear(7) @ A, B])
    assert not nonlinear.linear
    assert op.jacobian_dottest(nonlinear, x).passed
    assert op.jacobian_dottest(op.block_diag([jax_nonlinear(5), jax_nonlinear(5)]), xx).passed


def test_shape_errors_are_clear():
    A, B = matrix(M, "A"), matrix(N, "B")
    with pytest.raises(ValueError, match="cannot compose"):
        B @ A
    with pytest.raises(ValueError, match="cannot add"):
        A + B
    with pytest.raises(ValueError, match=r"expected shape \(5,\)"):
        A(np.ones(6))
    with pytest.raises(TypeError, match="nonlinear"):
        jax_nonlinear(7) @ np.ones(7)
    with pytest.raises(ValueError, match="share their input shape"):
        op.vstack([A, B])


def test_adjoint_operator_is_ours_and_composes():
    A = matrix(M, "A")
    AtA = A.H @ A
    assert isinstance(A.H, op.LinearOperator)
    x = RNG.standard_normal(5)
    np.testing.assert_allclose(AtA(x), M.T @ M @ x, rtol=1e-13)


def test_what_an_operators_methods_build_is_defined_beside_it_not_registered():
    """``A @ B``, ``A + B``, ``c * A``, ``A ** 0``, ``A.H``, ``linearize`` and ``from_jax``
    build classes of :mod:`operators.base` itself, which reaches nothing through a registry or a
    module ``__getattr__``; what they compute on arrays is in the modules below it."""
    import operators.base as base
    import operators.protocol as protocol
    import operators.rules as rules

    A, B, g = matrix(M, "A"), matrix(M, "B"), jax_nonlinear(5)
    built = [A.H @ B, A + B, 2 * A, A - B, -A, g @ g, g + g, 3 * g, g ** 0, A.H,
             g.linearize(np.ones(5)), op.Operator.from_jax(jnp.sin, (2,), (2,)),
             op.Operator.from_torch(torch.sin, (2,), (2,)), A @ pylops.MatrixMult(N)]
    assert {type(b).__module__ for b in built} == {"operators.base"}
    assert not hasattr(base, "__getattr__") and not hasattr(base, "register")
    assert not any(hasattr(m, "Operator") for m in (protocol, rules))
