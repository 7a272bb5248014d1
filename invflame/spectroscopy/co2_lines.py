"""A generated ¹²C¹⁶O₂ line list for the 15 µm ν2 band system (HITRAN molecule 2, isotopologue 1).

No CO₂ line list for 650–725 cm⁻¹ ships with the package, so :func:`generate_co2_lines` builds one
from published constants (:mod:`invflame.spectroscopy.co2_constants`, which cites each of them):

Positions
    Every vibrational level of :data:`co2_constants.LEVELS` (Rothman & Young 1981, up to
    3715 cm⁻¹) has e-parity term values E_e(J) = G + B·x − D·x² + H·x³, x = J(J+1). The f levels of
    ℓ = 1 states lie higher by q_eff·x (ℓ-type doubling), with q_eff = q·Σ c_i²(v2_i + 1)/2 over
    the normal-mode basis states of the level (Herzberg's (v2 + 1) scaling; c_i from the Fermi
    mixing below) and q the second-order value 2B²/ω2·[1 + 4ω2²/(ω3² − ω2²)] = 6.17 × 10⁻⁴ cm⁻¹.
    ℓ ≥ 2 levels are taken as e/f degenerate.
Nuclear spin statistics
    ¹⁶O has spin 0, so only rovibrational levels symmetric under exchange of the O nuclei exist:
    a level of parity label e (f) exists when (−1)^(J + v2 + v3) = +1 (−1). Σg⁺ states such as
    00001 keep only even J; each J of an ℓ > 0 state keeps one of e/f; all statistical weights
    are g = 2J + 1.
Band system and intensities
    All bands between these levels with Δv2 = +1, Δℓ = ±1 (perpendicular, ΔΛ = ±1: Σ–Π, Π–Δ,
    Π–Σ, Δ–Φ, …), v1 and v3 unchanged in the basis. Fermi polyads (10002/10001, 11102/11101, …,
    20003/20002/20001, 21103/21102/21101) are expanded in normal-mode basis states: dyad
    fractions from the sum rule of their B constants, triads from a Fermi matrix whose coupling
    ratios follow the harmonic matrix elements √(v1+1)·√(v2² − ℓ²)/2. Transition amplitudes
    are the harmonic bending matrix elements √((v2 ± ℓ + 2)/2) in units of the fundamental's,
    summed over basis states (so Fermi interference between 10002/10001 and 11102/11101
    bands is kept). Line strengths use Hönl–London factors (2J''+1)·⟨J'' ℓ''; 1 Δℓ | J' ℓ'⟩²,
    a factor 2 when one level is a Σ state (both ±ℓ components reach it), the Boltzmann factor
    and stimulated emission; the absolute scale is set by the published 296 K band intensity of
    01101←00001, which all other bands inherit through the matrix elements.
Line shape parameters
    γ_air, γ_self and n_air are the |m|-dependent fits of :data:`co2_constants.BROADENING`;
    δ_air is 0. The Einstein A follows from S(296) with the TIPS partition function Q(296 K)
    of HAPI.

What the list misses compared with HITEMP2010 / CDSD-4000
---------------------------------------------------------
* Other isotopologues (636, 628, 627, … together ≈ 1.6 % of CO₂, their bands shifted by up to
  ~20 cm⁻¹, e.g. the 636 ν2 Q branch at 648.5 cm⁻¹).
* Weak and high bands: levels above 3715 cm⁻¹ (v2 ≥ 6, v1 + v2 ≥ 4 polyads, v3 ≥ 2, the 00011
  ladder beyond 02211/10012/10011), Δv2 = 3 and "forbidden" bands, and Δℓ = 0 combinations.
  At flame temperatures these hot bands hold a growing share of the 15 µm emission
  (see the validation script for the measured shortfall at 1000 and 1500 K).
* Positions: the effective constants are fitted to J ≲ 60–80; positions drift by a few
  10⁻² cm⁻¹ at J ≈ 100. No J-dependence of q, no ℓ-doubling of Δ and Φ states and no ℓ-type
  resonance (Δℓ = ±2, e.g. 03301 with the f levels of 11101/11102): f-level lines of 11101
  come out 0.12–0.22 cm⁻¹ low at J = 50–63, those of 12201 up to 0.9 cm⁻¹ at J ≈ 85. The
  Rothman–Young term values of the weakest levels (e.g. 05501) are off by up to 0.09 cm⁻¹.
* Intensities: harmonic matrix elements, no Herman–Wallis factors, no electrical
  anharmonicity beyond what the Fermi mixing carries, no intensity borrowing through
  Coriolis or ℓ-type resonances; Fermi mixing from a two-constant model, not the full
  effective Hamiltonian of CDSD.
* Line shapes: no band dependence of broadening, no pressure shifts, no line mixing (which
  matters in the strong Q branches at 618, 667 and 721 cm⁻¹), no self-broadening temperature
  exponent.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from invflame.spectroscopy import co2_constants as const
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

Basis = tuple[int, int, int, int]
"""Normal-mode basis state (v1, v2, ℓ, v3)."""


@dataclass(frozen=True)
class Level:
    """A vibrational level: label, quantum numbers and its normal-mode composition.

    Attributes
    ----------
    label : str
        Five-digit HITRAN label v1 v2 ℓ v3 r, e.g. ``"10002"``.
    v1, v2, l, v3, r : int
        Quantum numbers of the label.
    composition : tuple of (float, Basis)
        Expansion coefficients over normal-mode basis states (sum of squares 1).
    """

    label: str
    v1: int
    v2: int
    l: int  # noqa: E741 - ℓ2 is the spectroscopic name
    v3: int
    r: int
    composition: tuple[tuple[float, Basis], ...]

    @property
    def constants(self) -> const.LevelConstants:
        """The [RY81] term value and rotational constants of this level."""
        return const.LEVELS[self.label]

    @property
    def hitran_v(self) -> str:
        """The 15-character HITRAN 2004 global quanta field, e.g. ``'       0 1 1 01'``."""
        return f"       {self.v1} {self.v2} {self.l} {self.v3}{self.r}"


def l_doubling_constant() -> float:
    """Second-order ℓ-type doubling constant q of the ν2 bending state, cm⁻¹ (Herzberg 1945)."""
    b0 = const.LEVELS["00001"].B
    w2, w3 = const.OMEGA2, const.OMEGA3
    return 2.0 * b0**2 / w2 * (1.0 + 4.0 * w2**2 / (w3**2 - w2**2))


def _parse_label(label: str) -> tuple[int, int, int, int, int]:
    v1, v2, l, v3, r = (int(c) for c in label)  # noqa: E741
    return v1, v2, l, v3, r


def _polyad_basis(v1: int, v2: int, l: int, v3: int) -> list[Basis]:  # noqa: E741
    """Normal-mode states of the Fermi polyad of a level, highest v1 first."""
    n = v1 + (v2 - l) // 2  # polyad index: members share 2·v1 + v2 and ℓ
    return [(k, 2 * (n - k) + l, l, v3) for k in range(n, -1, -1)]


def _dyad_fraction(lower: str, upper: str) -> float:
    """Share of the (0, v2+2) basis state in the lower member of a Fermi dyad (B sum rule).

    B is linear in the composition: B_lower − B_upper = (2f − 1)·ΔB°, where ΔB° is the
    unperturbed B difference of the basis states, taken from the 10002/10001 dyad with
    B°(02⁰0) extrapolated from the mean B of 01101.
    """
    levels = const.LEVELS
    b_mean_01101 = levels["01101"].B + 0.5 * l_doubling_constant()
    b_020 = levels["00001"].B + 2.0 * (b_mean_01101 - levels["00001"].B)
    b_100 = levels["10002"].B + levels["10001"].B - b_020
    delta_b = b_020 - b_100
    f = 0.5 + (levels[lower].B - levels[upper].B) / (2.0 * delta_b)
    return float(np.clip(f, 0.0, 1.0))


def _fermi_coupling_factor(a: Basis, b: Basis) -> float:
    """Harmonic Fermi matrix element between neighbouring basis states, in units of W."""
    big, small = (a, b) if a[1] > b[1] else (b, a)
    return 0.5 * np.sqrt(big[1] ** 2 - big[2] ** 2) * np.sqrt(big[0] + 1)


def _triad_vectors(basis: list[Basis], energies: np.ndarray) -> np.ndarray:
    """Eigenvectors of a Fermi triad whose eigenvalues match ``energies`` (ascending).

    Model: diagonal c + δ·(v1 − 1), couplings −W × harmonic factors. c is the mean of the
    observed energies; W and δ are solved from the two observed spacings.
    """
    from scipy.optimize import least_squares

    factors = np.array([_fermi_coupling_factor(basis[i], basis[i + 1]) for i in range(2)])
    v1 = np.array([b[0] for b in basis], dtype=float)

    def hamiltonian(p):
        w, delta = p
        h = np.diag(energies.mean() + delta * (v1 - 1.0))
        h[0, 1] = h[1, 0] = -w * factors[0]
        h[1, 2] = h[2, 1] = -w * factors[1]
        return h

    def residual(p):
        return np.linalg.eigvalsh(hamiltonian(p)) - energies

    fit = least_squares(residual, x0=[50.0, 10.0], bounds=([0.0, -np.inf], [np.inf, np.inf]))
    _, vectors = np.linalg.eigh(hamiltonian(fit.x))
    return vectors


@cache
def levels() -> dict[str, Level]:
    """All levels of :data:`co2_constants.LEVELS` with their Fermi compositions."""
    out = {}
    groups: dict[tuple[int, ...], list[str]] = {}
    for label in const.LEVELS:
        v1, v2, l, v3, _ = _parse_label(label)  # noqa: E741
        groups.setdefault((2 * v1 + v2, l, v3), []).append(label)
    for members in groups.values():
        members = sorted(members, key=lambda s: const.LEVELS[s].G)
        v1, v2, l, v3, _ = _parse_label(members[0])  # noqa: E741
        basis = _polyad_basis(v1, v2, l, v3)
        if len(basis) != len(members):
            raise ValueError(
                f"CO2 constants table is missing members of the Fermi polyad {members}: "
                f"expected {len(basis)} levels"
            )
        if len(basis) == 1:
            vectors = np.ones((1, 1))
        elif len(basis) == 2:
            f = _dyad_fraction(members[0], members[1])
            vectors = np.array([[np.sqrt(1 - f), -np.sqrt(f)], [np.sqrt(f), np.sqrt(1 - f)]])
        else:
            energies = np.array([const.LEVELS[s].G for s in members])
            vectors = _triad_vectors(basis, energies)
        for k, label in enumerate(members):
            comp = tuple((float(vectors[i, k]), basis[i]) for i in range(len(basis)))
            out[label] = Level(label, *_parse_label(label), composition=comp)
    return out


def q_effective(level: Level) -> float:
    """ℓ-doubling constant of an ℓ = 1 level, cm⁻¹ (E_f − E_e = q_eff·J(J+1)); 0 otherwise."""
    if level.l != 1:
        return 0.0
    weight = sum(c**2 * (b[1] + 1) / 2.0 for c, b in level.composition)
    return l_doubling_constant() * weight


def term_value(level: Level, J: np.ndarray, parity_f: np.ndarray) -> np.ndarray:
    """Rovibrational term value E(J, e/f), cm⁻¹, relative to 00001 J = 0."""
    x = J * (J + 1.0)
    k = level.constants
    return k.G + k.B * x - k.D * x**2 + k.H * x**3 + np.where(parity_f, q_effective(level) * x, 0)


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


@cache
def bands() -> tuple[tuple[str, str], ...]:
    """(lower, upper) label pairs of every allowed Δv2 = +1, Δℓ = ±1 band among the levels."""
    lv = levels()
    pairs = []
    for lo in lv.values():
        for up in lv.values():
            if up.constants.G > lo.constants.G and abs(band_amplitude(lo, up)) > 1e-12:
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
