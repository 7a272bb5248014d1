r"""Experiment configuration: validate and load a TOML file against one schema.

A configuration describes one reconstruction: the ground truth, the grid (its box and cells),
the camera rig, the spectral window, the instrument, measurement noise, the representation,
soot, the regularizer, the solver and its options, the initialization and the seed.
:data:`SCHEMA` holds, for every key, its type, default, unit, allowed values or range and a
one-line meaning. From it come

- :func:`validate`: a file states only what it changes; an unknown key, a value of the wrong
  type, outside its allowed values or range is refused with a :class:`ConfigError` naming the
  key, the value, what is allowed and the default;
- :data:`DEFAULTS`, the complete default configuration (the paper's setup on the quick grid);
- :func:`dumps_commented`, TOML with a comment per key (``invflame config --show-defaults``);
- :func:`keys_markdown`, the key tables of ``docs/guide/configuration.md``.

Conditions between keys (the window and the instrument, the data and the truth, the grid's
corners and cells, the rig and the grid, soot and the representation, ``solver.options`` and
the solver), the files the configuration names and the memory its arrays need are checked
after the keys, each by one function (:mod:`invflame.experiments.config_rules`). A
configuration is checked whole: the :class:`ConfigError` holds every error found, one message
each.

This module validates and loads; the schema is declared in
:mod:`invflame.experiments.config_schema`, configurations are written as text by
:mod:`invflame.experiments.config_text`, and the grids and cameras a configuration describes
are computed by :mod:`invflame.experiments.config_scene`. Their public names are re-exported
here (see ``__all__``): ``config.SCHEMA`` and ``config.dumps`` are the same objects as theirs.
"""

from __future__ import annotations

import copy
import difflib
import math
import tomllib
import warnings
from pathlib import Path

from invflame.errors import ConfigError
from invflame.experiments.config_keys import Key, Rule, Section, ValueType, _is_number, numbers
from invflame.experiments.config_rules import check_rules
from invflame.experiments.config_scene import (
    LINE_DATA_RANGE,
    line_by_line_grid,
    output_grid,
    reconstruction_grid,
    rig_spec,
)
from invflame.experiments.config_schema import (
    CHOICES,
    DEFAULTS,
    NON_NEGATIVE,
    POSITIVE,
    RENAMED_KEYS,
    RENAMED_VALUES,
    SCHEMA,
    _defaults,
    allowed,
    keys,
)
from invflame.experiments.config_text import (
    COMMENT_COLUMN,
    _literal,
    dumps,
    dumps_commented,
    keys_markdown,
)

__all__ = [  # in the order of the reference: the schema, validation and loading, text
    "ValueType", "numbers", "Rule", "Key", "Section", "SCHEMA", "keys", "DEFAULTS", "CHOICES",
    "POSITIVE", "NON_NEGATIVE", "RENAMED_KEYS", "RENAMED_VALUES", "LINE_DATA_RANGE", "allowed",
    "validate", "line_by_line_grid", "output_grid", "reconstruction_grid", "rig_spec", "load",
    "dumps", "COMMENT_COLUMN", "dumps_commented", "keys_markdown",
]


def _did_you_mean(word: str, candidates) -> str:
    close = difflib.get_close_matches(word, list(candidates), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _key_error(path: str, key: Key, problem: str) -> ConfigError:
    """A ConfigError for ``path``: the problem, then the default as the line to write."""
    section, _, name = path.rpartition(".")
    where = f" in [{section}]" if section else ""
    return ConfigError(f"'{path}'{problem}; the default is `{name} = {_literal(key.default)}`"
                       f"{where}")


def _checked(path: str, key: Key, value):
    """``value`` of ``key`` as stored, after checking its type, finiteness, choices, range and
    rule; a ConfigError naming ``path`` otherwise."""
    if not key.type.accepts(value):
        raise _key_error(path, key, f" must be {key.type.name.format(path=path)}, got {value!r}")
    value = key.type.convert(value) if key.type.convert else value
    if isinstance(value, str):
        if key.choices and value not in key.choices:
            raise _key_error(path, key, f" = {value!r} is not allowed"
                                        f"{_did_you_mean(value, key.choices)}; allowed: "
                                        f"{allowed(key, path)}")
    else:
        _check_numbers(path, key, value)
    if key.rule and not key.rule.holds(value):
        raise _key_error(path, key, f" must be {key.rule.text}, got {value!r}")
    return value


def _check_numbers(path: str, key: Key, value) -> None:
    """A ConfigError naming ``path`` where ``value`` (a number or a list) is not finite or
    outside the key's range."""
    values = value if isinstance(value, list) else [value]
    if any(_is_number(v) and not math.isfinite(v) for v in values):
        finite = "finite numbers" if isinstance(value, list) else "a finite number"
        raise _key_error(path, key, f" must be {finite}, got {value!r}")
    low, high = key.low, key.high
    if _is_number(value) and (low is not None and (value < low or key.above and value == low)
                              or high is not None and value > high):
        sign = "positive: " if (low or 0) > 0 and value <= 0 else ""
        unit = f" ({key.unit})" if key.unit else ""
        raise _key_error(path, key, f"{unit} must be {sign}{allowed(key, path)}, got {value!r}")


def _merge(schema: dict[str, Key | Section], given: dict, where: str, errors: list[str],
           refused: set[str]) -> dict:
    """``given`` over the defaults of ``schema``, each key checked; a refused key keeps its
    default, its message goes to ``errors`` and its dotted path to ``refused``."""
    full = _defaults(schema)
    for name, value in given.items():
        path = f"{where}.{name}" if where else name
        entry = schema.get(name)
        if entry is None:
            errors.append(f"unknown key {path!r}{_did_you_mean(name, schema)}; allowed: "
                          f"{', '.join(sorted(schema))}")
        elif isinstance(entry, Section) and not isinstance(value, dict):
            errors.append(f"{path!r} must be a table [{path}], got {value!r}")
        elif isinstance(entry, Section):
            full[name] = _merge(entry.keys, value, path, errors, refused)
            continue
        else:
            try:
                full[name] = _checked(path, entry, value)
                continue
            except ConfigError as err:
                errors += err.messages
        refused.add(path)
    return full


def _renamed(config: dict, errors: list[str]) -> dict:
    """``config`` with the former names of :data:`RENAMED_KEYS` and :data:`RENAMED_VALUES`
    replaced by the current ones, each with a FutureWarning saying what to write instead; a
    key given under both names goes to ``errors``."""
    config = copy.deepcopy(config)
    for (section, old), new in RENAMED_KEYS.items():
        table = config.get(section)
        if not isinstance(table, dict) or old not in table:
            continue
        if new in table:
            errors.append(f"'{section}.{old}' is the former name of '{section}.{new}'; give "
                          f"only '{section}.{new}'")
            del table[old]
            continue
        warnings.warn(f"'{section}.{old}' is now called '{section}.{new}': write "
                      f"`{new} = {table[old]!r}` in [{section}]; the old name will be refused "
                      "in a later version", FutureWarning, stacklevel=3)
        table[new] = table.pop(old)
    for (section, key), values in RENAMED_VALUES.items():
        table = config.get(section)
        value = table.get(key) if isinstance(table, dict) else None
        if isinstance(value, str) and value in values:
            warnings.warn(f"'{section}.{key}' = {value!r} is now called {values[value]!r}: "
                          f'write `{key} = "{values[value]}"` in [{section}]; the old name '
                          "will be refused in a later version", FutureWarning, stacklevel=3)
            table[key] = values[value]
    return config


def validate(config: dict) -> dict:
    """Merge ``config`` over the defaults and check every value against :data:`SCHEMA`, then
    the conditions between keys, the files named and the memory asked for
    (:func:`invflame.experiments.config_rules.check_rules`).

    Parameters
    ----------
    config : dict
        Nested dictionary as read from TOML (sections as sub-dictionaries).

    Returns
    -------
    dict
        The complete configuration (numbers of number keys as floats).

    Raises
    ------
    ConfigError
        Holding every error found, one message each (``err.messages``): an unknown key, a
        wrong type, a value outside its allowed values or range, keys that do not fit
        together, a missing or unusable file, arrays larger than the machine's memory; each
        names the key, the value and what is allowed (for a key, the default).
    """
    errors: list[str] = []
    refused: set[str] = set()
    full = _merge(SCHEMA, _renamed(config, errors), "", errors, refused)
    errors += check_rules(config, full, refused)
    if errors:
        raise ConfigError(*errors)
    return full


def load(path) -> dict:
    """Read and validate a TOML configuration file.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ConfigError
        If the TOML is malformed or a value is invalid (the message names the file).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"configuration file not found: {path}")
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8-sig"))  # a byte-order mark is no key
    except UnicodeDecodeError as err:
        raise ConfigError(f"{path}: not UTF-8 text ({err.reason} at byte {err.start}; a TOML "
                          "file must be UTF-8: save it again as UTF-8)") from err
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{path}: malformed TOML: {err}") from err
    try:
        return validate(raw)
    except ConfigError as err:
        raise ConfigError(*(f"{path}: {message}" for message in err.messages)) from err

