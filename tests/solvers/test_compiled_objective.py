"""The compiled objective (solvers.compiled_objective) against the operators' own methods."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import operators as op
import solvers
from operators.pylops_import import pylops
from operators.rte import KernelOperator

DIMS = (2, 3, 4, 2)
REGULARIZERS = {
    "none": lambda: None,
    "tikhonov": lambda: op.tikhonov(DIMS, (0.5, 0.25, 1.0)),
    "tv": lambda: op.total_variation(DIMS, (0.5, 0.25, 1.0)),
    "tv smoothed": lambda: op.total_variation(DIMS, (0.5, 0.25, 1.0), smoothing=0.3),
}


def nonlinear_map(rng, dtype=np.float64) -> op.Operator:
    """A JAX map from ``DIMS`` to spectra ``(6, 5)``."""
    a = rng.standard_normal((30, int(np.prod(DIMS)))) / 4
    return op.Operator.from_jax(lambda x: jnp.tanh(jnp.asarray(a, x.dtype) @ x.ravel()).reshape(
        6, 5), DIMS, (6, 5), dtype=dtype, name="tanh")


def both_paths(problem, x):
    compiled, operators = problem.evaluate(x), problem.evaluate(x, jacobians=True)
    assert compiled.forward_jacobian is None and operators.forward_jacobian is not None
    return compiled, operators


@pytest.mark.parametrize("regularizer", REGULARIZERS)
def test_compiled_loss_and_gradient_are_the_operators(regularizer):
    rng = np.random.default_rng(1)
    forward = op.Diagonal(rng.uniform(1, 2, (6, 5))) @ nonlinear_map(rng)
    problem = solvers.Problem(forward, rng.standard_normal((6, 5)),
                              regularizer=REGULARIZERS[regularizer](), lam=0.7)
    assert problem.compiled is not None
    x = rng.standard_normal(DIMS)
    compiled, operators = both_paths(problem, x)
    for part in ("loss", "misfit", "regularizer"):
        np.testing.assert_allclose(getattr(compiled, part), getattr(operators, part),
                                   rtol=1e-13, atol=0)
    np.testing.assert_allclose(compiled.grad, operators.grad, rtol=1e-12, atol=1e-14)
    assert compiled.grad.dtype == problem.dtype and compiled.grad.shape == DIMS


def test_exact_tv_uses_the_functional_s_subgradient_zero_at_zero():
    """At a flat field every difference is 0: TV's gradient there is 0, as L1.grad says (JAX's
    derivative of abs would give 1 and a non-zero gradient)."""
    rng = np.random.default_rng(2)
    problem = solvers.Problem(nonlinear_map(rng), np.zeros((6, 5)),
                              regularizer=op.total_variation(DIMS, 0.5), lam=1.0)
    x = np.full(DIMS, 0.3)
    compiled, operators = both_paths(problem, x)
    np.testing.assert_allclose(compiled.grad, operators.grad, rtol=1e-12, atol=1e-15)
    no_regularizer = solvers.Problem(problem.forward, problem.data).evaluate(x).grad
    np.testing.assert_allclose(compiled.grad, no_regularizer, rtol=1e-12, atol=1e-15)


def test_float32_sums_rows_on_the_device_and_the_rest_in_float64():
    rng = np.random.default_rng(3)
    forward = op.Operator.from_jax(lambda x: x * x, (200, 1000), (200, 1000), dtype=np.float32)
    data = rng.standard_normal((200, 1000)).astype(np.float32)
    problem = solvers.Problem(forward, data)
    x = rng.standard_normal((200, 1000)).astype(np.float32)
    exact = float(np.sum((x.astype(np.float64) ** 2 - data) ** 2))
    compiled, operators = both_paths(problem, x)
    assert abs(compiled.loss - exact) <= 1e-6 * exact
    assert abs(compiled.loss - operators.loss) <= 1e-6 * exact
    assert compiled.grad.dtype == np.float32


def test_an_operator_without_a_jax_form_uses_the_operators_methods():
    rng = np.random.default_rng(4)
    matrix = rng.standard_normal((5, 4))
    forward = op.aslinearoperator(pylops.MatrixMult(matrix))
    problem = solvers.Problem(forward, np.ones(5))
    assert problem.compiled is None
    evaluation = problem.evaluate(np.ones(4))
    assert evaluation.forward_jacobian is not None
    np.testing.assert_allclose(evaluation.grad, 2 * matrix.T @ (matrix @ np.ones(4) - 1),
                               rtol=1e-12)


class _Sum(op.Functional):
    """A functional that gives no terms per element."""

    def __call__(self, x):
        return float(np.sum(x))

    def grad(self, x):
        return np.ones_like(x)


def test_a_functional_without_terms_uses_the_operators_methods():
    rng = np.random.default_rng(5)
    problem = solvers.Problem(nonlinear_map(rng), np.zeros((6, 5)),
                              regularizer=(_Sum(), op.Gradient(DIMS)))
    assert problem.compiled is None
    assert np.isfinite(problem.evaluate(rng.standard_normal(DIMS)).grad).all()


def _positive_only(x):
    if np.min(x) < 0:
        raise ValueError(f"positive inputs only, got a minimum of {np.min(x):g}")


def test_the_domain_is_checked_at_the_inner_value_before_the_program():
    """A map with a domain after a sign change: the check sees the composed point."""
    kernel = KernelOperator(lambda radiance: (lambda a, x: a * jnp.sqrt(x)), (jnp.ones(3),), 1,
                            (3,), (3,), np.float64, "sqrt", domain=_positive_only)
    problem = solvers.Problem(kernel @ op.Diagonal(np.array([1.0, -1.0, 1.0])), np.zeros(3))
    assert problem.compiled is not None
    for jacobians in (False, True):
        with pytest.raises(ValueError, match="positive inputs only, got a minimum of -2"):
            problem.evaluate(np.array([1.0, 2.0, 3.0]), jacobians=jacobians)
    compiled, operators = both_paths(problem, np.array([1.0, -2.0, 3.0]))
    np.testing.assert_allclose(compiled.grad, operators.grad, rtol=1e-14)


def test_the_compiled_gradient_passes_the_taylor_test():
    rng = np.random.default_rng(6)
    problem = solvers.Problem(nonlinear_map(rng), rng.standard_normal((6, 5)),
                              regularizer=REGULARIZERS["tv smoothed"](), lam=0.5)
    x = rng.standard_normal(DIMS)
    result = op.gradient_taylor_test(lambda y: problem.evaluate(y).loss,
                                     lambda y: problem.evaluate(y).grad, x, seed=0)
    assert result.passed, result


def test_adam_iterates_the_same_on_both_paths():
    rng = np.random.default_rng(7)
    forward, data = nonlinear_map(rng), rng.standard_normal((6, 5))
    x0 = rng.standard_normal(DIMS)
    results = []
    for compiled in (True, False):
        problem = solvers.Problem(forward, data, regularizer=REGULARIZERS["tikhonov"](),
                                  lam=0.1, lower=-1.0, upper=1.0, x0=np.clip(x0, -1, 1))
        if not compiled:
            problem.compiled = None
        results.append(solvers.get("adam")(max_iter=20, lr=0.05).run(problem))
    np.testing.assert_allclose(results[0].x, results[1].x, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(results[0].history["loss"], results[1].history["loss"],
                               rtol=1e-12)


def test_the_point_gradient_and_adam_s_moments_stay_on_the_device(tmp_path):
    """A compiled evaluation keeps its point and gradient on JAX's device; the history's
    projected-gradient norm computed there is the host's; Adam's moments stay there between
    iterations and come to the host as NumPy arrays in a checkpoint."""
    rng = np.random.default_rng(8)
    problem = solvers.Problem(nonlinear_map(rng), rng.standard_normal((6, 5)),
                              regularizer=REGULARIZERS["tv smoothed"](), lam=0.2,
                              lower=-0.4, upper=0.4)
    x = problem.project(rng.standard_normal(DIMS))
    assert np.sum(np.abs(x) == 0.4) > 5
    assert [b.shape for b in problem.compiled.bounds] == [(1, 1, 1, 1)] * 2  # not copied whole
    evaluation = problem.evaluate(x)
    assert isinstance(evaluation.point, jax.Array)
    assert isinstance(evaluation.native_grad, jax.Array)
    assert evaluation.native_grad.shape == DIMS
    host = evaluation.grad
    assert isinstance(host, np.ndarray) and host.dtype == problem.dtype
    np.testing.assert_array_equal(host, np.asarray(evaluation.native_grad))
    on_device = problem.projected_gradient_norm(x, evaluation)
    on_host = np.linalg.norm(problem.projected_gradient(x, host))
    assert on_host < 0.95 * np.linalg.norm(host)  # some components pushed out of the box
    np.testing.assert_allclose(on_device, on_host, rtol=1e-14)

    states, path = [], tmp_path / "run.npz"
    result = solvers.get("adam")(max_iter=3, lr=0.05).run(
        problem, x0=x, callbacks=[lambda run: states.append(run.state),
                                  solvers.Checkpoint(path, every=1)])
    assert result.x.flags.writeable  # the host's copy of the device's point, the user's own
    assert all(isinstance(s[k], jax.Array) for s in states for k in ("m", "v"))
    saved = solvers.load_checkpoint(path).state
    for k in ("m", "v"):
        np.testing.assert_array_equal(saved[k], np.asarray(states[-1][k]))


def test_without_a_compiled_objective_adam_steps_in_numpy():
    rng = np.random.default_rng(9)
    problem = solvers.Problem(nonlinear_map(rng), rng.standard_normal((6, 5)), lower=-1.0)
    problem.compiled = None
    states = []
    solvers.get("adam")(max_iter=2, lr=0.05).run(
        problem, x0=np.zeros(DIMS), callbacks=[lambda run: states.append(run.state)])
    assert all(isinstance(s[k], np.ndarray) for s in states for k in ("m", "v"))


def test_float32_adam_on_the_device_is_as_accurate_as_numpy_s():
    """20 float32 Adam iterations, stepped on the device and in NumPy, each within 20 float32
    roundings (20 x 6e-8, relative) of the float64 run. (A float32 1 - beta2 computed on the
    device, 4.7e-5 off, put the device's iterates 4e-6 away. The float32 runs go without JAX's
    64-bit mode, as the invflame command and these tests run them: with it, JAX would compute
    that 1 - beta2 in float64 and the trap would not show.)"""
    rng = np.random.default_rng(11)
    data, x0 = rng.standard_normal((6, 5)), np.clip(rng.standard_normal(DIMS), -1, 1)
    results = {}
    for dtype in (np.float32, np.float64):
        forward = nonlinear_map(np.random.default_rng(10), dtype)  # one matrix for both
        for compiled in (True, False):
            problem = solvers.Problem(forward, data, lower=-1.0, upper=1.0, x0=x0.astype(dtype))
            if not compiled:
                problem.compiled = None
            results[dtype, compiled] = solvers.get("adam")(max_iter=20, lr=0.05).run(problem).x
    reference = results[np.float64, True]
    np.testing.assert_allclose(results[np.float64, False], reference, rtol=1e-12)
    for compiled in (True, False):
        x = results[np.float32, compiled]
        assert x.dtype == np.float32
        assert np.linalg.norm(x - reference) <= 20 * 6e-8 * np.linalg.norm(reference)
