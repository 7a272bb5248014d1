r"""What the cameras see behind the flame: a black-body wall or a measured background spectrum.

Each ray of a camera ends on the background, whose radiance :math:`I_\mathrm{bg}(\eta)` the
flame transmits with the ray's transmittance :math:`\tau_\mathrm{ray}(\eta)`, so a pixel sees
:math:`I = I_\mathrm{flame} + \tau_\mathrm{ray} I_\mathrm{bg}` (the emission kernel,
:mod:`operators.rte_kernel`). Two kinds, both evaluated on any line-by-line grid by
:meth:`Background.on_grid`:

- :class:`BlackbodyWall`: a grey wall, :math:`I_\mathrm{bg} = \varepsilon B_\eta(T_\mathrm{wall})`,
  the same for every camera;
- :class:`MeasuredBackground`: one spectrum per camera (or one for all) on its own wavenumber
  grid, e.g. a frame recorded without the flame, linearly interpolated onto the line-by-line
  grid and held at its end values beyond it. A spectrum measured through the instrument is
  already smoothed by its lineshape, which the model applies once more: use it for smooth
  backgrounds (walls, a cold sky), where this changes nothing.

Files (:func:`read_background`, :func:`write_background`) are NetCDF: a variable
``background`` (camera, wavenumber) in W/(m2 sr cm-1) with the coordinate ``wavenumber`` in
cm-1, or a measurement file (:mod:`invflame.measurement_file`) of a frame without the flame,
whose spectra are averaged over each camera's pixels (bad pixels and wavenumbers left out).
Configuration: ``[background] kind = "none" | "blackbody" | "file"``, ``temperature`` (K),
``emissivity``, ``file`` (:func:`background_from_config`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from invflame.atomic_files import read_netcdf, write_atomic
from invflame.errors import InputDataError
from operators.planck import planck

RADIANCE_UNITS = "W/(m2 sr cm-1)"
"""``units`` of a background file's ``background`` variable."""

KINDS = ("none", "blackbody", "file")
"""Values of ``background.kind`` in a configuration."""


class Background:
    """Radiance behind the flame, per camera, on any wavenumber grid."""

    def on_grid(self, wavenumber, n_cameras: int) -> np.ndarray:
        """The background radiance ``(n_cameras, n_eta)`` in W/(m²·sr·cm⁻¹) on ``wavenumber``
        (cm⁻¹)."""
        raise NotImplementedError

    def describe(self) -> dict:
        """The background in a JSON-able dictionary (for provenance)."""
        raise NotImplementedError


@dataclass(frozen=True)
class BlackbodyWall(Background):
    r"""A grey wall of temperature ``temperature`` (K) and emissivity ``emissivity``:
    :math:`I_\mathrm{bg} = \varepsilon B_\eta(T_\mathrm{wall})` for every camera.

    Raises
    ------
    ValueError
        For a temperature that is not positive and finite or an emissivity outside (0, 1].
    """

    temperature: float
    emissivity: float = 1.0

    def __post_init__(self):
        if not (np.isfinite(self.temperature) and self.temperature > 0):
            raise ValueError(f"the wall temperature must be positive and finite (K), got "
                             f"{self.temperature!r}")
        if not 0 < self.emissivity <= 1:
            raise ValueError(f"the wall emissivity must lie in (0, 1], got {self.emissivity!r}")

    def on_grid(self, wavenumber, n_cameras: int) -> np.ndarray:
        spectrum = self.emissivity * planck(np.asarray(wavenumber, np.float64),
                                            float(self.temperature))
        return np.tile(spectrum, (int(n_cameras), 1))

    def describe(self) -> dict:
        return {"kind": "blackbody", "temperature_K": float(self.temperature),
                "emissivity": float(self.emissivity)}


@dataclass(frozen=True, eq=False)
class MeasuredBackground(Background):
    """Measured background spectra: ``radiance`` ``(n_cameras, n_w)`` (or ``(n_w,)``, one for
    every camera) in W/(m²·sr·cm⁻¹) on ``wavenumber`` ``(n_w,)`` in cm⁻¹ (strictly monotone).

    Raises
    ------
    ValueError
        For shapes that do not match, a grid that is not strictly monotone, or values that
        are negative or not finite.
    """

    wavenumber: np.ndarray
    radiance: np.ndarray
    source: str = "measured"

    def __post_init__(self):
        wavenumber = np.asarray(self.wavenumber, np.float64)
        radiance = np.atleast_2d(np.asarray(self.radiance, np.float64))
        steps = np.diff(wavenumber)
        if wavenumber.ndim != 1 or wavenumber.size < 2 or not (
                np.all(steps > 0) or np.all(steps < 0)):
            raise ValueError(f"{self.source}: the background's wavenumbers must be a strictly "
                             f"monotone 1-D grid of at least 2 points (cm-1), got shape "
                             f"{wavenumber.shape}")
        if radiance.ndim != 2 or radiance.shape[1] != wavenumber.size:
            raise ValueError(f"{self.source}: background radiance must have shape (n_cameras, "
                             f"{wavenumber.size}) to match its wavenumbers; got "
                             f"{np.shape(self.radiance)}")
        if not np.all(np.isfinite(radiance)) or np.any(radiance < 0):
            raise ValueError(f"{self.source}: background radiance must be finite and >= 0 "
                             f"(W/(m2 sr cm-1)); {int(np.sum(~(radiance >= 0)))} values are not")
        order = np.argsort(wavenumber)
        object.__setattr__(self, "wavenumber", wavenumber[order])
        object.__setattr__(self, "radiance", radiance[:, order])

    def on_grid(self, wavenumber, n_cameras: int) -> np.ndarray:
        """Per camera, linear interpolation onto ``wavenumber`` (cm⁻¹), held at the end values
        beyond the measured grid.

        Raises
        ------
        ValueError
            If the spectra are per camera and there are not ``n_cameras`` of them.
        """
        if self.radiance.shape[0] not in (1, n_cameras):
            raise ValueError(f"{self.source}: the background holds {self.radiance.shape[0]} "
                             f"spectra but the rig has {n_cameras} cameras: give one spectrum "
                             "per camera, in the rig's order, or one for all")
        wavenumber = np.asarray(wavenumber, np.float64)
        spectra = np.array([np.interp(wavenumber, self.wavenumber, r) for r in self.radiance])
        return np.broadcast_to(spectra, (n_cameras, wavenumber.size)).copy()

    def describe(self) -> dict:
        return {"kind": "file", "source": self.source,
                "wavenumber_cm-1": [float(self.wavenumber[0]), float(self.wavenumber[-1])],
                "n_spectra": int(self.radiance.shape[0])}


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
                         "nor a measurement's 'radiance'; see invflame.background")


def _frame_background(path: Path) -> MeasuredBackground:
    """Per-camera mean spectrum of a measurement file, bad pixels and wavenumbers left out."""
    from invflame.measurement_file import read_measurement

    measured = read_measurement(path)
    sigma = np.broadcast_to(measured.measurement.sigma, measured.measurement.data.shape)
    good = np.isfinite(sigma)
    keep = good.any(axis=0)
    radiance = []
    for data, ok in zip(measured.rig.split_images(measured.measurement.data),
                        measured.rig.split_images(good), strict=True):
        data, ok = data.reshape(-1, data.shape[-1]), ok.reshape(-1, ok.shape[-1])
        radiance.append(np.sum(data * ok, axis=0)[keep] / np.maximum(ok.sum(axis=0)[keep], 1))
    return MeasuredBackground(measured.wavenumber[keep], np.array(radiance), str(path))


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
