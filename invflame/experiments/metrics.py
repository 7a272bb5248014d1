"""Reconstruction metrics: the paper's normalized MSE per field, PSNR, time and memory."""

from __future__ import annotations

import resource
import sys

import numpy as np

FIELD_NAMES = ("T", "CO2", "H2O", "CH4")


def normalized_mse(truth: np.ndarray, estimate: np.ndarray) -> dict[str, float]:
    """Mean squared error per field at voxel centres, each field min–max normalized.

    Both fields are mapped with the ground truth's range,
    :math:`\\hat f = (f - \\min f_\\text{true}) / (\\max f_\\text{true} - \\min f_\\text{true})`,
    as in the paper's Table 1.

    Parameters
    ----------
    truth, estimate : ndarray, shape (n_fields, nx, ny, nz)
        Fields in the order (T [K], X_CO2, X_H2O, X_CH4).

    Returns
    -------
    dict
        Field name → dimensionless MSE. A field that is constant in the truth is skipped.
    """
    truth, estimate = np.asarray(truth, np.float64), np.asarray(estimate, np.float64)
    if truth.shape != estimate.shape:
        raise ValueError(f"truth {truth.shape} and estimate {estimate.shape} differ in shape")
    out = {}
    for name, t, e in zip(FIELD_NAMES, truth, estimate, strict=False):
        span = t.max() - t.min()
        if span > 0:
            out[name] = float(np.mean(((e - t) / span) ** 2))
    return out


def psnr(truth: np.ndarray, estimate: np.ndarray) -> dict[str, float]:
    """Peak signal-to-noise ratio per field in dB, on the same normalization as the MSE."""
    return {k: float(-10.0 * np.log10(v)) if v > 0 else float("inf")
            for k, v in normalized_mse(truth, estimate).items()}


def hot_volume_ratio(truth: np.ndarray, estimate: np.ndarray, threshold: float = 500.0) -> float:
    """Volume with T above ``threshold`` (K) in the estimate over that in the truth.

    A reconstruction that lost the flame (e.g. smoothed to ambient air) has a ratio near 0 even
    when its MSE looks good, because the MSE over a mostly ambient domain rewards a flat field.

    Parameters
    ----------
    truth, estimate : ndarray, shape (n_fields, nx, ny, nz)
        Fields with temperature (K) first.
    threshold : float, optional
        Temperature in K (default 500).
    """
    hot = np.count_nonzero(np.asarray(truth)[0] > threshold)
    if hot == 0:
        raise ValueError(f"the truth has no voxel above {threshold} K")
    return float(np.count_nonzero(np.asarray(estimate)[0] > threshold) / hot)


def peak_memory_mb() -> float:
    """Peak resident memory of this process so far, in MB (10⁶ bytes)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss / 1e6 if sys.platform == "darwin" else rss * 1024 / 1e6
