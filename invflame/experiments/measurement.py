r"""Synthetic measurements without the inverse crime, and FTIR noise.

Data made by the very model, grid and spectral grid that then invert them (the "inverse
crime", Kaipio & Somersalo, *Statistical and Computational Inverse Problems*, 2005, sec. 1.2)
fit to round-off and flatter any method. By default :func:`simulate_measurement` renders the
truth instead

* on its **native grid** (the 60³ OpenFOAM cells of the pool fire, whatever the reconstruction
  grid; a field file on its own grid),
* with **more sub-rays per pixel** (``data.rays_per_pixel``, default 25 = 5 × 5, against the
  reconstruction's 9),
* on a **finer line-by-line grid** (``spectrum.step / data.step_divisor``),

through the same cameras and instrument, then adds noise. A camera with a spectral window of
its own (:mod:`invflame.measurement`) measures only the channels inside it: its other
channels are masked in the data (``sigma = inf``, ``data = 0``), so no value or noise drawn
there is scored.

Noise
-----
An imaging FTIR spectrometer's noise is quoted as a noise-equivalent spectral radiance (NESR):
the standard deviation of a calibrated spectrum, per spectral sample, in W/(m²·sr·cm⁻¹).
Makers of long-wave imaging FTS specify an NESR of the order of 20 nW/(cm²·sr·cm⁻¹) = 2e-4
W/(m²·sr·cm⁻¹) in the middle of their band for one calibrated cube (e.g. the Telops
Hyper-Cam LW specification). The 650–725 cm⁻¹ window lies at the long-wave edge of an
MCT detector's response, where the NESR rises steeply; the default
:data:`DEFAULT_NESR` = 1e-3 W/(m²·sr·cm⁻¹) (100 nW/(cm²·sr·cm⁻¹)) assumes five times the
band-centre figure there. Give your instrument's NESR, constant or per wavenumber (a two-column
file), or a peak signal-to-noise ratio instead.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from invflame.errors import InputDataError
from invflame.field import Field
from invflame.measurement import Measurement
from invflame.representations.whitening import noise_weights
from invflame.scene import Scene
from invflame.spectroscopy.absorption_table import AbsorptionTable

DEFAULT_NESR = 1e-3
"""Default noise-equivalent spectral radiance in W/(m²·sr·cm⁻¹) (see the module docstring)."""


def read_nesr(path, out_wavenumber) -> np.ndarray:
    """NESR per output wavenumber from a text file of ``wavenumber NESR`` rows.

    Parameters
    ----------
    path : str or Path
        Whitespace- or comma-separated rows: wavenumber in cm⁻¹ (increasing), NESR in
        W/(m²·sr·cm⁻¹); lines starting with ``#`` are comments.
    out_wavenumber : array_like
        Output grid in cm⁻¹; the file must cover it. Linear interpolation in between.

    Returns
    -------
    ndarray, shape (n_out,)
        NESR in W/(m²·sr·cm⁻¹) at each output wavenumber.

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    InputDataError
        If it is not UTF-8 text of two numeric columns and at least two rows, its wavenumbers
        do not increase, an NESR is not a finite positive number, or it does not cover
        ``out_wavenumber``; the message names the file and the first bad row.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"noise.nesr file not found: {path} (give a number in "
                                "W/(m2 sr cm-1) or a file of 'wavenumber NESR' rows)")
    layout = "rows of 'wavenumber NESR' (cm-1, W/(m2 sr cm-1))"
    try:
        text = path.read_text(encoding="utf-8")
        with warnings.catch_warnings():  # an empty file: said below, as for a short one
            warnings.simplefilter("ignore", UserWarning)
            table = np.loadtxt(io.StringIO(text), delimiter="," if "," in text else None,
                               ndmin=2)
    except (UnicodeDecodeError, ValueError) as err:
        raise InputDataError(f"{path}: cannot be read as UTF-8 {layout}: {err}") from None
    if table.shape[1] != 2 or table.shape[0] < 2:
        raise InputDataError(f"{path}: need at least 2 {layout}; got {table.shape[0]} rows of "
                             f"{table.shape[1] if table.size else 0} columns")
    eta, nesr = table.T
    for bad, what in ((~np.isfinite(table).all(axis=1), "a value that is not a finite number"),
                      (nesr <= 0, "an NESR that is not positive"),
                      (np.r_[False, np.diff(eta) <= 0], "a wavenumber not above the row before")):
        if bad.any():
            row = int(np.argmax(bad))
            raise InputDataError(f"{path}: data row {row + 1} ({eta[row]:g} {nesr[row]:g}) holds "
                                 f"{what}; give {layout} with wavenumbers increasing")
    out = np.asarray(out_wavenumber, dtype=np.float64)
    if out.min() < eta[0] or out.max() > eta[-1]:
        raise InputDataError(f"{path}: covers {eta[0]:g}-{eta[-1]:g} cm-1 but the instrument "
                             f"samples {out.min():g}-{out.max():g} cm-1")
    return np.interp(out, eta, nesr)


def noise_sigma(noise: dict, clean: np.ndarray, out_wavenumber) -> np.ndarray | None:
    """Noise standard deviation per output wavenumber (W/(m²·sr·cm⁻¹)), or None for none.

    Parameters
    ----------
    noise : dict
        The configuration's ``[noise]``: ``kind`` "nesr" (``nesr`` a number or a file, see
        :func:`read_nesr`), "snr" (``max |clean| / snr``) or "none".
    clean : ndarray, shape (n_rays, n_out)
        Noise-free spectra, W/(m²·sr·cm⁻¹).
    out_wavenumber : array_like, shape (n_out,)
        Output grid in cm⁻¹.
    """
    n_out = len(out_wavenumber)
    if noise["kind"] == "none":
        return None
    if noise["kind"] == "snr":
        return np.full(n_out, np.abs(clean).max() / noise["snr"])
    if isinstance(noise["nesr"], str):
        return read_nesr(noise["nesr"], out_wavenumber)
    return np.full(n_out, float(noise["nesr"]))


def add_noise(clean: np.ndarray, sigma, seed: int) -> np.ndarray:
    """``clean`` plus independent Gaussian noise of standard deviation ``sigma``.

    Parameters
    ----------
    clean : ndarray, shape (n_rays, n_out)
        Spectra, W/(m²·sr·cm⁻¹).
    sigma : float or array_like broadcastable to ``clean`` (e.g. shape (n_out,))
        Standard deviation, same unit, > 0.
    seed : int
        Seed of the noise.
    """
    sigma = 1.0 / noise_weights(sigma, clean.shape)  # checked: broadcastable, > 0
    if not np.all(np.isfinite(sigma)):
        raise ValueError("sigma (noise standard deviation, W/(m2 sr cm-1)) must be finite and "
                         "positive to draw noise; got inf")
    noise = sigma * np.random.default_rng(seed).standard_normal(clean.shape)
    return (clean + noise).astype(clean.dtype)


def synthesis_scene(scene: Scene, truth: Field, table: AbsorptionTable,
                    rays_per_pixel: int) -> Scene:
    """The scene that renders synthetic data: ``scene``'s cameras, their windows and the
    instrument's output grid, the truth's own grid, ``rays_per_pixel`` sub-rays and
    ``table``'s line-by-line grid.

    Parameters
    ----------
    scene : Scene
        The reconstruction's scene (cameras, resolution in cm⁻¹, output wavenumbers).
    truth : Field
        Ground truth on its native grid (m).
    table : AbsorptionTable
        Cross-sections on the synthesis' line-by-line grid (cm⁻¹), usually finer than the
        reconstruction's.
    rays_per_pixel : int
        Sub-rays per pixel (a perfect square).
    """
    return Scene(truth.grid, scene.rig, table, resolution=scene.resolution,
                 out_wavenumber=scene.out_wavenumber, dtype=scene.dtype,
                 rays_per_pixel=rays_per_pixel, camera_windows=scene.camera_windows)


def simulate_measurement(synthesis: Scene, truth: Field, noise: dict, seed: int,
                         provenance: dict | None = None) -> Measurement:
    """Render the truth through ``synthesis`` and add the configured noise; each camera
    measures only the channels inside its window (:attr:`.Scene.measured_channels`).

    Parameters
    ----------
    synthesis : Scene
        Scene on the truth's grid (see :func:`synthesis_scene`).
    truth : Field
        Ground truth on ``synthesis.grid``.
    noise : dict
        The configuration's ``[noise]`` (see :func:`noise_sigma`).
    seed : int
        Seed of the noise.
    provenance : dict, optional
        More to record with the data.
    """
    if truth.grid != synthesis.grid:
        raise ValueError("the truth must be given on the synthesis scene's grid")
    clean = synthesis.simulate(truth.values)
    channels = synthesis.measured_channels
    measured = np.where(channels, clean, 0)  # the values the cameras measure
    sigma = noise_sigma(noise, measured, synthesis.out_wavenumber)
    record = {"grid": list(truth.grid.shape), "rays_per_pixel": synthesis.rays_per_pixel,
              "step_cm-1": synthesis.step, "noise": dict(noise), **(provenance or {})}
    if synthesis.camera_windows is not None:
        record["camera_windows_cm-1"] = [None if w is None else list(w)
                                         for w in synthesis.camera_windows]
    if sigma is None:
        return Measurement(clean, np.ones(clean.shape[1]), False, record).restricted(channels)
    record["peak_snr"] = float(np.abs(measured).max() / sigma[channels.any(axis=0)].max())
    return Measurement(add_noise(clean, sigma, seed), sigma, True, record).restricted(channels)
