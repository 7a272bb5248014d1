"""Compare the generated ¹²C¹⁶O₂ line list with a HITRAN reference slice.

Lines are matched by band (V' V''), branch, J'' and e/f symmetry (the HITRAN Q'' field);
intensities are compared at 296 K and, after the HITRAN temperature scaling with the TIPS
partition function of HAPI, at flame temperatures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from invflame.spectroscopy.co2_lines import T_REF, generate_co2_lines
from invflame.spectroscopy.line_parameters import line_intensity
from invflame.spectroscopy.linelist import LineList, read_par


def line_keys(lines: LineList) -> list[tuple[str, str, str]]:
    """Matching key per line: (V', V'', Q'') with whitespace normalized."""
    return [
        (" ".join(vu.split()), " ".join(vl.split()), " ".join(ql.split()))
        for vu, vl, ql in zip(lines.V_upper, lines.V_lower, lines.Q_lower, strict=True)
    ]


@dataclass(frozen=True)
class Comparison:
    """Matched and unmatched lines of a generated list against a reference in one window.

    Attributes
    ----------
    generated, reference : LineList
        The reference lines inside the window; the generated lines inside it plus the
        partners of reference lines that the model places outside it.
    matched : ndarray of int, shape (n, 2)
        Index pairs (generated, reference) of lines with the same band, branch, J'' and e/f.
    in_window : ndarray of bool
        Which generated lines lie inside the window.
    temperatures : tuple of float
        Temperatures (K) at which intensities were compared.
    """

    generated: LineList
    reference: LineList
    matched: np.ndarray
    in_window: np.ndarray
    temperatures: tuple[float, ...]

    def unmatched(self, which: str) -> np.ndarray:
        """In-window lines of ``which`` (``"generated"``/``"reference"``) without a partner."""
        column = {"generated": 0, "reference": 1}[which]
        candidates = np.flatnonzero(self._window_mask(which))
        return np.setdiff1d(candidates, self.matched[:, column])

    def _window_mask(self, which: str) -> np.ndarray:
        if which == "generated":
            return self.in_window
        return np.ones(len(self.reference), dtype=bool)

    def total(self, which: str, T: float) -> float:
        """Total intensity of the in-window lines of ``which`` at ``T`` (K), cm/molecule."""
        lines = getattr(self, which)
        return float(line_intensity(lines, T)[self._window_mask(which)].sum())

    def position_error(self) -> np.ndarray:
        """ν_generated − ν_reference of the matched lines, cm⁻¹."""
        return self.generated.nu[self.matched[:, 0]] - self.reference.nu[self.matched[:, 1]]

    def intensity_ratio(self, T: float) -> np.ndarray:
        """S_generated/S_reference of the matched lines at temperature ``T`` (K)."""
        g = line_intensity(self.generated, T)[self.matched[:, 0]]
        r = line_intensity(self.reference, T)[self.matched[:, 1]]
        return g / r

    def total_ratio(self, T: float) -> float:
        """Total intensity in the window, generated/reference, at temperature ``T`` (K)."""
        return self.total("generated", T) / self.total("reference", T)

    def unmatched_share(self, which: str, T: float) -> float:
        """Share of the total intensity of ``which`` held by its unmatched lines at ``T`` (K)."""
        S = line_intensity(getattr(self, which), T)
        return float(S[self.unmatched(which)].sum()) / self.total(which, T)


def compare(
    generated: LineList,
    reference: LineList,
    nu_min: float,
    nu_max: float,
    temperatures=(296.0, 1000.0, 1500.0),
) -> Comparison:
    """Match ``generated`` against ``reference`` lines within ``nu_min``–``nu_max`` (cm⁻¹)."""
    ref = reference.window(nu_min, nu_max)
    partner = {key: i for i, key in enumerate(line_keys(generated))}
    ref_partner = np.array([partner.get(key, -1) for key in line_keys(ref)], dtype=np.int64)
    inside = (generated.nu >= nu_min) & (generated.nu <= nu_max)
    keep = inside.copy()
    keep[ref_partner[ref_partner >= 0]] = True
    gen = generated.select(keep)
    new_index = np.cumsum(keep) - 1
    has = ref_partner >= 0
    matched = np.stack([new_index[ref_partner[has]], np.flatnonzero(has)], axis=1)
    return Comparison(gen, ref, matched, inside[keep], tuple(float(t) for t in temperatures))


REFERENCE_S_MIN = 1e-30
"""Intensity cutoff of the HITRAN CO₂ lists, S(296 K) in cm/molecule (the CDSD-296 cutoff adopted
by HITRAN; Tashkun et al. 2015, JQSRT 152, 45). Lines below it are missing from the reference,
so generated lines below it are left out of the comparison."""


def validate_against_par(
    path, nu_min: float = 691.38, nu_max: float = 692.68, S_min: float = REFERENCE_S_MIN
) -> Comparison:
    """Generate lines around ``nu_min``–``nu_max`` (cm⁻¹) and compare with the ``.par`` file.

    ``S_min`` (cm/molecule at 296 K) drops generated lines weaker than the reference's cutoff;
    pass 0 to compare every generated line.
    """
    reference = read_par(path)
    generated = generate_co2_lines(nu_min - 1.0, nu_max + 1.0, S_min=S_min)
    return compare(generated, reference, nu_min, nu_max)


def format_report(c: Comparison, max_rows: int = 40) -> str:
    """Human-readable report: matched-line table, unmatched lines, totals."""
    out = []
    T_hot = [t for t in c.temperatures if t != T_REF]
    out.append(
        f"window {c.reference.nu.min():.3f}–{c.reference.nu.max():.3f} cm⁻¹: "
        f"{c.in_window.sum()} generated, {len(c.reference)} reference, {len(c.matched)} matched"
    )
    ratios = {T: c.intensity_ratio(T) for T in c.temperatures}
    dnu = c.position_error()
    S_ref = c.reference.S296[c.matched[:, 1]]
    order = np.argsort(-S_ref)
    head = (
        f"{'V_upper':>15} {'V_lower':>15} {'Q_lower':>8} {'nu_ref':>11} {'dnu':>8} {'S296_ref':>9}"
    )
    out.append(head + "".join(f" {'ratio@' + str(int(T)) + 'K':>12}" for T in c.temperatures))
    for k in order[:max_rows]:
        i, j = c.matched[k]
        row = (
            f"{c.reference.V_upper[j]:>15} {c.reference.V_lower[j]:>15} "
            f"{c.reference.Q_lower[j].strip():>8} {c.reference.nu[j]:11.5f} {dnu[k]:+8.4f} "
            f"{S_ref[k]:9.2e}"
        )
        out.append(row + "".join(f" {ratios[T][k]:12.3f}" for T in c.temperatures))
    if len(order) > max_rows:
        out.append(f"... {len(order) - max_rows} weaker matched lines not shown")
    if len(c.matched):
        out.append(
            f"position error: median |dnu| {np.median(np.abs(dnu)):.4f}, "
            f"max {np.abs(dnu).max():.4f} cm⁻¹"
        )
        for T in c.temperatures:
            r = ratios[T]
            out.append(
                f"intensity ratio at {T:.0f} K: median {np.median(r):.3f}, "
                f"range {r.min():.3f}–{r.max():.3f}"
            )
    for which in ("reference", "generated"):
        idx = c.unmatched(which)
        lines = getattr(c, which)
        shares = "; ".join(
            f"{c.unmatched_share(which, T) * 100:.1f} % at {T:.0f} K" for T in c.temperatures
        )
        out.append(f"unmatched {which} lines: {idx.size} ({shares} of the {which} intensity)")
        S = lines.S296[idx]
        for i in idx[np.argsort(-S)][:10]:
            out.append(
                f"   {lines.V_upper[i]} <- {lines.V_lower[i]} {lines.Q_lower[i].strip():>6} "
                f"nu {lines.nu[i]:.5f} S296 {lines.S296[i]:.2e} E'' {lines.E_lower[i]:.1f}"
            )
    for T in T_hot:
        gen_total, ref_total = c.total("generated", T), c.total("reference", T)
        out.append(
            f"total intensity at {T:.0f} K: generated {gen_total:.4e}, reference {ref_total:.4e}"
            f" cm/molecule, ratio {gen_total / ref_total:.3f}"
        )
    return "\n".join(out)
