"""One way to write an operator, adjoints and powers that stay ours, Jacobians of combinations
built once per point, strict shapes."""

import jax.numpy as jnp
import numpy as np
import pylops
import pytest

import operators as op
import solvers

RNG = np.random.default_rng(11)
M = RNG.standard_normal((6, 4))
S = RNG.standard_normal((4, 4))


class Shaped(op.LinearOperator):
    """x (2, 3) -> M x per row, written on shaped arrays only."""

    def __init__(self):
        self.m = RNG.standard_normal((5, 3))
        super().__init__((2, 3), (2, 5), name="Shaped")

    def _forward(self, x):
        return x @ self.m.T

    def _adjoint(self, y):
        return y @ self.m


class Counting(op.JaxOperator):
    """A JAX operator that counts its linearizations and its point-wise Jacobian products."""

    def __init__(self, fun, n, name):
        super().__init__(fun, (n,), (n,), name=name)
        self.linearizations = 0
        self.products = 0

    def linearize(self, x):
        self.linearizations += 1
        return super().linearize(x)

    def _jvp(self, x, v):
        self.products += 1
        return super()._jvp(x, v)

    def _vjp(self, x, w):
        self.products += 1
        return super()._vjp(x, w)


def nonlinear(n, name, counting=False):
    cls = Counting if counting else op.JaxOperator
    if counting:
        return cls(lambda x: jnp.sin(x) * jnp.exp(0.2 * x), n, name)
    return cls(lambda x: jnp.sin(x) * jnp.exp(0.2 * x), (n,), (n,), name=name)


def test_a_shaped_linear_operator_gets_pylops_methods_and_passes_dot_tests():
    A = Shaped()
    x = RNG.standard_normal((2, 3))
    np.testing.assert_allclose(A.matvec(x.ravel()), (x @ A.m.T).ravel(), rtol=1e-14)
    y = RNG.standard_normal((2, 5))
    np.testing.assert_allclose(A.rmatvec(y.ravel()), (y @ A.m).ravel(), rtol=1e-14)
    assert op.dottest(A).passed
    assert pylops.utils.dottest(A, 10, 6, rtol=1e-12)
    np.testing.assert_allclose(A.adjoint(y), A.H(y), rtol=0)
    np.testing.assert_allclose(A.vjp(x, y), A.adjoint(y), rtol=0)


def test_flat_methods_in_a_subclass_are_refused_with_the_way_to_write_it():
    with pytest.raises(TypeError, match="defines _matvec.*implements _forward"):
        class Flat(op.LinearOperator):  # noqa: F841
            def _matvec(self, x):
                return x


def test_adjoint_transpose_and_power_are_our_operators():
    A = op.aslinearoperator(pylops.MatrixMult(M), name="A")
    Q = op.aslinearoperator(pylops.MatrixMult(S), name="Q")
    for derived in (A.H, A.T, Q ** 2, Q ** 0, A.H @ A):
        assert isinstance(derived, op.LinearOperator)
        assert op.dottest(derived).passed
        x = RNG.standard_normal(derived.dims)
        assert derived.linearize(x).value.shape == derived.dimsd
    assert A.H.H is A
    x = RNG.standard_normal(4)
    np.testing.assert_allclose((Q ** 3)(x), S @ S @ S @ x, rtol=1e-12)
    np.testing.assert_allclose((Q ** 0)(x), x, rtol=0)
    np.testing.assert_allclose(A.T(RNG.standard_normal(6) * 0 + 1), M.T @ np.ones(6), rtol=1e-13)
    g = nonlinear(4, "g")
    np.testing.assert_allclose((g ** 2)(x), g(g(x)), rtol=1e-14)
    with pytest.raises(ValueError, match=r"A \*\* 2: the operator maps \(4,\) to \(6,\)"):
        A ** 2
    with pytest.raises(ValueError, match="integer p >= 0"):
        Q ** -1


COMBINATIONS = {
    "sum": lambda f, g, A: f @ A + g @ A,
    "scaled": lambda f, g, A: 2.5 * (f @ A),
    "difference": lambda f, g, A: f @ A - 0.5 * (g @ A),
    "vstack": lambda f, g, A: op.vstack([f @ A, g @ A, A]),
    "composition": lambda f, g, A: g @ f @ A,
    "power": lambda f, g, A: A.H @ (f ** 2) @ A,
}


@pytest.mark.parametrize("kind", sorted(COMBINATIONS))
def test_a_combination_linearizes_each_part_once_and_its_jacobian_is_exact(kind):
    f, g = nonlinear(6, "f", counting=True), nonlinear(6, "g", counting=True)
    A = op.aslinearoperator(pylops.MatrixMult(M), name="A")
    F = COMBINATIONS[kind](f, g, A)
    x = RNG.standard_normal(4)
    J = F.linearize(x)
    n_lin = (f.linearizations, g.linearizations)
    np.testing.assert_allclose(J.value, F(x), rtol=1e-13)
    for _ in range(3):
        v, w = RNG.standard_normal(F.dims), RNG.standard_normal(F.dimsd)
        np.testing.assert_allclose(J(v), F.jvp(x, v), rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(J.adjoint(w), F.vjp(x, w), rtol=1e-12, atol=1e-14)
    products_before = f.products + g.products
    for _ in range(4):
        J(RNG.standard_normal(F.dims))
        J.adjoint(RNG.standard_normal(F.dimsd))
    assert (f.linearizations, g.linearizations) == n_lin  # no new linearization per product
    assert f.products + g.products == products_before    # nor point-wise jvp/vjp of the parts
    assert isinstance(J, op.Jacobian) and J.linear
    assert op.dottest(J, rtol=1e-12).passed
    taylor = op.taylor_test(ViaLinearize(F), x)
    assert taylor.passed, str(taylor)
    assert abs(taylor.rate1 - 2) < 0.1


class ViaLinearize(op.Operator):
    """``F`` whose jvp is taken from ``F.linearize``: what a Taylor test of the Jacobian needs."""

    def __init__(self, F):
        super().__init__(F.dims, F.dimsd, name=f"lin[{F.name}]")
        self.F = F

    def _forward(self, x):
        return self.F(x)

    def _jvp(self, x, v):
        return self.F.linearize(x)(v)


def test_block_diagonal_jacobian_is_the_block_diagonal_of_the_parts():
    f, g = nonlinear(5, "f", counting=True), nonlinear(5, "g", counting=True)
    B = op.block_diag([f, g])
    x = RNG.standard_normal((2, 5))
    J = B.linearize(x)
    assert (f.linearizations, g.linearizations) == (1, 1)
    v = RNG.standard_normal((2, 5))
    np.testing.assert_allclose(J(v), np.stack([f.jvp(x[0], v[0]), g.jvp(x[1], v[1])]),
                               rtol=1e-13)
    assert op.dottest(J, rtol=1e-12).passed
    taylor = op.taylor_test(ViaLinearize(B), x)
    assert taylor.passed, str(taylor)


def test_operator_norm_of_a_matrix_is_its_largest_singular_value():
    A = op.aslinearoperator(pylops.MatrixMult(M), name="A")
    estimate = op.operator_norm(A, iterations=200)
    assert estimate == pytest.approx(np.linalg.norm(M, 2), rel=1e-8)
    assert op.operator_norm(0.0 * A) == 0.0
    with pytest.raises(TypeError, match="needs a linear operator"):
        op.operator_norm(nonlinear(4, "g"))


# -- strict shapes ---------------------------------------------------------------------------


def test_a_nonlinear_operator_refuses_a_transposed_input_and_cotangent():
    F = op.Operator.from_jax(lambda x: jnp.tanh(x) * 2, (3, 5), (3, 5), name="tanh2")
    x = RNG.standard_normal((3, 5))
    with pytest.raises(ValueError, match=r"tanh2: x expected shape \(3, 5\), got shape \(5, 3\)"):
        F(x.T)
    with pytest.raises(ValueError, match=r"tanh2: x expected shape \(3, 5\), got shape \(15,\)"):
        F(x.ravel())
    with pytest.raises(ValueError, match=r"tanh2: v expected shape \(3, 5\), got shape \(5, 3\)"):
        F.jvp(x, x.T)
    with pytest.raises(ValueError, match=r"tanh2: w expected shape \(3, 5\), got shape \(5, 3\)"):
        F.vjp(x, x.T)
    with pytest.raises(ValueError, match=r"tanh2: x expected shape"):
        F.linearize(x.T)


def test_linear_operators_take_their_shape_or_the_flat_vector_only():
    ils = op.ILSConvolution(np.linspace(650.0, 700.0, 101), n_rays=3, resolution=8.0)
    x = RNG.standard_normal(ils.dims)
    np.testing.assert_allclose(ils(x.ravel()), ils(x), rtol=0)
    with pytest.raises(ValueError, match=r"ILSConvolution: x expected shape \(3, 101\) \(or "
                                         r"flat, 303 elements\), got shape \(101, 3\)"):
        ils(x.T)
    w = RNG.standard_normal(ils.dimsd)
    with pytest.raises(ValueError, match=r"ILSConvolution: y expected shape \(3, \d+\)"):
        ils.adjoint(w.T)
    dims = (2, 3, 4, 5)
    dx = op.D_x(dims)
    f = RNG.standard_normal(dims)
    with pytest.raises(ValueError, match=r"D_x: x expected shape \(2, 3, 4, 5\).*\(5, 4, 3, 2\)"):
        dx(f.T)
    with pytest.raises(ValueError, match=r"expected shape \(2, 3, 4, 5\).*\(2, 60\)"):
        dx(f.reshape(2, 60))


def test_a_framework_function_returning_the_wrong_shape_is_named():
    F = op.Operator.from_jax(lambda x: jnp.concatenate([x, x, x]), (2,), (2,), name="triple")
    with pytest.raises(ValueError, match=r"triple: forward returned shape \(6,\), but the "
                                         r"operator declares \(2,\)"):
        F(np.ones(2))
    with pytest.raises(ValueError, match=r"triple: forward returned shape \(6,\)"):
        F.linearize(np.ones(2))
    with pytest.raises(ValueError, match=r"triple: jvp returned shape \(6,\)"):
        F.jvp(np.ones(2), np.ones(2))


def test_problem_data_must_have_the_predicted_shape():
    F = op.Operator.from_jax(jnp.sin, (4, 3), (4, 3), name="sin")
    data = RNG.standard_normal((4, 3))
    solvers.Problem(F, data)
    with pytest.raises(ValueError, match=r"data has shape \(3, 4\) but the forward operator "
                                         r"sin predicts shape \(4, 3\)"):
        solvers.Problem(F, data.T)
    with pytest.raises(ValueError, match=r"data has shape \(12,\)"):
        solvers.Problem(F, data.ravel())
    A = op.aslinearoperator(pylops.MatrixMult(M), name="A")
    assert solvers.Problem(A, np.ones(6)).data.shape == (6,)


def test_composition_still_links_layouts_of_equal_size():
    """A composition reshapes between parts whose shapes differ but sizes agree (checked when
    it is built), as pylops' flat operators need."""
    flat = op.aslinearoperator(pylops.MatrixMult(RNG.standard_normal((6, 6))), name="flat")
    F = op.Operator.from_jax(jnp.sin, (2, 3), (2, 3), name="sin")
    composed = F @ flat
    x = RNG.standard_normal(6)
    np.testing.assert_allclose(composed(x), np.sin(flat(x)).reshape(2, 3), rtol=1e-14)
    assert op.jacobian_dottest(composed, x).passed
