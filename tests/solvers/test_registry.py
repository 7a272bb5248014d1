"""The registry: names, lookup, errors, registering a new solver."""

import pytest

import solvers
from solvers.base import Solver, Step


def test_available_lists_the_generic_solvers():
    names = solvers.available()
    assert names == sorted(names)
    assert {"gd", "adam", "gauss-newton", "pdhg", "lbfgs", "jaxopt-lbfgs"} <= set(names)
    for name in names:
        cls = solvers.get(name)
        assert issubclass(cls, Solver) and cls.name == name


def test_unknown_name_lists_known_ones_and_suggests_the_closest():
    with pytest.raises(solvers.UnknownSolverError) as err:
        solvers.get("adma")
    message = str(err.value)
    assert "'adma'" in message and "Did you mean 'adam'?" in message
    for name in solvers.available():
        assert name in message


def test_unknown_option_names_the_valid_ones():
    with pytest.raises(TypeError, match="no option 'learning_rate'.*lr, betas, eps"):
        solvers.get("adam")(learning_rate=0.1)
    with pytest.raises(ValueError, match="option 'lr' = -1.0 \\(float\\) must be > 0"):
        solvers.get("adam")(lr=-1.0)
    with pytest.raises(ValueError, match="max_iter"):
        solvers.get("gd")(max_iter=-3)


def test_register_adds_a_solver_and_refuses_a_taken_name(nonlinear_problem):
    @solvers.register("test-fixed-point")
    class Stay(Solver):
        def step(self, run):
            return Step(run.x, run.current, run.state)

    try:
        assert "test-fixed-point" in solvers.available()
        assert Stay.Options.solver == "test-fixed-point" and dict(Stay().options) == {}
        with pytest.raises(TypeError, match="solver 'test-fixed-point' has no option 'lr'"):
            Stay(lr=0.1)
        result = solvers.solve(nonlinear_problem, "test-fixed-point", max_iter=3)
        assert result.iterations == 3 and result.solver == "test-fixed-point"
        with pytest.raises(ValueError, match="already registered"):
            solvers.register("test-fixed-point")(type("Other", (Solver,), {}))
    finally:
        solvers.registry._REGISTRY.pop("test-fixed-point")
    with pytest.raises(ValueError, match="lower-case"):
        solvers.register("Bad Name")
