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
``position``        (camera, xyz)              m: the cameras' pinholes
``look_at``         (camera, xyz)              m: a point on each optical axis
``up``              (camera, xyz)              1: each image's up direction
``focal_length``    (camera)                   m
``sensor_size``     (camera, uv)               m: (width, height)
``principal_point`` (camera, uv)               pixel, optional: (u, v) from the top-left
                                               corner (absent: the sensor's centre)
=================== ========================== =========================================

The camera variables are the records of a rig file (:mod:`invflame.geometry.rig_file`),
with the pixel counts from the ``u`` and ``v`` dimensions, so the rig round-trips to that
format. Global attributes: ``resolution`` (cm-1, 1/MOPD, finer than the measured band) and
``apodization`` (``"triangular"``) of the instrument, ``noise`` (``"nesr"``, ``"sigma"`` or
``"none"``), ``provenance`` (JSON: how the data were made), ``Conventions``,
``invflame_version``, ``date_created``. :func:`read_measurement` refuses a malformed file and
warns about radiance no flame can have emitted (:mod:`invflame.measurement_checks`); the user
guide's page *Measurement files* shows how to write one by hand.

**Masks.** ``radiance`` (and ``nesr`` or ``sigma``) may be NaN only where masked. In memory
(:class:`~invflame.measurement.Measurement`), a masked value has ``sigma = inf`` —
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
from invflame.geometry.rig_file import APODIZATIONS, parse_rig, rig_records
from invflame.measurement import Measurement
from invflame.measurement_checks import MeasurementReader, warn_implausible

RADIANCE_UNITS = "W/(m2 sr cm-1)"
"""``units`` of ``radiance``, ``nesr`` and ``sigma``."""

DIMS = ("camera", "v", "u", "wavenumber")
"""Dimensions of ``radiance`` and ``sigma``, in order."""

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
        rig's ray order, and their noise σ (``inf`` where masked).
    rig : CameraRig
        The cameras (all with the same pixel counts).
    wavenumber : ndarray, shape (n_out,)
        The measured wavenumbers in cm⁻¹.
    resolution : float
        The instrument's resolution 1/MOPD in cm⁻¹.
    apodization : str
        The instrument's apodization (one of
        :data:`invflame.geometry.rig_file.APODIZATIONS`).
    """

    measurement: Measurement
    rig: CameraRig
    wavenumber: np.ndarray
    resolution: float
    apodization: str = "triangular"

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
            ``apodization``, ``wavenumber_min`` and ``wavenumber_max`` (cm⁻¹) and
            ``n_wavenumbers``.
        """
        return {"from": f"the measurement file data.source = {source!r}, in place of "
                        "[instrument]",
                "resolution": float(self.resolution), "apodization": self.apodization,
                "wavenumber_min": float(np.min(self.wavenumber)),
                "wavenumber_max": float(np.max(self.wavenumber)),
                "n_wavenumbers": int(self.wavenumber.size)}

    def instrument_comment(self, source: str) -> str:
        """TOML comment lines saying what :meth:`instrument` says, for a run's
        ``config.toml`` (whose ``[instrument]`` the data replace)."""
        used = self.instrument(source)
        return (f"# [instrument] is not used: the measurement file data.source = {source!r} "
                "sets the instrument:\n"
                f"# resolution = {used['resolution']:g} cm-1, apodization = "
                f"{used['apodization']!r}, {used['n_wavenumbers']} wavenumbers "
                f"{used['wavenumber_min']:g}-{used['wavenumber_max']:g} cm-1\n")


def _mask(measurement: Measurement, rig: CameraRig) -> tuple[np.ndarray, np.ndarray]:
    """Bad pixels ``(n_pixels,)`` and bad wavenumbers ``(n_out,)`` of a measurement's inf σ."""
    masked = np.isinf(np.broadcast_to(measurement.sigma, measurement.data.shape))
    pixels, wavenumbers = masked.all(axis=1), masked.all(axis=0)
    if np.any(masked & ~pixels[:, None] & ~wavenumbers[None, :]):
        raise ValueError("masked values (sigma = inf) must make up whole pixels or whole "
                         "wavenumbers to be written: a measurement file masks bad pixels and "
                         "bad wavenumbers")
    return pixels, wavenumbers


def measurement_dataset(measured: MeasurementFile) -> xr.Dataset:
    """A measurement as an ``xarray.Dataset`` in the layout of the module docstring.

    Raises
    ------
    ValueError
        For cameras with different pixel counts, shapes that do not match the rig and the
        wavenumbers, or masked values that are not whole pixels or wavenumbers.
    """
    m, rig = measured.measurement, measured.rig
    wavenumber = np.asarray(measured.wavenumber, np.float64)
    if m.data.shape != (rig.n_rays, wavenumber.size):
        raise ValueError(f"the measurement's data {m.data.shape} do not match the rig's "
                         f"{rig.n_rays} pixels and {wavenumber.size} wavenumbers")
    if len(set(rig.image_shapes)) != 1:
        raise ValueError(f"a measurement file needs cameras with the same pixel counts; these "
                         f"have image shapes {rig.image_shapes}")
    bad_pixel, bad_wavenumber = _mask(m, rig)
    masked = bad_pixel[:, None] | bad_wavenumber[None, :]

    def images(values):
        return rig.to_images(np.where(masked, np.nan, values))

    variables = {"radiance": (DIMS, images(m.data),
                              {"units": RADIANCE_UNITS, "long_name": "measured spectral radiance"}),
                 "bad_pixel": (DIMS[:3], rig.to_images(bad_pixel.astype(np.int8)),
                               {"long_name": "1: pixel left out of the data term"}),
                 "bad_wavenumber": (("wavenumber",), bad_wavenumber.astype(np.int8),
                                    {"long_name": "1: wavenumber left out of the data term"})}
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


def read_measurement(path, rig: CameraRig | None = None,
                     rig_source: str = "the rig") -> MeasurementFile:
    """Read a measurement file (see the module docstring), checking every variable.

    Parameters
    ----------
    path : str or os.PathLike
        A file written by :func:`write_measurement` or by a user in its layout.
    rig : CameraRig, optional
        Cameras the data must come from (a configuration's rig): the file's must be the same.
    rig_source : str, optional
        What gave ``rig``, for messages (e.g. the rig file's name).

    Returns
    -------
    MeasurementFile
        Masked values have ``sigma = inf`` and ``data = 0``. ``sigma`` is per wavenumber for
        ``nesr`` (or unknown noise, σ = 1, ``noisy`` False) without bad pixels, else per value.

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    InputDataError
        For a file that is not NetCDF, a missing required variable or attribute, wrong
        dimensions or units, a shape or camera that does not match ``rig``, NaN outside the
        mask, masks that are not 0/1 flags or leave out every pixel or wavenumber, wavenumbers
        that are not positive and strictly monotone, a resolution coarser than the measured
        band or noise that is not positive; the message names the file and the variable.

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
    records = {name: read.variable(name, dims, units, required=name != "principal_point")
               for name, (dims, units, _) in CAMERA_VARIABLES.items()}
    spec = parse_rig([{key: values[i].tolist() for key, values in records.items()
                       if values is not None} | {"pixels": [nu, nv]}
                      for i in range(n_cameras)], str(path))
    if rig is not None:
        _check_same_rig(read, spec.rig, rig, rig_source)
    bad_pixel = read.flags("bad_pixel", DIMS[:3], "pixel")
    bad_wavenumber = read.flags("bad_wavenumber", ("wavenumber",), "wavenumber")
    read.check_mask(bad_pixel, bad_wavenumber)
    bad_pixel = bad_pixel.reshape(-1)
    masked = bad_pixel[:, None] | bad_wavenumber[None, :]
    data = radiance.reshape(-1, n_out)
    read.check_finite(data, masked, wavenumber, nu, nv)
    noise = read.attribute("noise")
    if noise == "nesr":
        sigma = read.variable("nesr", ("wavenumber",), RADIANCE_UNITS).astype(np.float64)
        read.positive("nesr", sigma, bad_wavenumber)
    elif noise == "sigma":
        sigma = read.variable("sigma", DIMS, RADIANCE_UNITS).astype(np.float64).reshape(-1, n_out)
        read.positive("sigma", sigma, masked)
    elif noise == "none":
        sigma = np.ones(n_out)
    else:
        read.fail(f"global attribute 'noise' = {noise!r}; allowed: 'nesr', 'sigma', 'none'")
    resolution = read.attribute("resolution")
    read.check_resolution(resolution, wavenumber)
    apodization = read.attribute("apodization")
    if apodization not in APODIZATIONS:
        read.fail(f"global attribute 'apodization' = {apodization!r} is not modelled; allowed: "
                  f"{', '.join(APODIZATIONS)}")
    try:
        provenance = json.loads(dataset.attrs.get("provenance", "{}"))
    except json.JSONDecodeError as err:
        read.fail(f"global attribute 'provenance' is not JSON: {err}")
    known = None if noise == "none" else np.broadcast_to(sigma, data.shape).reshape(radiance.shape)
    warn_implausible(radiance, known, masked.reshape(radiance.shape), wavenumber, path)
    if sigma.ndim == 2 or bad_pixel.any():
        sigma = np.where(masked, np.inf, np.broadcast_to(sigma, data.shape))
    else:
        sigma = np.where(bad_wavenumber, np.inf, sigma)
    measurement = Measurement(np.where(masked, 0, data).astype(data.dtype), sigma,
                              noise != "none", provenance)
    return MeasurementFile(measurement, spec.rig, wavenumber, float(resolution), apodization)


def _check_same_rig(read: MeasurementReader, found: CameraRig, expected: CameraRig,
                    source: str) -> None:
    """Refuse a file whose cameras are not ``expected``'s, naming the first difference."""
    if found.image_shapes != expected.image_shapes:
        read.fail(f"variable 'radiance' holds {found.n_cameras} camera(s) of image shape "
                  f"{found.image_shapes[0]} (v, u) but {source} has {expected.n_cameras} of "
                  f"{list(expected.image_shapes)}: use the rig the data were measured with")
    mine, theirs = _camera_columns(found), _camera_columns(expected)
    for key in CAMERA_VARIABLES:
        differs = ~np.isclose(mine[key], theirs[key], rtol=1e-9, atol=1e-12)
        if differs.any():
            camera = int(np.argwhere(differs)[0][0])
            read.fail(f"variable {key!r} of camera {camera} is {mine[key][camera].tolist()} but "
                      f"{source} says {theirs[key][camera].tolist()}: use the rig the data were "
                      "measured with")
