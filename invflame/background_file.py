"""Background spectra files, and the background of a configuration's ``[background]``.

Files (:func:`read_background`, :func:`write_background`) are NetCDF: a variable
``background`` (camera, wavenumber) in W/(m2 sr cm-1) (``units``
:data:`~invflame.measurement_file.RADIANCE_UNITS`) with the coordinate ``wavenumber`` in
cm-1, or a measurement file (:mod:`invflame.measurement_file`) of a frame without the flame,
whose spectra are averaged over each camera's pixels (bad pixels and wavenumbers left out).
Configuration: ``[background] kind = "none" | "blackbody" | "file"``, ``temperature`` (K),
``emissivity``, ``file`` (:func:`background_from_config`). The backgrounds themselves are
those of :mod:`invflame.background`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from invflame.atomic_files import read_netcdf, write_atomic
from invflame.background import Background, BlackbodyWall, MeasuredBackground
from invflame.errors import InputDataError
from invflame.measurement_file import RADIANCE_UNITS, read_measurement

KINDS = ("none", "blackbody", "file")
"""Values of ``background.kind`` in a configuration."""


def write_background(background: MeasuredBackground, path) -> Path:
    """Write measured background spectra as NetCDF (``background`` (camera, wavenumber) in
    W/(m2 sr cm-1), coordinate ``wavenumber`` in cm-1), atomically; returns ``path``."""
    dataset = xr.Dataset(
        {"background": (("camera", "wavenumber"), background.radiance,
                        {"units": RADIANCE_UNITS, "long_name": "background spectral radiance"})},
        coords={"wavenumber": ("wavenumber", background.wavenumber,
                               {"units": "cm-1", "long_name": "wavenumber"})},
        attrs={"title": "invflame background", "Conventions": "CF-1.10"})
    content = dataset.to_netcdf(engine="netcdf4", format="NETCDF4")
    return write_atomic(path, lambda handle: handle.write(content))


def read_background(path) -> MeasuredBackground:
    """Background spectra from a NetCDF file: a ``background`` variable (camera, wavenumber),
    or a measurement file of a frame without the flame (its spectra averaged per camera).

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    InputDataError
        For a file that is neither, or whose values are not usable; the message names the file
        and the variable.
    """
    path = Path(path)
    dataset = read_netcdf(path, "background file")
    try:
        if "background" in dataset.variables:
            variable = dataset["background"]
            if variable.dims != ("camera", "wavenumber"):
                raise InputDataError(f"{path}: variable 'background' has dimensions "
                                     f"{variable.dims}, expected ('camera', 'wavenumber')")
            if variable.attrs.get("units") != RADIANCE_UNITS:
                raise InputDataError(f"{path}: variable 'background' has units "
                                     f"{variable.attrs.get('units')!r}, expected "
                                     f"{RADIANCE_UNITS!r}")
            return MeasuredBackground(dataset["wavenumber"].values, variable.values, str(path))
        if "radiance" in dataset.variables:
            return _frame_background(path)
    except ValueError as err:
        raise InputDataError(str(err)) from err
    raise InputDataError(f"{path}: holds neither a variable 'background' (camera, wavenumber) "
                         "nor a measurement's 'radiance'; see invflame.background_file")


def _frame_background(path: Path) -> MeasuredBackground:
    """Per-camera mean spectrum of a measurement file, bad pixels and wavenumbers left out.

    A wavenumber some camera does not measure (outside its own spectral window, or masked in
    all its pixels) takes that camera's nearest measured value: the lineshape of a channel
    near the window's edge reaches a few resolutions beyond it, where a wall's spectrum is
    about as bright as at the edge.
    """
    measured = read_measurement(path)
    good = measured.measurement.measured
    keep = good.any(axis=0)
    wavenumber = measured.wavenumber[keep]
    radiance = []
    for camera, (data, ok) in enumerate(zip(measured.rig.split_images(measured.measurement.data),
                                            measured.rig.split_images(good), strict=True)):
        data, ok = data.reshape(-1, data.shape[-1])[:, keep], ok.reshape(-1, ok.shape[-1])[:, keep]
        counts = ok.sum(axis=0)
        mean = np.sum(np.where(ok, data, 0.0), axis=0) / np.maximum(counts, 1)
        seen = counts > 0
        if not seen.any():
            raise InputDataError(f"{path}: camera {camera} measures no value (every pixel or "
                                 "wavenumber masked); a background needs each camera's spectrum")
        radiance.append(np.interp(wavenumber, wavenumber[seen], mean[seen]))
    return MeasuredBackground(wavenumber, np.array(radiance), str(path))


def background_from_config(section: dict) -> Background | None:
    """The background of a configuration's ``[background]`` section (None for ``"none"``).

    Parameters
    ----------
    section : dict
        ``kind`` (one of :data:`KINDS`), ``temperature`` (K) and ``emissivity`` for
        ``"blackbody"``, ``file`` (a path) for ``"file"``.
    """
    kind = section["kind"]
    if kind == "blackbody":
        return BlackbodyWall(section["temperature"], section["emissivity"])
    if kind == "file":
        return read_background(section["file"])
    return None
