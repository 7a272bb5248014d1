r"""What a measurement file must hold, and what its radiance can plausibly be.

:class:`MeasurementReader` gives checked access to the variables of an open measurement file
(:mod:`invflame.measurement_file`): a missing variable, wrong dimensions or units, a mask that
is not 0/1 flags, wavenumbers that are not positive and strictly monotone, a resolution
coarser than the measured band, a mask that leaves nothing, pixel counts beyond the image
dimensions or a camera window that is not ``[min, max]`` are refused with an
:class:`~invflame.errors.InputDataError` naming the file and the variable.

:func:`warn_implausible` then looks at the radiance of each camera and warns
(:class:`MeasurementWarning`) where no flame can have emitted it as it stands:

- a camera whose radiance is negative on the whole (mean below zero by more than the noise):
  emitted radiance is never negative, so the sign or the background subtraction is wrong;
- a camera with more than :data:`UNITS_FRACTION` of its values above the black-body radiance
  at :data:`HOTTEST_FLAME`:
  the units are not W/(m²·sr·cm⁻¹) (1 W/(cm²·sr·cm⁻¹) = 1e4 W/(m²·sr·cm⁻¹));
- a few values beyond that radiance (e.g. 1e30): spikes, saturated or dead pixels to mask.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from invflame.errors import InputDataError
from invflame.geometry.rig_file import APODIZATIONS
from operators.rte.planck import planck

RADIANCE_UNITS = "W/(m2 sr cm-1)"
"""``units`` of ``radiance``, ``nesr`` and ``sigma``."""

DIMS = ("camera", "v", "u", "wavenumber")
"""Dimensions of ``radiance`` and ``sigma``, in order."""

HOTTEST_FLAME = 3500.0
"""Temperature in K whose black-body radiance bounds a flame's emission: above the adiabatic
flame temperature of hydrocarbons in air (about 2300 K) and in oxygen (about 3100 K)."""

NOISE_MARGIN = 5.0
"""Noise standard deviations a value may lie beyond a bound before it counts as beyond it."""

UNITS_FRACTION = 0.1
"""Fraction of a camera's values beyond the flame bound from which the cause is taken to be
the units rather than isolated bad values."""


class MeasurementWarning(UserWarning):
    """Measured radiance that reads correctly but that no flame can have emitted as it stands
    (the message names the file, the camera and the likely cause)."""


class MeasurementReader:
    """Checked access to the variables of an open measurement file.

    Parameters
    ----------
    dataset : xarray.Dataset
        The file's contents.
    path : pathlib.Path
        The file, named in every message.
    """

    def __init__(self, dataset: xr.Dataset, path: Path):
        self.dataset, self.path = dataset, path

    def fail(self, message: str):
        """Raise an :class:`~invflame.errors.InputDataError` naming the file."""
        raise InputDataError(f"{self.path}: {message}")

    def variable(self, name: str, dims: tuple[str, ...], units: str | None,
                 required: bool = True) -> np.ndarray | None:
        """The values of variable ``name`` with dimensions ``dims`` and ``units`` (None: no
        units); None for an absent variable that is not ``required``."""
        if name not in self.dataset.variables:
            if not required:
                return None
            self.fail(f"missing variable {name!r} (dimensions {dims}"
                      + (f", units {units!r}" if units else "") + "); a measurement file "
                      "holds the variables of invflame.measurement_file")
        var = self.dataset[name]
        if var.dims != dims:
            shape = tuple(self.dataset.sizes.get(dim, "any") for dim in dims)
            self.fail(f"variable {name!r} has dimensions {var.dims} (shape {var.shape}), "
                      f"expected {dims} (shape {shape})")
        if units is not None and var.attrs.get("units") != units:
            self.fail(f"variable {name!r} has units {var.attrs.get('units')!r}, expected "
                      f"{units!r}; convert it to {units}")
        return np.asarray(var.values)

    def flags(self, name: str, dims: tuple[str, ...], what: str) -> np.ndarray:
        """A mask variable (1: leave the ``what`` out, 0: keep it) as booleans of the shape of
        ``dims``; all False when the file has none."""
        shape = tuple(self.dataset.sizes[dim] for dim in dims)
        expected = (f"a flag per {what}, 1 to leave it out and 0 to keep it, over {dims} "
                    f"(shape {shape})")
        if name not in self.dataset.variables:
            return np.zeros(shape, bool)
        values = np.asarray(self.dataset[name].values)
        if self.dataset[name].dims != dims:
            self.fail(f"variable {name!r} must be {expected}; it has dimensions "
                      f"{self.dataset[name].dims} (shape {values.shape})"
                      + (f", the single value {values.item()!r}" if values.size == 1 else ""))
        wrong = ~np.isin(values, (0, 1))
        if wrong.any():
            self.fail(f"variable {name!r} must be {expected}; it holds {int(wrong.sum())} "
                      f"other values, the first {values[wrong][0].item()!r} at index "
                      f"{tuple(int(i) for i in np.argwhere(wrong)[0])}: flag each {what} to "
                      "leave out with 1 rather than give its index")
        return values.astype(bool)

    def attribute(self, name: str):
        """The global attribute ``name``."""
        if name not in self.dataset.attrs:
            self.fail(f"missing global attribute {name!r}")
        return self.dataset.attrs[name]

    def pixel_counts(self, n_cameras: int, nu: int, nv: int) -> np.ndarray:
        """Each camera's pixel counts ``(nu, nv)``, shape (n_cameras, 2): the variable
        ``pixels``, or the sizes ``nu`` and ``nv`` of the ``u`` and ``v`` dimensions for every
        camera when the file has none."""
        counts = self.variable("pixels", ("camera", "uv"), None, required=False)
        if counts is None:
            return np.tile([nu, nv], (n_cameras, 1))
        if not (np.issubdtype(counts.dtype, np.integer) and np.all(counts >= 1)
                and np.all(counts <= [nu, nv])):
            self.fail(f"variable 'pixels' must hold each camera's pixel counts (nu, nv) as "
                      f"integers from 1 to the sizes of 'u' and 'v', ({nu}, {nv}); got "
                      f"{counts.tolist()}")
        return counts.astype(int)

    def windows(self, n_cameras: int) -> tuple | None:
        """Each camera's spectral window ``(min, max)`` in cm⁻¹ from the variable ``window``
        (None for a camera whose row is NaN, NaN: it measures every wavenumber); None when
        the file has none."""
        values = self.variable("window", ("camera", "bound"), "cm-1", required=False)
        if values is None:
            return None
        if values.shape != (n_cameras, 2):
            self.fail(f"variable 'window' must hold [min, max] in cm-1 for each of the "
                      f"{n_cameras} cameras, shape ({n_cameras}, 2); got shape {values.shape}")
        windows = []
        for camera, (low, high) in enumerate(values.astype(np.float64)):
            if np.isnan(low) and np.isnan(high):
                windows.append(None)
            elif np.isfinite(low) and np.isfinite(high) and 0 < low < high:
                windows.append((float(low), float(high)))
            else:
                self.fail(f"camera {camera}: 'window' must be [min, max] in cm-1 with 0 < min "
                          f"< max (or NaN, NaN: every wavenumber), got [{low:g}, {high:g}]")
        return tuple(windows) if any(w is not None for w in windows) else None

    def noise(self, n_out: int, masked: np.ndarray, unmeasured: np.ndarray
              ) -> tuple[str, np.ndarray]:
        """The attribute ``noise`` and the noise σ in W/(m²·sr·cm⁻¹) it names: ``nesr`` per
        wavenumber (``n_out``), ``sigma`` per value (of ``radiance``'s shape), or ones per
        wavenumber for ``"none"``.

        Parameters
        ----------
        n_out : int
            Number of wavenumbers.
        masked : ndarray of bool, shape of ``radiance``
            The values left out, where ``sigma`` may be NaN.
        unmeasured : ndarray of bool, shape (n_out,)
            The wavenumbers no pixel measures, where ``nesr`` may be NaN.
        """
        noise = self.attribute("noise")
        if noise == "nesr":
            sigma = self.variable("nesr", ("wavenumber",), RADIANCE_UNITS).astype(np.float64)
            self.positive("nesr", sigma, unmeasured)
        elif noise == "sigma":
            sigma = self.variable("sigma", DIMS, RADIANCE_UNITS).astype(np.float64)
            self.positive("sigma", sigma, masked)
        elif noise == "none":
            sigma = np.ones(n_out)
        else:
            self.fail(f"global attribute 'noise' = {noise!r}; allowed: 'nesr', 'sigma', 'none'")
        return noise, sigma

    def apodization(self) -> str:
        """The global attribute ``apodization``, one that invflame models."""
        apodization = self.attribute("apodization")
        if apodization not in APODIZATIONS:
            self.fail(f"global attribute 'apodization' = {apodization!r} is not modelled; "
                      f"allowed: {', '.join(APODIZATIONS)}")
        return apodization

    def positive(self, name: str, values: np.ndarray, masked: np.ndarray) -> None:
        """Refuse values of ``name`` that are not positive outside the mask."""
        ok = np.isnan(values) & masked | (values > 0)
        if not np.all(ok):
            self.fail(f"variable {name!r} must be positive where not masked (NaN allowed only "
                      f"in bad pixels and wavenumbers and outside a camera's window); "
                      f"{int((~ok).sum())} values are not")

    def check_wavenumber(self, wavenumber: np.ndarray) -> None:
        """Refuse wavenumbers (cm⁻¹) that are not finite, positive and strictly monotone."""
        if not np.all(np.isfinite(wavenumber)):
            self.fail("variable 'wavenumber' must be finite (cm-1)")
        if np.any(wavenumber <= 0):
            self.fail(f"variable 'wavenumber' holds {int(np.sum(wavenumber <= 0))} values that "
                      f"are not positive, the first {wavenumber[wavenumber <= 0][0]:g}: "
                      "wavenumbers are positive, in cm-1 (1e4 / wavelength in µm)")
        steps = np.diff(wavenumber)
        if not (np.all(steps > 0) or np.all(steps < 0)):
            self.fail("variable 'wavenumber' must be strictly monotone (cm-1)")

    def check_resolution(self, resolution, wavenumber: np.ndarray) -> None:
        """Refuse a resolution (cm⁻¹) that is not positive or is coarser than the measured band
        (or, for one wavenumber, than the wavenumber itself)."""
        if isinstance(resolution, np.generic):
            resolution = resolution.item()
        if not (isinstance(resolution, int | float) and resolution > 0):
            self.fail(f"global attribute 'resolution' must be a positive number in cm-1, got "
                      f"{resolution!r}")
        low, high = wavenumber.min(), wavenumber.max()
        band = high - low if wavenumber.size > 1 else low
        if resolution > band:
            self.fail(f"global attribute 'resolution' = {resolution:g} cm-1 is coarser than the "
                      f"measured band {low:g}-{high:g} cm-1: the spectra would hold less than "
                      "one resolution element; give the instrument's 1/MOPD in cm-1 (e.g. 8 "
                      "for 0.125 cm maximum optical path difference)")

    def check_mask(self, bad_pixel: np.ndarray, bad_wavenumber: np.ndarray) -> None:
        """Refuse a mask that leaves out every pixel or every wavenumber."""
        for name, flags, what in (("bad_pixel", bad_pixel, "pixel"),
                                  ("bad_wavenumber", bad_wavenumber, "wavenumber")):
            if flags.all():
                self.fail(f"variable {name!r} leaves out every {what} ({flags.size}): no data "
                          f"are left; set the flag of each good {what} to 0")

    def check_finite(self, data: np.ndarray, masked: np.ndarray, wavenumber: np.ndarray,
                     nu: int, nv: int) -> None:
        """Refuse NaN or infinite radiance outside the mask (``data`` ``(n_pixels, n_out)``
        in the file's camera, v, u order, ``nv`` × ``nu`` per camera)."""
        bad = ~np.isfinite(data) & ~masked | np.isinf(data)
        if bad.any():
            where = np.argwhere(bad)[0]
            camera, pixel = divmod(int(where[0]), nu * nv)
            self.fail(f"variable 'radiance' holds {int(bad.sum())} NaN or infinite values "
                      f"outside the mask, the first at camera {camera}, v {pixel // nu}, "
                      f"u {pixel % nu}, wavenumber {wavenumber[where[1]]:g} cm-1; flag those "
                      "pixels in 'bad_pixel', wavenumbers in 'bad_wavenumber', or give the "
                      "camera its 'window'")


def warn_implausible(radiance: np.ndarray, sigma: np.ndarray | None, masked: np.ndarray,
                     wavenumber: np.ndarray, path) -> None:
    """Warn (:class:`MeasurementWarning`) about each camera's radiance that no flame can have
    emitted as it stands (see the module docstring).

    Parameters
    ----------
    radiance : ndarray, shape (n_cameras, nv, nu, n_out)
        Measured spectra in W/(m²·sr·cm⁻¹), finite outside the mask.
    sigma : ndarray or None
        Noise standard deviation in W/(m²·sr·cm⁻¹), broadcast to ``radiance``'s shape; None
        when the noise is unknown.
    masked : ndarray of bool, broadcast to ``radiance``'s shape
        The values left out (bad pixels and wavenumbers); they are not looked at.
    wavenumber : ndarray, shape (n_out,)
        Wavenumbers in cm⁻¹, positive.
    path : str or Path
        The file, named in the messages.
    """
    shape = radiance.shape
    ceiling = np.broadcast_to(planck(wavenumber, HOTTEST_FLAME), shape)
    noise = np.zeros(shape) if sigma is None else np.broadcast_to(sigma, shape)
    keep = ~np.broadcast_to(masked, shape)
    for camera in range(shape[0]):
        ok = keep[camera]
        values = radiance[camera][ok].astype(np.float64)
        if values.size == 0:
            continue
        bound = ceiling[camera][ok] + NOISE_MARGIN * noise[camera][ok]
        beyond = np.abs(values) > bound
        at = f"{path}: camera {camera}"
        if beyond.mean() > UNITS_FRACTION:
            warnings.warn(f"{at}: {int(beyond.sum())} of its {values.size} values exceed the "
                          f"radiance of a black body at {HOTTEST_FLAME:g} K (up to "
                          f"{np.max(np.abs(values) / bound):.3g} times it), more than any flame "
                          "emits: 'radiance' must be in W/(m2 sr cm-1) (1 W/(cm2 sr cm-1) = "
                          "1e4 W/(m2 sr cm-1))", MeasurementWarning, stacklevel=3)
        elif beyond.any():
            first = np.argwhere(ok)[np.argmax(beyond)]
            count = int(beyond.sum())
            warnings.warn(f"{at}: {count} value{'s' * (count > 1)} beyond the radiance of a black "
                          f"body at {HOTTEST_FLAME:g} K, the first {values[beyond][0]:g} "
                          f"W/(m2 sr cm-1) at v {first[0]}, u {first[1]}, wavenumber "
                          f"{wavenumber[first[2]]:g} cm-1: spikes, saturated or dead pixels; "
                          "flag them in 'bad_pixel' or 'bad_wavenumber'", MeasurementWarning,
                          stacklevel=3)
        plausible = values[~beyond]
        if plausible.size:
            _warn_negative(plausible, noise[camera][ok][~beyond], sigma is not None, at)


def _warn_negative(values: np.ndarray, noise: np.ndarray, noisy: bool, at: str) -> None:
    """Warn when a camera's radiance ``values`` (W/(m²·sr·cm⁻¹)) are negative on the whole:
    their mean below zero by more than five standard errors and, with a known noise σ
    (``noise``, per value), by more than the median σ."""
    mean = values.mean()
    spread = np.sqrt(np.sum(noise ** 2)) if noisy else values.std() * np.sqrt(values.size)
    threshold = max(NOISE_MARGIN * spread / values.size, np.median(noise) if noisy else 0.0)
    if mean < -threshold:
        warnings.warn(f"{at}: its radiance is negative on the whole (mean {mean:.3g} "
                      f"W/(m2 sr cm-1), {np.mean(values < 0):.0%} of the values below zero); "
                      "emitted radiance is never negative: check the sign of the spectra and "
                      "the background subtraction", MeasurementWarning, stacklevel=4)
