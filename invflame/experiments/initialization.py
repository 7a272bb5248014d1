"""Starting fields that need no data: ambient air, and the paper's noisy truth; and the soot
field a start holds when soot is reconstructed."""

from __future__ import annotations

import numpy as np

AMBIENT = np.array([300.0, 4.2e-4, 0.01, 0.0])
"""Ambient air: 300 K, 420 ppm CO2, 1 % H2O (about 30 % relative humidity), no CH4."""


def noisy_truth(truth: np.ndarray, noise: float, seed: int,
                temperature_range=(250.0, 2500.0)) -> np.ndarray:
    r"""The paper's initialization: the ground truth plus Gaussian noise.

    :math:`f_0 = f_\text{true} + \text{noise}\,(\max f_\text{true} - \min
    f_\text{true})\,\epsilon`, :math:`\epsilon \sim \mathcal{N}(0, 1)` independently per
    voxel and field, then clipped to the physical bounds (T in ``temperature_range`` K,
    0 ≤ X ≤ 1). The noise is relative to each field's range, i.e. 20 % on the min–max
    normalized fields on which the paper reports MSE. Clipping at the bounds removes much of
    it in the ambient air: on the packaged pool fire with seed 0 the start scores MSE_T 0.022
    at 30³ and 60³, and the same start smoothed by a Gaussian of one voxel
    (:func:`~invflame.experiments.metrics.smoothed`), with no data at all, 0.0058 at 30³ and
    0.0042 at 60³ — below every row of the paper's Table 1 (the ``start smoothed`` baseline of
    ``invflame reproduce`` prints it for every run). This start knows the answer; use it only
    to reproduce the paper.

    Parameters
    ----------
    truth : ndarray, shape (4, nx, ny, nz)
        Ground-truth fields (T in K, mole fractions).
    noise : float
        Standard deviation relative to each field's range (the paper's 0.2).
    seed : int
        Seed of the noise.
    temperature_range : tuple of float
        Bounds on T in K.
    """
    if noise < 0:
        raise ValueError(f"noise must be >= 0, got {noise}")
    rng = np.random.default_rng(seed)
    span = truth.max(axis=(1, 2, 3), keepdims=True) - truth.min(axis=(1, 2, 3), keepdims=True)
    start = truth + noise * span * rng.standard_normal(truth.shape)
    start[0] = np.clip(start[0], *temperature_range)
    start[1:] = np.clip(start[1:], 0.0, 1.0)
    return start.astype(truth.dtype)


def with_soot_field(fields: np.ndarray, soot: bool) -> np.ndarray:
    """Starting fields with or without the soot volume fraction as a fifth field.

    Parameters
    ----------
    fields : ndarray, shape (4, nx, ny, nz) or (5, nx, ny, nz)
        T in K and mole fractions of CO2, H2O, CH4, optionally then the soot volume fraction.
    soot : bool
        True: five fields, a soot-free start gaining f_v = 0 (no soot until the data ask for
        it); False: the four gas fields.
    """
    fields = np.asarray(fields)
    if not soot:
        return fields[:4]
    if len(fields) == 5:
        return fields
    return np.concatenate([fields, np.zeros((1, *fields.shape[1:]), fields.dtype)])


def ambient(shape, air=AMBIENT) -> np.ndarray:
    """Uniform ambient air on a grid of ``shape`` (nx, ny, nz): knows nothing of the flame.

    Parameters
    ----------
    shape : tuple of int
        ``(nx, ny, nz)``.
    air : array_like, shape (4,), optional
        T in K and mole fractions of CO2, H2O, CH4 (default :data:`AMBIENT`).
    """
    air = np.asarray(air, dtype=np.float64)
    if air.shape != (4,):
        raise ValueError(f"air must be (T [K], X_CO2, X_H2O, X_CH4), got shape {air.shape}")
    return np.broadcast_to(air.reshape(4, 1, 1, 1), (4, *shape)).astype(np.float32)
