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
projected accelerated gradient (:func:`~invflame.experiments.linear_tomography.band_tomography`).
Four cameras on two axes give two independent directions; non-negativity is the prior that
makes so few views usable: a pixel that sees nothing beyond ambient air forces every voxel on
its path to zero. The weight :math:`\lambda` follows the discrepancy principle
(:func:`solvers.discrepancy_principle`): the smoothest solution that fits the band data to the
noise. The ambient air should be the one around the flame: assuming 1 % of water vapour in dry
air leaves a misfit hundreds of times the noise at peak SNR 1000; the start then hardly
changes, but the principle warns and takes its smallest weight.

**Channels.** Line cores that saturate make the band integral fall below the thin limit, most
at the CO₂ ν₂ Q branch (667 cm⁻¹) in gas of a few hundred kelvin.
:func:`~invflame.experiments.band_channels.thin_channels` keeps the channels where a column of
every state of the state relation, as short as the brightest pixel allows, still emits at least
:data:`~invflame.experiments.band_channels.THIN_RATIO` of its thin limit.

**Masked values.** A bad wavenumber (masked in every pixel) leaves the channels, and so does
one that some camera does not measure (outside its own spectral window), as long as the
cameras share a channel; a pixel whose band then lacks a value, a bad pixel, contributes no
row to the linear system: :math:`b`, :math:`A` and :math:`\sigma_b` keep only the pixels
measured in every channel used, and :math:`M` counts those.

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

from itertools import pairwise

import numpy as np

from invflame.experiments.band_channels import channel_emission, channel_weights, thin_channels
from invflame.experiments.initialization import AMBIENT, with_soot_field

# the smoothing weights the band tomography tries, importable from here too
from invflame.experiments.linear_tomography import SMOOTHING_RANGE as SMOOTHING_RANGE
from invflame.experiments.linear_tomography import band_tomography, pixel_path_lengths
from invflame.representations.state_relation import DEFAULT_TEMPERATURE_RISE_ST, StateRelation
from invflame.representations.whitening import noise_weights


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
        unknown): the fixed :data:`~invflame.experiments.linear_tomography.DEFAULT_SMOOTHING`.
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
        Output channels of the band integral (default
        :func:`~invflame.experiments.band_channels.thin_channels`).
    smoothing : float, optional
        Smoothing weight μ ≥ 0 (dimensionless, see
        :func:`~invflame.experiments.linear_tomography.band_tomography`), overriding the rules
        above.
    n_states : int, optional
        States tabulated along the state relation (≥ 2).
    measured : array_like of bool, shape ``scene.data_shape``, optional
        False for a masked value (a bad pixel or wavenumber, a channel outside a camera's
        window; see the module notes); default:
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
    cameras = [measured[start:stop].any(axis=0) for start, stop in pairwise(scene.rig.ray_offsets)]
    somewhere = np.logical_and.reduce(cameras)  # measured by every camera, else by some pixel
    somewhere = somewhere if somewhere.any() else measured.any(axis=0)
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
