"""Every registered solver, swapped by name on one problem, lowers the objective and finds
known minimizers."""

import jax
import numpy as np
import pytest

import solvers

# options that make each solver converge on the small test problems
OPTIONS = {
    "gd": {"max_iter": 300},
    "adam": {"lr": 0.01, "max_iter": 2000},
    "gauss-newton": {"max_iter": 20},
    "pdhg": {"max_iter": 20, "inner_iter": 100},
    "lbfgs": {"max_iter": 200, "ftol": 1e-15, "pgtol": 1e-12},
    "jaxopt-lbfgs": {"max_iter": 200, "tol": 1e-10},
    "preconditioned-lbfgs": {"max_iter": 200, "gtol": 1e-10},
}


# fewer iterations on the nonlinear problem, where every operator application goes through JAX
NONLINEAR = {**OPTIONS, "adam": {"lr": 0.05, "max_iter": 100}, "gd": {"max_iter": 50},
             "pdhg": {"max_iter": 10, "inner_iter": 20}}


def test_every_solver_has_test_options():
    assert set(solvers.available()) <= set(OPTIONS)


@pytest.mark.parametrize("name", solvers.available())
def test_solver_lowers_a_nonlinear_objective(nonlinear_problem, name):
    result = solvers.solve(nonlinear_problem, name, **NONLINEAR[name])
    loss = result.history["loss"]
    assert result.solver == name and result.iterations == len(loss) - 1 >= 1
    assert loss[-1] < 1e-2 * loss[0], result
    assert result.loss == pytest.approx(nonlinear_problem.objective(result.x), rel=1e-10)
    for column in ("misfit", "regularizer", "grad_norm", "time"):
        assert np.all(np.isfinite(result.history[column]))
    assert np.all(np.diff(result.history["time"]) >= 0)


@pytest.mark.parametrize("name", solvers.available())
def test_solver_reaches_the_closed_form_tikhonov_minimizer(tikhonov_problem, name):
    problem, x_star = tikhonov_problem
    result = solvers.solve(problem, name, **OPTIONS[name])
    np.testing.assert_allclose(result.x, x_star, atol=1e-6, rtol=0, err_msg=str(result))


@pytest.mark.parametrize("name", solvers.available())
def test_solver_keeps_the_bounds_and_finds_the_bounded_minimizer(tikhonov_problem, name):
    problem, x_star = tikhonov_problem
    upper = np.full(problem.dims, np.inf)
    upper[np.argmax(x_star)] = 0.5 * x_star.max()  # one active bound
    assert x_star.max() > 0
    boxed = solvers.Problem(problem.forward, problem.data, problem.regularizer, problem.lam,
                            upper=upper, x0=problem.x0)
    reference = solvers.solve(boxed, "lbfgs", **OPTIONS["lbfgs"]).x
    result = solvers.solve(boxed, name, **OPTIONS[name])
    assert np.all(result.x <= upper)
    np.testing.assert_allclose(result.x, reference, atol=1e-5, rtol=0, err_msg=str(result))


@pytest.mark.parametrize("name", solvers.available())
def test_a_float64_run_leaves_jax_64_bit_mode_as_it_found_it(nonlinear_problem, name):
    """Every solver runs a float64 problem in float64 without JAX's 64-bit mode on for the
    process, and leaves the mode as it found it: off, or on where the caller turned it on
    (jaxopt's runs inside :func:`operators.precision`, the mode for the calling thread only)."""
    assert not jax.config.jax_enable_x64
    result = solvers.solve(nonlinear_problem, name, **{**NONLINEAR[name], "max_iter": 3})
    assert result.x.dtype == np.float64 and not jax.config.jax_enable_x64
    with jax.enable_x64(True):  # a caller's own mode is kept too
        solvers.solve(nonlinear_problem, name, **{**NONLINEAR[name], "max_iter": 1})
        assert jax.config.jax_enable_x64
    assert not jax.config.jax_enable_x64


@pytest.mark.parametrize("name", solvers.available())
def test_solver_stops_at_the_first_iterate_within_the_misfit_target(nonlinear_problem, name):
    start = nonlinear_problem.evaluate(nonlinear_problem.x0).misfit
    target = 0.05 * start
    result = solvers.solve(nonlinear_problem, name, misfit_target=target, **NONLINEAR[name])
    misfit = np.asarray(result.history["misfit"])
    assert result.stop_reason.startswith("misfit_target:") and result.converged, result
    assert misfit[-1] <= target and np.all(misfit[:-1] > target), misfit
