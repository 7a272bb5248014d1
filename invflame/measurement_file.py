r"""Measured spectra as a NetCDF file: radiance, wavenumbers, cameras, instrument, noise, mask.

A measurement file holds what a reconstruction needs from the instrument, with no ground
truth: ``invflame simulate --out m.nc`` writes one, ``[data] source = "m.nc"`` makes
``invflame run`` reconstruct from it. NetCDF-4 through ``xarray`` (``netCDF4`` engine), CF-style
as :mod:`invflame.export`, every variable with its ``units``:

=================== ========================== =========================================
variable            dimensions                 units: meaning
=================== ========================== =========================================
``radiance``        (camera, v, u, wavenumber) W/(m2 sr cm-1): the measured spectra,
                                               ``image[v, u]`` with row 0 at the top
``wavenumber``      (wavenumber)               cm-1, coordinate: any strictly monotone
                                               grid of positive values (irregular allowed)
``nesr``            (wavenumber)               W/(m2 sr cm-1): noise standard deviation
                                               per wavenumber, or
``sigma``           (camera, v, u, wavenumber) W/(m2 sr cm-1): one per value (neither:
                                               noise unknown, an unweighted misfit)
``bad_pixel``       (camera, v, u)             optional, 1 for a pixel to leave out, else 0
                                               (absent: every pixel kept)
``bad_wavenumber``  (wavenumber)               optional, 1 for a wavenumber to leave out,
                                               else 0 (absent: every wavenumber kept)
``window``          (camera, bound)            cm-1, optional: each camera's own spectral
                                               window [min, max]; NaN, NaN for a camera
                                               measuring every wavenumber (absent: all do)
``pixels``          (camera, uv)               optional, integers: each camera's pixel
                                               counts (nu, nv) (absent: the sizes of u, v)
``position``        (camera, xyz)              m: the cameras' pinholes
``look_at``         (camera, xyz)              m: a point on each optical axis
``up``              (camera, xyz)              1: each image's up direction
``focal_length``    (camera)                   m
``sensor_size``     (camera, uv)               m: (width, height)
``principal_point`` (camera, uv)               pixel, optional: (u, v) from the top-left
                                               corner (absent: the sensor's centre)
=================== ========================== =========================================

The camera variables are the records of a rig file (:mod:`invflame.geometry.rig_file`),
with the pixel counts from ``pixels`` or the ``u`` and ``v`` dimensions, so the rig
round-trips to that format. Cameras of different pixel counts share the ``v`` and ``u``
dimensions of the largest: camera ``c``'s image is ``radiance[c, :nv, :nu]``, the rest is
padding (NaN, ``bad_pixel`` 1), not data. Global attributes: ``resolution`` (cm-1,
1/MOPD, finer than the measured band; one for all cameras) and ``apodization``
(``"triangular"``) of the instrument, ``noise`` (``"nesr"``, ``"sigma"`` or ``"none"``),
``provenance`` (JSON: how the data were made), ``Conventions``, ``invflame_version``,
``date_created``. :func:`read_measurement` refuses a malformed file and
warns about radiance no flame can have emitted (:mod:`invflame.measurement_checks`); the user
guide's page *Measurement files* shows how to write one by hand.

**Masks.** ``radiance`` (and ``nesr`` or ``sigma``) may be NaN only where masked: a bad
pixel, a bad wavenumber, or a wavenumber outside the camera's ``window`` (a camera measures
the wavenumbers :math:`\eta` with ``min <= eta <= max`` of its window, see
:mod:`invflame.measurement`; the window may differ per camera, the resolution may not). In
memory (:class:`~invflame.measurement.Measurement`), a masked value has ``sigma = inf`` —
weight 0 in the data term (:func:`invflame.representations.whitening.noise_weights`) — and
``data = 0``; ``n_measurements`` counts only the others.
"""

from __future__ import annotations

import datetime
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from invflame import __version__
from invflame.atomic_files import read_netcdf, write_atomic
from invflame.geometry import CameraRig
from invflame.geometry.rig_file import parse_rig, rig_records
from invflame.measurement import (
    Measurement,
    camera_channels,
    channel_mask,
    check_windows,
    combined_windows,
    stated,
    window_text,
)
from invflame.measurement_checks import (
    DIMS,
    RADIANCE_UNITS,
    MeasurementReader,
    warn_implausible,
)

CAMERA_VARIABLES = {
    # variable: (dimensions, units, long name)
    "position": (("camera", "xyz"), "m", "camera pinhole"),
    "look_at": (("camera", "xyz"), "m", "point on the optical axis"),
    "up": (("camera", "xyz"), "1", "up direction of the image"),
    "focal_length": (("camera",), "m", "focal length"),
    "sensor_size": (("camera", "uv"), "m", "sensor width and height"),
    "principal_point": (("camera", "uv"), "pixel",
                        "optical axis on the sensor, from the image's top-left corner"),
}
"""The rig's variables: the keys of a rig file's camera records."""


@dataclass(frozen=True, eq=False)
class MeasurementFile:
    """A measurement with the cameras and instrument that made it.

    Attributes
    ----------
    measurement : Measurement
        Spectra ``(n_pixels, n_out)`` in W/(m²·sr·cm⁻¹), pixels camera after camera in the
        rig's ray order, and their noise σ (``inf`` where masked, and outside a camera's
        window).
    rig : CameraRig
        The cameras, each with its own pixel counts.
    wavenumber : ndarray, shape (n_out,)
        The measured wavenumbers in cm⁻¹.
    resolution : float
        The instrument's resolution 1/MOPD in cm⁻¹.
    apodization : str
        The instrument's apodization (one of
        :data:`invflame.geometry.rig_file.APODIZATIONS`).
    windows : tuple of ((float, float) or None), or None
        Each camera's own spectral window ``(min, max)`` in cm⁻¹ (None: every wavenumber);
        None when no camera has one (:mod:`invflame.measurement`).
    """

    measurement: Measurement
    rig: CameraRig
    wavenumber: np.ndarray
    resolution: float
    apodization: str = "triangular"
    windows: tuple | None = None

    def instrument(self, source: str) -> dict:
        """The instrument the data set for a run in place of ``[instrument]``, for its records.

        Parameters
        ----------
        source : str
            The file, as the configuration names it (``data.source``).

        Returns
        -------
        dict
            ``from`` (where the settings come from, in words), ``resolution`` (cm⁻¹),
            ``apodization``, ``wavenumber_min`` and ``wavenumber_max`` (cm⁻¹),
            ``n_wavenumbers`` and ``windows`` (each camera's ``[min, max]`` in cm⁻¹ or None;
            None when no camera has one).
        """
        return {"from": f"the measurement file data.source = {source!r}, in place of "
                        "[instrument]",
                "resolution": float(self.resolution), "apodization": self.apodization,
                "wavenumber_min": float(np.min(self.wavenumber)),
                "wavenumber_max": float(np.max(self.wavenumber)),
                "n_wavenumbers": int(self.wavenumber.size),
                "windows": None if not stated(self.windows) else [
                    None if w is None else [float(w[0]), float(w[1])] for w in self.windows]}

    def instrument_comment(self, source: str) -> str:
        """TOML comment lines saying what :meth:`instrument` says, for a run's
        ``config.toml`` (whose ``[instrument]`` the data replace)."""
        used = self.instrument(source)
        return (f"# [instrument] is not used: the measurement file data.source = {source!r} "
                "sets the instrument:\n"
                f"# resolution = {used['resolution']:g} cm-1, apodization = "
                f"{used['apodization']!r}, {used['n_wavenumbers']} wavenumbers "
                f"{used['wavenumber_min']:g}-{used['wavenumber_max']:g} cm-1"
                + "".join(f", camera {camera} only {window_text(window)}"
                          for camera, window in enumerate(self.windows or ())
                          if window is not None) + "\n")


def _mask(measurement: Measurement, channels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bad pixels ``(n_pixels,)`` and bad wavenumbers ``(n_out,)`` of a measurement's inf σ,
    the values outside ``channels`` (the cameras' windows, ``(n_pixels, n_out)``) aside."""
    masked = ~measurement.measured | ~channels
    pixels, wavenumbers = masked.all(axis=1), masked.all(axis=0)
    if np.any(masked & channels & ~pixels[:, None] & ~wavenumbers[None, :]):
        raise ValueError("masked values (sigma = inf) must make up whole pixels or whole "
                         "wavenumbers, or lie outside their camera's window, to be written: a "
                         "measurement file masks bad pixels, bad wavenumbers and each camera's "
                         "channels outside its window")
    return pixels, wavenumbers


def _images(rig: CameraRig, values: np.ndarray, fill) -> np.ndarray:
    """Per-pixel ``values`` ``(n_pixels, ...)`` as images ``(n_cameras, nv, nu, ...)`` of the
    largest pixel counts, each camera's at the top left, padded with ``fill``."""
    nv, nu = np.max(rig.image_shapes, axis=0)
    out = np.full((rig.n_cameras, nv, nu, *values.shape[1:]), fill, values.dtype)
    for padded, image in zip(out, rig.split_images(values), strict=True):
        padded[:image.shape[0], :image.shape[1]] = image
    return out


def measurement_dataset(measured: MeasurementFile) -> xr.Dataset:
    """A measurement as an ``xarray.Dataset`` in the layout of the module docstring.

    Raises
    ------
    ValueError
        For shapes that do not match the rig and the wavenumbers, or masked values that are
        neither whole pixels or wavenumbers nor outside their camera's window.
    """
    m, rig = measured.measurement, measured.rig
    wavenumber = np.asarray(measured.wavenumber, np.float64)
    if m.data.shape != (rig.n_rays, wavenumber.size):
        raise ValueError(f"the measurement's data {m.data.shape} do not match the rig's "
                         f"{rig.n_rays} pixels and {wavenumber.size} wavenumbers")
    channels = channel_mask(rig, measured.windows, wavenumber)
    bad_pixel, bad_wavenumber = _mask(m, channels)
    masked = bad_pixel[:, None] | bad_wavenumber[None, :] | ~channels

    def images(values):
        return _images(rig, np.where(masked, np.nan, values), np.nan)

    variables = {"radiance": (DIMS, images(m.data),
                              {"units": RADIANCE_UNITS, "long_name": "measured spectral radiance"}),
                 "bad_pixel": (DIMS[:3], _images(rig, bad_pixel.astype(np.int8), 1),
                               {"long_name": "1: pixel left out of the data term"}),
                 "bad_wavenumber": (("wavenumber",), bad_wavenumber.astype(np.int8),
                                    {"long_name": "1: wavenumber left out of the data term"}),
                 "pixels": (("camera", "uv"), np.array([c.n_pixels for c in rig.cameras],
                                                       np.int32),
                            {"long_name": "pixel counts (nu, nv) of each camera's image"})}
    if stated(measured.windows):
        variables["window"] = (("camera", "bound"), np.array(
            [(np.nan, np.nan) if w is None else w for w in measured.windows], np.float64),
            {"units": "cm-1", "long_name": "spectral window [min, max] of each camera"})
    sigma = np.asarray(m.sigma, np.float64)
    noise = "none" if not m.noisy else "nesr" if sigma.ndim == 1 else "sigma"
    if noise == "nesr":
        variables["nesr"] = (("wavenumber",), np.where(bad_wavenumber, np.nan, sigma),
                             {"units": RADIANCE_UNITS,
                              "long_name": "noise-equivalent spectral radiance"})
    elif noise == "sigma":
        variables["sigma"] = (DIMS, images(np.broadcast_to(sigma, m.data.shape)),
                              {"units": RADIANCE_UNITS,
                               "long_name": "noise standard deviation per value"})
    for (name, value), (dims, units, long_name) in zip(
            _camera_columns(rig).items(), CAMERA_VARIABLES.values(), strict=True):
        variables[name] = (dims, value, {"units": units, "long_name": long_name})
    now = datetime.datetime.now(datetime.UTC).replace(microsecond=0).isoformat()
    attrs = {"Conventions": "CF-1.10", "title": "invflame measurement",
             "source": f"invflame {__version__}", "invflame_version": __version__,
             "date_created": now, "resolution": float(measured.resolution),
             "resolution_units": "cm-1", "apodization": measured.apodization, "noise": noise,
             "provenance": json.dumps(m.provenance)}
    coords = {"wavenumber": ("wavenumber", wavenumber,
                             {"units": "cm-1", "long_name": "wavenumber"})}
    return xr.Dataset(variables, coords=coords, attrs=attrs)


def _camera_columns(rig: CameraRig) -> dict[str, np.ndarray]:
    """The rig's records as one array per key of :data:`CAMERA_VARIABLES`."""
    records = rig_records(rig)
    return {key: np.array([r[key] for r in records], np.float64) for key in CAMERA_VARIABLES}


def write_measurement(measured: MeasurementFile, path) -> Path:
    """Write a measurement file atomically (NetCDF-4; see the module docstring).

    Parameters
    ----------
    measured : MeasurementFile
        Spectra, noise, mask, cameras and instrument.
    path : str or os.PathLike
        Destination (``.nc``); parent folders are created.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    dataset = measurement_dataset(measured)
    encoding = {name: {"zlib": True, "complevel": 4} for name in ("radiance", "sigma")
                if name in dataset}
    content = dataset.to_netcdf(engine="netcdf4", format="NETCDF4", encoding=encoding)
    return write_atomic(path, lambda handle: handle.write(content))


def read_measurement(path, rig: CameraRig | None = None, rig_source: str = "the rig",
                     windows=None) -> MeasurementFile:
    """Read a measurement file (see the module docstring), checking every variable.

    Parameters
    ----------
    path : str or os.PathLike
        A file written by :func:`write_measurement` or by a user in its layout.
    rig : CameraRig, optional
        Cameras the data must come from (a configuration's rig): the file's must be the same.
    rig_source : str, optional
        What gave ``rig`` and ``windows``, for messages (e.g. the rig file's name).
    windows : tuple of ((float, float) or None), optional
        Each camera's own spectral window in cm⁻¹ as the configuration's rig states it
        (:class:`~invflame.geometry.rig_file.RigSpec`): a camera measures only the wavenumbers
        inside both its window in the file and this one.

    Returns
    -------
    MeasurementFile
        Masked values have ``sigma = inf`` and ``data = 0``. ``sigma`` is per wavenumber for
        ``nesr`` (or unknown noise, σ = 1, ``noisy`` False) when only whole wavenumbers are
        masked, else per value. ``windows`` are those of the file and of ``windows`` together.

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    InputDataError
        For a file that is not NetCDF, a missing required variable or attribute, wrong
        dimensions or units, a shape or camera that does not match ``rig``, NaN outside the
        mask, masks that are not 0/1 flags or leave out every pixel or wavenumber, wavenumbers
        that are not positive and strictly monotone, a resolution coarser than the measured
        band, noise that is not positive, pixel counts beyond the image dimensions, or a
        camera window that is not ``[min, max]`` with ``0 < min < max`` or holds none of the
        wavenumbers; the message names the file (or ``rig_source``) and the variable (or the
        camera and the key).

    Warns
    -----
    MeasurementWarning
        For a camera whose radiance no flame can have emitted as it stands: negative on the
        whole, or beyond a black body's at :data:`~invflame.measurement_checks.HOTTEST_FLAME`
        (:func:`~invflame.measurement_checks.warn_implausible`).
    """
    path = Path(path)
    dataset = read_netcdf(path, "measurement file")
    read = MeasurementReader(dataset, path)
    radiance = read.variable("radiance", DIMS, RADIANCE_UNITS)
    wavenumber = read.variable("wavenumber", ("wavenumber",), "cm-1").astype(np.float64)
    read.check_wavenumber(wavenumber)
    n_cameras, nv, nu, n_out = radiance.shape
    pixels = read.pixel_counts(n_cameras, nu, nv)
    records = {name: read.variable(name, dims, units, required=name != "principal_point")
               for name, (dims, units, _) in CAMERA_VARIABLES.items()}
    spec = parse_rig([{key: values[i].tolist() for key, values in records.items()
                       if values is not None} | {"pixels": pixels[i].tolist()}
                      for i in range(n_cameras)], str(path))
    if rig is not None:
        _check_same_rig(read, spec.rig, rig, rig_source)
    own = read.windows(n_cameras)
    check_windows(own, wavenumber, str(path), "measured")
    own = combined_windows(own, windows, rig_source, f"the measurement file {path}")
    check_windows(own, wavenumber, rig_source, "measured")
    inside = (np.arange(nv)[:, None] < pixels[:, None, None, 1]) & (
        np.arange(nu) < pixels[:, None, None, 0])  # (camera, v, u): not padding
    bad_pixel = read.flags("bad_pixel", DIMS[:3], "pixel") & inside
    bad_wavenumber = read.flags("bad_wavenumber", ("wavenumber",), "wavenumber")
    read.check_mask(bad_pixel[inside], bad_wavenumber)
    channels = camera_channels(own, wavenumber, n_cameras)
    masked = ((~inside | bad_pixel)[..., None] | bad_wavenumber
              | ~channels[:, None, None, :])  # radiance's shape
    read.check_finite(radiance.reshape(-1, n_out), masked.reshape(-1, n_out), wavenumber, nu, nv)
    noise, sigma = read.noise(n_out, masked, bad_wavenumber | ~channels.any(axis=0))
    resolution = read.attribute("resolution")
    read.check_resolution(resolution, wavenumber)
    apodization = read.apodization()
    try:
        provenance = json.loads(dataset.attrs.get("provenance", "{}"))
    except json.JSONDecodeError as err:
        read.fail(f"global attribute 'provenance' is not JSON: {err}")
    warn_implausible(radiance, None if noise == "none" else np.broadcast_to(sigma, masked.shape),
                     masked, wavenumber, path)
    kept = inside.reshape(-1)
    data, masked = radiance.reshape(-1, n_out)[kept], masked.reshape(-1, n_out)[kept]
    if sigma.ndim > 1 or np.any(masked & ~bad_wavenumber):
        sigma = np.where(masked, np.inf, np.broadcast_to(sigma, radiance.shape).reshape(
            -1, n_out)[kept])
    else:
        sigma = np.where(bad_wavenumber, np.inf, sigma)
    measurement = Measurement(np.where(masked, 0, data).astype(data.dtype), sigma,
                              noise != "none", provenance)
    return MeasurementFile(measurement, spec.rig, wavenumber, float(resolution), apodization,
                           own)


def _shapes(rig: CameraRig) -> str:
    """The image shapes ``(nv, nu)`` of a rig's cameras, in words."""
    shapes = rig.image_shapes
    return (f"image shape {shapes[0]}" if len(set(shapes)) == 1
            else f"image shapes {list(shapes)}")


def _check_same_rig(read: MeasurementReader, found: CameraRig, expected: CameraRig,
                    source: str) -> None:
    """Refuse a file whose cameras are not ``expected``'s, naming the first difference."""
    if found.image_shapes != expected.image_shapes:
        read.fail(f"variable 'radiance' holds {found.n_cameras} camera(s) of {_shapes(found)} "
                  f"(v, u) but {source} has {expected.n_cameras} of "
                  f"{list(expected.image_shapes)}: use the rig the data were measured with")
    mine, theirs = _camera_columns(found), _camera_columns(expected)
    for key in CAMERA_VARIABLES:
        differs = ~np.isclose(mine[key], theirs[key], rtol=1e-9, atol=1e-12)
        if differs.any():
            camera = int(np.argwhere(differs)[0][0])
            read.fail(f"variable {key!r} of camera {camera} is {mine[key][camera].tolist()} but "
                      f"{source} says {theirs[key][camera].tolist()}: use the rig the data were "
                      "measured with")
