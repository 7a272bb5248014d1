"""Bad input to the solvers through the Python API: data that are not finite, unknown solvers
and options, option values of the wrong type, a negative seed; each raises naming it."""

import numpy as np
import pytest

import operators as op
import solvers


def problem(data) -> solvers.Problem:
    """A 3-unknown identity problem with ``data``."""
    return solvers.Problem(op.aslinearoperator(np.eye(3)), np.asarray(data), x0=np.zeros(3))


@pytest.mark.parametrize(("call", "match"), [
    (lambda: problem([1.0, np.nan, 0.0]), "NaN"),
    (lambda: problem([1.0, np.inf, 0.0]), "infinite|inf"),
    (lambda: solvers.get("adamm"), "adamm"),
    (lambda: solvers.get("adam")(lrr=0.1), "lrr"),
    (lambda: solvers.get("adam")(lr="0.1"), "lr"),
    (lambda: solvers.solve(problem(np.ones(3)), "gd", seed=-1), "seed"),
], ids=["Problem NaN data", "Problem inf data", "unknown solver", "solver option typo",
        "solver lr as text", "solver negative seed"])
def test_bad_solver_input_is_named(call, match):
    with pytest.raises(Exception, match=match):
        call()
