"""Measured against simulated spectra: the brightest pixel's spectrum and every camera's band
image, for a rig of any cameras (each with its own pixel counts)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from invflame.geometry import CameraRig  # noqa: E402

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
                             label: str = "reconstruction", path=None, dpi: int = 130):
    """The brightest measured pixel's spectrum against the simulated one, and each camera's
    band radiance, measured (top row) and simulated (bottom row), on one colour scale.

    Parameters
    ----------
    wavenumber : array_like, shape (n_out,)
        Output wavenumbers in cm⁻¹, evenly spaced.
    measured, simulated : array_like, shape (n_rays, n_out)
        Spectra in W/(m²·sr·cm⁻¹), one per pixel of ``rig``, camera after camera.
    rig : CameraRig
        The cameras; each camera's images have its own ``(nv, nu)`` pixels.
    label : str, optional
        What the simulated spectra were computed from (named in the legend and titles).
    path : str or os.PathLike, optional
        Write a PNG there (parent folders created).
    dpi : int, optional
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
        The spectrum panel, then two image panels per camera (measured, simulated), then the
        colour bar of the band radiance in W/(m²·sr).

    Raises
    ------
    ValueError
        If the spectra do not hold one row per pixel of the rig.
    """
    eta = np.asarray(wavenumber, dtype=np.float64)
    measured, simulated = np.asarray(measured), np.asarray(simulated)
    if measured.shape != simulated.shape or measured.shape[:1] != (rig.n_rays,):
        raise ValueError(f"measured {measured.shape} and simulated {simulated.shape} spectra "
                         f"must both hold one row per pixel of the rig: {rig.n_rays} pixels "
                         f"over cameras of {list(rig.image_shapes)} (rows, columns)")
    step = eta[1] - eta[0]
    images = {"measured": rig.split_images(measured.sum(axis=1) * step),
              f"simulated from {label}": rig.split_images(simulated.sum(axis=1) * step)}
    vmax = max(float(image.max()) for row in images.values() for image in row)
    brightest = int(np.argmax(measured.sum(axis=1)))
    camera, row, column = pixel_of_ray(rig, brightest)

    fig = plt.figure(layout="constrained", figsize=(
        _SPECTRUM_INCHES + _IMAGE_INCHES * rig.n_cameras + 1.0, 5.0))
    cells = fig.add_gridspec(2, rig.n_cameras + 1,
                             width_ratios=[_SPECTRUM_INCHES] + [_IMAGE_INCHES] * rig.n_cameras)
    spectrum = fig.add_subplot(cells[:, 0])
    spectrum.plot(eta, measured[brightest], "k.-", label="measured")
    spectrum.plot(eta, simulated[brightest], "r-", label=f"simulated from {label}")
    spectrum.set(xlabel="wavenumber [cm⁻¹]", ylabel="radiance [W/(m²·sr·cm⁻¹)]",
                 title=f"brightest pixel: camera {camera + 1}, row {row + 1}, column "
                       f"{column + 1} (ray {brightest})")
    spectrum.legend(fontsize=8)
    panels = []
    for r, (what, per_camera) in enumerate(images.items()):
        for c, image in enumerate(per_camera):
            ax = fig.add_subplot(cells[r, c + 1])
            shown = ax.imshow(image, cmap="inferno", vmin=0.0, vmax=vmax)
            if c == camera:
                ax.plot(column, row, "s", markersize=8, markerfacecolor="none",
                        markeredgecolor="cyan")
            rows, columns = image.shape
            ax.set_title(f"camera {c + 1} ({columns}×{rows} px)\n{what}", fontsize=8)
            ax.set(xticks=[], yticks=[])
            panels.append(ax)
    fig.colorbar(shown, ax=panels, label="band radiance [W/(m²·sr)]", shrink=0.8)
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi)
    return fig
