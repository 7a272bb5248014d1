"""Reconstruction metrics: the paper's normalized MSE per field, PSNR, time and memory."""

from __future__ import annotations

import resource
import sys

import numpy as np
import scipy.ndimage

FIELD_NAMES = ("T", "CO2", "H2O", "CH4", "soot")


def normalized_mse(truth: np.ndarray, estimate: np.ndarray, spans=None) -> dict[str, float]:
    r"""Mean squared error per field at voxel centres, each field min–max normalized.

    Both fields are mapped with the ground truth's range,
    :math:`\hat f = (f - \min f_\text{true}) / (\max f_\text{true} - \min f_\text{true})`,
    as in the paper's Table 1.

    Parameters
    ----------
    truth, estimate : ndarray, shape (n_fields, nx, ny, nz)
        Fields in the order (T [K], X_CO2, X_H2O, X_CH4), then optionally the soot volume
        fraction f_v [1] (scored as ``"soot"``).
    spans : array_like, shape (n_fields,), optional
        Ranges to normalize by (default: the truth's max − min per field).

    Returns
    -------
    dict
        Field name → dimensionless MSE. A field that is constant in the truth is skipped.
    """
    truth, estimate = np.asarray(truth, np.float64), np.asarray(estimate, np.float64)
    if truth.shape != estimate.shape:
        raise ValueError(f"truth {truth.shape} and estimate {estimate.shape} differ in shape")
    if spans is None:
        spans = truth.max(axis=(1, 2, 3)) - truth.min(axis=(1, 2, 3))
    out = {}
    for name, t, e, span in zip(FIELD_NAMES, truth, estimate, spans, strict=False):
        if span > 0:
            out[name] = float(np.mean(((e - t) / span) ** 2))
    return out


def flame_mse(truth: np.ndarray, estimate: np.ndarray,
              threshold: float = 500.0) -> dict[str, float]:
    """:func:`normalized_mse` over the flame region only: voxels above ``threshold`` (K) in the
    truth or in the estimate.

    Over a domain that is mostly ambient air the plain MSE rewards a flat field; here a method
    is judged where there is flame (or where it put one). Same normalization as
    :func:`normalized_mse` (each field by the truth's range over the whole domain).

    Parameters
    ----------
    truth, estimate : ndarray, shape (n_fields, nx, ny, nz)
        Fields with temperature (K) first.
    threshold : float, optional
        Temperature in K (default 500).

    Returns
    -------
    dict
        Field name → dimensionless MSE; empty when neither field has a voxel that hot.
    """
    truth, estimate = np.asarray(truth, np.float64), np.asarray(estimate, np.float64)
    if truth.shape != estimate.shape:
        raise ValueError(f"truth {truth.shape} and estimate {estimate.shape} differ in shape")
    region = _hot(truth, threshold) | _hot(estimate, threshold)
    if not region.any():
        return {}
    return normalized_mse(truth[:, region][..., None, None], estimate[:, region][..., None, None],
                          spans=truth.max(axis=(1, 2, 3)) - truth.min(axis=(1, 2, 3)))


def common_fields(truth: np.ndarray, estimate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fields both hold: the gas (T in K, mole fractions), and the soot volume fraction
    only when the truth and the estimate both carry it as a fifth field."""
    truth, estimate = np.asarray(truth), np.asarray(estimate)
    common = min(len(truth), len(estimate))
    return truth[:common], estimate[:common]


def psnr(truth: np.ndarray, estimate: np.ndarray) -> dict[str, float]:
    """Peak signal-to-noise ratio per field in dB, on the same normalization as the MSE (the
    fields of :func:`common_fields`)."""
    truth, estimate = common_fields(truth, estimate)
    return {k: float(-10.0 * np.log10(v)) if v > 0 else float("inf")
            for k, v in normalized_mse(truth, estimate).items()}


def hot_volume_ratio(truth: np.ndarray, estimate: np.ndarray, threshold: float = 500.0) -> float:
    """Volume with T above ``threshold`` (K) in the estimate over that in the truth.

    A reconstruction that lost the flame (e.g. smoothed to ambient air) has a ratio near 0 even
    when its MSE looks good, because the MSE over a mostly ambient domain rewards a flat field.
    The parameters are those of :func:`flame_mse`.
    """
    hot = np.count_nonzero(_hot(truth, threshold))
    if hot == 0:
        raise ValueError(f"the truth has no voxel above {threshold} K")
    return float(np.count_nonzero(_hot(estimate, threshold)) / hot)


def _hot(fields: np.ndarray, threshold: float) -> np.ndarray:
    """The voxels of ``fields`` (temperature in K first) above ``threshold`` K, shape (nx, ny,
    nz)."""
    return np.asarray(fields)[0] > threshold


def peak_memory_mb() -> float:
    """Peak resident memory of this process so far, in MB (10⁶ bytes)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss / 1e6 if sys.platform == "darwin" else rss * 1024 / 1e6


def smoothed(fields: np.ndarray, sigma_voxels: float = 1.0) -> np.ndarray:
    """Each field convolved with a Gaussian of ``sigma_voxels`` voxels (no data used).

    Parameters
    ----------
    fields : ndarray, shape (n_fields, nx, ny, nz)
        Fields in any units.
    sigma_voxels : float, optional
        Standard deviation in voxels (default 1); the boundary is mirrored.
    """
    return scipy.ndimage.gaussian_filter(np.asarray(fields, np.float64),
                                         sigma=(0, *(3 * [sigma_voxels])), mode="reflect")


def field_scores(truth: np.ndarray, estimate: np.ndarray, threshold: float = 500.0) -> dict:
    """Every score of one estimate against the truth: ``mse``, ``mse_flame`` (see
    :func:`flame_mse`) and ``hot_volume_ratio`` (None when the truth has no voxel above
    ``threshold`` K), over the fields of :func:`common_fields`."""
    truth, estimate = common_fields(truth, estimate)
    hot = np.any(_hot(truth, threshold))
    return {"mse": normalized_mse(truth, estimate),
            "mse_flame": flame_mse(truth, estimate, threshold),
            "hot_volume_ratio": hot_volume_ratio(truth, estimate, threshold) if hot else None}
