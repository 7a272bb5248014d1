"""A generated ¹²C¹⁶O₂ line list for the 15 µm ν2 band system (HITRAN molecule 2, isotopologue 1).

No CO₂ line list for 650–725 cm⁻¹ ships with the package, so :func:`generate_co2_lines` builds one
from published constants (:mod:`invflame.spectroscopy.co2_constants`, which cites each of them):

Levels and positions
    :mod:`invflame.spectroscopy.co2_levels`: the 25 levels tabulated by Rothman & Young (1981,
    up to 3715 cm⁻¹) with their published constants, and every other level of the Fermi
    polyads 2v1 + v2 ≤ 9, v3 ≤ 2 below 9000 cm⁻¹ (v2 up to 9; 30004…30001, 22203…, 14402/14401,
    06601, 07701, 08801, 11112/11111, 21113…, 00021, …: 172 levels in all) from an effective
    Hamiltonian fitted to the published term values and rotational constants. f levels of
    ℓ = 1 states lie q_eff·J(J+1) above the e levels.
Nuclear spin statistics
    ¹⁶O has spin 0, so only rovibrational levels symmetric under exchange of the O nuclei exist:
    a level of parity label e (f) exists when (−1)^(J + v2 + v3) = +1 (−1). Σg⁺ states such as
    00001 keep only even J; each J of an ℓ > 0 state keeps one of e/f; all statistical weights
    are g = 2J + 1.
Band system and intensities
    All bands with Δv2 = +1, Δℓ = ±1 (perpendicular, ΔΛ = ±1: Σ–Π, Π–Δ, Π–Σ, Δ–Φ, …) between a
    lower level below :data:`MAX_LOWER_ENERGY` and a level of the next polyad with the same v3,
    v1 and v3 unchanged in the normal-mode basis (≈ 490 bands, among them the ν3 = 1 and 2 hot
    bands 01111←00011, 11111/11112←10011/10012, 01121←00021, …). Transition amplitudes are the
    harmonic bending matrix elements √((v2 ± ℓ + 2)/2) in units of the fundamental's, summed
    over the Fermi compositions of both levels (so Fermi interference, e.g. between the
    10002/10001 and 11102/11101 bands, is kept). Line strengths use Hönl–London factors
    (2J''+1)·⟨J'' ℓ''; 1 Δℓ | J' ℓ'⟩², a factor 2 when one level is a Σ state (both ±ℓ
    components reach it), the Boltzmann factor and stimulated emission; the absolute scale is
    set by the 296 K band intensity of 01101←00001, which all other bands inherit through the
    matrix elements.
Line shape parameters
    γ_air, γ_self and n_air are the |m|-dependent fits of :data:`co2_constants.BROADENING`;
    δ_air is 0. The Einstein A follows from S(296) with the TIPS partition function Q(296 K)
    of HAPI.

What the list misses compared with HITEMP2010 / CDSD-4000
---------------------------------------------------------
* Other isotopologues (636, 628, 627, … together ≈ 1.6 % of CO₂, their bands shifted by up to
  ~20 cm⁻¹, e.g. the 636 ν2 Q branch at 648.5 cm⁻¹).
* High levels: polyads 2v1 + v2 ≥ 10 (v2 ≥ 10), v3 ≥ 3, lower levels above 7000 cm⁻¹ (their
  Boltzmann factor is < 2 % at 2500 K, but their number grows fast), Δv2 = 3 and "forbidden"
  bands (ΔP ≠ 1 between polyads, Δℓ = 0 combinations, bands that borrow intensity through
  ℓ-type or Coriolis resonance, e.g. 03301←10002).
* Positions of model levels: their term values are extrapolated from levels below 3715 cm⁻¹
  (the effective Hamiltonian reproduces the published term values to 0.05 cm⁻¹ and their
  J ≤ 60 rotational levels to 0.3 cm⁻¹; extrapolated band lines come out a few 10⁻² to 0.3
  cm⁻¹ off at J ≈ 30–70). Tabulated constants are fitted to J ≲ 60–80 and drift by a few
  10⁻² cm⁻¹ at J ≈ 100. No J-dependence of q beyond the Fermi mixing, no ℓ-doubling of Δ and
  Φ states and no ℓ-type resonance (Δℓ = ±2): f-level lines of 11101 come out 0.07–0.14 cm⁻¹
  low at J = 50–63, Q lines of 12201←11101 up to 0.9 cm⁻¹ low at J ≈ 85 (the e levels of
  12201 are pushed by the Σ levels of its polyad, the f levels are not).
* Intensities: harmonic matrix elements, no Herman–Wallis factors, no electrical
  anharmonicity beyond what the Fermi mixing carries (bands between Fermi-mixed levels are up
  to 20–35 % off, e.g. 20001←11101 +16 %, 30001←21101 +32 %).
* Line shapes: no band dependence of broadening, no pressure shifts, no line mixing (which
  matters in the strong Q branches at 618, 667 and 721 cm⁻¹), no self-broadening temperature
  exponent.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from invflame.spectroscopy import co2_constants as const
from invflame.spectroscopy.co2_levels import Basis, Level, levels, term_value
from invflame.spectroscopy.linelist import LineList
from invflame.spectroscopy.partition import partition_function

C2 = 1.4387769
"""Second radiation constant hc/k, cm·K."""

C_CM = 2.99792458e10
"""Speed of light, cm/s."""

T_REF = 296.0
"""HITRAN reference temperature, K."""

J_MAX_LIMIT = 200
"""Largest accepted J_max (the effective constants are fitted far below it)."""


def exists(level: Level, J: np.ndarray, parity_f: np.ndarray) -> np.ndarray:
    """Whether rovibrational levels exist for 626 (O nuclei are spin-0 bosons)."""
    J = np.asarray(J)
    sign_even = (J + level.v2 + level.v3) % 2 == 0
    ok = np.where(parity_f, ~sign_even, sign_even) & (J >= level.l)
    if level.l == 0:
        ok = ok & ~np.asarray(parity_f)
    return ok


def _basis_amplitude(a: Basis, b: Basis) -> float:
    """Harmonic ν2 matrix element ⟨b|μ|a⟩ per signed-ℓ component, in units of the fundamental's."""
    if a[0] != b[0] or a[3] != b[3] or b[1] != a[1] + 1:
        return 0.0
    if b[2] == a[2] + 1:
        return np.sqrt((a[1] + a[2] + 2) / 2.0)
    if b[2] == a[2] - 1:
        return np.sqrt((a[1] - a[2] + 2) / 2.0)
    return 0.0


def band_amplitude(lower: Level, upper: Level) -> float:
    """Vibrational transition amplitude upper←lower, in units of the 01101←00001 amplitude."""
    return float(
        sum(
            ca * cb * _basis_amplitude(a, b)
            for ca, a in lower.composition
            for cb, b in upper.composition
        )
    )


def hoenl_london(J_low, l_low: int, J_up, l_up: int) -> np.ndarray:
    """Hönl–London factor (2J''+1)·⟨J'' ℓ''; 1 Δℓ | J' ℓ'⟩² for Δℓ = ℓ' − ℓ'' = ±1.

    Summed over J' it equals 2J''+1. For Σ→Π: R (J''+2)/2, Q (2J''+1)/2, P (J''−1)/2.
    """
    j = np.asarray(J_low, dtype=float)
    jp = np.asarray(J_up, dtype=float)
    m = float(l_up)
    d = l_up - l_low
    if d not in (1, -1):
        raise ValueError(f"perpendicular bands need ℓ' − ℓ'' = ±1, got {d}")
    with np.errstate(divide="ignore", invalid="ignore"):
        if d == 1:
            cg2 = np.select(
                [jp == j + 1, jp == j, jp == j - 1],
                [
                    (j + m) * (j + m + 1) / ((2 * j + 1) * (2 * j + 2)),
                    (j + m) * (j - m + 1) / (2 * j * (j + 1)),
                    (j - m) * (j - m + 1) / (2 * j * (2 * j + 1)),
                ],
            )
        else:
            cg2 = np.select(
                [jp == j + 1, jp == j, jp == j - 1],
                [
                    (j - m) * (j - m + 1) / ((2 * j + 1) * (2 * j + 2)),
                    (j - m) * (j + m + 1) / (2 * j * (j + 1)),
                    (j + m + 1) * (j + m) / (2 * j * (2 * j + 1)),
                ],
            )
    return np.nan_to_num((2 * j + 1) * cg2)


@dataclass(frozen=True)
class BandLines:
    """Lines of one band before the absolute intensity scale is applied (arrays per line)."""

    lower: Level
    upper: Level
    nu: np.ndarray
    E_lower: np.ndarray
    J_lower: np.ndarray
    J_upper: np.ndarray
    branch: np.ndarray
    f_lower: np.ndarray
    relative_strength: np.ndarray


def band_lines(lower: Level, upper: Level, J_max: int) -> BandLines:
    """All P/Q/R lines of upper←lower up to J'' = ``J_max``, with relative 296 K strengths."""
    J = np.arange(lower.l, J_max + 1)
    J_low = np.concatenate([J, J])
    f_low = np.concatenate([np.zeros(J.size, bool), np.ones(J.size, bool)])
    keep = exists(lower, J_low, f_low)
    J_low, f_low = J_low[keep], f_low[keep]
    dJ = np.repeat(np.array([-1, 0, 1]), J_low.size)
    J_low, f_low = np.tile(J_low, 3), np.tile(f_low, 3)
    J_up = J_low + dJ
    f_up = np.where(dJ == 0, ~f_low, f_low)
    keep = exists(upper, J_up, f_up)
    J_low, f_low, J_up, f_up, dJ = J_low[keep], f_low[keep], J_up[keep], f_up[keep], dJ[keep]
    e_low = term_value(lower, J_low, f_low)
    nu = term_value(upper, J_up, f_up) - e_low
    sigma_factor = 2.0 if (lower.l == 0 or upper.l == 0) else 1.0
    strength = (
        sigma_factor
        * band_amplitude(lower, upper) ** 2
        * hoenl_london(J_low, lower.l, J_up, upper.l)
        * nu
        * np.exp(-C2 * e_low / T_REF)
        * -np.expm1(-C2 * nu / T_REF)
    )
    branch = np.array(["P", "Q", "R"])[dJ + 1]
    return BandLines(lower, upper, nu, e_low, J_low, J_up, branch, f_low, strength)


MAX_LOWER_ENERGY = 7000.0
"""Bands start from levels below this term value, cm⁻¹ (their Boltzmann factor at 2500 K is
≥ 2 × 10⁻²)."""


@cache
def bands() -> tuple[tuple[str, str], ...]:
    """(lower, upper) labels of every Δv2 = +1, Δℓ = ±1 band from levels below MAX_LOWER_ENERGY.

    Upper levels lie in the polyad 2v1 + v2 one higher with the same v3; the band is kept when
    its harmonic amplitude over the Fermi compositions is non-zero.
    """
    lv = levels()
    by_polyad: dict[tuple[int, int], list[Level]] = {}
    for level in lv.values():
        by_polyad.setdefault((level.polyad, level.v3), []).append(level)
    pairs = []
    for lo in lv.values():
        if lo.G > MAX_LOWER_ENERGY:
            continue
        for up in by_polyad.get((lo.polyad + 1, lo.v3), []):
            if abs(up.l - lo.l) == 1 and abs(band_amplitude(lo, up)) > 1e-12:
                pairs.append((lo.label, up.label))
    return tuple(pairs)


def _intensity_scale(J_max: int) -> float:
    """Factor turning relative strengths into S(296), cm/molecule: the fundamental's band sum."""
    lv = levels()
    fundamental = band_lines(lv["00001"], lv["01101"], J_max)
    return const.FUNDAMENTAL_BAND_INTENSITY_296 / fundamental.relative_strength.sum()


def broadening(m_abs: np.ndarray) -> dict[str, np.ndarray]:
    """γ_air, γ_self (cm⁻¹/atm at 296 K) and n_air for rotational indices |m| (held to 1–100)."""
    m = np.clip(np.asarray(m_abs, dtype=float), 1.0, 100.0)
    out = {}
    for name, p in const.BROADENING.items():
        out[name] = p.a + p.b * np.exp(-m / p.c) + p.d * m + p.e * m**2
    return out


def einstein_a(nu, S296, E_lower, g_upper) -> np.ndarray:
    """Einstein A coefficient, s⁻¹, from the HITRAN line intensity at 296 K (cm/molecule)."""
    q296 = partition_function(const.MOLECULE, const.ISOTOPOLOGUE, T_REF)
    boltzmann = np.exp(-C2 * E_lower / T_REF) * -np.expm1(-C2 * nu / T_REF)
    return 8.0 * np.pi * C_CM * nu**2 * S296 * q296 / (const.ABUNDANCE * g_upper * boltzmann)


def generate_co2_lines(
    nu_min: float = 600.0, nu_max: float = 800.0, J_max: int = 120, S_min: float = 1e-30
) -> LineList:
    """Generate ¹²C¹⁶O₂ lines of the 15 µm ν2 band system.

    Parameters
    ----------
    nu_min, nu_max : float
        Wavenumber window, cm⁻¹; lines with ``nu_min <= nu <= nu_max`` are kept.
    J_max : int
        Highest lower-state rotational quantum number J''.
    S_min : float
        Drop lines with S(296 K) below this, cm/molecule.

    Returns
    -------
    LineList
        Lines sorted by wavenumber, HITRAN conventions (S296 includes the 626 abundance,
        E_lower relative to 00001 J = 0, HITRAN 2004 quanta strings, g = 2J + 1).

    Raises
    ------
    ValueError
        If the window is empty or reversed, ``J_max`` is outside 1–200 or ``S_min`` is negative.
    """
    if not nu_min < nu_max:
        raise ValueError(f"need nu_min < nu_max (cm⁻¹), got nu_min={nu_min}, nu_max={nu_max}")
    if not 1 <= int(J_max) <= J_MAX_LIMIT:
        raise ValueError(f"J_max must be between 1 and {J_MAX_LIMIT}, got {J_max}")
    if S_min < 0:
        raise ValueError(f"S_min must be >= 0 cm/molecule, got {S_min}")
    J_max = int(J_max)
    scale = _intensity_scale(J_max)
    lv = levels()
    parts = []
    for lo, up in bands():
        bl = band_lines(lv[lo], lv[up], J_max)
        S = scale * bl.relative_strength
        keep = (bl.nu >= nu_min) & (bl.nu <= nu_max) & (S >= S_min)
        if not keep.any():
            continue
        J_low, J_up, nu, E = bl.J_lower[keep], bl.J_upper[keep], bl.nu[keep], bl.E_lower[keep]
        branch, f_low, S = bl.branch[keep], bl.f_lower[keep], S[keep]
        m_abs = np.where(branch == "R", J_low + 1, J_low)
        widths = broadening(m_abs)
        g_up = 2.0 * J_up + 1.0
        sym = np.where(f_low, "f", "e")
        parts.append(
            LineList(
                molecule=np.full(nu.size, const.MOLECULE),
                isotopologue=np.full(nu.size, const.ISOTOPOLOGUE),
                nu=nu,
                S296=S,
                A=einstein_a(nu, S, E, g_up),
                gamma_air=widths["gamma_air"],
                gamma_self=widths["gamma_self"],
                E_lower=E,
                n_air=widths["n_air"],
                delta_air=np.zeros(nu.size),
                V_upper=np.full(nu.size, bl.upper.hitran_v),
                V_lower=np.full(nu.size, bl.lower.hitran_v),
                Q_upper=np.full(nu.size, " " * 15),
                Q_lower=[
                    f"     {b}{j:3d}{s}     " for b, j, s in zip(branch, J_low, sym, strict=True)
                ],
                g_upper=g_up,
                g_lower=2.0 * J_low + 1.0,
            )
        )
    lines = LineList.concatenate(parts)
    return lines.select(np.argsort(lines.nu, kind="stable"))
