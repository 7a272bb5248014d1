"""Published spectroscopic constants for ¹²C¹⁶O₂ (HITRAN molecule 2, isotopologue 1, "626").

Everything :mod:`invflame.spectroscopy.co2_lines` needs to generate the 15 µm ν2 band system,
with its source. Vibrational levels use the HITRAN/AFGL label v1 v2 ℓ2 v3 r (Rothman & Young
1981): ``r`` ranks the members of a Fermi polyad from the top (r = 1 is the highest).

Sources
-------
[RY81]  L. S. Rothman and L. D. G. Young, "Infrared energy levels and intensities of carbon
        dioxide — II", JQSRT 25, 505–524 (1981), table of vibrational term values G_v and
        effective rotational constants B_v, D_v, H_v of ¹²C¹⁶O₂. These are the constants of the
        e-parity (ℓ-doubling-free) rotational series, E_e(J) = G_v + B_v J(J+1) − D_v [J(J+1)]²
        + H_v [J(J+1)]³, with the −B_v ℓ² term absorbed in G_v.
[H45]   G. Herzberg, *Molecular Spectra and Molecular Structure II: Infrared and Raman Spectra of
        Polyatomic Molecules* (Van Nostrand, 1945): harmonic matrix elements of the degenerate
        bending oscillator, the Fermi-resonance matrix elements ∝ √(v1+1)·√(v2² − ℓ²)/2, and the
        second-order ℓ-type doubling constant of a Π state,
        q = (2B²/ω2)·[1 + 4 Σ_k ζ_2k² ω2²/(ω_k² − ω2²)]. For CO₂ only ζ_23 = 1 contributes
        (ν1 is σg, ν2 πu, ν3 σu).
[JV90]  Band intensity of 01101←00001 at 296 K, 7.9 × 10⁻¹⁸ cm/molecule including the natural
        abundance, quoted as the HITRAN 626 ν2 band sum (Rothman et al. 1992, JQSRT 48, 537)
        and consistent with the absolute measurements of J. W. C. Johns and J. Vander Auwera,
        J. Mol. Spectrosc. 140, 71–102 (1990). The number has not been checked against either
        paper (neither was reachable); with it the fundamental's R(30)e line of HITRAN is
        reproduced to −6 % (no Herman–Wallis factor is applied).
[GM66]  H. R. Gordon and T. K. McCubbin Jr., "The 2.8-micron bands of CO₂", J. Mol. Spectrosc.
        19, 137 (1966): anharmonicity constant x33 = −12.50 cm⁻¹, used for v3 = 2 levels
        (the [RY81] levels have v3 ≤ 1 and cannot fix it; with it 00021 comes out at
        4673.3 cm⁻¹).
[C79]   A. Chédin, "The carbon dioxide molecule: potential, spectroscopic, and molecular
        constants from its infrared spectrum", J. Mol. Spectrosc. 76, 430–491 (1979): the form
        of the effective vibrational Hamiltonian of :mod:`invflame.spectroscopy.co2_levels`
        (Dunham-type diagonal terms, Fermi coupling with vibrational dependence); its
        constants are fitted there to the [RY81] term values, not taken from [C79].
[HIT]   HITRAN natural abundance of ¹²C¹⁶O₂, 0.984204 (Gordon et al. 2022, JQSRT 277, 107949).
[GL13]  R. R. Gamache and J. Lamouroux, "Predicting accurate line shape parameters for CO₂
        transitions", JQSRT 130, 158–171 (2013): the half-widths adopted in HITRAN for CO₂
        depend on the rotational index |m| (m = −J'' in P, J'' in Q, J''+1 in R) and hardly on
        the band. :data:`BROADENING` holds smooth least-squares fits to those HITRAN 626 values
        (γ_air, γ_self at 296 K in cm⁻¹/atm; n_air) over 2 ≤ |m| ≤ 100, sampled from the HITRAN
        lines at 691.4–692.7 cm⁻¹; rms residuals 0.0002, 0.0005 cm⁻¹/atm and 0.009. These fits
        are derived from HITRAN values, not from a published |m| formula (none could be
        consulted: Rosenmann et al. 1988, Appl. Opt. 27, 3902, and the HITRAN 2008 CO₂
        description, Rothman et al. 2009, JQSRT 110, 533, are the sources to replace them with).

Levels not in :data:`LEVELS` (v2 ≥ 6, polyads 2v1 + v2 ≥ 6, v3 = 2, …) come from the effective
Hamiltonian of :mod:`invflame.spectroscopy.co2_levels`, fitted to :data:`LEVELS`.

The levels at 3181–3500 cm⁻¹ are assigned to the HITRAN labels (21103, 13302, 21102, 05501,
13301, 21101) by checking which term values reproduce the HITRAN line positions.
"""

from __future__ import annotations

from dataclasses import dataclass

MOLECULE = 2
"""HITRAN molecule number of CO₂."""

ISOTOPOLOGUE = 1
"""HITRAN local isotopologue number of ¹²C¹⁶O₂."""

ABUNDANCE = 0.984204
"""Natural abundance of ¹²C¹⁶O₂ used in HITRAN intensities [HIT]."""

FUNDAMENTAL_BAND_INTENSITY_296 = 7.9e-18
"""Band intensity of 01101←00001 at 296 K, cm/molecule, abundance included [JV90]; it sets
the absolute scale of every band."""

OMEGA2 = 667.38
"""ν2 fundamental wavenumber, cm⁻¹ (G of 01101 in [RY81]); used in the ℓ-doubling estimate."""

OMEGA3 = 2349.14
"""ν3 fundamental wavenumber, cm⁻¹ (G of 00011 in [RY81]); used in the ℓ-doubling estimate."""

X33 = -12.50
"""Anharmonicity constant x33 of ν3, cm⁻¹ [GM66]; only levels with v3 ≥ 2 depend on it."""


@dataclass(frozen=True)
class LevelConstants:
    """Term value and e-parity rotational constants of one vibrational level [RY81].

    Attributes
    ----------
    G : float
        Vibrational term value, cm⁻¹.
    B, D, H : float
        Effective rotational constants of the e-parity series, cm⁻¹.
    """

    G: float
    B: float
    D: float
    H: float


LEVELS: dict[str, LevelConstants] = {
    "00001": LevelConstants(0.0, 0.39021894, 1.33373e-7, 0.16e-13),
    "01101": LevelConstants(667.379, 0.39064230, 1.359e-7, 0.17e-13),
    "10002": LevelConstants(1285.4087, 0.39048230, 1.57161e-7, 2.33e-13),
    "02201": LevelConstants(1335.129, 0.39167020, 1.389e-7, 0.0),
    "10001": LevelConstants(1388.1847, 0.39018893, 1.14952e-7, 1.91e-13),
    "11102": LevelConstants(1932.472, 0.39073215, 1.441e-7, 0.0),
    "03301": LevelConstants(2003.244, 0.39238558, 1.403e-7, 0.0),
    "11101": LevelConstants(2076.855, 0.39041600, 1.281e-7, 0.0),
    "00011": LevelConstants(2349.1433, 0.38714140, 1.33034e-7, 0.17e-13),
    "20003": LevelConstants(2548.373, 0.39110670, 1.7820e-7, 0.40e-13),
    "12202": LevelConstants(2585.032, 0.39193800, 1.390e-7, 0.0),
    "20002": LevelConstants(2671.146, 0.38954820, 1.2630e-7, 4.65e-13),
    "04401": LevelConstants(2671.716, 0.39308410, 1.42e-7, 0.0),
    "12201": LevelConstants(2760.735, 0.39153500, 1.44e-7, 0.0),
    "20001": LevelConstants(2797.140, 0.39059100, 0.88e-7, 0.0),
    "01111": LevelConstants(3004.012, 0.38759300, 1.349e-7, 0.0),
    "21103": LevelConstants(3181.450, 0.3910280, 1.63e-7, 0.0),
    "13302": LevelConstants(3240.564, 0.3926960, 1.51e-7, 0.0),
    "21102": LevelConstants(3339.340, 0.3900350, 1.37e-7, 0.0),
    "05501": LevelConstants(3340.501, 0.393908, 1.44e-7, 0.0),
    "13301": LevelConstants(3442.256, 0.3922100, 1.36e-7, 0.0),
    "21101": LevelConstants(3500.590, 0.3904610, 1.14e-7, 0.0),
    "10012": LevelConstants(3612.842, 0.38750493, 1.58150e-7, 2.74e-13),
    "02211": LevelConstants(3659.271, 0.38864000, 1.37445e-7, 0.0),
    "10011": LevelConstants(3714.783, 0.38706227, 1.13570e-7, 1.10e-13),
}
"""Vibrational levels of ¹²C¹⁶O₂ up to 3715 cm⁻¹ with their [RY81] constants, keyed by the
five-digit label v1 v2 ℓ2 v3 r."""


@dataclass(frozen=True)
class BroadeningFit:
    """Smooth fit y(|m|) = a + b·exp(−|m|/c) + d·|m| + e·m² of a HITRAN line-shape parameter."""

    a: float
    b: float
    c: float
    d: float
    e: float


BROADENING: dict[str, BroadeningFit] = {
    "gamma_air": BroadeningFit(0.065377, 0.02885, 11.921, 1.4709e-4, -3.1252e-6),
    "gamma_self": BroadeningFit(0.11968, 0.012021, 2.8541, -1.2666e-3, 7.0627e-6),
    "n_air": BroadeningFit(0.64615, 0.0, 1.0, 4.5001e-3, -5.4103e-5),
}
"""|m|-dependent half-width fits for 626 lines [GL13]: γ_air and γ_self in cm⁻¹/atm at 296 K,
n_air dimensionless. Valid for 1 ≤ |m| ≤ 100; :func:`co2_lines.broadening` holds |m| in that
range."""
