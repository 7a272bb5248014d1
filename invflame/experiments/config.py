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
the solver) are checked after the keys, each by one function.

This module validates and loads; the schema is declared in
:mod:`invflame.experiments.config_schema` and configurations are written as text by
:mod:`invflame.experiments.config_text`. Their public names are re-exported here (see
``__all__``): ``config.SCHEMA`` and ``config.dumps`` are the same objects as theirs.
"""

from __future__ import annotations

import copy
import difflib
import math
import tomllib
import warnings
from pathlib import Path

import numpy as np

from invflame.errors import ConfigError
from invflame.experiments.config_keys import Key, Rule, Section, ValueType, _is_number, numbers
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

LINE_DATA_RANGE = (600.0, 800.0)
"""cm⁻¹ covered by the built-in line lists (packaged H2O, generated CO2)."""


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


def _merge(schema: dict[str, Key | Section], given: dict, where: str) -> dict:
    full = _defaults(schema)
    for name, value in given.items():
        path = f"{where}.{name}" if where else name
        if name not in schema:
            raise ConfigError(f"unknown key {path!r}{_did_you_mean(name, schema)}; allowed: "
                              f"{', '.join(sorted(schema))}")
        entry = schema[name]
        if isinstance(entry, Section):
            if not isinstance(value, dict):
                raise ConfigError(f"{path!r} must be a table [{path}], got {value!r}")
            full[name] = _merge(entry.keys, value, path)
        else:
            full[name] = _checked(path, entry, value)
    return full


def _renamed(config: dict) -> dict:
    """``config`` with the former names of :data:`RENAMED_KEYS` and :data:`RENAMED_VALUES`
    replaced by the current ones, each with a FutureWarning saying what to write instead."""
    config = copy.deepcopy(config)
    for (section, old), new in RENAMED_KEYS.items():
        table = config.get(section)
        if not isinstance(table, dict) or old not in table:
            continue
        if new in table:
            raise ConfigError(f"'{section}.{old}' is the former name of '{section}.{new}'; "
                              f"give only '{section}.{new}'")
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
    the conditions between keys.

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
        For an unknown key, a wrong type, a value outside its allowed values or range, or
        keys that do not fit together; the message names the key, the value, what is allowed
        and the default.
    """
    full = _merge(SCHEMA, _renamed(config), "")
    _check_sources(config, full)
    _check_grid(config, full)
    _check_soot(full)
    _check_tv_smoothing(full)
    _check_regularizer(full["regularizer"])
    _check_background(full["background"])
    _check_spectrum(full)
    _check_rig(full)
    _check_solver(full["solver"])
    return full


def _check_regularizer(regularizer: dict) -> None:
    if regularizer["lambda"] == "discrepancy" and regularizer["scaling"] != "chi2":
        raise ConfigError("'regularizer.lambda' = 'discrepancy' needs 'regularizer.scaling' = "
                          "'chi2' (the rule compares the noise-weighted misfit with the number "
                          "of measurements): set scaling = \"chi2\" or give lambda a number")


def _check_background(background: dict) -> None:
    source = background["file"]
    if background["kind"] == "file" and not Path(source).is_file():
        raise ConfigError(f"'background.kind' = 'file' needs 'background.file' to be an existing "
                          f"NetCDF file of background spectra (see invflame.background), got "
                          f"{source!r}")


def line_by_line_grid(spectrum: dict, step: float | None = None) -> np.ndarray:
    """The line-by-line wavenumbers of a ``[spectrum]`` section, cm⁻¹.

    Parameters
    ----------
    spectrum : dict
        ``min``, ``max`` and ``step`` in cm⁻¹.
    step : float, optional
        Step in cm⁻¹ instead of ``spectrum["step"]`` (the finer grid of a measurement).
    """
    step = spectrum["step"] if step is None else step
    n = int(round((spectrum["max"] - spectrum["min"]) / step)) + 1
    return spectrum["min"] + step * np.arange(n)


def output_grid(cfg: dict, wavenumber) -> np.ndarray:
    """The instrument's output wavenumbers (cm⁻¹) over a line-by-line grid: from one
    ``instrument.resolution`` inside the window, every ``instrument.sampling``.

    Raises
    ------
    ConfigError
        If the window is narrower than two resolutions (no output point).
    """
    from operators.ils import default_output_grid

    instrument = cfg["instrument"]
    try:
        out = default_output_grid(np.asarray(wavenumber), instrument["resolution"])
    except ValueError as err:
        raise ConfigError(f"'spectrum.min'..'spectrum.max' and 'instrument.resolution': {err}"
                          ) from err
    return np.arange(out[0], out[-1] + 1e-9, instrument["sampling"])


def _check_spectrum(full: dict) -> None:
    spectrum, instrument = full["spectrum"], full["instrument"]
    lo, hi, step = spectrum["min"], spectrum["max"], spectrum["step"]
    if not lo < hi:
        raise ConfigError(f"'spectrum.min' must be below 'spectrum.max', got {lo!r} and {hi!r} "
                          "cm-1: swap them or widen the window")
    if not step <= instrument["resolution"] / 2:
        raise ConfigError(f"'spectrum.step' = {step!r} cm-1 must be at most half of "
                          f"'instrument.resolution' = {instrument['resolution']!r} cm-1 (the "
                          "lineshape needs several line-by-line points per resolution)")
    if hi < LINE_DATA_RANGE[0] or lo > LINE_DATA_RANGE[1]:
        raise ConfigError(f"the window 'spectrum.min'..'spectrum.max' = {lo:g}-{hi:g} cm-1 "
                          f"holds no absorption line: the built-in line data cover "
                          f"{LINE_DATA_RANGE[0]:g}-{LINE_DATA_RANGE[1]:g} cm-1")
    n_out = output_grid(full, line_by_line_grid(spectrum)).size
    if n_out < 2:
        raise ConfigError(f"'instrument.sampling' = {instrument['sampling']!r} cm-1 leaves "
                          f"{n_out} output point in the window {lo:g}-{hi:g} cm-1 (less one "
                          f"resolution {instrument['resolution']:g} cm-1 at each end): make it "
                          "smaller or widen the window")


def _check_sources(raw: dict, full: dict) -> None:
    """Where the data, the truth and the rig come from. With ``data.source`` and no
    ``truth.source`` given, the run has no ground truth (``truth.source = "none"``), which
    needs a measurement file and a start that is not the truth's; a rig comes from
    ``rig.file`` or ``rig.cameras``, not both."""
    stated = raw.get("truth", {}) if isinstance(raw.get("truth"), dict) else {}
    if full["data"]["source"] and "source" not in stated:
        full["truth"]["source"] = "none"
    if full["truth"]["source"] == "none":
        if not full["data"]["source"]:
            raise ConfigError("'truth.source' = 'none' needs measured data: set 'data.source' "
                              "to a measurement file")
        if full["init"]["kind"] == "noisy-truth":
            raise ConfigError("'init.kind' = 'noisy-truth' needs a ground truth but "
                              "'truth.source' is 'none': start from the data "
                              "('band-tomography') or 'ambient', or give 'truth.source'")
    source = full["data"]["source"]
    if source and not Path(source).is_file():
        raise ConfigError(f"'data.source' = {source!r} is not an existing measurement file "
                          "(.nc, see invflame.measurement_file)")
    if full["rig"]["file"] and full["rig"]["cameras"]:
        raise ConfigError("[rig] gives both 'file' and [[rig.cameras]]: give the cameras in one "
                          "place")


def _check_grid(raw: dict, full: dict) -> None:
    grid = full["grid"]
    lower, upper = grid["lower"], grid["upper"]
    if not all(lo < hi for lo, hi in zip(lower, upper, strict=True)):
        raise ConfigError(f"'grid.upper' = {upper!r} m must exceed 'grid.lower' = {lower!r} m on "
                          "every axis (x, y, z): swap the corners or widen the box")
    stated = raw.get("truth", {}) if isinstance(raw.get("truth"), dict) else {}
    if grid["cells"] and "grid" in stated:
        raise ConfigError("both 'truth.grid' and 'grid.cells' give the voxels of the "
                          "reconstruction grid: give them in one place ('grid.cells' for "
                          "[nx, ny, nz])")


def reconstruction_grid(cfg: dict):
    """The reconstruction grid of a configuration: the box ``grid.lower``..``grid.upper``
    (m, y up) with ``grid.cells`` voxels, or ``truth.grid`` on every axis.

    Parameters
    ----------
    cfg : dict
        Validated configuration.

    Returns
    -------
    invflame.geometry.VoxelGrid
    """
    from invflame.geometry import VoxelGrid

    grid = cfg["grid"]
    cells = tuple(grid["cells"]) or (cfg["truth"]["grid"],) * 3
    return VoxelGrid(grid["lower"], grid["upper"], cells, up_axis=1)


def _check_soot(full: dict) -> None:
    soot, truth = full["soot"], full["truth"]
    if not soot["reconstruct"]:
        return
    kind = full["representation"]["kind"]
    if kind != "voxel":
        raise ConfigError(f"'soot.reconstruct' = true needs 'representation.kind' = 'voxel' (the "
                          f"networks render gas only), got {kind!r}: use the voxel "
                          "representation or set reconstruct = false")
    if truth["soot"] > soot["max"]:
        raise ConfigError(f"'truth.soot' = {truth['soot']!r} exceeds 'soot.max' = "
                          f"{soot['max']!r}, the bound of the reconstructed soot volume "
                          "fraction: raise soot.max to at least truth.soot")


def _check_tv_smoothing(full: dict) -> None:
    reg, kind = full["regularizer"], full["representation"]["kind"]
    if reg["tv_smoothing"] == 0:
        return
    if reg["kind"] != "tv":
        raise ConfigError(f"'regularizer.tv_smoothing' = {reg['tv_smoothing']!r} smooths total "
                          f"variation, but 'regularizer.kind' = {reg['kind']!r}: set kind = "
                          "'tv' or tv_smoothing = 0")
    if kind != "voxel":
        raise ConfigError(f"'regularizer.tv_smoothing' needs 'representation.kind' = 'voxel', "
                          f"got {kind!r} (the networks' regularizer is exact TV): set "
                          "tv_smoothing = 0")


def rig_spec(cfg: dict):
    """The cameras of ``rig.file`` or ``rig.cameras`` as a
    :class:`invflame.geometry.rig_file.RigSpec`; None for the paper's rig
    (``rig.pixels``, ``rig.distance``, ``rig.focal_length``)."""
    from invflame.geometry.rig_file import parse_rig, read_rig

    rig = cfg["rig"]
    if rig["file"]:
        return read_rig(rig["file"])
    return parse_rig(rig["cameras"], "rig.cameras") if rig["cameras"] else None


def _check_rig(full: dict) -> None:
    from invflame.errors import GeometryError, InputDataError
    from invflame.geometry import paper_rig
    from invflame.geometry.rig_file import check_rig_sees_grid

    rig = full["rig"]
    grid = reconstruction_grid(full)
    where = f"'rig.file' = {rig['file']!r}" if rig["file"] else "'rig.cameras'"
    try:
        spec = rig_spec(full)
        if spec is not None:
            check_rig_sees_grid(spec.rig, grid)
    except (InputDataError, GeometryError, FileNotFoundError) as err:
        raise ConfigError(f"{where}: {err}") from err
    if spec is None:
        try:
            paper_rig(grid, distance=rig["distance"], n_pixels=rig["pixels"],
                      focal_length=rig["focal_length"])
        except GeometryError as err:
            raise ConfigError(f"'rig.distance' = {rig['distance']!r}: {err}") from err
    nesr, noise = full["noise"]["nesr"], full["noise"]["kind"]
    if noise == "nesr" and isinstance(nesr, str) and not Path(nesr).is_file():
        raise ConfigError(f"'noise.nesr' = {nesr!r} is neither a number nor an existing file "
                          "of (wavenumber, NESR) rows")


def _check_solver(solver: dict) -> None:
    """The solver's name and options: the stopping rules' types here, the algorithm options by
    the solver's own ``Options`` dataclass (:mod:`solvers.options`)."""
    import solvers
    from solvers.options import STOPPING_RULES, OptionError

    try:
        cls = solvers.get(solver["name"])
    except ValueError as err:
        raise ConfigError(f"'solver.name': {err}") from err
    options = solver["options"]
    if "max_iter" in options:
        raise ConfigError("'solver.options.max_iter' clashes with 'solver.iterations' (the "
                          "iteration limit): remove it from the options and set "
                          "'solver.iterations'")
    for key in STOPPING_RULES:  # the algorithm options are checked by the solver's Options
        value = options.get(key)
        if isinstance(value, str | bool):
            raise ConfigError(f"'solver.options.{key}' must be a number, got {value!r} "
                              f"(write {key} = {value} without quotes)")
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"'solver.options.{key}' must be a finite number, got {value!r}")
    try:
        cls(max_iter=solver["iterations"], **options)
    except OptionError as err:
        if err.allowed is None:  # an unknown name: the message lists the allowed ones
            raise ConfigError(f"'solver.options' = {options!r}: {err}") from err
        unquote = (f" (write {err.option} = {err.value} without quotes)"
                   if isinstance(err.value, str) else "")
        raise ConfigError(f"'solver.options' = {options!r}: 'solver.options.{err.option}' "
                          f"must be {err.allowed}, got {err.value!r}{unquote} (an option of "
                          f"solver {err.solver!r})") from err
    except (TypeError, ValueError, OverflowError) as err:  # the stopping rules
        raise ConfigError(f"'solver.options' = {options!r}: {err}") from err


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
        raise ConfigError(f"{path}: {err}") from err

