"""Experiment configuration: a TOML file, validated with errors that name the bad key.

A configuration describes one reconstruction: the ground truth, the grid, the camera rig, the
spectral window, the instrument, measurement noise, the representation, the regularizer, the
solver and its options, the initialization and the seed. Every section and key has a default
(the paper's setup on the quick grid); a file only states what it changes. Example::

    seed = 0

    [truth]
    source = "poolfire"        # "poolfire", "synthetic" or a path to a field .npz
    grid = 30                  # voxels per axis of the reconstruction grid

    [rig]
    pixels = 32                # per side; 4 cameras at +-distance on the horizontal axes
    distance = 1.5             # m
    focal_length = 0.59        # m

    [spectrum]
    min = 650.0                # cm-1
    max = 725.0                # cm-1
    step = 0.04                # cm-1, line-by-line grid
    pressure = 101325.0        # Pa

    [instrument]
    resolution = 8.0           # cm-1 (1/MOPD), triangular apodization
    sampling = 2.0             # cm-1, output spacing

    [noise]
    kind = "none"              # or "gaussian"
    snr = 100.0                # peak signal / noise standard deviation

    [representation]
    kind = "voxel"             # or "neural"

    [regularizer]
    kind = "none"              # "none", "tikhonov" or "tv"
    lambda = 1e-3

    [solver]
    name = "adam"
    iterations = 200
    options = { learning_rate = 0.01 }

    [init]
    kind = "noisy-truth"       # ground truth + noise (the paper's); or "ambient"
    noise = 0.2                # relative standard deviation for "noisy-truth"
"""

from __future__ import annotations

import copy
import difflib
import tomllib
from pathlib import Path
from typing import Any

DEFAULTS: dict[str, Any] = {
    "seed": 0,
    "truth": {"source": "poolfire", "grid": 30},
    "rig": {"pixels": 32, "distance": 1.5, "focal_length": 0.59},
    "spectrum": {"min": 650.0, "max": 725.0, "step": 0.04, "pressure": 101325.0},
    "instrument": {"resolution": 8.0, "sampling": 2.0},
    "noise": {"kind": "none", "snr": 100.0},
    "representation": {"kind": "voxel", "frequencies": 10, "hidden": 64, "layers": 4,
                       "coarse_samples": 32, "fine_samples": 32, "rays_per_batch": 1024,
                       "pretrain_iterations": 1000},
    "regularizer": {"kind": "none", "lambda": 1e-3},
    "solver": {"name": "adam", "iterations": 200, "options": {}},
    "init": {"kind": "noisy-truth", "noise": 0.2},
}

CHOICES = {
    ("noise", "kind"): ("none", "gaussian"),
    ("representation", "kind"): ("voxel", "neural", "neural-centres"),
    ("regularizer", "kind"): ("none", "tikhonov", "tv"),
    ("init", "kind"): ("noisy-truth", "ambient"),
}

POSITIVE = {("truth", "grid"), ("rig", "pixels"), ("rig", "distance"),
            ("rig", "focal_length"), ("spectrum", "step"), ("spectrum", "pressure"),
            ("instrument", "resolution"), ("instrument", "sampling"), ("noise", "snr"),
            ("representation", "frequencies"), ("representation", "hidden"),
            ("representation", "layers"), ("representation", "coarse_samples"),
            ("representation", "fine_samples"), ("representation", "rays_per_batch"),
            ("solver", "iterations")}
NON_NEGATIVE = {("regularizer", "lambda"), ("init", "noise"),
                ("representation", "pretrain_iterations")}


class ConfigError(ValueError):
    """A configuration value or key is invalid; the message names it and what is allowed."""


def _suggest(key: str, allowed) -> str:
    close = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return f"{hint}; allowed: {', '.join(sorted(allowed))}"


def _merge(base: dict, update: dict, where: str) -> dict:
    merged = copy.deepcopy(base)
    for key, value in update.items():
        path = f"{where}.{key}" if where else key
        if key not in base:
            raise ConfigError(f"unknown key {path!r}{_suggest(key, base)}")
        default = base[key]
        if isinstance(default, dict) and key != "options":
            if not isinstance(value, dict):
                raise ConfigError(f"{path!r} must be a table [{path}], got {value!r}")
            merged[key] = _merge(default, value, path)
        elif key == "options":
            if not isinstance(value, dict):
                raise ConfigError(f"{path!r} must be a table of solver options, got {value!r}")
            merged[key] = dict(value)
        else:
            merged[key] = _check_type(path, value, default)
    return merged


def _check_type(path: str, value, default):
    if isinstance(default, bool) or isinstance(value, bool):
        if not isinstance(value, bool) or not isinstance(default, bool):
            raise ConfigError(f"{path!r} must be {type(default).__name__}, got {value!r}")
        return value
    if isinstance(default, int) and not isinstance(value, int):
        raise ConfigError(f"{path!r} must be an integer, got {value!r}")
    if isinstance(default, float):
        if not isinstance(value, int | float):
            raise ConfigError(f"{path!r} must be a number, got {value!r}")
        return float(value)
    if isinstance(default, str) and not isinstance(value, str):
        raise ConfigError(f"{path!r} must be a string, got {value!r}")
    return value


def validate(config: dict) -> dict:
    """Merge ``config`` over the defaults and check every value.

    Parameters
    ----------
    config : dict
        Nested dictionary as read from TOML (sections as sub-dictionaries).

    Returns
    -------
    dict
        The complete configuration.

    Raises
    ------
    ConfigError
        For an unknown key, a wrong type, a value outside its allowed set or range.
    """
    full = _merge(DEFAULTS, config, "")
    for (section, key), allowed in CHOICES.items():
        if full[section][key] not in allowed:
            raise ConfigError(f"'{section}.{key}' = {full[section][key]!r} is not allowed"
                              f"{_suggest(str(full[section][key]), allowed)}")
    for section, key in POSITIVE:
        if not full[section][key] > 0:
            raise ConfigError(f"'{section}.{key}' must be positive, got {full[section][key]!r}")
    for section, key in NON_NEGATIVE:
        if full[section][key] < 0:
            raise ConfigError(f"'{section}.{key}' must be >= 0, got {full[section][key]!r}")
    if not full["spectrum"]["min"] < full["spectrum"]["max"]:
        raise ConfigError("'spectrum.min' must be below 'spectrum.max' (cm-1)")
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
        raw = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{path}: malformed TOML: {err}") from err
    try:
        return validate(raw)
    except ConfigError as err:
        raise ConfigError(f"{path}: {err}") from err


def dumps(config: dict) -> str:
    """Write a configuration as TOML text (flat tables, as :func:`load` reads it back)."""
    lines = [f"seed = {config['seed']}"]
    for section, values in config.items():
        if not isinstance(values, dict):
            continue
        lines.append(f"\n[{section}]")
        for key, value in values.items():
            lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    return repr(value)
