r"""The FTIR instrument lineshape (ILS) as a linear operator.

A Michelson interferometer with maximum optical path difference :math:`L` (cm) and triangular
apodization measures the true spectrum convolved with

.. math:: \mathrm{ILS}(\nu) = L\,\mathrm{sinc}^2(\pi \nu L), \qquad
          \mathrm{sinc}(u) = \sin(u)/u, \qquad \int \mathrm{ILS}\,d\nu = 1 .

**Resolution.** "Resolution :math:`\Delta\nu`" means :math:`\Delta\nu = 1/L` (the unapodized
resolution, as FTIR software quotes it). The triangular-apodized lineshape then has its first
zeros at :math:`\pm\Delta\nu` and a full width at half maximum of :math:`0.886\,\Delta\nu`:
7.09 cm⁻¹ at 8 cm⁻¹ resolution.

**Discretization and edges.** The line-by-line spectrum is known on a uniform grid
:math:`\eta_i` (cm⁻¹) inside a finite window. Output point :math:`j` is the lineshape-weighted
mean of the spectrum over the window,

.. math:: g_j = \sum_i K_{ji} I_i, \qquad K_{ji} = \frac{\mathrm{ILS}(\nu_j - \eta_i)}
          {\sum_{i'} \mathrm{ILS}(\nu_j - \eta_{i'})},

i.e. the lineshape is truncated at the window edges and renormalized to unit area, so a flat
spectrum is reproduced exactly. By default the output grid keeps one resolution away from the
window edges (there the truncated tails hold less than 5 % of the lineshape's area) and is
sampled every :math:`\Delta\nu/4` (2 cm⁻¹ at 8 cm⁻¹ resolution: the spectral sampling of an
interferogram zero-filled by a factor of 2).

**Speed.** :math:`K` is dense (the sinc² tails are long) but small, ``(n_out, n_eta)``; applying
it to all rays is one matrix product, faster than FFT convolution at these sizes
(``benchmarks/bench_ils.py`` prints the figures).
"""

from __future__ import annotations

import numpy as np

from operators.base import LinearOperator


def triangular_ils(nu, resolution: float) -> np.ndarray:
    r"""Lineshape of triangular apodization, unit area, in 1/cm⁻¹.

    Parameters
    ----------
    nu : array_like
        Offset from the line centre in cm⁻¹.
    resolution : float
        Resolution :math:`\Delta\nu = 1/L` in cm⁻¹.
    """
    mopd = 1.0 / resolution
    return mopd * np.sinc(np.asarray(nu) * mopd) ** 2  # np.sinc(x) = sin(pi x)/(pi x)


def default_output_grid(wavenumber, resolution: float) -> np.ndarray:
    """Output wavenumbers (cm⁻¹): one resolution inside the window, every resolution/4."""
    lo, hi = wavenumber[0] + resolution, wavenumber[-1] - resolution
    if hi < lo:
        raise ValueError(
            f"the window {wavenumber[0]:g}-{wavenumber[-1]:g} cm-1 is narrower than twice the "
            f"resolution {resolution:g} cm-1: widen it or pass out_wavenumber"
        )
    step = resolution / 4.0
    return lo + step * np.arange(int(np.floor((hi - lo) / step + 1e-9)) + 1)


class ILSConvolution(LinearOperator):
    r"""Instrument-lineshape convolution and resampling of line-by-line spectra.

    Maps spectral radiance :math:`I(\text{ray}, \eta)` on a uniform line-by-line grid to the
    measured spectra :math:`g(\text{ray}, \nu_\text{out})` (both in W/(m²·sr·cm⁻¹)). See the
    module docstring for the lineshape, the resolution convention and edge handling.

    Parameters
    ----------
    wavenumber : array_like, shape (n_eta,)
        Uniform line-by-line grid in cm⁻¹, increasing.
    n_rays : int
        Number of spectra (rays) per application.
    resolution : float, optional
        Spectral resolution :math:`\Delta\nu = 1/\mathrm{MOPD}` in cm⁻¹ (default 8).
    out_wavenumber : array_like, optional
        Output grid in cm⁻¹ inside the window: any strictly monotone grid (a measurement's own
        wavenumbers, irregular spacing allowed); default :func:`default_output_grid`.
    dtype : numpy dtype, optional
        float32 or float64 (default).

    Attributes
    ----------
    matrix : ndarray, shape (n_out, n_eta)
        The sampled, row-normalized lineshape :math:`K`; rows sum to 1.
    out_wavenumber : ndarray, shape (n_out,)
    """

    def __init__(self, wavenumber, n_rays: int, resolution: float = 8.0,
                 out_wavenumber=None, dtype=np.float64):
        wavenumber = np.asarray(wavenumber, dtype=np.float64)
        if wavenumber.ndim != 1 or wavenumber.size < 2:
            raise ValueError("wavenumber must be a 1-D grid of at least 2 points (cm-1)")
        steps = np.diff(wavenumber)
        if np.any(steps <= 0) or np.ptp(steps) > 1e-6 * steps.mean():
            raise ValueError("wavenumber must be uniform and increasing (cm-1)")
        if not resolution > 0:
            raise ValueError(f"resolution must be positive (cm-1), got {resolution}")
        if out_wavenumber is None:
            out_wavenumber = default_output_grid(wavenumber, resolution)
        out_wavenumber = np.atleast_1d(np.asarray(out_wavenumber, dtype=np.float64))
        if out_wavenumber.ndim != 1 or not np.all(np.isfinite(out_wavenumber)):
            raise ValueError(f"out_wavenumber must be a 1-D grid of finite values (cm-1); got "
                             f"shape {out_wavenumber.shape}")
        out_steps = np.diff(out_wavenumber)
        direction = 1.0 if out_steps.size and out_steps[0] > 0 else -1.0
        if np.any(out_steps * direction <= 0):
            point = int(np.flatnonzero(out_steps * direction <= 0)[0]) + 1
            raise ValueError(f"out_wavenumber must be strictly monotone (cm-1); point {point} "
                             f"({out_wavenumber[point]:g} cm-1) breaks the order")
        outside = (out_wavenumber < wavenumber[0]) | (out_wavenumber > wavenumber[-1])
        if np.any(outside):
            raise ValueError(
                f"out_wavenumber must lie inside the line-by-line window "
                f"{wavenumber[0]:g}-{wavenumber[-1]:g} cm-1; {int(outside.sum())} points do not"
            )
        n_rays = int(n_rays)
        if n_rays < 1:
            raise ValueError(f"n_rays must be >= 1, got {n_rays}")
        kernel = triangular_ils(out_wavenumber[:, None] - wavenumber[None, :], resolution)
        self.matrix = (kernel / kernel.sum(axis=1, keepdims=True)).astype(dtype)
        self.wavenumber = wavenumber
        self.out_wavenumber = out_wavenumber
        self.resolution = float(resolution)
        super().__init__((n_rays, wavenumber.size), (n_rays, out_wavenumber.size),
                         dtype=dtype, name="ILSConvolution")

    def _forward(self, x):
        return x @ self.matrix.T

    def _adjoint(self, y):
        return y @ self.matrix
