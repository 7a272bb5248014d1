"""The solver registry: pick a solver by name.

>>> import solvers
>>> solvers.available()                      # doctest: +SKIP
['adam', 'gauss-newton', 'gd', 'jaxopt-lbfgs', 'lbfgs', 'pdhg']
>>> solver = solvers.get("adam")(lr=1e-2, max_iter=200)

A new solver joins with the :func:`register` decorator on a :class:`solvers.base.Solver`
subclass.
"""

from __future__ import annotations

import difflib

_REGISTRY: dict[str, type] = {}


class UnknownSolverError(ValueError):
    """A solver name that is not registered."""


def register(name: str):
    """Class decorator registering a solver class under ``name``.

    Sets ``cls.name``, and names the solver in its ``Options`` dataclass for error messages (a
    solver that declares no ``Options`` of its own gets a subclass of the inherited one).

    Parameters
    ----------
    name : str
        Registry name, lower case with dashes (e.g. ``"gauss-newton"``).
    """
    if not name or name != name.strip().lower():
        raise ValueError(f"solver names are non-empty lower-case strings, got {name!r}")

    def decorate(cls):
        if name in _REGISTRY and _REGISTRY[name] is not cls:
            raise ValueError(f"a solver named {name!r} is already registered "
                             f"({_REGISTRY[name].__qualname__})")
        cls.name = name
        if "Options" not in vars(cls):
            cls.Options = type(f"{cls.__name__}Options", (cls.Options,),
                               {"__doc__": cls.Options.__doc__, "__module__": cls.__module__,
                                "__qualname__": f"{cls.__qualname__}.Options"})
        cls.Options.solver = name
        _REGISTRY[name] = cls
        return cls

    return decorate


def available() -> list[str]:
    """Names of all registered solvers, sorted."""
    return sorted(_REGISTRY)


def get(name: str) -> type:
    """The solver class registered under ``name``.

    Raises
    ------
    UnknownSolverError
        If no solver has that name; the message lists the known names and the closest match.
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        pass
    close = difflib.get_close_matches(str(name), available(), n=1)
    hint = f" Did you mean {close[0]!r}?" if close else ""
    raise UnknownSolverError(
        f"unknown solver {name!r}.{hint} Known solvers: {', '.join(available())}"
    )
