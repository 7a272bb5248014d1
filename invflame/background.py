r"""What the cameras see behind the flame: a black-body wall or a measured background spectrum.

Each ray of a camera ends on the background, whose radiance :math:`I_\mathrm{bg}(\eta)` the
flame transmits with the ray's transmittance :math:`\tau_\mathrm{ray}(\eta)`, so a pixel sees
:math:`I = I_\mathrm{flame} + \tau_\mathrm{ray} I_\mathrm{bg}` (the emission kernel,
:mod:`operators.rte.kernel`). Two kinds, both evaluated on any line-by-line grid by
:meth:`Background.on_grid`:

- :class:`BlackbodyWall`: a grey wall, :math:`I_\mathrm{bg} = \varepsilon B_\eta(T_\mathrm{wall})`,
  the same for every camera;
- :class:`MeasuredBackground`: one spectrum per camera (or one for all) on its own wavenumber
  grid, e.g. a frame recorded without the flame, linearly interpolated onto the line-by-line
  grid and held at its end values beyond it. A spectrum measured through the instrument is
  already smoothed by its lineshape, which the model applies once more: use it for smooth
  backgrounds (walls, a cold sky), where this changes nothing.

Measured backgrounds are read from files, and a configuration's ``[background]`` made into a
background, by :mod:`invflame.background_file`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from operators.rte.planck import planck


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
