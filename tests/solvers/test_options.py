"""Typed solver options: each registered solver's dataclass, its checks, its messages."""

import dataclasses
import pydoc
import re
import typing

import numpy as np
import pytest

import solvers
from solvers.options import STOPPING_RULES, OptionError, SolverOptions


@pytest.mark.parametrize("name", solvers.available())
def test_every_solver_has_a_documented_frozen_options_dataclass(name):
    options = solvers.get(name).Options
    assert issubclass(options, SolverOptions) and dataclasses.is_dataclass(options)
    assert options.solver == name
    made = solvers.get(name)().options
    assert isinstance(made, options) and dict(made) == options.defaults()
    with pytest.raises(dataclasses.FrozenInstanceError):
        made.__setattr__(next(iter(made)), 1)
    shown = pydoc.render_doc(options, renderer=pydoc.plaintext)
    for f in dataclasses.fields(options):
        # help() shows every option with its type and default; the docstring documents it
        assert f"{f.name}: '" in shown and f"= {f.default!r}" in shown
        assert re.search(rf"^    ([a-z_]+, )*{f.name}(, [a-z_]+)* : \S.*(\n        .*)*?\(default ",
                         options.__doc__, re.MULTILINE), f.name


@pytest.mark.parametrize("name", solvers.available())
def test_a_string_for_a_number_names_solver_option_value_and_type(name):
    options = solvers.get(name).Options
    hints = typing.get_type_hints(options)
    for f in dataclasses.fields(options):
        with pytest.raises(OptionError) as err:
            solvers.get(name)(**{f.name: "0.1"})
        message = str(err.value)
        assert f"solver {name!r}: option {f.name!r} = '0.1' (str) must be" in message
        assert isinstance(err.value, TypeError) and isinstance(err.value, ValueError)
        if hints[f.name] is int:
            assert "must be an integer" in message


@pytest.mark.parametrize(("name", "options", "message"), [
    ("adam", {"lr": 0.0}, "option 'lr' = 0.0 (float) must be > 0"),
    ("adam", {"lr": float("nan")}, "option 'lr' = nan (float) must be a number"),
    ("adam", {"betas": (0.9,)}, "option 'betas' = (0.9,) (tuple) must be tuple of 2 numbers"),
    ("adam", {"betas": [0.9, 1.0]}, r"option 'betas' = \[0.9, 1.0\] \(list\) must be two "
                                    r"numbers in \[0, 1\)"),
    ("adam", {"eps": True}, "option 'eps' = True (bool) must be a number"),
    ("gd", {"shrink": 1.0}, r"option 'shrink' = 1.0 \(float\) must be in \(0, 1\)"),
    ("gd", {"max_backtracks": 2.5}, "option 'max_backtracks' = 2.5 (float) must be an integer"),
    ("lbfgs", {"maxcor": 0}, "option 'maxcor' = 0 (int) must be >= 1"),
    ("jaxopt-lbfgs", {"tol": -1}, "option 'tol' = -1 (int) must be >= 0"),
    ("gauss-newton", {"damping": 0}, "option 'damping' = 0 (int) must be > 0"),
    ("pdhg", {"tau": 0.1}, "option 'sigma' = None .* set both tau and sigma, or neither"),
    ("pdhg", {"tau": -1.0, "sigma": 1.0}, "option 'tau' = -1.0 .* None or > 0"),
    ("preconditioned-lbfgs", {"precondition": 1}, "option 'precondition' = 1 (int) must be "
                                                   "true or false"),
])
def test_out_of_range_values_name_the_range(name, options, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")
                       if "\\" not in message else message):
        solvers.get(name)(**options)


def test_values_are_converted_to_the_declared_types():
    adam = solvers.get("adam")(lr=1, betas=np.array([0.5, 0.25]), eps=np.float32(0.5))
    assert adam.options.lr == 1.0 and type(adam.options.lr) is float
    assert adam.options.betas == (0.5, 0.25) and type(adam.options.betas) is tuple
    assert adam.options["eps"] == 0.5 and type(adam.options.eps) is float
    gd = solvers.get("gd")(max_backtracks=np.int64(4), step=2)
    assert gd.options.max_backtracks == 4 and type(gd.options.max_backtracks) is int
    assert solvers.get("lbfgs")(maxcor=7.0).options.maxcor == 7
    pdhg = solvers.get("pdhg")(tau=1, sigma=0.5)
    assert (pdhg.options.tau, pdhg.options.sigma) == (1.0, 0.5)
    # as a checkpoint stores them: plain JSON values
    assert adam.options.as_dict() == {"lr": 1.0, "betas": [0.5, 0.25], "eps": 0.5}


def test_unknown_option_lists_the_allowed_ones_and_the_closest():
    with pytest.raises(TypeError) as err:
        solvers.get("gd")(stepsize=0.1)
    message = str(err.value)
    assert "solver 'gd' has no option 'stepsize'. Did you mean 'step'?" in message
    for name in [*solvers.get("gd").Options.defaults(), *STOPPING_RULES]:
        assert name in message


def test_the_call_style_and_describe_still_work(nonlinear_problem):
    result = solvers.solve(nonlinear_problem, "adam", lr=0.05, max_iter=3)
    assert result.options["lr"] == 0.05 and result.options["max_iter"] == 3
    assert solvers.get("adam").Options.describe()["lr"] == "a number, > 0"
    assert solvers.get("pdhg").Options.describe()["tau"] == "a number or None, None or > 0"
