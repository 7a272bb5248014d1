r"""Non-negative, smoothed linear emission tomography of band-integrated radiances.

In the optically thin limit a pixel's band radiance beyond ambient air, :math:`b_p`
(W/(m²·sr)), is a line integral of an emission density :math:`\varepsilon` (W/(m³·sr)):
:math:`b_p = \sum_k A_{pk}\, \varepsilon_k`, with :math:`A_{pk}` the length (m) of pixel
:math:`p`'s sub-rays in voxel :math:`k`, averaged over the pixel's sub-rays
(:func:`pixel_path_lengths`). :func:`band_tomography` solves for :math:`\varepsilon \ge 0`
with a smoothing weight chosen by the discrepancy principle when the noise is known. The start
of a reconstruction built on it: :mod:`invflame.experiments.data_start`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse

import operators as op
import solvers

SMOOTHING_RANGE = (1.0, 1e-7)
"""Largest and smallest smoothing weight μ (dimensionless) the discrepancy principle tries."""

DEFAULT_SMOOTHING = 3e-3
"""Smoothing weight μ (dimensionless) when the noise is unknown: the discrepancy principle's
choice on the synthetic plume at peak SNR 1000; the start changes little over a decade around
it, because non-negativity, not the smoothing, shapes the solution."""


def pixel_path_lengths(scene) -> scipy.sparse.csr_array:
    """Path-length matrix of the pixels: each pixel's sub-ray lengths averaged.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Its ``segments`` hold ``rays_per_pixel`` consecutive sub-rays per pixel (1 when the
        scene has no such attribute).

    Returns
    -------
    scipy.sparse.csr_array, shape (n_pixels, n_voxels)
        Mean length in m of a pixel's sub-rays in each voxel (C-order voxel index).
    """
    group = int(getattr(scene, "rays_per_pixel", 1))
    lengths = scene.segments.to_csr()
    n_rays, n_voxels = lengths.shape
    if group < 1 or n_rays % group:
        raise ValueError(f"the scene traces {n_rays} sub-rays, not a multiple of its "
                         f"rays_per_pixel = {group}")
    n_pixels = n_rays // group
    mean = scipy.sparse.csr_array(
        (np.full(n_rays, 1.0 / group), (np.repeat(np.arange(n_pixels), group),
                                        np.arange(n_rays))), shape=(n_pixels, n_rays))
    return scipy.sparse.csr_array(mean @ lengths)


@dataclass(frozen=True)
class BandTomography:
    r"""Result of :func:`band_tomography`.

    Attributes
    ----------
    emission : ndarray, shape (nx, ny, nz)
        Emission density beyond ambient air, W/(m³·sr), ≥ 0.
    smoothing : float
        The weight μ used (dimensionless, relative to :math:`\lambda_0`, see
        :func:`band_tomography`).
    chi2 : float
        Misfit :math:`\chi^2` at the solution: whitened by the band noise when known
        (≈ the number of pixels at the noise level), else the plain sum of squares in
        (W/(m²·sr))².
    choice : solvers.ParameterChoice or None
        The discrepancy principle's sweep, when the noise was known.
    """

    emission: np.ndarray
    smoothing: float
    chi2: float
    choice: solvers.ParameterChoice | None


def _largest_eigenvalue(matrix, iterations: int = 30) -> float:
    """Largest eigenvalue of ``matrix.T @ matrix`` for a non-negative sparse ``matrix``
    (power iteration from the all-ones vector, which the Perron vector is close to)."""
    x = np.ones(matrix.shape[1])
    value = 0.0
    for _ in range(iterations):
        y = matrix.T @ (matrix @ x)
        value = float(np.linalg.norm(y))
        if value == 0.0:
            raise ValueError("no pixel sees the grid: the path-length matrix is zero")
        x = y / value
    return value


def band_tomography(lengths, band, grid, sigma_band=None, smoothing=None,
                    max_iter: int = 5000, tol: float = 1e-5) -> BandTomography:
    r"""Non-negative, smoothed linear emission tomography of band-integrated radiances.

    Minimizes over the emission density :math:`\varepsilon \ge 0` (per voxel)

    .. math:: J = \frac{1}{M}\sum_p \Big(\frac{(A\varepsilon)_p - b_p}{\sigma_{b,p}}\Big)^2
              + \mu\,\lambda_0\, \operatorname{mean}|\nabla\varepsilon|^2,

    with :math:`\nabla` forward differences per metre (:func:`operators.Gradient`) and
    :math:`\lambda_0 = (\|A/\sigma_b\|^2/M) / (\|\nabla\|^2/N)` the ratio of the norms of
    the two terms' Hessians (:math:`M` pixels, :math:`N` voxels), so that μ is dimensionless
    and means the same on any grid. Each problem is solved by projected accelerated gradient
    (FISTA, Beck & Teboulle, SIAM J. Imaging Sci. 2, 2009) with adaptive restart
    (O'Donoghue & Candès, Found. Comput. Math. 15, 2015), warm-started from the solution of
    the nearest weight tried.

    With ``sigma_band`` given and ``smoothing`` None, μ follows the discrepancy principle
    (:func:`solvers.discrepancy_principle`, τ = 1) over :data:`SMOOTHING_RANGE`: the
    smoothest solution with :math:`\chi^2 \le M`. Without ``sigma_band`` the misfit is not
    whitened and μ is :data:`DEFAULT_SMOOTHING`.

    Parameters
    ----------
    lengths : scipy.sparse matrix, shape (M, N)
        Path lengths in m of each pixel in each voxel (:func:`pixel_path_lengths`).
    band : array_like, shape (M,)
        Band-integrated radiance per pixel, W/(m²·sr).
    grid : invflame.geometry.VoxelGrid
        The grid of the N voxels (shape and spacing in m).
    sigma_band : float or array_like, shape (M,), optional
        Noise standard deviation of ``band`` in W/(m²·sr).
    smoothing : float, optional
        μ ≥ 0; overrides the rules above.
    max_iter : int, optional
        Iterations per solve at most.
    tol : float, optional
        A solve stops when an iteration changes ε by less than ``tol`` times its norm.

    Returns
    -------
    BandTomography
    """
    lengths = scipy.sparse.csr_array(lengths, dtype=np.float64)
    n_pixels, n_voxels = lengths.shape
    if n_voxels != grid.n_voxels:
        raise ValueError(f"lengths has {n_voxels} columns, the grid {grid.shape} has "
                         f"{grid.n_voxels} voxels")
    band = np.asarray(band, np.float64)
    if band.shape != (n_pixels,) or not np.all(np.isfinite(band)):
        raise ValueError(f"band must be {n_pixels} finite values (one per pixel, W/(m2 sr)), "
                         f"got shape {band.shape}")
    if sigma_band is None:
        weight = np.ones(n_pixels)
    else:
        sigma_band = np.broadcast_to(np.asarray(sigma_band, np.float64), (n_pixels,))
        if not np.all(np.isfinite(sigma_band) & (sigma_band > 0)):
            raise ValueError("sigma_band must be positive and finite (W/(m2 sr))")
        weight = 1.0 / sigma_band
    if smoothing is not None and not (np.isfinite(smoothing) and smoothing >= 0):
        raise ValueError(f"smoothing must be a finite number >= 0, got {smoothing}")

    whitened = scipy.sparse.csr_array(scipy.sparse.diags_array(weight) @ lengths)
    target = weight * band
    gradient = op.Gradient((1, *grid.shape), grid.spacing)

    data_norm = _largest_eigenvalue(whitened) / n_pixels
    slope_norm = 4.0 * np.sum(1.0 / grid.spacing**2) / n_voxels  # bound on |D|^2 / N
    lam0 = data_norm / slope_norm

    def solve(mu, x0):
        # step 1/L for the Lipschitz constant L of the gradient, with 5 % margin (the power
        # iteration approaches the norm from below)
        lam = mu * lam0
        step = 1.0 / (2.1 * (data_norm + lam * slope_norm))
        x = y = x0
        momentum = 1.0
        for _ in range(max_iter):
            gradient_at_y = (2.0 * (whitened.T @ (whitened @ y - target)) / n_pixels
                             + 2.0 * lam * gradient.rmatvec(gradient.matvec(y)) / n_voxels)
            x_next = np.maximum(y - step * gradient_at_y, 0.0)
            change = x_next - x
            if (y - x_next) @ change > 0:  # momentum points uphill: restart
                momentum = 1.0
            momentum_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * momentum**2))
            y = x_next + (momentum - 1.0) / momentum_next * change
            x, momentum = x_next, momentum_next
            if np.linalg.norm(change) <= tol * np.linalg.norm(x):
                break
        residual = whitened @ x - target
        slope = gradient.matvec(x)
        return x, float(residual @ residual), float(slope @ slope) / n_voxels

    start = np.zeros(n_voxels)
    if sigma_band is None or smoothing is not None:
        mu = DEFAULT_SMOOTHING if smoothing is None else float(smoothing)
        x, chi2, _ = solve(mu, start)
        choice = None
    else:
        solved = {}

        def warm_solve(mu):  # from the solution of the nearest weight tried so far
            nearest = min(solved, key=lambda m: abs(np.log(m / mu)), default=None)
            solved[mu] = solve(mu, start if nearest is None else solved[nearest][0])
            return solved[mu]

        choice = solvers.discrepancy_principle(warm_solve, n_pixels, *SMOOTHING_RANGE)
        mu = choice.lam
        x, chi2, _ = solved[mu]
    return BandTomography(emission=np.maximum(x, 0.0).reshape(grid.shape), smoothing=mu,
                          chi2=chi2, choice=choice)
