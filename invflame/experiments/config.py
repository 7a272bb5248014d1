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
    rays_per_pixel = 9         # k*k sub-rays averaged into each pixel (9: every voxel seen)

    [spectrum]
    min = 650.0                # cm-1
    max = 725.0                # cm-1
    step = 0.04                # cm-1, line-by-line grid
    pressure = 101325.0        # Pa

    [instrument]
    resolution = 8.0           # cm-1 (1/MOPD), triangular apodization
    sampling = 2.0             # cm-1, output spacing

    [data]
    inverse_crime = false      # true: data from the reconstruction's own grid, rays and step
    rays_per_pixel = 25        # sub-rays per pixel of the synthetic measurement
    step_divisor = 2           # its line-by-line step is spectrum.step / step_divisor

    [noise]
    kind = "nesr"              # "nesr", "snr" or "none"
    nesr = 1e-3                # W/(m2 sr cm-1), or a file of (wavenumber, NESR) rows
    snr = 100.0                # peak signal / noise standard deviation, for kind "snr"

    [representation]
    kind = "voxel"             # or "neural", "neural-centres"

    [regularizer]
    kind = "none"              # "none", "tikhonov" or "tv"
    lambda = 1e-3              # or "discrepancy" (chosen from the data, see parameter choice)
    scaling = "chi2"           # "chi2": chi^2/M + lambda Phi; "paper": per-ray misfit
    lambda_range = [1e-3, 1e2] # search range of "discrepancy" (1/Phi units)
    tau = 1.0                  # "discrepancy": largest lambda with chi^2 <= tau M

    [solver]
    name = "adam"
    iterations = 200           # at most; the stopping rules in options may end it sooner
    options = { lr = 0.01 }

    [init]
    kind = "band-tomography"   # from the data; or "ambient", or "noisy-truth" (the paper's)
    noise = 0.2                # relative standard deviation for "noisy-truth"
    temperature_rise = 1500.0  # K, flame-sheet rise of the state relation for "band-tomography"
    ambient = [300.0, 0.0, 0.0, 0.0]  # the air around the flame: T [K], X_CO2, X_H2O, X_CH4
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
    "rig": {"pixels": 32, "distance": 1.5, "focal_length": 0.59, "rays_per_pixel": 9},
    "spectrum": {"min": 650.0, "max": 725.0, "step": 0.04, "pressure": 101325.0},
    "instrument": {"resolution": 8.0, "sampling": 2.0},
    "data": {"inverse_crime": False, "rays_per_pixel": 25, "step_divisor": 2},
    "noise": {"kind": "nesr", "nesr": 1e-3, "snr": 100.0},
    "representation": {"kind": "voxel", "frequencies": 10, "hidden": 64, "layers": 4,
                       "coarse_samples": 32, "fine_samples": 32, "rays_per_batch": 1024,
                       "pretrain_iterations": 1000},
    "regularizer": {"kind": "none", "lambda": 1e-3, "scaling": "chi2",
                    "lambda_range": [1e-3, 1e2], "tau": 1.0},
    "solver": {"name": "adam", "iterations": 200, "options": {}},
    "init": {"kind": "band-tomography", "noise": 0.2, "temperature_rise": 1500.0,
             "ambient": [300.0, 0.0, 0.0, 0.0]},
}

CHOICES = {
    ("noise", "kind"): ("nesr", "snr", "none"),
    ("representation", "kind"): ("voxel", "neural", "neural-centres"),
    ("regularizer", "kind"): ("none", "tikhonov", "tv"),
    ("regularizer", "scaling"): ("chi2", "paper"),
    ("init", "kind"): ("band-tomography", "ambient", "noisy-truth"),
}

POSITIVE = {("truth", "grid"), ("rig", "pixels"), ("rig", "distance"),
            ("rig", "focal_length"), ("spectrum", "step"), ("spectrum", "pressure"),
            ("instrument", "resolution"), ("instrument", "sampling"), ("noise", "snr"),
            ("representation", "frequencies"), ("representation", "hidden"),
            ("representation", "layers"), ("representation", "coarse_samples"),
            ("representation", "fine_samples"), ("representation", "rays_per_batch"),
            ("solver", "iterations"), ("rig", "rays_per_pixel"), ("data", "rays_per_pixel"),
            ("data", "step_divisor"), ("init", "temperature_rise")}
NON_NEGATIVE = {("init", "noise"), ("representation", "pretrain_iterations")}

LAMBDA_RULES = ("discrepancy",)
"""Words ``regularizer.lambda`` may hold instead of a number: rules that choose it from the data."""


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


NUMBER_OR_WORD = {"regularizer.lambda", "noise.nesr"}
"""Keys that take a number or a string (a rule's name, a file)."""


def _check_type(path: str, value, default):
    if path in NUMBER_OR_WORD and isinstance(value, str):
        return value
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
    if isinstance(default, list):
        if not (isinstance(value, list) and len(value) == len(default)
                and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)):
            raise ConfigError(f"{path!r} must be a list of {len(default)} numbers, got {value!r}")
        return [float(v) for v in value]
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
    lam = full["regularizer"]["lambda"]
    if isinstance(lam, str) and lam not in LAMBDA_RULES:
        raise ConfigError(f"'regularizer.lambda' = {lam!r} is neither a number nor a rule"
                          f"{_suggest(lam, LAMBDA_RULES)}")
    if not isinstance(lam, str) and lam < 0:
        raise ConfigError(f"'regularizer.lambda' must be >= 0, got {lam!r}")
    air = full["init"]["ambient"]
    if not (150.0 < air[0] < 500.0 and all(0.0 <= x <= 1.0 for x in air[1:]) and sum(air[1:]) < 1):
        raise ConfigError(f"'init.ambient' must be [T in K (150-500), X_CO2, X_H2O, X_CH4] with "
                          f"mole fractions in [0, 1] summing below 1, got {air!r}")
    low, high = full["regularizer"]["lambda_range"]
    if not 0 < low < high:
        raise ConfigError(f"'regularizer.lambda_range' must be [low, high] with 0 < low < high, "
                          f"got {[low, high]!r}")
    if not full["regularizer"]["tau"] >= 1:
        raise ConfigError(f"'regularizer.tau' must be >= 1, got {full['regularizer']['tau']!r}")
    if lam == "discrepancy" and full["regularizer"]["scaling"] != "chi2":
        raise ConfigError("'regularizer.lambda' = 'discrepancy' needs 'regularizer.scaling' = "
                          "'chi2' (the rule compares the noise-weighted misfit with the number "
                          "of measurements)")
    nesr = full["noise"]["nesr"]
    if not isinstance(nesr, str) and not nesr > 0:
        raise ConfigError(f"'noise.nesr' must be positive (W/(m2 sr cm-1)) or a file of "
                          f"(wavenumber, NESR) rows, got {nesr!r}")
    for section in ("rig", "data"):
        n = full[section]["rays_per_pixel"]
        if round(n**0.5) ** 2 != n:
            raise ConfigError(f"'{section}.rays_per_pixel' must be a perfect square k*k (k x k "
                              f"sub-rays per pixel: 1, 4, 9, 16, 25, ...), got {n!r}")
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
