"""jaxopt L-BFGS on a float64 problem: float64 results, and JAX's 64-bit mode of the process
untouched while it runs (other threads keep seeing the process's own setting)."""

import threading

import jax
import numpy as np
import pytest

import solvers
from solvers.jaxopt_lbfgs import _from_words, _to_words, _word_shape


def process_x64() -> bool:
    """JAX's 64-bit mode as a thread that never set its own sees it."""
    seen = []
    thread = threading.Thread(target=lambda: seen.append(bool(jax.config.jax_enable_x64)))
    thread.start()
    thread.join()
    return seen[0]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("dims", [(), (3,), (2, 3)])
def test_words_carry_the_exact_bits_jax_gives(dtype, dims):
    value = np.random.default_rng(0).standard_normal(dims).astype(dtype) / 3
    words = _to_words(value, dtype, dims)
    assert words.dtype == np.uint32 and words.shape == _word_shape(dims, dtype)
    with jax.enable_x64(True):
        np.testing.assert_array_equal(words, jax.lax.bitcast_convert_type(value, np.uint32))
    back = _from_words(words, dtype, dims)
    assert back.dtype == dtype and back.shape == dims
    np.testing.assert_array_equal(back, value)


def test_a_float64_solve_leaves_the_process_mode_alone(nonlinear_problem):
    before = bool(jax.config.jax_enable_x64)
    during = []
    result = solvers.solve(nonlinear_problem, "jaxopt-lbfgs", max_iter=5,
                           callbacks=[lambda run: during.append(process_x64())])
    assert during and set(during) == {before}
    assert bool(jax.config.jax_enable_x64) == before and process_x64() == before
    assert result.x.dtype == np.float64


def test_a_float64_solve_matches_scipy_to_float64_accuracy(nonlinear_problem):
    reference = solvers.solve(nonlinear_problem, "lbfgs", max_iter=200, ftol=1e-15,
                              pgtol=1e-12).x
    result = solvers.solve(nonlinear_problem, "jaxopt-lbfgs", max_iter=200, tol=1e-10).x
    np.testing.assert_allclose(result, reference, atol=1e-7, rtol=0)
