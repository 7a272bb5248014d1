"""Typed solver options: one frozen dataclass per solver, checked when it is made.

Each registered solver names its options class in ``Solver.Options``; ``help()`` on that class
lists every option with its type, default, unit and allowed range. A field is declared with
:func:`option`, which carries the range as a predicate and its description::

    @dataclass(frozen=True)
    class AdamOptions(SolverOptions):
        lr: float = option(1e-3, "> 0", lambda v: v > 0)

Values are checked against the field's type (``float`` takes an int or a float, never a bool
or a string; ``int`` takes an integral number; ``X | None`` also None; ``tuple[float, float]``
a sequence of two numbers; ``bool`` only True or False) and converted to it, then against the
range. A bad value raises :class:`OptionError` naming the solver, the option, the value and
what is allowed; an unknown option name lists the allowed ones. An options object reads like
a dict (``o["lr"]``) and :meth:`SolverOptions.as_dict` gives the plain values stored in
checkpoints.
"""

from __future__ import annotations

import difflib
import math
import typing
from collections.abc import Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from numbers import Integral, Real
from types import NoneType, UnionType

STOPPING_RULES = ("max_iter", "rtol_loss", "rtol_x", "gtol", "time_budget", "loss_window",
                  "misfit_target")
"""Options every solver takes beside its own (see :class:`solvers.stopping.StoppingRule`)."""


class OptionError(TypeError, ValueError):
    """A solver option with an unknown name, a wrong type or a value out of range.

    Subclasses both ``TypeError`` (wrong name or type, as for a bad keyword argument) and
    ``ValueError`` (out of range), so either ``except`` catches it.

    Attributes
    ----------
    solver : str
        Registry name of the solver.
    option : str
        The option's name.
    value
        The value given.
    allowed : str or None
        What the value must be (type and range in words); None for an unknown option.
    """

    def __init__(self, message: str, solver: str, option: str, value=None,
                 allowed: str | None = None):
        super().__init__(message)
        self.solver, self.option, self.value, self.allowed = solver, option, value, allowed


def option(default, rule: str = "", check=None):
    """A dataclass field of a solver option.

    Parameters
    ----------
    default
        Default value.
    rule : str, optional
        The allowed range in words, for error messages (e.g. ``"> 0"``, ``"in (0, 1)"``).
    check : callable, optional
        ``check(value) -> bool`` on the converted value; False means out of range.
    """
    return field(default=default, metadata={"rule": rule, "check": check})


def _type_name(hint) -> str:
    if typing.get_origin(hint) is tuple:
        return f"tuple of {len(typing.get_args(hint))} numbers"
    if isinstance(hint, UnionType):
        return " or ".join(_type_name(h) for h in typing.get_args(hint))
    return {float: "a number", int: "an integer", bool: "true or false",
            NoneType: "None"}.get(hint, str(hint))


def _convert(value, hint):
    """``value`` as the type ``hint``; raises ValueError when it is not one."""
    if isinstance(hint, UnionType):
        for option_type in typing.get_args(hint):
            try:
                return _convert(value, option_type)
            except ValueError:
                pass
        raise ValueError
    if hint is NoneType:
        if value is None:
            return None
        raise ValueError
    if hint is bool:
        if isinstance(value, bool):
            return value
        raise ValueError
    if isinstance(value, bool | str | bytes) or value is None:
        raise ValueError
    if hint is float:
        if isinstance(value, Real) and math.isfinite(float(value)):
            return float(value)
        raise ValueError
    if hint is int:
        if isinstance(value, Integral):
            return int(value)
        if isinstance(value, Real) and math.isfinite(float(value)) and float(value).is_integer():
            return int(value)
        raise ValueError
    if typing.get_origin(hint) is tuple:
        items = typing.get_args(hint)
        if not isinstance(value, Sequence) and not hasattr(value, "__array__"):
            raise ValueError
        values = list(value)
        if len(values) != len(items):
            raise ValueError
        return tuple(_convert(v, h) for v, h in zip(values, items, strict=True))
    raise TypeError(f"unsupported option type {hint!r}")


@dataclass(frozen=True)
class SolverOptions(Mapping):
    """Base class of the solvers' options (a solver without options uses it as it is).

    Subclasses are frozen dataclasses whose fields are made with :func:`option`; their
    docstring lists each option with its unit and meaning (what ``help()`` shows).
    """

    #: Registry name of the solver, for messages (set by :func:`solvers.register`).
    solver = "solver"

    def __post_init__(self):
        hints = typing.get_type_hints(type(self))
        for f in fields(self):
            value = getattr(self, f.name)
            try:
                converted = _convert(value, hints[f.name])
            except ValueError:
                raise self.error(f.name, value, _type_name(hints[f.name])) from None
            object.__setattr__(self, f.name, converted)
            check, rule = f.metadata.get("check"), f.metadata.get("rule", "")
            if check is not None and not check(converted):
                raise self.error(f.name, value, rule)
        self.check()

    def check(self) -> None:
        """Checks that involve several options; raise with :meth:`error`."""

    def error(self, name: str, value, allowed: str) -> OptionError:
        """The error for option ``name`` holding ``value``, which must be ``allowed``."""
        return OptionError(f"solver {self.solver!r}: option {name!r} = {value!r} "
                           f"({type(value).__name__}) must be {allowed}", self.solver, name,
                           value, allowed)

    @classmethod
    def from_kwargs(cls, options: dict) -> SolverOptions:
        """The options from keyword arguments, refusing unknown names.

        Raises
        ------
        OptionError
            For an unknown name (with the allowed names and the closest one), a wrong type or
            a value out of range.
        """
        known = [f.name for f in fields(cls)]
        unknown = [k for k in options if k not in known]
        if unknown:
            close = difflib.get_close_matches(str(unknown[0]), known + list(STOPPING_RULES), n=1)
            hint = f" Did you mean {close[0]!r}?" if close else ""
            raise OptionError(
                f"solver {cls.solver!r} has no option {unknown[0]!r}.{hint} Its options are "
                f"{', '.join(known) or '(none)'}, plus the stopping rules "
                f"{', '.join(STOPPING_RULES)}", cls.solver, unknown[0])
        return cls(**options)

    @classmethod
    def defaults(cls) -> dict:
        """Each option's default value."""
        return {f.name: f.default for f in fields(cls) if f.default is not MISSING}

    @classmethod
    def describe(cls) -> dict:
        """Each option's type and range in words, e.g. ``{"lr": "a number, > 0"}``."""
        hints = typing.get_type_hints(cls)
        return {f.name: ", ".join(filter(None, (_type_name(hints[f.name]),
                                                f.metadata.get("rule", ""))))
                for f in fields(cls)}

    def as_dict(self) -> dict:
        """The options as plain values (tuples as lists), as a checkpoint stores them."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self.items()}

    def __getitem__(self, name):
        if name not in self.__dataclass_fields__:
            raise KeyError(name)
        return getattr(self, name)

    def __iter__(self):
        return (f.name for f in fields(self))

    def __len__(self) -> int:
        return len(fields(self))
