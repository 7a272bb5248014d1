r"""Experiment configuration: one schema that validates a TOML file and documents every key.

A configuration describes one reconstruction: the ground truth, the grid, the camera rig, the
spectral window, the instrument, measurement noise, the representation, the regularizer, the
solver and its options, the initialization and the seed. :data:`SCHEMA` holds, for every key,
its type, default, unit, allowed values or range and a one-line meaning. From it come

- :func:`validate`: a file states only what it changes; an unknown key, a value of the wrong
  type, outside its allowed values or range is refused with a :class:`ConfigError` naming the
  key, the value, what is allowed and the default;
- :data:`DEFAULTS`, the complete default configuration (the paper's setup on the quick grid);
- :func:`dumps_commented`, TOML with a comment per key (``invflame config --show-defaults``);
- :func:`keys_markdown`, the key tables of ``docs/guide/configuration.md``.

Conditions between keys (the window and the instrument, the data and the truth, the rig and
the grid, ``solver.options`` and the solver) are checked after the keys, each by one function.
"""

from __future__ import annotations

import copy
import difflib
import math
import tomllib
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from invflame.errors import ConfigError


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
AMBIENT = Rule(lambda a: 150.0 < a[0] < 500.0 and all(0.0 <= x <= 1.0 for x in a[1:])
               and sum(a[1:]) < 1.0,
               "[T in K (150-500), X_CO2, X_H2O, X_CH4] with mole fractions in [0, 1] summing "
               "below 1")
LOW_HIGH = Rule(lambda r: 0.0 < r[0] < r[1], "[low, high] with 0 < low < high")


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


SCHEMA: dict[str, Key | Section] = {
    "seed": Key(INTEGER, 0, "seed of the noise, the networks' initial weights and the noisy "
                "start; a run records it", low=0.0),
    "truth": Section("the flame", {
        "source": Key(STRING, "poolfire", "ground truth: 'poolfire' (the packaged OpenFOAM pool "
                      "fire), 'synthetic' (an analytic plume), 'none' (measured data only) or "
                      "the path of a field .npz"),
        "grid": Key(INTEGER, 30, "voxels per axis of the reconstruction grid (the truth is "
                    "resampled onto it for scoring)", low=4.0,
                    why="voxels per axis (the regularizers and metrics need neighbours)"),
        "soot": Key(NUMBER, 0.0, "peak soot volume fraction of a soot layer in the truth's hot "
                    "fuel (invflame.phantoms.plume.plume_soot), seen in the synthetic data; "
                    "the reconstruction models gas only; 0: soot-free", low=0.0, high=1e-3,
                    why="(flames hold at most ppm)"),
    }),
    "rig": Section("the cameras", {
        "pixels": _positive(INTEGER, 32, "pixels per side of each of the four cameras"),
        "distance": _positive(NUMBER, 1.5, "distance of the cameras from the grid's centre, at "
                              "± on the two horizontal axes", "m"),
        "focal_length": _positive(NUMBER, 0.59, "pinhole focal length", "m"),
        "rays_per_pixel": _positive(INTEGER, 9, "sub-rays per pixel of the reconstruction, k × k "
                                    "averaged into the pixel (9: every voxel seen)", rule=SQUARE),
        "file": Key(STRING, "", "a rig file (TOML, one [[cameras]] table per camera, see "
                    "invflame.geometry.rig_file) or preset ('paper'); replaces pixels, distance "
                    "and focal_length"),
        "cameras": Key(TABLES, [], "the same camera records inline, as [[rig.cameras]] tables "
                       "(not with rig.file)"),
    }),
    "spectrum": Section("the line-by-line window", {
        "min": Key(NUMBER, 650.0, "lower end of the window, below spectrum.max", "cm⁻¹"),
        "max": Key(NUMBER, 725.0, "upper end of the window", "cm⁻¹"),
        "step": _positive(NUMBER, 0.04, "step of the line-by-line grid, at most half of "
                          "instrument.resolution", "cm⁻¹"),
        "pressure": _positive(NUMBER, 101325.0, "total pressure of the gas", "Pa"),
    }),
    "instrument": Section("the FTIR spectrometer", {
        "resolution": _positive(NUMBER, 8.0, "resolution 1/L (L the maximum optical path "
                                "difference), triangular apodization", "cm⁻¹"),
        "sampling": _positive(NUMBER, 2.0, "spacing of the output spectrum", "cm⁻¹"),
    }),
    "data": Section("the measurement: a file, or how the synthetic one is made", {
        "source": Key(STRING, "", "a measurement file (.nc, see invflame.measurement_file) to "
                      "reconstruct instead of simulating; without truth.source the run has no "
                      "ground truth"),
        "inverse_crime": Key(BOOLEAN, False, "true: data from the reconstruction's own grid, "
                             "rays and step (the paper's protocol); false: from the truth's "
                             "native grid, more sub-rays and a finer step"),
        "rays_per_pixel": _positive(INTEGER, 25, "sub-rays per pixel of the synthetic "
                                    "measurement", rule=SQUARE),
        "step_divisor": _positive(INTEGER, 2, "the synthetic measurement's line-by-line step is "
                                  "spectrum.step / step_divisor"),
    }),
    "noise": Section("measurement noise", {
        "kind": Key(STRING, "nesr", "'nesr': a noise-equivalent spectral radiance; 'snr': a "
                    "peak signal-to-noise ratio; 'none': noise-free data",
                    choices=("nesr", "snr", "none")),
        "nesr": _positive(NUMBER_OR_STRING, 1e-3, "noise standard deviation per spectral "
                          "sample, or the path of a file of (wavenumber, NESR) rows",
                          "W/(m²·sr·cm⁻¹)"),
        "snr": _positive(NUMBER, 100.0, "for kind 'snr': the largest clean radiance over the "
                         "noise standard deviation"),
    }),
    "background": Section("what the cameras see behind the flame", {
        "kind": Key(STRING, "none", "'none': a cold black background; 'blackbody': a grey wall "
                    "of background.temperature and background.emissivity; 'file': measured "
                    "spectra per camera from background.file (see invflame.background)",
                    choices=("none", "blackbody", "file")),
        "temperature": _positive(NUMBER, 300.0, "'blackbody': the wall's temperature", "K"),
        "emissivity": Key(NUMBER, 1.0, "'blackbody': the wall's emissivity", low=0.0,
                          high=1.0, above=True),
        "file": Key(STRING, "", "'file': a NetCDF file of background spectra (a variable "
                    "'background' (camera, wavenumber) in W/(m2 sr cm-1), or a measurement file "
                    "of a frame without the flame)"),
    }),
    "representation": Section("what the solver optimizes", {
        "kind": Key(STRING, "voxel", "'voxel': values per voxel; 'neural-field': a NeRF-like "
                    "field rendered along the rays; 'neural-centres': a network evaluated at the "
                    "voxel centres", choices=("voxel", "neural-field", "neural-centres")),
        "frequencies": _positive(INTEGER, 10, "networks: frequencies of the positional encoding "
                                 "of each coordinate"),
        "hidden": _positive(INTEGER, 64, "networks: units per hidden layer"),
        "depth": _positive(INTEGER, 4, "networks: number of hidden layers (formerly 'layers', "
                           "still read with a warning)"),
        "coarse_samples": _positive(INTEGER, 32, "'neural-field': stratified samples per "
                                    "sub-ray"),
        "fine_samples": _positive(INTEGER, 32, "'neural-field': importance samples per sub-ray, "
                                  "drawn from the weights of the coarse pass"),
        "rays_per_batch": _positive(INTEGER, 1024, "'neural-field': pixels per solver iteration "
                                    "(a stochastic objective)"),
        "pretrain_iterations": Key(INTEGER, 1000, "networks: iterations fitting the networks to "
                                   "the starting fields before the reconstruction", low=0.0),
    }),
    "regularizer": Section("the penalty Φ and its weight λ", {
        "kind": Key(STRING, "none", "'tikhonov': mean squared gradient; 'tv': mean absolute "
                    "gradient (anisotropic total variation) of the normalized fields",
                    choices=("none", "tikhonov", "tv")),
        "lambda": Key(NUMBER_OR_STRING, 1e-3, "the weight λ of Φ, or 'discrepancy' to "
                      "choose it from the data", "1/Φ", choices=("discrepancy",), low=0.0),
        "scaling": Key(STRING, "chi2", "'chi2': minimize χ²/M + λΦ (noise-weighted "
                       "misfit); 'paper': the unweighted misfit per pixel + λΦ",
                       choices=("chi2", "paper")),
        "lambda_range": Key(numbers(2), [1e-3, 1e2], "the range 'discrepancy' searches", "1/Φ",
                            rule=LOW_HIGH),
        "tau": Key(NUMBER, 1.0, "'discrepancy' takes the largest λ with χ² ≤ τM",
                   low=1.0),
    }),
    "solver": Section("the optimizer and its stopping rules", {
        "name": Key(STRING, "adam", "a solver's name from solvers.available() (gd, adam, "
                    "gauss-newton, pdhg, lbfgs, ...)"),
        "iterations": _positive(INTEGER, 200, "the most iterations; stopping rules in options "
                                "may end sooner"),
        "options": Key(TABLE, {}, "the solver's own options and stopping rules (lr, rtol_loss, "
                       "loss_window, rtol_x, gtol, time_budget, ...), see solvers.solve"),
    }),
    "init": Section("the start", {
        "kind": Key(STRING, "band-tomography", "'band-tomography': from the data (band-"
                    "integrated linear tomography and a methane state relation); 'ambient': "
                    "flat ambient air; 'noisy-truth': the paper's truth plus noise",
                    choices=("band-tomography", "ambient", "noisy-truth")),
        "noise": Key(NUMBER, 0.2, "'noisy-truth': standard deviation of the noise",
                     "fraction of each field's range", low=0.0, high=1.0,
                     why="(the paper's 0.2)"),
        "temperature_rise": _positive(NUMBER, 1500.0, "'band-tomography': flame-sheet "
                                      "temperature rise of the state relation", "K"),
        "ambient": Key(numbers(4), [300.0, 0.0, 0.0, 0.0], "the air around the flame: "
                       "[T, X_CO2, X_H2O, X_CH4]", "K, mol/mol", rule=AMBIENT),
    }),
}
"""Every key of a configuration: top-level keys and ``[section]`` tables, in file order."""


def keys(schema: dict[str, Key | Section] = SCHEMA) -> Iterator[tuple[str, str, Key]]:
    """Every key of a schema, in file order.

    Parameters
    ----------
    schema : dict, optional
        Top-level keys and sections; :data:`SCHEMA` if not given.

    Yields
    ------
    tuple of (str, str, Key)
        ``(section, name, key)``, ``section`` empty for a top-level key.
    """
    for name, entry in schema.items():
        if isinstance(entry, Section):
            yield from ((name, key_name, key) for key_name, key in entry.keys.items())
        else:
            yield "", name, entry


def _defaults(schema: dict[str, Key | Section]) -> dict[str, Any]:
    return {name: _defaults(entry.keys) if isinstance(entry, Section)
            else copy.deepcopy(entry.default) for name, entry in schema.items()}


DEFAULTS: dict[str, Any] = _defaults(SCHEMA)
"""The complete default configuration, from :data:`SCHEMA`."""
CHOICES = {(section, name): key.choices for section, name, key in keys() if key.choices}
"""The strings allowed for ``(section, key)``, from :data:`SCHEMA`."""
POSITIVE = {(section, name) for section, name, key in keys()
            if section and key.low is not None and (key.low > 0 or key.above)}
"""``(section, key)`` of the numbers that must be positive, from :data:`SCHEMA`."""
NON_NEGATIVE = {(section, name) for section, name, key in keys()
                if section and key.low == 0 and not key.above}
"""``(section, key)`` of the numbers that may be zero but not negative, from :data:`SCHEMA`."""

RENAMED_KEYS = {("representation", "layers"): "depth"}
"""Former key names, still read (with a FutureWarning): (section, old key) → new key."""
RENAMED_VALUES = {("representation", "kind"): {"neural": "neural-field"}}
"""Former values, still read (with a FutureWarning): (section, key) → {old: new}."""

"""Stopping rules a solver takes beside its algorithm options (``solver.options``)."""
LINE_DATA_RANGE = (600.0, 800.0)
"""cm⁻¹ covered by the built-in line lists (packaged H2O, generated CO2)."""


def _did_you_mean(word: str, candidates) -> str:
    close = difflib.get_close_matches(word, list(candidates), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _words(choices) -> str:
    quoted = [repr(c) for c in choices]
    return quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} or {quoted[-1]}"


def _range(key: Key) -> str:
    """The range of a number key in words, completing "must be"."""
    if key.high is not None:
        return f"in {'(' if key.above else '['}{key.low:g}, {key.high:g}]"
    if key.low == 0:
        return f"a {'positive' if key.above else 'non-negative'} {key.type.noun}"
    return f"{'above' if key.above else 'at least'} {key.low:g}"


def allowed(key: Key, path: str) -> str:
    """What ``key`` accepts, in words completing "must be" (``"a positive number"``, ``"'nesr',
    'snr' or 'none'"``, ``"at least 4 voxels per axis (...)"``).

    Parameters
    ----------
    key : Key
        An entry of :data:`SCHEMA`.
    path : str
        Its name in the file (``"rig.cameras"``), for the types that name it.

    Returns
    -------
    str
        Its type, range with the reason, rule, and the strings allowed.
    """
    if key.type is STRING and key.choices:
        return _words(key.choices)
    if key.low is None and key.high is None:
        text = key.rule.text if key.rule else key.type.name.format(path=path)
    else:
        text = " ".join(filter(None, (_range(key), key.why)))
        text += f", {key.rule.text}" if key.rule else ""
    if key.type is NUMBER_OR_STRING:
        text += f" or {_words(key.choices) if key.choices else 'a string'}"
    return text


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
        return value
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
    if key.rule and not key.rule.holds(value):
        raise _key_error(path, key, f" must be {key.rule.text}, got {value!r}")
    return value


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
    from invflame.geometry import VoxelGrid, paper_rig
    from invflame.geometry.rig_file import check_rig_sees_grid

    rig = full["rig"]
    grid = VoxelGrid.poolfire(full["truth"]["grid"])
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
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as err:
        raise ConfigError(f"{path}: not UTF-8 text ({err.reason} at byte {err.start}; a TOML "
                          "file must be UTF-8: save it again as UTF-8)") from err
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{path}: malformed TOML: {err}") from err
    try:
        return validate(raw)
    except ConfigError as err:
        raise ConfigError(f"{path}: {err}") from err


def dumps(config: dict) -> str:
    """Write a configuration as TOML text that :func:`load` reads back to the same values.

    Parameters
    ----------
    config : dict
        Configuration (e.g. from :func:`validate`): top-level keys, then one table per section.

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
    allowed (``invflame config --show-defaults``); :func:`load` reads it back.

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
