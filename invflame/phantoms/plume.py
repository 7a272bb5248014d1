"""Analytic buoyant pool-fire plume: McCaffrey centreline, Heskestad width, Burke–Schumann gas.

Centreline temperature rise (McCaffrey 1979, "Purely buoyant diffusion flames: some
experimental results", NBSIR 79-1910, eq. for ΔT with C = 0.9)::

    ΔT_c / T_0 = (κ / (C √(2 g)))² (z / Q^{2/5})^{2η − 1}

with z in m, Q in kW and (κ, η) = (6.8, 1/2) in the continuous flame (z/Q^{2/5} < 0.08),
(1.9, 0) in the intermittent region (< 0.20) and (1.1, −1/3) in the plume above.

Radial profile: Gaussian with the half-width of Heskestad's plume (Heskestad, "Virtual origins
of fire plumes", Fire Safety J. 5, 1983; SFPE Handbook, ch. "Fire plumes")
``b = 0.12 √(T_c/T_0) (z − z_0)``, ``z_0 = −1.02 D + 0.083 Q^{2/5}``, widened near the base to
cover the pool while the continuous flame necks in.

Composition: the temperature rise sets a lean mixture fraction ``Z = Z_st ΔT / ΔT_f`` with
``ΔT_f`` McCaffrey's continuous-flame rise (the time-averaged flame temperature), and a
fuel-rich core above the pool adds ``Z`` up to 1 at the pool surface; gas and temperature then
follow complete combustion CH4 + 2 O2 + 7.52 N2 → CO2 + 2 H2O + 7.52 N2
(:func:`~invflame.phantoms.composition.burke_schumann_methane`) with a stoichiometric rise of
``ΔT_f``. That makes every point one flame state, a flame whose sheet is only ``ΔT_f`` (≈ 870 K
at 13 kW) above ambient, so the gas carries as much CO2 and H2O per kelvin of rise as a sheet of
that temperature would: about twice what a real methane flame, whose sheet is 1500–1950 K above
ambient, leaves in its time average. ``sheet_rise`` gives the sheet its own rise ``ΔT_s``: each
point then holds the Burke–Schumann state of rise ``ΔT_s`` a fraction ``ΔT_f / ΔT_s`` of the
time and ambient air otherwise (intermittency), which keeps McCaffrey's mean temperature and
moves the mass fractions toward air's by that fraction. In every state of a sheet, temperature
rise and products grow in proportion to the fuel burnt, on either side of stoichiometry, so any
time average of its states and air keeps the sheet's products per kelvin. With
``sheet_rise=1950`` the median of ``(T − T_0)/(X_CO2 + X_H2O)`` over the gas holding more than
1 % of products is 6570 K, near the OpenFOAM pool fire's 7800 K (LES, infinitely fast chemistry,
radiation); without it, 2950 K (each on its 60³ grid).

Optional soot layer (:func:`plume_soot`): soot forms where fuel is hot, on the rich side of the
flame sheet, so its volume fraction is taken proportional to the fuel's mole fraction times the
temperature rise, scaled to a given peak. The plume itself, like the pool fire, is soot-free;
the layer is a separate field, known to a :class:`invflame.scene.Scene` (``soot=``) or carried
by the truth as its fifth field (:meth:`invflame.field.Field.with_soot`, ``truth.soot`` in a
configuration).

Optional perturbation: puffing, a travelling-wave modulation of the centreline rise at the
frequency ``f = 1.5 / √D`` Hz (Cetegen & Ahmed, Combust. Flame 93, 1993), and turbulence, a
smooth random factor (correlation length 0.05 m); both of relative amplitude ``perturbation``.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter

from invflame.field import SPECIES, Field
from invflame.geometry import VoxelGrid
from invflame.phantoms.composition import (
    MOLAR_MASS,
    Z_STOICHIOMETRIC,
    burke_schumann_methane,
    mass_to_mole_fractions,
)

GRAVITY = 9.81  # m/s²
_MCCAFFREY_C = 0.9
# (upper end of z/Q^(2/5) in m/kW^(2/5), kappa, eta) per region
_MCCAFFREY_REGIONS = ((0.08, 6.8, 0.5), (0.20, 1.9, 0.0), (np.inf, 1.1, -1.0 / 3.0))
_TURBULENCE_LENGTH = 0.05  # m, correlation length of the random factor

POOLFIRE_HEAT_RELEASE_KW = 13.0
"""Heat release of the OpenFOAM case in kW: 0.2 m × 0.2 m of CH4 at 0.01 m/s, 300 K, 1 atm
(0.652 kg/m³ → 2.6e-4 kg/s) times its lower heating value 50.0 MJ/kg."""


def mccaffrey_centreline_rise(height, heat_release_kw: float, ambient: float) -> np.ndarray:
    """Time-averaged centreline temperature rise ΔT_c in K of a buoyant fire (McCaffrey 1979).

    Parameters
    ----------
    height : array_like
        Height above the fire source in m (values ≤ 0 count as the continuous flame).
    heat_release_kw : float
        Heat release rate Q in kW.
    ambient : float
        Ambient temperature T_0 in K.
    """
    zstar = np.asarray(height, dtype=np.float64) / heat_release_kw**0.4
    rise = np.empty_like(zstar)
    lower = -np.inf
    for upper, kappa, eta in _MCCAFFREY_REGIONS:
        inside = (zstar >= lower) & (zstar < upper)
        scale = (kappa / (_MCCAFFREY_C * np.sqrt(2 * GRAVITY))) ** 2
        rise[inside] = ambient * scale * np.maximum(zstar[inside], 1e-12) ** (2 * eta - 1)
        lower = upper
    return rise


def synthetic_plume(
    grid: VoxelGrid | None = None,
    *,
    heat_release_kw: float = POOLFIRE_HEAT_RELEASE_KW,
    pool_size: float = 0.2,
    ambient: float = 300.0,
    sheet_rise: float | None = None,
    perturbation: float = 0.0,
    seed: int | None = None,
) -> Field:
    """Methane pool-fire plume on a grid, from McCaffrey's correlations (see module notes).

    The pool (a square of side ``pool_size``) lies at the bottom of the box along
    ``grid.up_axis``, centred horizontally.

    Parameters
    ----------
    grid : VoxelGrid, optional
        Target grid (m); default ``VoxelGrid.poolfire(60)``.
    heat_release_kw : float, optional
        Heat release rate in kW; the default matches the OpenFOAM pool fire (≈ 13 kW).
    pool_size : float, optional
        Side of the square pool in m.
    ambient : float, optional
        Ambient (and fuel) temperature in K.
    sheet_rise : float, optional
        Temperature rise in K of the flame sheet (the stoichiometric state), at least
        McCaffrey's continuous-flame rise ``ΔT_f``; the gas is that sheet's state a fraction
        ``ΔT_f / sheet_rise`` of the time and ambient air otherwise (see module notes; the
        adiabatic rise of methane–air is about 1950 K). Default: ``ΔT_f`` itself, every point
        one flame state.
    perturbation : float, optional
        Relative amplitude in [0, 1) of puffing and turbulent fluctuations; 0 gives the smooth
        time-averaged plume.
    seed : int, optional
        Seed of the random phase and turbulence; required when ``perturbation > 0``.

    Returns
    -------
    Field
        ``T`` [K] and mole fractions of CO2, H2O, CH4; metadata records the parameters.
    """
    grid = VoxelGrid.poolfire(60) if grid is None else grid
    if heat_release_kw <= 0 or pool_size <= 0 or ambient <= 0:
        raise ValueError(
            f"heat_release_kw ({heat_release_kw} kW), pool_size ({pool_size} m) and ambient "
            f"({ambient} K) must be positive"
        )
    flame_rise = mccaffrey_centreline_rise(0.0, heat_release_kw, ambient)
    sheet_rise = float(flame_rise if sheet_rise is None else sheet_rise)
    if not sheet_rise >= flame_rise:
        raise ValueError(f"sheet_rise ({sheet_rise} K) must be at least the continuous flame's "
                         f"time-averaged rise ({flame_rise:.0f} K at {heat_release_kw} kW): the "
                         "sheet is the hottest state the mean is made of")
    if not 0 <= perturbation < 1:
        raise ValueError(f"perturbation must lie in [0, 1); got {perturbation}")
    if perturbation > 0 and seed is None:
        raise ValueError("a perturbed plume needs an explicit seed (seed=...)")

    up = grid.up_axis
    centres = grid.centres()
    height = centres[..., up] - grid.lower[up]
    horizontal = [a for a in range(3) if a != up]
    axis = grid.centre[horizontal]
    radius = np.sqrt(sum((centres[..., a] - c) ** 2 for a, c in zip(horizontal, axis, strict=True)))

    q25 = heat_release_kw**0.4
    pool_radius = pool_size / np.sqrt(np.pi)  # radius of the disc of the same area
    continuous_top = 0.08 * q25  # m
    centre_rise = mccaffrey_centreline_rise(height, heat_release_kw, ambient)

    rng = np.random.default_rng(seed)
    if perturbation > 0:
        frequency = 1.5 / np.sqrt(2 * pool_radius)  # Hz, Cetegen & Ahmed 1993
        velocity = 1.9 * heat_release_kw**0.2  # m/s, McCaffrey's intermittent-region velocity
        phase = rng.uniform(0, 2 * np.pi)
        centre_rise = centre_rise * (
            1 + perturbation * np.sin(2 * np.pi * frequency * height / velocity + phase)
        )

    virtual_origin = -1.02 * 2 * pool_radius + 0.083 * q25
    plume_width = 0.12 * np.sqrt(1 + centre_rise / ambient) * np.maximum(
        height - virtual_origin, 0.0
    )
    base_width = pool_radius * np.clip(1 - height / continuous_top, 0.0, 1.0)
    half_width = np.sqrt(plume_width**2 + base_width**2) + 1e-3 * float(grid.spacing.min())
    rise = centre_rise * np.exp(-np.log(2) * (radius / half_width) ** 2)
    if perturbation > 0:
        sigma = _TURBULENCE_LENGTH / grid.spacing
        noise = gaussian_filter(rng.standard_normal(grid.shape), sigma, mode="wrap")
        rise = rise * (1 + perturbation * noise / max(float(noise.std()), 1e-12))

    lean = np.clip(Z_STOICHIOMETRIC * rise / flame_rise, 0.0, Z_STOICHIOMETRIC)
    core_length = 0.5 * continuous_top / np.log(1 / Z_STOICHIOMETRIC)
    core = np.exp(-((radius / pool_radius) ** 4) - height / core_length)
    mixture = np.maximum(lean, core)
    temperature, _ = burke_schumann_methane(mixture, flame_rise, ambient)
    _, sheet = burke_schumann_methane(mixture, sheet_rise, ambient)
    _, air = burke_schumann_methane(0.0, sheet_rise, ambient)  # one state, broadcast
    share = flame_rise / sheet_rise  # of the time the gas holds the sheet's state
    mass = {s: share * sheet[s] + (1 - share) * air[s] for s in sheet}
    mole = mass_to_mole_fractions(mass, MOLAR_MASS)
    values = np.stack([temperature] + [mole[s] for s in SPECIES])
    metadata = {
        "source": "synthetic",
        "model": "McCaffrey 1979 centreline, Heskestad 1983 width, Burke-Schumann CH4-air",
        "heat_release_kw": heat_release_kw,
        "pool_size_m": pool_size,
        "ambient_K": ambient,
        "sheet_rise_K": sheet_rise,
        "perturbation": perturbation,
        "seed": seed,
    }
    return Field(grid, values, metadata)


def plume_soot(field: Field, peak_volume_fraction: float) -> np.ndarray:
    r"""A soot layer for a methane flame: :math:`f_v \propto X_\mathrm{CH_4} (T - T_0)`.

    Soot forms where fuel meets heat, on the rich side of the flame sheet; this places it
    there, scaled so that its largest value is ``peak_volume_fraction``.

    Parameters
    ----------
    field : Field
        A flame (T in K, mole fractions), e.g. :func:`synthetic_plume`; :math:`T_0` is its
        lowest temperature.
    peak_volume_fraction : float
        The largest soot volume fraction (dimensionless, in [0, 1); lightly sooting flames
        hold 1e-8 to 1e-6).

    Returns
    -------
    ndarray, shape ``field.grid.shape``
        Soot volume fraction per voxel (zero everywhere when the flame holds no hot fuel).

    Raises
    ------
    ValueError
        For a peak outside [0, 1).
    """
    if not 0 <= peak_volume_fraction < 1:
        raise ValueError(f"peak_volume_fraction must lie in [0, 1), got {peak_volume_fraction!r}")
    temperature, fuel = field.values[0], field.values[1 + SPECIES.index("CH4")]
    sooting = fuel * (temperature - temperature.min())
    largest = float(sooting.max())
    if largest <= 0:
        return np.zeros(field.grid.shape)
    return peak_volume_fraction * sooting / largest
