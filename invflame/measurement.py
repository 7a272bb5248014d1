r"""Measured spectra and their noise: what the data term of a reconstruction compares against.

A :class:`Measurement` comes from a simulation (:mod:`invflame.experiments.measurement`) or
from a measurement file (:mod:`invflame.measurement_file`); either way it is the spectra per
pixel, their noise standard deviation and how they were made.

Spectral windows per camera
---------------------------
The cameras of a rig may come from different instruments and measure different bands. Each
camera may state its own spectral window ``[min, max]`` in cm⁻¹ (a rig file's ``window``,
:mod:`invflame.geometry.rig_file`; a measurement file's variable ``window``): it measures the
channels :math:`\eta` of the instrument's output grid with ``min <= eta <= max`` and no
others; a camera without a window measures every channel. The model renders every channel
for every pixel (one instrument lineshape: the resolution and the apodization may not differ
between cameras), and the data term weighs only the measured ones: a channel outside its
camera's window has ``sigma = inf`` (weight 0) and ``data = 0`` (:meth:`Measurement.restricted`),
is not counted in :attr:`~Measurement.n_measurements`, is NaN in a measurement file and is left
out of the figures.

In memory, the windows of a rig are a tuple with one entry per camera, a ``(min, max)`` pair in
cm⁻¹ or None (no window of its own), or None as a whole when no camera states one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from invflame.errors import InputDataError

WINDOW_TOLERANCE = 1e-9
"""cm⁻¹ by which a channel may lie beyond a window's edge and still count as inside it."""


@dataclass(frozen=True)
class Measurement:
    """Measured spectra and their noise.

    Attributes
    ----------
    data : ndarray, shape (n_rays, n_out)
        Spectra per pixel in W/(m²·sr·cm⁻¹) (0 where masked).
    sigma : ndarray, shape (n_out,) or (n_rays, n_out)
        Noise standard deviation per output wavenumber, or per value, in W/(m²·sr·cm⁻¹)
        (ones for noise-free data, so that a whitened misfit is the plain sum of squares);
        ``inf`` for a masked value (a bad pixel or wavenumber, a channel outside its camera's
        window: weight 0 in the data term, see :mod:`invflame.measurement_file`).
    noisy : bool
        Whether noise was added (False: ``sigma`` carries no information).
    provenance : dict
        How the data were made (grid, sub-rays, step, noise).
    """

    data: np.ndarray
    sigma: np.ndarray
    noisy: bool
    provenance: dict

    @property
    def measured(self) -> np.ndarray:
        """Where a value was measured (finite ``sigma``): bool, shape (n_rays, n_out)."""
        return np.isfinite(np.broadcast_to(self.sigma, self.data.shape))

    @property
    def n_measurements(self) -> int:
        """Number of measured values M (pixels × output wavenumbers), masked ones left out."""
        return int(np.count_nonzero(self.measured))

    @property
    def unweighted_sigma(self) -> np.ndarray | None:
        """σ of a misfit that weighs every measured value alike and no masked one: None
        when nothing is masked, else 1 where measured and ``inf`` where masked, shape
        (n_rays, n_out)."""
        measured = self.measured
        return None if measured.all() else np.where(measured, 1.0, np.inf)

    def restricted(self, channels: np.ndarray) -> Measurement:
        """This measurement with the values outside ``channels`` masked (``data`` 0,
        ``sigma`` inf).

        Parameters
        ----------
        channels : ndarray of bool, shape (n_rays, n_out)
            The values measured, e.g. :func:`channel_mask` of the cameras' windows.
        """
        if np.all(channels):
            return self
        sigma = np.where(channels, np.broadcast_to(self.sigma, self.data.shape), np.inf)
        return Measurement(np.where(channels, self.data, 0).astype(self.data.dtype), sigma,
                           self.noisy, self.provenance)


def stated(windows) -> bool:
    """Whether some camera states a window of its own.

    Parameters
    ----------
    windows : tuple of ((float, float) or None), or None
        One window (cm⁻¹) per camera, or None.
    """
    return windows is not None and any(window is not None for window in windows)


def window_text(window) -> str:
    """A window ``(min, max)`` in cm⁻¹ as ``"min-max cm-1"``, for messages."""
    return f"{window[0]:g}-{window[1]:g} cm-1"


def camera_channels(windows, wavenumber, n_cameras: int) -> np.ndarray:
    """The channels each camera measures.

    Parameters
    ----------
    windows : tuple of ((float, float) or None), or None
        One window (cm⁻¹) per camera, or None: every camera measures every channel.
    wavenumber : array_like, shape (n_out,)
        The instrument's channels in cm⁻¹.
    n_cameras : int
        Number of cameras.

    Returns
    -------
    ndarray of bool, shape (n_cameras, n_out)
        True where the camera measures the channel.
    """
    eta = np.asarray(wavenumber, np.float64)
    if not stated(windows):
        return np.ones((n_cameras, eta.size), bool)
    if len(windows) != n_cameras:
        raise ValueError(f"give one window (or None) per camera: {n_cameras} cameras, "
                         f"{len(windows)} windows")
    return np.stack([np.ones(eta.size, bool) if window is None else
                     (eta >= window[0] - WINDOW_TOLERANCE) & (eta <= window[1] + WINDOW_TOLERANCE)
                     for window in windows])


def channel_mask(rig, windows, wavenumber) -> np.ndarray:
    """The channels each pixel measures: its camera's (:func:`camera_channels`).

    Parameters
    ----------
    rig : invflame.geometry.CameraRig
        The cameras; pixels are stacked camera after camera.
    windows : tuple of ((float, float) or None), or None
        One window (cm⁻¹) per camera, or None.
    wavenumber : array_like, shape (n_out,)
        The instrument's channels in cm⁻¹.

    Returns
    -------
    ndarray of bool, shape (n_rays, n_out)
        True where the pixel measures the channel.
    """
    per_camera = camera_channels(windows, wavenumber, rig.n_cameras)
    return np.repeat(per_camera, np.diff(rig.ray_offsets), axis=0)


def check_windows(windows, wavenumber, where: str, what: str) -> None:
    """Refuse a camera window that holds none of the instrument's channels.

    Parameters
    ----------
    windows : tuple of ((float, float) or None), or None
        One window (cm⁻¹) per camera, or None (nothing to check).
    wavenumber : array_like, shape (n_out,)
        The instrument's channels in cm⁻¹.
    where : str
        What states the windows (a file), for the message.
    what : str
        What the channels are, for the message (e.g. ``"simulated"``).

    Raises
    ------
    InputDataError
        Naming ``where``, the camera and the key ``'window'``.
    """
    if not stated(windows):
        return
    eta = np.asarray(wavenumber, np.float64)
    for camera, inside in enumerate(camera_channels(windows, eta, len(windows))):
        if not inside.any():
            raise InputDataError(
                f"{where}: camera {camera}: 'window' = {window_text(windows[camera])} holds "
                f"none of the {eta.size} {what} channels {eta.min():g}-{eta.max():g} cm-1: "
                "widen the camera's window to hold at least one of them")


def combined_windows(first, second, where: str, other: str):
    """Camera by camera, the channels both ``first`` and ``second`` let through (a camera's
    window in a measurement file and in the configuration's rig).

    Parameters
    ----------
    first, second : tuple of ((float, float) or None), or None
        One window (cm⁻¹) per camera each, or None.
    where : str
        What states ``second`` (e.g. the rig file), for the message.
    other : str
        What states ``first``, for the message.

    Returns
    -------
    tuple of ((float, float) or None), or None
        None when neither states a window.

    Raises
    ------
    InputDataError
        For a camera whose two windows do not overlap, naming ``where``, the camera and the
        key ``'window'``.
    """
    if not stated(second):
        return first if stated(first) else None
    if not stated(first):
        return tuple(second)
    both = []
    for camera, (a, b) in enumerate(zip(first, second, strict=True)):
        if a is None or b is None:
            both.append(b if a is None else a)
            continue
        low, high = max(a[0], b[0]), min(a[1], b[1])
        if low >= high:
            raise InputDataError(f"{where}: camera {camera}: 'window' = {window_text(b)} does "
                                 f"not overlap {other}'s {window_text(a)} for that camera: "
                                 "give the camera's window of the instrument that measured it")
        both.append((low, high))
    return tuple(both)
