"""The output channels of the band integral: what a gas state emits in each, as the instrument
sees it (:func:`channel_emission`), each channel's weight (:func:`channel_weights`), and the
channels where the optically thin limit holds for the flame seen (:func:`thin_channels`).

Line cores that saturate make the band integral fall below the thin limit, most at the CO₂ ν₂
Q branch (667 cm⁻¹) in gas of a few hundred kelvin; the band tomography
(:mod:`invflame.experiments.linear_tomography`) assumes the thin limit, so the start
(:mod:`invflame.experiments.data_start`) integrates over the channels where it holds.
"""

from __future__ import annotations

import numpy as np

from operators.rte.planck import planck

THIN_RATIO = 0.6
"""Least ratio of a channel's emission to its optically thin limit (see :func:`thin_channels`).

On the synthetic plume at peak SNR 1000 it drops the four channels at the CO₂ Q branch and
lowers the start's MSE_T by about 30 %; 0.7 drops eight channels with the same result."""


def channel_emission(scene, states, length: float | None = None) -> np.ndarray:
    r"""Band emission of gas states per output channel, as the instrument sees it.

    Thin limit (``length`` None): the emission density
    :math:`\sum_i K_{ji}\, \kappa(\eta_i)\, B(\eta_i, T)` with :math:`K` the scene's
    lineshape matrix (``scene.ils.matrix``), :math:`\kappa` from the scene's absorption table
    and :math:`B` Planck's law. With ``length`` :math:`L`: the radiance of a uniform column of
    that length per unit length, :math:`\sum_i K_{ji}\, B\,(1 - e^{-\kappa L}) / L`,
    which self-absorption keeps below the thin limit.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Absorption table, line-by-line window and instrument.
    states : array_like, shape (4, n)
        T in K (inside the table's range) and mole fractions of CO2, H2O, CH4.
    length : float, optional
        Column length in m (> 0).

    Returns
    -------
    ndarray, shape (n, n_out)
        W/(m³·sr·cm⁻¹).
    """
    states = np.asarray(states, dtype=np.float64)
    if states.ndim != 2 or states.shape[0] != 4:
        raise ValueError(f"states must have shape (4, n): T [K] and mole fractions of CO2, H2O, "
                         f"CH4; got {states.shape}")
    start = int(np.argmin(np.abs(scene.table.wavenumber - scene.wavenumber[0])))
    columns = slice(start, start + scene.wavenumber.size)  # the scene's window in the table
    kappa = scene.table.kappa(states[0], states[1:])[:, columns]  # m⁻¹
    source = planck(scene.wavenumber[None, :], states[0][:, None])
    if length is None:
        spectrum = kappa * source
    elif length > 0:
        spectrum = -np.expm1(-kappa * length) * source / length
    else:
        raise ValueError(f"length must be positive (m), got {length}")
    return spectrum @ np.asarray(scene.ils.matrix, np.float64).T


def channel_weights(scene, channels=None) -> np.ndarray:
    """Weights (cm⁻¹) of the output channels in the band integral: their widths, 0 if unused.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Its output grid ``out_wavenumber`` (cm⁻¹).
    channels : array_like of bool, shape (n_out,), optional
        Channels to integrate over (default: all of them).

    Returns
    -------
    ndarray, shape (n_out,)
        Channel widths in cm⁻¹ (``numpy.gradient`` of the output grid) where selected.
    """
    out = np.asarray(scene.out_wavenumber, np.float64)
    widths = np.gradient(out) if out.size > 1 else np.ones(1)
    if channels is None:
        return widths
    channels = np.asarray(channels)
    if channels.shape != out.shape or channels.dtype != bool:
        raise ValueError(f"channels must be a boolean mask of shape {out.shape} (one per output "
                         f"wavenumber), got dtype {channels.dtype} and shape {channels.shape}")
    if not channels.any():
        raise ValueError("channels selects no output wavenumber; select at least one")
    return np.where(channels, widths, 0.0)


def thin_channels(scene, band_peak: float, states,
                  min_ratio: float = THIN_RATIO) -> np.ndarray:
    """Output channels where the optically thin limit holds well enough for the flame seen.

    The reference column is the shortest column of the hottest state of ``states`` (the last)
    that gives the brightest pixel's band radiance ``band_peak`` (all channels, thin limit):
    any flame seen is at least that thick. A channel is kept when, for every state, such a
    column emits at least ``min_ratio`` of its thin-limit emission
    (:func:`channel_emission`): line cores that saturate make the band integral, and hence
    the tomography, underestimate the emission.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Absorption table, window and instrument.
    band_peak : float
        Largest band radiance over the pixels beyond ambient air, all channels, W/(m²·sr).
    states : array_like, shape (4, n)
        States of the state relation, the hottest (stoichiometric) last.
    min_ratio : float, optional
        In (0, 1] (default :data:`THIN_RATIO`).

    Returns
    -------
    ndarray of bool, shape (n_out,)
        The channels kept; all of them when no pixel sees emission beyond ambient air, the
        least saturated one when none reaches ``min_ratio``.
    """
    if not 0 < min_ratio <= 1:
        raise ValueError(f"min_ratio must lie in (0, 1], got {min_ratio}")
    thin = channel_emission(scene, states)
    emitting = thin.sum(axis=1) > 0
    peak = thin[-1] @ channel_weights(scene)
    if not (band_peak > 0 and peak > 0):
        return np.ones(scene.out_wavenumber.size, dtype=bool)
    column = band_peak / peak  # m
    thick = channel_emission(scene, np.asarray(states)[:, emitting], column)
    ratio = thick / np.maximum(thin[emitting], np.finfo(float).tiny)
    keep = ratio.min(axis=0) >= min_ratio
    return keep if keep.any() else ratio.min(axis=0) == ratio.min(axis=0).max()
