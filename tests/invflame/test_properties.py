"""Property tests: random input to the configuration validator and the ``.par`` reader gives a
clear error or a valid result, never another exception."""

import copy
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from invflame.errors import ConfigError, InputDataError
from invflame.experiments import config
from invflame.spectroscopy.linelist import RECORD_LENGTH, read_par

BOUNDED = settings(max_examples=150, deadline=None, derandomize=True, database=None,
                   suppress_health_check=[HealthCheck.too_slow,
                                          HealthCheck.function_scoped_fixture])
"""Seeded and bounded: each property runs in seconds."""

SCALARS = st.one_of(
    st.booleans(),
    st.integers(min_value=-10, max_value=10),
    st.integers(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-2.0, max_value=1e3),
    st.text(max_size=12),
    st.sampled_from(["", "adam", "gd", "lbfgs", "tv", "tikhonov", "none", "nesr", "snr",
                     "voxel", "neural-field", "chi2", "paper", "ambient", "discrepancy",
                     "poolfire", "synthetic", "no_such_file.nc", "\x00"]),
)
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=5), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=8)


def _keys(table: dict):
    """Every (section, key) and top-level key of the defaults, with the solver's options."""
    out = []
    for key, value in table.items():
        if isinstance(value, dict):
            out += [(key, sub) for sub in value]
        else:
            out.append((key,))
    return out + [("solver", "options", "lr"), ("solver", "options", "betas"),
                  ("solver", "options", "rtol_loss"), ("solver", "options", "loss_window"),
                  ("solver", "options", "step"), ("solver", "options", "maxcor")]


KEYS = st.one_of(st.sampled_from(_keys(config.DEFAULTS)),
                 st.tuples(st.sampled_from(list(config.DEFAULTS)), st.text(max_size=8)),
                 st.tuples(st.text(max_size=8)))


def _default(path):
    value = config.DEFAULTS
    for part in path:
        if not isinstance(value, dict) or part not in value:
            return None
        value = value[part]
    return value


def like(default):
    """Values of the default's own type, often in range (None: any value)."""
    if isinstance(default, bool):
        return st.booleans()
    if isinstance(default, int):
        return st.integers(-2, 64)
    if isinstance(default, float):
        return st.one_of(st.floats(-1.0, 2000.0), st.sampled_from([default, default * 2]))
    if isinstance(default, str):
        return SCALARS.filter(lambda v: isinstance(v, str))
    if isinstance(default, list) and default and isinstance(default[0], float):
        return st.lists(st.floats(-1.0, 2000.0), min_size=len(default), max_size=len(default))
    return VALUES


@st.composite
def configurations(draw):
    """Tables with a few keys (known, unknown) set to random values, of random types or of
    the default's own type."""
    raw: dict = {}
    for path in draw(st.lists(KEYS, min_size=1, max_size=4)):
        table = raw
        for part in path[:-1]:
            if not isinstance(table.get(part), dict):
                table[part] = {}
            table = table[part]
        default = _default(path)
        typed = like(default) if default is not None else VALUES
        table[path[-1]] = draw(st.one_of(typed, VALUES) if draw(st.booleans()) else typed)
    return raw


def _check_valid(full: dict) -> None:
    """A validated configuration: every default key, values of the defaults' types."""
    assert set(full) == set(config.DEFAULTS)
    for section, defaults in config.DEFAULTS.items():
        if not isinstance(defaults, dict):
            assert type(full[section]) is type(defaults)
            continue
        assert set(full[section]) == set(defaults)
        for key, default in defaults.items():
            value = full[section][key]
            if isinstance(default, float):  # a number, or a word where one is allowed
                assert isinstance(value, str) or (isinstance(value, float)
                                                  and math.isfinite(value)), (section, key)
            elif isinstance(default, bool | int) and not isinstance(default, float):
                assert type(value) is type(default), (section, key)
    assert config.validate(copy.deepcopy(full)) == full  # a valid configuration stays valid


@BOUNDED
@given(configurations())
def test_the_validator_gives_a_valid_configuration_or_a_config_error(raw):
    try:
        full = config.validate(copy.deepcopy(raw))
    except ConfigError as err:
        assert str(err).strip()  # a message, naming what was wrong
        return
    _check_valid(full)


@pytest.fixture(scope="module")
def records(h2o_par):
    """Twenty real H2O records (bytes, 160 characters each)."""
    lines = h2o_par.read_bytes().splitlines()
    return [line for line in lines[::80] if len(line) == RECORD_LENGTH][:20]


ASCII = st.text(st.characters(max_codepoint=127), min_size=1, max_size=12).map(str.encode)


def mutations(text):
    """Up to three edits of the records: replace, cut, extend or blank ``text`` at a column."""
    return st.lists(
        st.tuples(st.integers(0, 19), st.sampled_from(["replace", "cut", "extend", "blank"]),
                  st.integers(0, RECORD_LENGTH - 1), text),
        min_size=1, max_size=3)


@BOUNDED
@given(mutations(ASCII))
def test_the_par_reader_names_the_bad_line_or_reads_valid_records(records, tmp_path, mutations):
    _check_mutated_file(records, tmp_path, mutations)


@BOUNDED
@given(st.integers(0, 19), st.integers(67, 126), st.integers(128, 255))
def test_a_non_ascii_byte_in_the_quanta_is_named_with_its_line(records, tmp_path, index, column,
                                                               byte):
    _check_mutated_file(records, tmp_path, [(index, "replace", column, bytes([byte]))])


def _check_mutated_file(records, tmp_path, mutations):
    """Write the records with ``mutations`` applied and read them: either the error names a
    mutated line or every record read is valid."""
    lines = list(records)
    mutated = set()
    for index, kind, column, text in mutations:
        line = lines[index]
        text = text.replace(b"\n", b"?").replace(b"\r", b"?")
        if kind == "replace":
            line = line[:column] + text + line[column + len(text):]
        elif kind == "cut":
            line = line[:column]
        elif kind == "extend":
            line = line + text
        else:
            line = line[:column] + b" " * len(text) + line[column + len(text):]
        if line != lines[index]:
            lines[index] = line
            mutated.add(index + 1)  # 1-based line number in the file
    path = tmp_path / "mutated.par"
    path.write_bytes(b"\n".join(lines) + b"\n")
    try:
        parsed = read_par(path)
    except InputDataError as err:
        named = [n for n in mutated if f"{path}: line {n}: " in str(err)]
        assert named, f"the error names no mutated line {sorted(mutated)}: {err}"
        return
    blank = sum(not line.strip() for line in lines)
    assert len(parsed) == len(lines) - blank
    for name in ("nu", "S296", "A", "gamma_air", "gamma_self", "E_lower", "n_air",
                 "delta_air", "g_upper", "g_lower"):
        assert np.all(np.isfinite(getattr(parsed, name))), name
    for name in ("S296", "A", "gamma_air", "gamma_self", "g_upper", "g_lower"):
        assert np.all(getattr(parsed, name) >= 0), name
    assert np.all(parsed.isotopologue >= 1) and np.all(parsed.molecule >= 0)
