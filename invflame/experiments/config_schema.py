"""The configuration schema: every key's type, default, unit, allowed values or range and meaning.

:data:`SCHEMA` declares the keys of an experiment configuration, top-level keys and
``[section]`` tables in file order, with the value types and rules of
:mod:`invflame.experiments.config_keys`. From it come the tables kept for callers
(:data:`DEFAULTS`, :data:`CHOICES`, :data:`POSITIVE`, :data:`NON_NEGATIVE`), the former names
still read (:data:`RENAMED_KEYS`, :data:`RENAMED_VALUES`) and :func:`allowed`, what a key
accepts in words.

:mod:`invflame.experiments.config` validates and loads a configuration against this schema
(and re-exports its names); :mod:`invflame.experiments.config_text` writes one as text.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from typing import Any

from invflame.experiments.config_keys import (
    AMBIENT,
    AT_LEAST_TWO,
    BOOLEAN,
    CELLS,
    INTEGER,
    LOW_HIGH,
    NUMBER,
    NUMBER_OR_STRING,
    POWER_OF_TWO,
    SQUARE,
    STRING,
    TABLE,
    TABLES,
    TORCH_DEVICE,
    Key,
    Section,
    _positive,
    numbers,
)

SCHEMA: dict[str, Key | Section] = {
    "seed": Key(INTEGER, 0, "seed of the noise, the networks' initial weights and the noisy "
                "start; a run records it", low=0.0),
    "truth": Section("the flame", {
        "source": Key(STRING, "poolfire", "ground truth: 'poolfire' (the packaged OpenFOAM pool "
                      "fire), 'synthetic' (an analytic plume), 'none' (measured data only) or "
                      "the path of a field .npz"),
        "grid": Key(INTEGER, 30, "voxels per axis of the reconstruction grid, unless "
                    "grid.cells gives them (the truth is resampled onto it for scoring)",
                    low=4.0,
                    why="voxels per axis (the regularizers and metrics need neighbours)"),
        "soot": Key(NUMBER, 0.0, "peak soot volume fraction of a soot layer in the truth's hot "
                    "fuel (invflame.phantoms.plume.plume_soot), seen in the synthetic data and "
                    "scored when soot.reconstruct; 0: soot-free", low=0.0, high=1e-3,
                    why="(flames hold at most ppm)"),
    }),
    "grid": Section("the reconstruction box", {
        "lower": Key(numbers(3), [-0.5, 0.0, -0.5], "lower corner (x, y, z) of the box; y is up",
                     "m"),
        "upper": Key(numbers(3), [0.5, 1.0, 0.5], "upper corner (x, y, z), above grid.lower on "
                     "every axis (default with lower: the pool fire's box)", "m"),
        "cells": Key(CELLS, [], "voxels along x, y, z (not with truth.grid); []: truth.grid on "
                     "every axis", rule=AT_LEAST_TWO),
    }),
    "soot": Section("soot in the reconstruction", {
        "reconstruct": Key(BOOLEAN, False, "true: the soot volume fraction f_v is a fifth "
                           "field reconstructed beside T and the mole fractions (voxel "
                           "representation), in [0, soot.max], starting at 0; false: the "
                           "reconstruction models gas only"),
        "max": Key(NUMBER, 1e-5, "upper bound of the reconstructed soot volume fraction (at "
                   "least truth.soot)", low=0.0, high=1e-3, above=True,
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
        "pressure": Key(NUMBER, 101325.0, "total pressure of the gas", "Pa", low=1e3,
                        high=1e7, why="(1 kPa, a low-pressure flame, to 10 MPa, a high-pressure "
                        "combustor: the Voigt lines without line mixing hold there)"),
        "broadening": Key(STRING, "local", "'local': each voxel's lines broadened and shifted "
                          "by its own H2O and CO2 fractions (the cross-sections tabulated on "
                          "self-fraction nodes); 'fixed': at X_CO2 = 0.1 and X_H2O = 0.2 "
                          "whatever the gas holds", choices=("local", "fixed")),
        "co2_lines": Key(STRING, "", "a HITRAN or HITEMP .par file of CO2 lines (160-character "
                         "records) to use instead of the generated CO2 list"),
        "h2o_lines": Key(STRING, "", "a HITRAN or HITEMP .par file of H2O lines to use instead "
                         "of the packaged HITRAN2012 lines"),
        "points_per_bin": _positive(INTEGER, 8, "most spectral points per line-by-line bin "
                                    "(sub-bins where lines saturate inside a bin); 1: one "
                                    "optical depth per bin", rule=POWER_OF_TWO),
    }),
    "instrument": Section("the FTIR spectrometer", {
        "resolution": _positive(NUMBER, 8.0, "resolution 1/L (L the maximum optical path "
                                "difference), triangular apodization", "cm⁻¹"),
        "sampling": _positive(NUMBER, 2.0, "spacing of the output spectrum", "cm⁻¹"),
        "margin": Key(NUMBER, 4.0, "lineshape modelled beyond the outermost channels of a "
                      "measurement file (data.source), in resolutions: spectrum.min and "
                      "spectrum.max widen to hold it, on the line-by-line step, with a note in "
                      "the log (the sinc² tails cut at 1 resolution miss up to 2 % of the peak "
                      "radiance at 8 cm⁻¹, at 4 resolutions 0.2 %: "
                      "docs/guide/measurement_files.md)", "resolutions", low=0.0, high=20.0,
                      why="(a larger margin costs table size and reaches past the packaged "
                      "line data, 626-774 cm⁻¹)"),
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
        "temperature": _positive(NUMBER, 300.0, "'blackbody': the wall's temperature", "K",
                                 high=2500.0, why="(the absorption table's highest "
                                 "temperature: a wall no hotter than the flame)"),
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
        "parameters": Key(STRING, "state-relation", "'state-relation': per point a progress "
                          "of the methane flame (mixture fraction over its stoichiometric value) "
                          "and a temperature factor, the fields following from the state "
                          "relation of init.temperature_rise and init.ambient (no temperature "
                          "without products; invflame.representations.state_relation); "
                          "'fields': T and the three mole fractions free (the paper's)",
                          choices=("state-relation", "fields")),
        "factor_range": Key(numbers(2), [0.3, 2.0], "'state-relation': bounds of the "
                            "temperature factor h (T - T0 = h x the relation's rise)",
                            rule=LOW_HIGH),
        "subvoxel_spread": Key(NUMBER, 1.0, "'state-relation' on voxels and 'neural-centres': "
                               "render each voxel at the progress that emits what a presumed "
                               "spread of progress inside it emits, the spread this many times "
                               "the progress's change over one voxel "
                               "(invflame.representations.subvoxel); 0: render the mean state",
                               low=0.0),
        "frequencies": _positive(INTEGER, 4, "networks: frequencies of the positional encoding "
                                 "of each coordinate (the paper's 10 resolve structure far "
                                 "finer than the voxels the fields are scored on)"),
        "hidden": _positive(INTEGER, 64, "networks: units per hidden layer"),
        "depth": _positive(INTEGER, 4, "networks: number of hidden layers (formerly 'layers', "
                           "still read with a warning)"),
        "grid_levels": Key(INTEGER, 0, "networks: levels of a learned multi-resolution "
                           "feature grid joining the positional encoding (two features per "
                           "node and level, the finest at the voxels' resolution, each coarser "
                           "one halved); 0: none, the paper's network", low=0.0),
        "coarse_samples": _positive(INTEGER, 32, "'neural-field': stratified samples per "
                                    "sub-ray"),
        "fine_samples": _positive(INTEGER, 32, "'neural-field': importance samples per sub-ray, "
                                  "drawn from the weights of the coarse pass"),
        "rays_per_batch": _positive(INTEGER, 1024, "'neural-field': pixels per solver iteration "
                                    "(a stochastic objective)"),
        "pretrain_iterations": Key(INTEGER, 1000, "networks: iterations fitting the networks to "
                                   "the starting fields before the reconstruction", low=0.0),
        "network_start": Key(STRING, "pretrained", "networks: 'pretrained': fitted to the "
                             "starting fields (the paper's); 'offset': the networks' output adds "
                             "to the starting fields' own values, interpolated between the voxel "
                             "centres, and starts at zero, so they begin at the start exactly and "
                             "learn its correction", choices=("pretrained", "offset")),
        "device": Key(STRING, "auto", "networks: torch's device for the networks, samples and "
                      "losses (made the process's default); 'auto': the first CUDA GPU when "
                      "JAX computes on a GPU and torch has CUDA, else the CPU",
                      rule=TORCH_DEVICE),
    }),
    "regularizer": Section("the penalty Φ and its weight λ", {
        "kind": Key(STRING, "tikhonov", "'tikhonov': mean squared gradient; 'tv': mean "
                    "absolute gradient (anisotropic total variation) of the normalized fields "
                    "(or of the state relation's progress and factor); the default with "
                    "lambda, solver and init is the honest study's VG/Tikh.",
                    choices=("none", "tikhonov", "tv")),
        "lambda": Key(NUMBER_OR_STRING, 30.0, "the weight λ of Φ, or 'discrepancy' to "
                      "choose it from the data", "1/Φ", choices=("discrepancy",), low=0.0),
        "scaling": Key(STRING, "chi2", "'chi2': minimize χ²/M + λΦ (noise-weighted "
                       "misfit); 'paper': the unweighted misfit per pixel + λΦ",
                       choices=("chi2", "paper")),
        "lambda_range": Key(numbers(2), [1e-3, 1e2], "the range 'discrepancy' searches", "1/Φ",
                            rule=LOW_HIGH),
        "tau": Key(NUMBER_OR_STRING, 1.0, "'discrepancy' takes the largest λ with χ² ≤ τM; "
                   "'model-error': τ = 1 + the model error estimated from prior flames "
                   "(invflame.experiments.model_error)", choices=("model-error",), low=1.0),
        "tv_smoothing": Key(NUMBER, 0.0, "Huber smoothing ε of TV's absolute gradients "
                            "(voxels; 0: exact TV): makes TV differentiable, so that L-BFGS "
                            "does not stall at large λ", "1/m", low=0.0),
    }),
    "solver": Section("the optimizer and its stopping rules", {
        "name": Key(STRING, "lbfgs", "a solver's name from solvers.available() (gd, adam, "
                    "gauss-newton, pdhg, lbfgs, ...)"),
        "iterations": _positive(INTEGER, 400, "the most iterations; stopping rules in options "
                                "may end sooner"),
        "options": Key(TABLE, {"rtol_loss": 1e-3, "loss_window": 10},
                       "the solver's own options and stopping rules (lr, rtol_loss, "
                       "loss_window, rtol_x, gtol, time_budget, ...), see solvers.solve; a "
                       "table given replaces this one whole"),
        "stop_chi2": Key(NUMBER, 0.0, "stop at the first iterate whose χ²/M is at most this "
                         "level: the discrepancy principle as a stopping rule, which makes the "
                         "iteration count a regularizer (0: off; needs regularizer.scaling = "
                         "'chi2' and data with a noise σ)", low=0.0),
    }),
    "init": Section("the start", {
        "kind": Key(STRING, "band-tomography", "'band-tomography': from the data (band-"
                    "integrated linear tomography and a methane state relation); 'ambient': "
                    "flat ambient air; 'noisy-truth': the paper's truth plus noise",
                    choices=("band-tomography", "ambient", "noisy-truth")),
        "noise": Key(NUMBER, 0.2, "'noisy-truth': standard deviation of the noise",
                     "fraction of each field's range", low=0.0, high=1.0,
                     why="(the paper's 0.2)"),
        "temperature_rise": _positive(NUMBER, 1500.0, "'band-tomography' and "
                                      "representation.parameters = 'state-relation': flame-"
                                      "sheet temperature rise of the state relation at factor "
                                      "h = 1", "K"),
        "calibrate": Key(BOOLEAN, True, "'band-tomography': fit the start's amplitude and the "
                         "state relation's temperature factor to the spectra (two numbers, "
                         "invflame.experiments.calibration)"),
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
