"""Configurations as text: TOML that reads back to the same values, and the documented key tables.

:func:`dumps` writes a configuration as TOML; :func:`parse_setting` reads one setting written
``SECTION.KEY=VALUE``; :func:`dumps_commented` writes a complete one with
a comment per key (``invflame config --show-defaults``); :func:`keys_markdown` writes the key
tables of ``docs/guide/configuration.md`` (``invflame config --markdown``). Every key's unit,
meaning and allowed values come from :mod:`invflame.experiments.config_schema`;
:mod:`invflame.experiments.config` validates and loads a configuration and re-exports these
functions.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterator

import tomli_w

from invflame.experiments.config_keys import Key, Section
from invflame.experiments.config_schema import DEFAULTS, SCHEMA, allowed, keys


def dumps(config: dict) -> str:
    """Write a configuration as TOML text that :func:`~invflame.experiments.config.load` reads
    back to the same values.

    Parameters
    ----------
    config : dict
        Configuration (e.g. from :func:`~invflame.experiments.config.validate`): top-level
        keys, then one table per section.

    Returns
    -------
    str
        TOML text written by ``tomli_w``.

    Raises
    ------
    TypeError
        If a value has no TOML form (e.g. None), naming its type.
    """
    return tomli_w.dumps(config)


def _literal(value) -> str:
    """``value`` as a one-line TOML literal (arrays and tables inline)."""
    if isinstance(value, list):
        return "[" + ", ".join(map(_literal, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_literal_key(k)} = {_literal(v)}" for k, v in value.items()) + "}"
    return tomli_w.dumps({"v": value}).removeprefix("v = ").rstrip("\n")


def _literal_key(name: str) -> str:
    """``name`` as a TOML key, quoted where a bare key cannot be."""
    return tomli_w.dumps({name: 0}).rsplit(" = ", 1)[0]


def _groups() -> Iterator[tuple[str, str, dict[str, Key]]]:
    """The keys of :data:`SCHEMA` by table: ``(section, title, keys)``, the top level first
    (section and title empty)."""
    yield "", "", {name: key for section, name, key in keys() if not section}
    for name, entry in SCHEMA.items():
        if isinstance(entry, Section):
            yield name, entry.title, entry.keys


COMMENT_COLUMN = 40
"""Comments of :func:`dumps_commented` line up after values up to this many characters."""


def dumps_commented(config: dict = DEFAULTS) -> str:
    """A complete configuration as TOML with a comment per key: its unit, meaning and what is
    allowed (``invflame config --show-defaults``);
    :func:`~invflame.experiments.config.load` reads it back.

    Parameters
    ----------
    config : dict, optional
        A validated configuration (every key of :data:`SCHEMA`); the defaults if not given.

    Returns
    -------
    str
        TOML text: top-level keys, then one ``[section]`` per table of :data:`SCHEMA`, a key
        per line with its comment aligned after the value.
    """
    blocks = []
    for section, title, group in _groups():
        values = config[section] if section else config
        lines = [f"{name} = {_literal(values[name])}" for name in group]
        width = max((len(line) for line in lines if len(line) <= COMMENT_COLUMN), default=0)
        block = [f"[{section}]  # {title}"] if section else []
        for line, (name, key) in zip(lines, group.items(), strict=True):
            unit = f"[{key.unit}] " if key.unit else ""
            path = f"{section}.{name}" if section else name
            block.append(f"{line:<{width}}  # {unit}{key.meaning}; allowed: "
                         f"{allowed(key, path)}")
        blocks.append("\n".join(block))
    return ("# invflame configuration; after each key: [unit] meaning; allowed: values\n"
            + "\n\n".join(blocks) + "\n")


def keys_markdown() -> str:
    """The keys of :data:`SCHEMA` as Markdown tables, one per section (key, default, unit,
    allowed values, meaning): the reference in ``docs/guide/configuration.md``.

    Returns
    -------
    str
        A ``###`` heading and a table per section, the top-level keys first.
    """
    out = []
    for section, title, group in _groups():
        out += [f"### `[{section}]`: {title}" if section else "### Top level", "",
                "| key | default | unit | allowed | meaning |", "|---|---|---|---|---|"]
        for name, key in group.items():
            path = f"{section}.{name}" if section else name
            out.append(f"| `{path}` | `{_literal(key.default)}` | {key.unit or '—'} | "
                       f"{allowed(key, path)} | {key.meaning} |")
        out.append("")
    return "\n".join(out)


def parse_setting(text: str) -> tuple[str, str, object]:
    """``(section, key, value)`` of a setting written ``SECTION.KEY=VALUE`` (VALUE in TOML,
    e.g. ``solver.iterations=400`` or ``solver.name="adam"``).

    Raises
    ------
    ValueError
        When the text is not of that form, names no section of the schema or its value is
        not TOML. The key and value are checked by :func:`~invflame.experiments.config.validate`.
    """
    name, _, value = text.partition("=")
    section, _, key = name.strip().partition(".")
    sections = [name for name, entry in SCHEMA.items() if isinstance(entry, Section)]
    if section not in sections or not key or not value.strip():
        raise ValueError(f"setting {text!r}: write SECTION.KEY=VALUE, SECTION one of "
                         f"{', '.join(sections)}")
    try:
        return section, key, tomllib.loads(f"v = {value}")["v"]
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"setting {text!r}: its value is not TOML ({error}); quote a string, "
                         "e.g. solver.name=\"adam\"") from error
