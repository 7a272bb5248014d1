"""The building blocks of a configuration schema: value types, rules, keys and sections.

:mod:`invflame.experiments.config_schema` declares the keys of an experiment configuration
with them.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


@dataclass(frozen=True)
class ValueType:
    """The kind of value a key holds.

    Attributes
    ----------
    name : str
        What a value must be, in messages (``{path}`` stands for the key).
    accepts : callable
        True for a value of this type as read from TOML.
    convert : callable or None
        The value as stored (integers given for a number become floats); None: as given.
    noun : str
        ``"integer"`` or ``"number"`` for types whose values have a range; empty otherwise.
    """

    name: str
    accepts: Callable[[Any], bool]
    convert: Callable[[Any], Any] | None = None
    noun: str = ""


INTEGER = ValueType("an integer", lambda v: isinstance(v, int) and not isinstance(v, bool),
                    int, "integer")
NUMBER = ValueType("a number", _is_number, float, "number")
BOOLEAN = ValueType("true or false", lambda v: isinstance(v, bool))
STRING = ValueType("a string", lambda v: isinstance(v, str))
NUMBER_OR_STRING = ValueType("a number or a string",
                             lambda v: _is_number(v) or isinstance(v, str),
                             lambda v: v if isinstance(v, str) else float(v), "number")
TABLE = ValueType("a table such as {{ lr = 0.01 }}", lambda v: isinstance(v, dict))
TABLES = ValueType("[[{path}]] tables",
                   lambda v: isinstance(v, list) and all(isinstance(t, dict) for t in v))


def numbers(n: int) -> ValueType:
    """The type of a list of ``n`` numbers, stored as floats.

    Parameters
    ----------
    n : int
        How many numbers the list holds.

    Returns
    -------
    ValueType
        Accepting exactly ``n`` integers or floats (not booleans).
    """
    return ValueType(f"a list of {n} numbers",
                     lambda v: isinstance(v, list) and len(v) == n and all(map(_is_number, v)),
                     lambda v: [float(x) for x in v])


@dataclass(frozen=True)
class Rule:
    """A condition on a value that a range cannot state, and its wording (``"a perfect
    square ..."``, completing "must be")."""

    holds: Callable[[Any], bool]
    text: str


SQUARE = Rule(lambda n: round(n ** 0.5) ** 2 == n,
              "a perfect square k*k (k x k sub-rays per pixel: 1, 4, 9, 16, 25, ...)")
POWER_OF_TWO = Rule(lambda n: n & (n - 1) == 0, "a power of two (1, 2, 4, 8, 16)")
AMBIENT = Rule(lambda a: 250.0 <= a[0] < 500.0 and all(0.0 <= x <= 1.0 for x in a[1:])
               and sum(a[1:]) < 1.0,
               "[T in K (250-500: the absorption tables start at 250 K), X_CO2, X_H2O, X_CH4] "
               "with mole fractions in [0, 1] summing below 1")
LOW_HIGH = Rule(lambda r: 0.0 < r[0] < r[1], "[low, high] with 0 < low < high")
CELLS = ValueType("a list of 3 integers [nx, ny, nz], or [] for 'truth.grid' on every axis",
                  lambda v: isinstance(v, list) and len(v) in (0, 3) and all(
                      isinstance(n, int) and not isinstance(n, bool) for n in v))
TORCH_DEVICE = Rule(lambda d: re.fullmatch(r"auto|cpu|cuda(:\d+)?", d) is not None,
                    "'auto', 'cpu', 'cuda' or 'cuda:N' (N: the GPU's index)")
AT_LEAST_TWO = Rule(lambda cells: all(n >= 2 for n in cells),
                    "[nx, ny, nz] with at least 2 voxels on every axis, or []")


@dataclass(frozen=True)
class Key:
    """One configuration key.

    Attributes
    ----------
    type : ValueType
        What the value is.
    default : object
        The value when a file does not state it.
    meaning : str
        One line: what the key sets.
    unit : str
        Unit of the numbers (empty for counts and dimensionless values).
    choices : tuple of str
        The strings allowed (for a number-or-string key: the words allowed besides numbers);
        empty when any string is (a path, a name checked elsewhere).
    low, high : float or None
        Smallest and largest number allowed (None: unbounded).
    above : bool
        True: numbers must be above ``low``, not equal to it.
    rule : Rule or None
        A further condition (a perfect square, a list's entries).
    why : str
        Said after the range: what is counted, or why it is bounded.
    """

    type: ValueType
    default: Any
    meaning: str
    unit: str = ""
    choices: tuple[str, ...] = ()
    low: float | None = None
    high: float | None = None
    above: bool = False
    rule: Rule | None = None
    why: str = ""


@dataclass(frozen=True)
class Section:
    """A table of keys, ``[name]`` in the file, with a few words on what it sets."""

    title: str
    keys: dict[str, Key]


def _positive(type_: ValueType, default, meaning: str, unit: str = "", **more) -> Key:
    return Key(type_, default, meaning, unit, low=0.0, above=True, **more)
