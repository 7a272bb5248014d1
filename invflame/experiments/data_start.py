r"""A starting point for a reconstruction built from the measurements alone.

No ground truth enters: only the measured spectra, their noise, the scene (grid, cameras,
absorption table, instrument) and a state relation of the fuel.

**1. Band-integrated linear emission tomography.** Every pixel's spectrum, less what ambient
air alone would give (a forward simulation of uniform ambient air), is integrated over
the selected output channels :math:`j` with widths :math:`\Delta\nu_j` (cm⁻¹):

.. math:: b_p = \sum_j \Delta\nu_j\, (g_{pj} - g^\text{amb}_{pj})
          \quad [\mathrm{W/(m^2\,sr)}].

In the optically thin limit this is a line integral of an emission density,
:math:`b_p = \sum_k A_{pk}\, \varepsilon_k` with :math:`A_{pk}` the length (m) of pixel
:math:`p`'s sub-rays in voxel :math:`k`, averaged over the pixel's sub-rays, and

.. math:: \varepsilon(\text{state}) = \sum_j \Delta\nu_j \sum_i K_{ji}\,
          \kappa(\eta_i)\, B(\eta_i, T) \quad [\mathrm{W/(m^3\,sr)}]

(:math:`K` the instrument lineshape matrix, :math:`\kappa` in m⁻¹, :math:`B` Planck's law),
measured relative to ambient air. The solve is

.. math:: \min_{\varepsilon \ge 0} \; \chi^2(\varepsilon)/M + \lambda\, \Phi(\varepsilon), \quad
          \chi^2 = \sum_p \Big(\frac{(A\varepsilon)_p - b_p}{\sigma_{b,p}}\Big)^2,
          \quad \Phi = \operatorname{mean} \|\nabla \varepsilon\|^2,

with :math:`\sigma_{b,p}` the measurement noise propagated to the band integral, solved by
projected accelerated gradient (:func:`band_tomography`). Four cameras on two axes give two
independent directions; non-negativity is the prior that makes so few views usable: a pixel
that sees nothing beyond ambient air forces every voxel on its path to zero. The weight
:math:`\lambda` follows the discrepancy principle (:func:`solvers.discrepancy_principle`): the
smoothest solution that fits the band data to the noise. The ambient air should be the one
around the flame: assuming 1 % of water vapour in dry air leaves a misfit hundreds of times the
noise at peak SNR 1000; the start then hardly changes, but the principle warns and takes its
smallest weight.

**Channels.** Line cores that saturate make the band integral fall below the thin limit, most
at the CO₂ ν₂ Q branch (667 cm⁻¹) in gas of a few hundred kelvin.
:func:`thin_channels` keeps the channels where a column of every state of the state relation,
as short as the brightest pixel allows, still emits at least :data:`THIN_RATIO` of its thin
limit.

**Masked values.** A bad wavenumber (masked in every pixel) leaves the channels; a pixel
whose band then lacks a value, a bad pixel, contributes no row to the linear system:
:math:`b`, :math:`A` and :math:`\sigma_b` keep only the pixels measured in every channel
used, and :math:`M` counts those.

**2. State relation.** Burke–Schumann methane–air combustion
(:func:`invflame.phantoms.composition.burke_schumann_methane`) on its lean branch, mixture
fraction from 0 (ambient air, carrying its humidity and CO₂) to stoichiometric, gives
temperature and mole fractions as functions of one variable, and with the same channels and
lineshape an emission density :math:`\varepsilon` that rises monotonically along it. Each
voxel's :math:`\varepsilon` is inverted by interpolation; values beyond the stoichiometric one
take the stoichiometric state, and CH₄ stays zero (the rich core over a pool is not
represented).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse

import operators as op
import solvers
from invflame.experiments.initialization import AMBIENT, with_soot_field
from invflame.representations.state_relation import DEFAULT_TEMPERATURE_RISE_ST, StateRelation
from invflame.representations.whitening import noise_weights
from operators.planck import planck

SMOOTHING_RANGE = (1.0, 1e-7)
"""Largest and smallest smoothing weight μ (dimensionless) the discrepancy principle tries."""

DEFAULT_SMOOTHING = 3e-3
"""Smoothing weight μ (dimensionless) when the noise is unknown: the discrepancy principle's
choice on the synthetic plume at peak SNR 1000; the start changes little over a decade around
it, because non-negativity, not the smoothing, shapes the solution."""

THIN_RATIO = 0.6
"""Least ratio of a channel's emission to its optically thin limit (see :func:`thin_channels`).

On the synthetic plume at peak SNR 1000 it drops the four channels at the CO₂ Q branch and
lowers the start's MSE_T by about 30 %; 0.7 drops eight channels with the same result."""


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


def lean_branch(temperature_rise_st: float = DEFAULT_TEMPERATURE_RISE_ST, ambient=AMBIENT,
                n_points: int = 257) -> tuple[np.ndarray, np.ndarray]:
    """States of the methane–air flame from ambient air to stoichiometric (lean branch).

    Fuel (CH4 at the ambient temperature) mixes with ambient air, i.e. dry air (O2 + 3.76 N2)
    carrying the ambient mole fractions of CO2, H2O and CH4 as inert diluents, and burns
    completely (:func:`~invflame.phantoms.composition.burke_schumann_methane`, applied to the
    fuel and the dry air). The temperature rise is the Burke–Schumann one diluted by the
    mass share of the diluents: the states of
    :class:`~invflame.representations.state_relation.StateRelation` at factor 1.

    Parameters
    ----------
    temperature_rise_st : float, optional
        Temperature rise in K at the stoichiometric mixture of fuel and dry air
        (default :data:`~invflame.representations.state_relation.DEFAULT_TEMPERATURE_RISE_ST`).
    ambient : array_like, shape (4,), optional
        Ambient air: T in K, then mole fractions of CO2, H2O, CH4 (default
        :data:`invflame.experiments.initialization.AMBIENT`).
    n_points : int, optional
        Number of states, uniform in the mixture fraction of fuel and dry air (≥ 2).

    Returns
    -------
    mixture_fraction : ndarray, shape (n_points,)
        Mass fraction of the mixture that came from the fuel, from 0 (ambient air) to
        stoichiometric, increasing.
    states : ndarray, shape (4, n_points)
        T in K and mole fractions of CO2, H2O, CH4 along the branch.
    """
    if int(n_points) != n_points or n_points < 2:
        raise ValueError(f"n_points must be an integer >= 2, got {n_points}")
    relation = StateRelation(ambient, temperature_rise_st, factor_range=(1.0, 1.0))
    progress = np.linspace(0.0, 1.0, int(n_points))
    return relation.mixture_fraction(progress), np.stack(relation.states(progress))


def channel_emission(scene, states, length: float | None = None) -> np.ndarray:
    r"""Band emission of gas states per output channel, as the instrument sees it.

    Thin limit (``length`` None): the emission density
    :math:`\sum_i K_{ji}\, \kappa(\eta_i)\, B(\eta_i, T)` with :math:`K` the scene's
    lineshape matrix (``scene.ils.matrix``), :math:`\kappa` from the scene's absorption table
    and :math:`B` Planck's law. With ``length`` :math:`L`: the radiance of a uniform column of
    that length per unit length, :math:`\sum_i K_{ji}\, B\,(1 - e^{-\kappa L}) / L`,
    which self-absorption keeps below the thin limit.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Absorption table, line-by-line window and instrument.
    states : array_like, shape (4, n)
        T in K (inside the table's range) and mole fractions of CO2, H2O, CH4.
    length : float, optional
        Column length in m (> 0).

    Returns
    -------
    ndarray, shape (n, n_out)
        W/(m³·sr·cm⁻¹).
    """
    states = np.asarray(states, dtype=np.float64)
    if states.ndim != 2 or states.shape[0] != 4:
        raise ValueError(f"states must have shape (4, n): T [K] and mole fractions of CO2, H2O, "
                         f"CH4; got {states.shape}")
    start = int(np.argmin(np.abs(scene.table.wavenumber - scene.wavenumber[0])))
    columns = slice(start, start + scene.wavenumber.size)  # the scene's window in the table
    kappa = scene.table.kappa(states[0], states[1:])[:, columns]  # m⁻¹
    source = planck(scene.wavenumber[None, :], states[0][:, None])
    if length is None:
        spectrum = kappa * source
    elif length > 0:
        spectrum = -np.expm1(-kappa * length) * source / length
    else:
        raise ValueError(f"length must be positive (m), got {length}")
    return spectrum @ np.asarray(scene.ils.matrix, np.float64).T


def channel_weights(scene, channels=None) -> np.ndarray:
    """Weights (cm⁻¹) of the output channels in the band integral: their widths, 0 if unused.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Its output grid ``out_wavenumber`` (cm⁻¹).
    channels : array_like of bool, shape (n_out,), optional
        Channels to integrate over (default: all of them).

    Returns
    -------
    ndarray, shape (n_out,)
        Channel widths in cm⁻¹ (``numpy.gradient`` of the output grid) where selected.
    """
    out = np.asarray(scene.out_wavenumber, np.float64)
    widths = np.gradient(out) if out.size > 1 else np.ones(1)
    if channels is None:
        return widths
    channels = np.asarray(channels)
    if channels.shape != out.shape or channels.dtype != bool:
        raise ValueError(f"channels must be a boolean mask of shape {out.shape} (one per output "
                         f"wavenumber), got dtype {channels.dtype} and shape {channels.shape}")
    if not channels.any():
        raise ValueError("channels selects no output wavenumber; select at least one")
    return np.where(channels, widths, 0.0)


def thin_channels(scene, band_peak: float, states,
                  min_ratio: float = THIN_RATIO) -> np.ndarray:
    """Output channels where the optically thin limit holds well enough for the flame seen.

    The reference column is the shortest column of the hottest state of ``states`` (the last)
    that gives the brightest pixel's band radiance ``band_peak`` (all channels, thin limit):
    any flame seen is at least that thick. A channel is kept when, for every state, such a
    column emits at least ``min_ratio`` of its thin-limit emission
    (:func:`channel_emission`): line cores that saturate make the band integral, and hence
    the tomography, underestimate the emission.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Absorption table, window and instrument.
    band_peak : float
        Largest band radiance over the pixels beyond ambient air, all channels, W/(m²·sr).
    states : array_like, shape (4, n)
        States of the state relation, the hottest (stoichiometric) last.
    min_ratio : float, optional
        In (0, 1] (default :data:`THIN_RATIO`).

    Returns
    -------
    ndarray of bool, shape (n_out,)
        The channels kept; all of them when no pixel sees emission beyond ambient air, the
        least saturated one when none reaches ``min_ratio``.
    """
    if not 0 < min_ratio <= 1:
        raise ValueError(f"min_ratio must lie in (0, 1], got {min_ratio}")
    thin = channel_emission(scene, states)
    emitting = thin.sum(axis=1) > 0
    peak = thin[-1] @ channel_weights(scene)
    if not (band_peak > 0 and peak > 0):
        return np.ones(scene.out_wavenumber.size, dtype=bool)
    column = band_peak / peak  # m
    thick = channel_emission(scene, np.asarray(states)[:, emitting], column)
    ratio = thick / np.maximum(thin[emitting], np.finfo(float).tiny)
    keep = ratio.min(axis=0) >= min_ratio
    return keep if keep.any() else ratio.min(axis=0) == ratio.min(axis=0).max()


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


def band_tomography_start(scene, data, sigma=None,
                          temperature_rise_st: float = DEFAULT_TEMPERATURE_RISE_ST, *,
                          ambient=AMBIENT, channels=None, smoothing=None,
                          n_states: int = 257, measured=None) -> np.ndarray:
    """Starting fields from the measurements alone: band tomography, then a state relation.

    See the module docstring for the method; nothing of the truth is used.

    Parameters
    ----------
    scene : invflame.scene.Scene
        Grid, cameras (``rays_per_pixel`` sub-rays per pixel, 1 when absent), absorption
        table and instrument.
    data : array_like, shape ``scene.data_shape``
        Measured spectra in W/(m²·sr·cm⁻¹).
    sigma : float or array_like, optional
        Noise standard deviation of ``data`` in W/(m²·sr·cm⁻¹): a scalar, one value per
        output wavenumber, or one per value; independent between values; ``inf`` for a
        masked value. Given, the smoothing follows the discrepancy principle; None (noise
        unknown): the fixed :data:`DEFAULT_SMOOTHING`.
    temperature_rise_st : float, optional
        Temperature rise in K at stoichiometry of the state relation (default
        :data:`~invflame.representations.state_relation.DEFAULT_TEMPERATURE_RISE_ST`);
        ``ambient[0] + temperature_rise_st`` must lie inside the absorption table's
        temperature range.
    ambient : array_like, shape (4,), optional
        Ambient air around the flame: T in K and mole fractions of CO2, H2O, CH4 (default
        :data:`~invflame.experiments.initialization.AMBIENT`). Its simulated spectra are
        subtracted from the data, and it is the cold end of the state relation.
    channels : array_like of bool, shape (n_out,), optional
        Output channels of the band integral (default :func:`thin_channels`).
    smoothing : float, optional
        Smoothing weight μ ≥ 0 (dimensionless, see :func:`band_tomography`), overriding the
        rules above.
    n_states : int, optional
        States tabulated along the state relation (≥ 2).
    measured : array_like of bool, shape ``scene.data_shape``, optional
        False for a masked value (a bad pixel or wavenumber; see the module notes); default:
        where ``sigma`` is finite (everything without ``sigma``).

    Returns
    -------
    ndarray, shape (4, nx, ny, nz)
        T in K and mole fractions of CO2, H2O, CH4 (float64); voxels without emission beyond
        ambient air hold the ambient air. A scene that reconstructs soot starts from these
        and no soot (:func:`~invflame.experiments.initialization.with_soot_field`).
    """
    data = np.asarray(data, np.float64)
    if data.shape != tuple(scene.data_shape):
        raise ValueError(f"data must have the scene's shape {tuple(scene.data_shape)} (pixels, "
                         f"output wavenumbers), got {data.shape}")
    if not np.all(np.isfinite(data)):
        raise ValueError("data contains NaN or infinite values")
    with np.errstate(divide="ignore"):  # a masked value's weight 0: noise inf
        noise = None if sigma is None else 1.0 / noise_weights(sigma, data.shape)
    measured = _measured_values(data.shape, noise, measured)
    _, states = lean_branch(temperature_rise_st, ambient, n_states)
    air = with_soot_field(np.broadcast_to(states[:, :1, None, None], (4, *scene.grid.shape)),
                          scene.field_shape[0] == 5)  # soot-free air
    excess = np.where(measured, data - np.asarray(scene.simulate(air), np.float64), 0.0)
    somewhere = measured.any(axis=0)  # a wavenumber masked in every pixel leaves the band
    if channels is None:
        peak = float(np.max(excess @ (channel_weights(scene) * somewhere)))
        channels = thin_channels(scene, peak, states)
    weights = channel_weights(scene, channels) * somewhere
    rows = measured[:, weights > 0].all(axis=1)  # a pixel lacking a channel gives no row
    if not (weights.any() and rows.any()):
        raise ValueError("the mask leaves no pixel measured in every channel of the band "
                         "integral: no row for the band tomography")
    band = excess[rows] @ weights  # W/(m² sr)
    sigma_band = None if noise is None else np.sqrt(
        np.where(measured, noise, 0.0)[rows]**2 @ weights**2)
    tomography = band_tomography(pixel_path_lengths(scene)[rows], band, scene.grid, sigma_band,
                                 smoothing)
    density = channel_emission(scene, states) @ weights
    density = density - density[0]  # beyond ambient air, W/(m³ sr)
    if np.any(np.diff(density) <= 0):
        raise ValueError("the band emission density does not rise along the state relation "
                         "for these channels; select channels where hot combustion products "
                         "emit more than ambient air")
    index = np.arange(density.size)
    position = np.interp(tomography.emission.ravel(), density, index)
    fields = np.stack([np.interp(position, index, field) for field in states])
    return fields.reshape((4, *scene.grid.shape))


def _measured_values(shape, noise, measured) -> np.ndarray:
    """Where the data were measured, ``shape``: ``measured`` if given, else where the noise
    (W/(m²·sr·cm⁻¹)) is finite, else everywhere."""
    if measured is None:
        return np.ones(shape, bool) if noise is None else np.isfinite(noise)
    measured = np.asarray(measured)
    if measured.shape != shape or measured.dtype != bool:
        raise ValueError(f"measured must be a boolean mask of the data's shape {shape}, got "
                         f"dtype {measured.dtype} and shape {measured.shape}")
    return measured
