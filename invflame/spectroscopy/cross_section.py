r"""Line-by-line absorption cross-sections on a uniform wavenumber grid.

:math:`\sigma(\eta) = \sum_i S_i(T)\, f_i(\eta - \nu_i^*)` in cm²/molecule, with
:math:`\nu_i^* = \nu_i + \delta_\mathrm{air} (p - p_\mathrm{self})` (no self shift in the
record, :func:`~invflame.spectroscopy.line_parameters.pressure_shift`) and :math:`f_i` a Voigt
profile of Doppler HWHM :math:`\gamma_D` and Lorentz HWHM :math:`\gamma_L`
(:mod:`invflame.spectroscopy.line_parameters`).

**Bin averages.** Grid point :math:`\eta_k` stands for the bin
:math:`[\eta_k - h/2, \eta_k + h/2]` (h = grid step) and :math:`\sigma_k` is the mean of
:math:`\sigma` over it, so :math:`h \sum_k \sigma_k` conserves the line areas although lines
(HWHM down to ~0.005 cm⁻¹ at 1 atm and flame temperatures) are narrower than the 0.04 cm⁻¹ grid.

* **Core** (bins whose centre lies within ``core`` = 0.5 cm⁻¹ of the line's nearest bin): the
  Voigt profile (:func:`scipy.special.voigt_profile`) is averaged over ``m`` equally spaced
  sub-samples per bin, with the fine step ``h/m`` at most 0.01 cm⁻¹ and at most half the line's
  Voigt HWHM (``m`` a power of two, chosen per line). Sampling a profile at half its HWHM
  integrates its area to better than 1e-5.
* **Wings** (beyond the core out to the cutoff): the profile is evaluated at the bin centre as a
  Lorentzian. There the Doppler part (HWHM < 0.005 cm⁻¹ in this window up to 5000 K) no longer
  matters, and the midpoint rule errs by :math:`h^2/(4 d^2)` ≈ 0.2 % of the local wing value at
  d = 0.5 cm⁻¹, less further out.
* **Cutoff**: each line is truncated ``wing`` = 25 cm⁻¹ from its centre (to within half a
  bin: ``round(wing/h)`` bins from the bin nearest the centre). This is the convention of
  line-by-line codes for the continuum split (Clough et al. 1989, Atmos. Res. 23, 229): a
  Lorentzian holds :math:`2\gamma_L/(\pi \cdot 25)` ≈ 0.1 % of its area beyond it at 1 atm,
  and real CO2 far wings are sub-Lorentzian anyway. Lines centred up to 25 cm⁻¹ outside the
  grid contribute their wings, so give line lists that extend 25 cm⁻¹ beyond it.
"""

from __future__ import annotations

import numpy as np
from scipy.special import voigt_profile

from invflame.spectroscopy.line_parameters import (
    ATM,
    doppler_hwhm,
    line_intensity,
    lorentz_hwhm,
    pressure_shift,
)
from invflame.spectroscopy.linelist import LineList

#: Default line-by-line grid: 650–725 cm⁻¹ every 0.04 cm⁻¹ (1876 points).
DEFAULT_RANGE = (650.0, 725.0)
DEFAULT_STEP = 0.04
#: Default line cutoff from the line centre, cm⁻¹.
WING_CUTOFF = 25.0
#: Half width of the finely sampled line core, cm⁻¹.
CORE_HALF_WIDTH = 0.5
#: Largest fine sampling step inside line cores, cm⁻¹.
MAX_FINE_STEP = 0.01
_MAX_OVERSAMPLE = 1024
_CHUNK_ELEMENTS = 2_000_000


def default_wavenumber() -> np.ndarray:
    """The default line-by-line grid, 650–725 cm⁻¹ at 0.04 cm⁻¹ (1876 points), in cm⁻¹."""
    n = int(round((DEFAULT_RANGE[1] - DEFAULT_RANGE[0]) / DEFAULT_STEP)) + 1
    return DEFAULT_RANGE[0] + DEFAULT_STEP * np.arange(n)


def grid_step(wavenumber) -> float:
    """Step (cm⁻¹) of a uniform increasing grid; ``ValueError`` if the grid is not uniform."""
    wavenumber = np.asarray(wavenumber, dtype=np.float64)
    if wavenumber.ndim != 1 or wavenumber.size < 2:
        raise ValueError(f"wavenumber must be 1-D with >= 2 points, got shape {wavenumber.shape}")
    steps = np.diff(wavenumber)
    step = (wavenumber[-1] - wavenumber[0]) / (wavenumber.size - 1)
    if step <= 0 or not np.allclose(steps, step, rtol=1e-6, atol=0):
        raise ValueError("wavenumber must be uniform and increasing (cm-1)")
    return float(step)


def voigt_hwhm(gamma_doppler, gamma_lorentz):
    """Voigt half width at half maximum (cm⁻¹), Olivero & Longbothum (1977), JQSRT 17, 233."""
    return 0.5346 * gamma_lorentz + np.sqrt(0.2166 * gamma_lorentz**2 + gamma_doppler**2)


def _oversampling(step: float, hwhm: np.ndarray) -> np.ndarray:
    """Sub-samples per bin: a power of two with step/m <= MAX_FINE_STEP and <= hwhm / 2."""
    needed = np.maximum(step / MAX_FINE_STEP, 2.0 * step / hwhm)
    m = 2 ** np.ceil(np.log2(np.maximum(needed, 1.0))).astype(np.int64)
    return np.minimum(m, _MAX_OVERSAMPLE)


def _add_cores(padded, pad, step, position, intensity, sigma, gamma, core_bins, m):
    """Bin-averaged Voigt cores of lines (position in bin units from the first grid point)."""
    nearest = np.rint(position).astype(np.int64)
    offsets = np.arange(-core_bins, core_bins + 1)
    sub = (np.arange(m) + 0.5) / m - 0.5
    fine = ((offsets[:, None] + sub) * step).ravel()
    chunk = max(1, _CHUNK_ELEMENTS // fine.size)
    for start in range(0, position.size, chunk):
        part = slice(start, start + chunk)
        x = fine - ((position[part] - nearest[part]) * step)[:, None]
        profile = voigt_profile(x, sigma[part, None], gamma[part, None])
        values = intensity[part, None] * profile.reshape(-1, offsets.size, m).mean(axis=2)
        bins = (nearest[part, None] + pad) + offsets
        padded += np.bincount(bins.ravel(), weights=values.ravel(), minlength=padded.size)


def _add_wings(padded, pad, step, position, intensity, gamma, core_bins, wing_bins):
    """Lorentz wings evaluated at bin centres, from the core edge out to the cutoff."""
    if wing_bins <= core_bins:
        return
    nearest = np.rint(position).astype(np.int64)
    outer = np.arange(core_bins + 1, wing_bins + 1)
    offsets = np.concatenate([-outer[::-1], outer])
    chunk = max(1, _CHUNK_ELEMENTS // offsets.size)
    for start in range(0, position.size, chunk):
        part = slice(start, start + chunk)
        x = offsets * step - ((position[part] - nearest[part]) * step)[:, None]
        x *= x
        x += (gamma[part] ** 2)[:, None]
        values = (intensity[part] * gamma[part] / np.pi)[:, None] / x
        bins = (nearest[part, None] + pad) + offsets
        padded += np.bincount(bins.ravel(), weights=values.ravel(), minlength=padded.size)


def cross_section(
    lines: LineList,
    wavenumber,
    temperature: float,
    pressure: float = ATM,
    self_fraction: float = 0.0,
    wing: float = WING_CUTOFF,
) -> np.ndarray:
    """Bin-averaged absorption cross-section of a line list, cm²/molecule.

    See the module docstring for the line shape, bin averaging and cutoff.

    Parameters
    ----------
    lines : LineList
        Lines of one absorbing gas (any isotopologues); intensities as in HITRAN (natural
        abundance included).
    wavenumber : array_like, shape (n_eta,)
        Uniform increasing grid of bin centres, cm⁻¹.
    temperature : float
        K.
    pressure : float
        Total pressure in Pa (default 1 atm = 101325 Pa).
    self_fraction : float
        Mole fraction of the absorbing gas, for self broadening (0 to 1).
    wing : float
        Line cutoff distance from the line centre, cm⁻¹ (> 0.5).

    Returns
    -------
    ndarray, shape (n_eta,), float64
    """
    wavenumber = np.asarray(wavenumber, dtype=np.float64)
    step = grid_step(wavenumber)
    if not 0.0 <= self_fraction <= 1.0:
        raise ValueError(f"self_fraction must be a mole fraction in [0, 1], got {self_fraction}")
    if not pressure > 0:
        raise ValueError(f"pressure must be positive (Pa), got {pressure}")
    if not wing > CORE_HALF_WIDTH:
        raise ValueError(f"wing cutoff must exceed the core half width {CORE_HALF_WIDTH} cm-1")
    centre = lines.nu + pressure_shift(lines, pressure, self_fraction * pressure)
    reach = wing + step / 2
    lines = lines.select((centre >= wavenumber[0] - reach) & (centre <= wavenumber[-1] + reach))
    if len(lines) == 0:
        return np.zeros(wavenumber.size)
    centre = lines.nu + pressure_shift(lines, pressure, self_fraction * pressure)
    position = (centre - wavenumber[0]) / step
    intensity = line_intensity(lines, temperature)
    gamma = lorentz_hwhm(lines, temperature, pressure, self_fraction * pressure)
    gamma_d = doppler_hwhm(lines, temperature)
    sigma = gamma_d / np.sqrt(2.0 * np.log(2.0))
    core_bins = int(round(CORE_HALF_WIDTH / step))
    wing_bins = int(round(wing / step))
    pad = 2 * wing_bins + 2  # lines up to one cutoff outside, wings one cutoff further
    padded = np.zeros(wavenumber.size + 2 * pad)
    oversample = _oversampling(step, voigt_hwhm(gamma_d, gamma))
    for m in np.unique(oversample):
        group = oversample == m
        _add_cores(
            padded, pad, step, position[group], intensity[group], sigma[group], gamma[group],
            core_bins, int(m),
        )
    _add_wings(padded, pad, step, position, intensity, gamma, core_bins, wing_bins)
    return padded[pad : pad + wavenumber.size]
