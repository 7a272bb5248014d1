"""Measured against simulated spectra: the brightest pixel's spectrum and every camera's band
image, for a rig of any cameras (each with its own pixel counts and spectral window)."""

from __future__ import annotations

from itertools import pairwise

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.geometry import CameraRig  # noqa: E402
from invflame.plotting import save_figure

_IMAGE_INCHES = 2.4  # width of one camera's column of images
_SPECTRUM_INCHES = 5.0  # width of the spectrum panel


def pixel_of_ray(rig: CameraRig, ray: int) -> tuple[int, int, int]:
    """The camera, image row and image column of a ray of the rig's stacked ray list.

    Parameters
    ----------
    rig : CameraRig
        The cameras; rays are stacked camera after camera, row-major within a camera.
    ray : int
        Index in ``0 .. rig.n_rays - 1``.

    Returns
    -------
    (camera, row, column) : tuple of int
        Zero-based; row 0 is the top of the image.
    """
    if not 0 <= ray < rig.n_rays:
        raise ValueError(f"ray {ray} is outside the rig's {rig.n_rays} rays")
    camera = int(np.searchsorted(rig.ray_offsets, ray, side="right")) - 1
    row, column = divmod(ray - int(rig.ray_offsets[camera]), rig.cameras[camera].n_pixels[0])
    return camera, row, column


def plot_spectrum_and_images(wavenumber, measured, simulated, rig: CameraRig,
                             label: str = "reconstruction", path=None, dpi: int = 130,
                             channels=None):
    """The brightest measured pixel's spectrum against the simulated one, and each camera's
    band radiance, measured (top row) and simulated (bottom row), on one colour scale.

    Only measured values are drawn: a camera's spectra over the channels it measures, its
    band images summed over them (measured and simulated alike). When the cameras measure
    different channels (each its own spectral window, :mod:`invflame.measurement`), the
    spectrum panel shows the brightest pixel of every camera, and each camera's images name
    its channels.

    Parameters
    ----------
    wavenumber : array_like, shape (n_out,)
        Output wavenumbers in cm⁻¹, evenly spaced.
    measured : array_like, shape (n_rays, n_out)
        Spectra in W/(m²·sr·cm⁻¹), one per pixel of ``rig``, camera after camera.
    simulated : array_like, shape (n_rays, n_out), or None
        Spectra simulated from ``label``, W/(m²·sr·cm⁻¹); None: the measured ones alone
        (one row of images).
    rig : CameraRig
        The cameras; each camera's images have its own ``(nv, nu)`` pixels.
    label : str, optional
        What the simulated spectra were computed from (named in the legend and titles).
    path : str or os.PathLike, optional
        Write a PNG there (parent folders created).
    dpi : int, optional
        Resolution of the PNG.
    channels : array_like of bool, shape (n_rays, n_out), optional
        Where a value was measured (default: everywhere), e.g.
        :attr:`invflame.measurement.Measurement.measured`.

    Returns
    -------
    matplotlib.figure.Figure
        The spectrum panel, then one or two image panels per camera (measured, simulated),
        then the colour bar of the band radiance in W/(m²·sr).

    Raises
    ------
    ValueError
        If the spectra do not hold one row per pixel of the rig.
    """
    eta = np.asarray(wavenumber, dtype=np.float64)
    rows = {"measured": np.asarray(measured)}
    if simulated is not None:
        rows[f"simulated from {label}"] = np.asarray(simulated)
    shape = rows["measured"].shape
    if any(values.shape != shape for values in rows.values()) or shape[:1] != (rig.n_rays,):
        raise ValueError(f"measured {shape} and simulated {np.shape(simulated)} spectra "
                         f"must both hold one row per pixel of the rig: {rig.n_rays} pixels "
                         f"over cameras of {list(rig.image_shapes)} (rows, columns)")
    kept = np.ones(shape, bool) if channels is None else np.broadcast_to(
        np.asarray(channels, bool), shape)
    step = eta[1] - eta[0]
    images = {what: rig.split_images(np.where(kept, values, 0).sum(axis=1) * step)
              for what, values in rows.items()}
    vmax = max(float(image.max()) for row in images.values() for image in row)
    brightness = np.where(kept, rows["measured"], 0).sum(axis=1)
    bounds = list(pairwise(rig.ray_offsets))
    per_camera = [kept[start:stop].any(axis=0) for start, stop in bounds]
    own = any(not np.array_equal(c, per_camera[0]) for c in per_camera)  # windows differ
    shown = ([start + int(np.argmax(brightness[start:stop])) for start, stop in bounds]
             if own else [int(np.argmax(brightness))])

    fig = plt.figure(layout="constrained", figsize=(
        _SPECTRUM_INCHES + _IMAGE_INCHES * rig.n_cameras + 1.0, max(3.6, 2.5 * len(rows))))
    cells = fig.add_gridspec(len(rows), rig.n_cameras + 1,
                             width_ratios=[_SPECTRUM_INCHES] + [_IMAGE_INCHES] * rig.n_cameras)
    spectrum = fig.add_subplot(cells[:, 0])
    marks = [pixel_of_ray(rig, ray) for ray in shown]
    for index, (ray, (camera, _, _)) in enumerate(zip(shown, marks, strict=True)):
        for number, ((what, values), (fmt, colour)) in enumerate(zip(
                rows.items(), ((".-", "k"), ("-", "r")), strict=False)):
            named = (f"camera {camera + 1}, {_channels_text(eta[per_camera[camera]])}"
                     if number == 0 else "_") if own else what  # own: one entry per camera
            spectrum.plot(eta, np.where(kept[ray], values[ray], np.nan), fmt,
                          color=f"C{index}" if own else colour, label=named)
    camera, row, column = marks[0]
    spectrum.set(xlabel="wavenumber [cm⁻¹]", ylabel="radiance [W/(m²·sr·cm⁻¹)]",
                 title="brightest pixel of each camera\n(dots: measured"
                       + (f", lines: simulated from {label})" if simulated is not None else ")")
                 if own else f"brightest pixel: camera {camera + 1}, row {row + 1}, column "
                             f"{column + 1} (ray {shown[0]})")
    spectrum.legend(fontsize=8)
    panels = []
    for r, (what, per_image) in enumerate(images.items()):
        for c, image in enumerate(per_image):
            ax = fig.add_subplot(cells[r, c + 1])
            shown_image = ax.imshow(image, cmap="inferno", vmin=0.0, vmax=vmax)
            for camera, row, column in marks:
                if camera == c:
                    ax.plot(column, row, "s", markersize=8, markerfacecolor="none",
                            markeredgecolor="cyan")
            n_rows, n_columns = image.shape
            measures = f"\n{_channels_text(eta[per_camera[c]])}" if own else ""
            ax.set_title(f"camera {c + 1} ({n_columns}×{n_rows} px){measures}\n{what}",
                         fontsize=8)
            ax.set(xticks=[], yticks=[])
            panels.append(ax)
    fig.colorbar(shown_image, ax=panels, label="band radiance [W/(m²·sr)]", shrink=0.8)
    return save_figure(fig, path, dpi)


def _channels_text(channels: np.ndarray) -> str:
    """The span of a camera's channels (cm⁻¹) in words."""
    return f"{channels.min():g}–{channels.max():g} cm⁻¹" if channels.size else "no channel"
