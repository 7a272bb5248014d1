"""Vibration–rotation levels of ¹²C¹⁶O₂ for the 15 µm line list: term values and compositions.

Two sources of rovibrational term values are combined:

Tabulated levels
    The 25 levels of :data:`co2_constants.LEVELS` (Rothman & Young 1981, up to 3715 cm⁻¹) use
    their published constants: E_e(J) = G + B·x − D·x² + H·x³, x = J(J+1).
Model levels
    Every other level of the polyads 2v1 + v2 ≤ :data:`MAX_POLYAD`, v3 ≤ :data:`MAX_V3` comes from
    an effective Hamiltonian in the normal-mode basis |v1 v2 ℓ v3⟩ (the form of Chédin 1979):
    diagonal Dunham-type terms ω_i v_i + x_ij v_i v_j + x_ℓℓ ℓ² + y_222 v2³, and Fermi coupling
    ⟨v1 v2 ℓ v3|H|v1−1 v2+2 ℓ v3⟩ = −W·√v1·√((v2+2)² − ℓ²)/2 with W linear in v1, v2, v3.
    Its 14 constants are least-squares fitted to the 25 published term values (rms residual
    ≈ 0.02 cm⁻¹); x33, which those levels (v3 ≤ 1) cannot fix, is the value of Gordon &
    McCubbin (1966). Rotational constants of the basis states, B° and D°, are linear in the
    quantum numbers; together with a rotational Fermi term W_J·J(J+1) they are least-squares
    fitted to the published e-level term values of the same levels at J = 0–80 (agreement
    ≤ 0.1 cm⁻¹ at J = 30, ≤ 0.3 cm⁻¹ at J = 60). Rotational levels of a polyad are the
    eigenvalues of H_vib + diag(B°·x − D°·x²) at each J, so the J-dependence of the Fermi
    mixing (the large D and H of strongly mixed levels) comes out of the diagonalization.

Compositions (Fermi mixing coefficients, used for intensities) are the J = 0 eigenvectors of
the model for every polyad, tabulated or not. Labels follow HITRAN/AFGL: v1 v2 ℓ v3 r with v1
the largest v1 of the polyad, v2 = ℓ, r ranking members from the top (r = 1 highest).

ℓ-type doubling: f levels of ℓ = 1 states lie q_eff·x above e levels, q_eff = q·Σ c_i²(v2_i + 1)/2
(Herzberg's (v2 + 1) scaling) with the second-order value q of the bending fundamental;
ℓ ≥ 2 levels are taken as e/f degenerate and no ℓ-type resonance (Δℓ = ±2) is included.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from invflame.spectroscopy import co2_constants as const

MAX_POLYAD = 9
"""Highest Fermi polyad number 2v1 + v2 generated (keeps one-digit HITRAN quanta)."""

MAX_V3 = 2
"""Highest ν3 quantum number generated."""

MAX_ENERGY = 9000.0
"""Levels whose J = 0 term value exceeds this (cm⁻¹) are left out."""

J_TABLE = 202
"""Term values are tabulated for J = 0 … J_TABLE − 1 (covers J'' ≤ 200 and J' = J'' + 1)."""

Basis = tuple[int, int, int, int]
"""Normal-mode basis state (v1, v2, ℓ, v3)."""


@dataclass(frozen=True, eq=False)
class Level:
    """A vibrational level with its composition and rotational term values.

    Attributes
    ----------
    label : str
        Five-digit HITRAN label v1 v2 ℓ v3 r, e.g. ``"10002"``.
    v1, v2, l, v3, r : int
        Quantum numbers of the label.
    composition : tuple of (float, Basis)
        Expansion coefficients over normal-mode basis states (sum of squares 1).
    G : float
        Vibrational term value, cm⁻¹ (J = ℓ energy less B·ℓ(ℓ+1), the Rothman–Young convention).
    E_e, E_f : ndarray, shape (J_TABLE,)
        Term values of the e and f rotational levels for J = 0 … J_TABLE − 1, cm⁻¹.
    tabulated : bool
        Whether the level's constants are the published ones rather than the model's.
    """

    label: str
    v1: int
    v2: int
    l: int  # noqa: E741 - ℓ2 is the spectroscopic name
    v3: int
    r: int
    composition: tuple[tuple[float, Basis], ...]
    G: float
    E_e: np.ndarray
    E_f: np.ndarray
    tabulated: bool

    @property
    def polyad(self) -> int:
        """Fermi polyad number 2v1 + v2."""
        return 2 * self.v1 + self.v2

    @property
    def hitran_v(self) -> str:
        """The 15-character HITRAN 2004 global quanta field, e.g. ``'       0 1 1 01'``."""
        return f"      {self.v1:2d}{self.v2:2d}{self.l:2d}{self.v3:2d}{self.r:1d}"


def l_doubling_constant() -> float:
    """Second-order ℓ-type doubling constant q of the ν2 bending state, cm⁻¹ (Herzberg 1945)."""
    b0 = const.LEVELS["00001"].B
    w2, w3 = const.OMEGA2, const.OMEGA3
    return 2.0 * b0**2 / w2 * (1.0 + 4.0 * w2**2 / (w3**2 - w2**2))


def polyad_basis(polyad: int, l: int, v3: int) -> list[Basis]:  # noqa: E741
    """Normal-mode states of the Fermi polyad (2v1 + v2 = ``polyad``, ℓ, v3), highest v1 first."""
    n = (polyad - l) // 2
    return [(k, polyad - 2 * k, l, v3) for k in range(n, -1, -1)]


def _diagonal_terms(b: Basis) -> np.ndarray:
    v1, v2, l, v3 = b  # noqa: E741
    return np.array([v1, v2, v3, v1 * v1, v2 * v2, v1 * v2, v1 * v3, v2 * v3, l * l, v2**3])


def _fermi_terms(upper_v1: Basis) -> np.ndarray:
    """Fermi matrix element between ``upper_v1`` and the state with v1 − 1, v2 + 2 over W."""
    v1, v2, l, v3 = upper_v1  # noqa: E741
    harmonic = 0.5 * np.sqrt(v1) * np.sqrt((v2 + 2) ** 2 - l**2)
    return -harmonic * np.array([1.0, v1, v2, v3])


@dataclass(frozen=True)
class VibrationalModel:
    """Effective vibrational Hamiltonian (cm⁻¹) fitted to the published term values.

    Attributes
    ----------
    diagonal : ndarray, shape (10,)
        ω1, ω2, ω3, x11, x22, x12, x13, x23, x_ℓℓ, y222 (term values relative to 00001).
    fermi : ndarray, shape (4,)
        W0, W_1, W_2, W_3: Fermi constant W = W0 + W_1·v1 + W_2·v2 + W_3·v3.
    rms : float
        Rms residual of the fit to the tabulated term values, cm⁻¹.
    """

    diagonal: np.ndarray
    fermi: np.ndarray
    rms: float

    def hamiltonian(self, basis: list[Basis]) -> np.ndarray:
        """Vibrational Hamiltonian matrix of a polyad basis (see :func:`polyad_basis`)."""
        n = len(basis)
        h = np.zeros((n, n))
        for i, b in enumerate(basis):
            h[i, i] = _diagonal_terms(b) @ self.diagonal + const.X33 * b[3] ** 2
            if i + 1 < n:
                h[i, i + 1] = h[i + 1, i] = _fermi_terms(b) @ self.fermi
        return h


def _tabulated_polyads() -> dict[tuple[int, int, int], list[str]]:
    """Labels of :data:`co2_constants.LEVELS` grouped by polyad (2v1 + v2, ℓ, v3), lowest first."""
    groups: dict[tuple[int, int, int], list[str]] = {}
    for label in const.LEVELS:
        v1, v2, l, v3, _ = (int(c) for c in label)  # noqa: E741
        groups.setdefault((2 * v1 + v2, l, v3), []).append(label)
    for key, members in groups.items():
        members.sort(key=lambda s: const.LEVELS[s].G)
        if len(members) != len(polyad_basis(*key)):
            raise ValueError(f"CO2 constants table lacks members of the Fermi polyad {members}")
    return groups


@cache
def vibrational_model() -> VibrationalModel:
    """Fit the effective vibrational Hamiltonian to the [RY81] term values (cached)."""
    from scipy.optimize import least_squares

    groups = _tabulated_polyads()
    n_diag = 10

    def residual(p):
        model = VibrationalModel(p[:n_diag], p[n_diag:], 0.0)
        out = []
        for key, members in groups.items():
            energies = np.linalg.eigvalsh(model.hamiltonian(polyad_basis(*key)))
            out.extend(energies - [const.LEVELS[s].G for s in members])
        return np.array(out)

    start = np.array([1340.0, 667.0, 2349.0, -3.0, 0.0, 0.0, -19.0, -12.0, 0.0, 0.0])
    fit = least_squares(residual, np.concatenate([start, [50.0, 0.0, 0.0, 0.0]]))
    rms = float(np.sqrt(np.mean(fit.fun**2)))
    return VibrationalModel(fit.x[:n_diag], fit.x[n_diag:], rms)


def _rotational_terms(b: Basis) -> np.ndarray:
    v1, v2, l, v3 = b  # noqa: E741
    return np.array([1.0, v1, v2, v3, v1 * v1, v2 * v2, v1 * v2, l * l, v1 * v3, v2 * v3])


def _distortion_terms(b: Basis) -> np.ndarray:
    v1, v2, _, v3 = b
    return np.array([1.0, v1, v2, v3])


def _q_effective(composition) -> float:
    """ℓ-doubling constant of an ℓ = 1 level from its composition, cm⁻¹."""
    return l_doubling_constant() * sum(c**2 * (b[1] + 1) / 2.0 for c, b in composition)


@dataclass(frozen=True)
class RotationalModel:
    """Rotational constants of the normal-mode basis states (cm⁻¹), linear in the quanta.

    B°(v) = b·(1, v1, v2, v3, v1², v2², v1v2, ℓ², v1v3, v2v3) is the mean of the e and f
    series (ℓ-doubling removed), D°(v) = d·(1, v1, v2, v3), and the Fermi coupling gains a
    rotational term: W → W + W_J·J(J+1).
    """

    b: np.ndarray
    d: np.ndarray
    fermi_j: float

    def term_values(self, vib: VibrationalModel, basis: list[Basis], x: np.ndarray) -> np.ndarray:
        """Mean (e/f-averaged) term values of a polyad, shape (len(x), n), highest member first."""
        h = vib.hamiltonian(basis)
        n = len(basis)
        b0 = np.array([_rotational_terms(s) @ self.b for s in basis])
        d0 = np.array([_distortion_terms(s) @ self.d for s in basis])
        stack = np.broadcast_to(h, (x.size, n, n)).copy()
        idx = np.arange(n)
        stack[:, idx, idx] += x[:, None] * b0 - x[:, None] ** 2 * d0
        for i in range(n - 1):
            w_j = -self.fermi_j * _fermi_terms(basis[i])[0] * x
            stack[:, i, i + 1] += w_j
            stack[:, i + 1, i] += w_j
        return np.linalg.eigvalsh(stack)[:, ::-1]


def _compositions(vib: VibrationalModel, basis: list[Basis]) -> np.ndarray:
    """J = 0 eigenvectors of a polyad as columns, highest member first."""
    _, vectors = np.linalg.eigh(vib.hamiltonian(basis))
    return vectors[:, ::-1]


FIT_J = np.arange(0, 90, 10)
"""Rotational quantum numbers at which the model is fitted to the published term values."""


@cache
def rotational_model() -> RotationalModel:
    """Fit B°, D° and W_J to the [RY81] e-level term values of the tabulated levels, J = 0–80."""
    from scipy.optimize import least_squares

    vib = vibrational_model()
    x = FIT_J * (FIT_J + 1.0)
    targets = []
    for key, members in _tabulated_polyads().items():
        basis = polyad_basis(*key)
        vectors = _compositions(vib, basis)
        observed = []
        for k, label in enumerate(reversed(members)):
            c = const.LEVELS[label]
            comp = list(zip(vectors[:, k], basis, strict=True))
            half_q = 0.5 * _q_effective(comp) if key[1] == 1 else 0.0
            observed.append(c.G + (c.B + half_q) * x - c.D * x**2 + c.H * x**3)
        targets.append((basis, np.stack(observed, axis=1)))

    def model(p):
        return RotationalModel(p[:10], p[10:14] * 1e-7, p[14] * 1e-5)

    def residual(p):
        rot = model(p)
        return np.concatenate(
            [(rot.term_values(vib, basis, x) - obs).ravel() for basis, obs in targets]
        )

    start = np.zeros(15)
    start[0], start[10] = const.LEVELS["00001"].B, const.LEVELS["00001"].D * 1e7
    fit = least_squares(residual, start, x_scale="jac")
    return model(fit.x)


def _label(basis: list[Basis], r: int) -> str:
    v1, v2, l, v3 = basis[0]  # noqa: E741
    return f"{v1}{v2}{l}{v3}{r}"


def _parity_split(mean: np.ndarray, l: int, q_eff: float, x: np.ndarray):  # noqa: E741
    if l != 1:
        return mean, mean
    return mean - 0.5 * q_eff * x, mean + 0.5 * q_eff * x


@cache
def levels() -> dict[str, Level]:
    """All levels of polyads 2v1 + v2 ≤ MAX_POLYAD, v3 ≤ MAX_V3 below MAX_ENERGY, by label."""
    vib, rot = vibrational_model(), rotational_model()
    tabulated = _tabulated_polyads()
    J = np.arange(J_TABLE, dtype=float)
    x = J * (J + 1.0)
    out = {}
    for v3 in range(MAX_V3 + 1):
        for polyad in range(MAX_POLYAD + 1):
            for l in range(polyad % 2, polyad + 1, 2):  # noqa: E741
                basis = polyad_basis(polyad, l, v3)
                vectors = _compositions(vib, basis)
                key = (polyad, l, v3)
                if key in tabulated:
                    term = None
                    g0 = [const.LEVELS[s].G for s in reversed(tabulated[key])]
                else:
                    term = rot.term_values(vib, basis, x)
                    # G in the Rothman–Young convention: E(J = ℓ) − B·ℓ(ℓ+1) ≈ E(J = 0)
                    g0 = list(term[0])
                for k in range(len(basis)):
                    if g0[k] > MAX_ENERGY:
                        continue
                    label = _label(basis, k + 1)
                    comp = tuple((float(vectors[i, k]), basis[i]) for i in range(len(basis)))
                    q_eff = _q_effective(comp)
                    if term is None:
                        c = const.LEVELS[label]
                        e = c.G + c.B * x - c.D * x**2 + c.H * x**3
                        e_f = e + (q_eff * x if l == 1 else 0.0)
                    else:
                        e, e_f = _parity_split(term[:, k], l, q_eff, x)
                    v1 = basis[0][0]
                    out[label] = Level(
                        label, v1, l, l, v3, k + 1, comp, float(g0[k]), e, e_f, term is None
                    )
    return out


def term_value(level: Level, J, parity_f) -> np.ndarray:
    """Rovibrational term value E(J, e/f), cm⁻¹, relative to 00001 J = 0."""
    J = np.asarray(J)
    return np.where(parity_f, level.E_f[J], level.E_e[J])


def q_effective(level: Level) -> float:
    """ℓ-doubling constant of an ℓ = 1 level, cm⁻¹ (E_f − E_e = q_eff·J(J+1)); 0 otherwise."""
    return _q_effective(level.composition) if level.l == 1 else 0.0
