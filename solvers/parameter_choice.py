r"""Choosing the regularization weight :math:`\lambda` from the data, without ground truth.

Scaling of :math:`\lambda`
--------------------------
The data term is whitened: with :math:`M` measurements :math:`d_i` of noise standard deviation
:math:`\sigma_i`,

.. math:: \chi^2(\theta) = \sum_{i=1}^{M} \Big(\frac{F_i(\theta) - d_i}{\sigma_i}\Big)^2,

which is dimensionless and close to :math:`M` when the model fits the data to the noise
(:math:`\mathbb{E}\,\chi^2(\theta_\text{true}) = M` for Gaussian noise of known :math:`\sigma`).
The regularizer :math:`\Phi` is a *mean* over grid points and fields (``operators.tikhonov``,
``operators.total_variation``). The objective of this module is

.. math:: J(\theta) = \chi^2(\theta) / M + \lambda\, \Phi(\theta),

so :math:`\lambda` (units: one over the units of :math:`\Phi`) keeps its meaning when the
number of pixels, wavenumbers or voxels changes. :class:`solvers.Problem` minimizes the sum of
squares :math:`\|F(\theta) - d\|^2 + \text{lam}\,\Phi(\theta)` of whitened :math:`F` and
:math:`d`, which is :math:`M\,J(\theta)` for ``lam`` :math:`= \lambda M`
(:func:`problem_weight`). Every :math:`\lambda` below, given or returned, is on the
:math:`J` scale.

Rules
-----
:func:`discrepancy_principle` (noise level known) takes the largest :math:`\lambda` whose
solution fits the data to the noise, :math:`\chi^2(\theta_\lambda) \le \tau M` (Morozov 1966;
Engl, Hanke & Neubauer 1996, §4.3). :func:`l_curve` (noise level unknown) takes the sweep point
where the curve :math:`(\log\chi^2, \log\Phi)` bends most (Hansen 1992; Hansen & O'Leary
1993). Both return a :class:`ParameterChoice`, which holds the sweep (the tried :math:`\lambda`,
:math:`\chi^2` and :math:`\Phi`) for a plot of the L-curve.

References
----------
V. A. Morozov, "On the solution of functional equations by the method of regularization",
Soviet Math. Dokl. 7 (1966) 414–417.
H. W. Engl, M. Hanke, A. Neubauer, *Regularization of Inverse Problems*, Kluwer (1996), §4.3.
P. C. Hansen, "Analysis of discrete ill-posed problems by means of the L-curve",
SIAM Rev. 34 (1992) 561–580.
P. C. Hansen, D. P. O'Leary, "The use of the L-curve in the regularization of discrete
ill-posed problems", SIAM J. Sci. Comput. 14 (1993) 1487–1503.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

#: Relative decrease of :math:`\chi^2` (or increase of :math:`\Phi`) from one tried
#: :math:`\lambda` to the next larger one tolerated before the sweep is called non-monotone.
MONOTONE_RTOL = 1e-6

#: Fewest sweep points :func:`l_curve` accepts (two interior candidates for the corner).
MIN_L_CURVE_POINTS = 4


def problem_weight(lam: float, n_measurements: int) -> float:
    r"""Weight ``lam`` of :class:`solvers.Problem` for the weight :math:`\lambda` of
    :math:`J = \chi^2/M + \lambda\Phi`.

    Parameters
    ----------
    lam : float
        :math:`\lambda \ge 0` on the :math:`J` scale (units: one over the units of
        :math:`\Phi`).
    n_measurements : int
        :math:`M`, the number of measured values in the whitened data term.

    Returns
    -------
    float
        :math:`\lambda M`, the weight on :math:`\|F(\theta) - d\|^2 + \text{lam}\,\Phi(\theta)`
        with whitened :math:`F` and :math:`d`.
    """
    _check_count(n_measurements)
    if not (np.isfinite(lam) and lam >= 0):
        raise ValueError(f"lam must be a finite number >= 0, got {lam}")
    return float(lam) * int(n_measurements)


@dataclass(frozen=True)
class ParameterChoice:
    r"""The regularization weight a rule chose and the sweep it chose it from.

    Attributes
    ----------
    rule : str
        ``"discrepancy"`` or ``"l-curve"``.
    index : int
        Position of the chosen point in ``lams``.
    reached : bool
        Discrepancy: some :math:`\lambda` met :math:`\chi^2 \le \tau M`. L-curve: the sweep
        bends like an L (some point has positive curvature). When False, ``message`` says why
        and the choice is only the best available.
    message : str
        What was chosen and every caveat (criterion not met, range not bracketed, non-monotone
        sweep).
    lams : ndarray
        Tried :math:`\lambda` (units: one over the units of :math:`\Phi`), increasing.
    chi2 : ndarray
        Whitened misfit :math:`\chi^2(\theta_\lambda)` at each (dimensionless).
    phi : ndarray
        Regularizer :math:`\Phi(\theta_\lambda)` at each (units of :math:`\Phi`).
    n_measurements : int or None
        :math:`M`, when known.
    target : float or None
        Discrepancy level :math:`\tau M` (dimensionless); None for the L-curve.
    curvature : ndarray or None
        L-curve: signed curvature of :math:`(\log\chi^2, \log\Phi)` at each point (NaN where
        not computed); None for the discrepancy principle.
    theta : any
        The solution at the chosen :math:`\lambda` as ``solve`` returned it; None for the
        L-curve, which gets points only.
    """

    rule: str
    index: int
    reached: bool
    message: str
    lams: np.ndarray
    chi2: np.ndarray
    phi: np.ndarray
    n_measurements: int | None = None
    target: float | None = None
    curvature: np.ndarray | None = None
    theta: Any = None

    @property
    def lam(self) -> float:
        r"""The chosen :math:`\lambda` (units: one over the units of :math:`\Phi`)."""
        return float(self.lams[self.index])

    def as_dict(self) -> dict:
        """Everything but ``theta`` as plain JSON-serializable values (NaN as None)."""

        def plain(values):
            return None if values is None else [None if np.isnan(v) else float(v)
                                                for v in values]

        return {"rule": self.rule, "lam": self.lam, "index": self.index,
                "reached": self.reached, "message": self.message,
                "n_measurements": self.n_measurements, "target": self.target,
                "lams": plain(self.lams), "chi2": plain(self.chi2), "phi": plain(self.phi),
                "curvature": plain(self.curvature)}


def discrepancy_principle(solve: Callable[[float], tuple[Any, float, float]],
                          n_measurements: int, lam_max: float, lam_min: float, *,
                          tau: float = 1.0, factor: float = 10.0,
                          refine: int = 5) -> ParameterChoice:
    r"""Largest :math:`\lambda` in ``[lam_min, lam_max]`` with :math:`\chi^2(\theta_\lambda)
    \le \tau M` (Morozov's discrepancy principle).

    ``solve`` is called on a geometric ladder from ``lam_max`` down, at most ``factor`` apart,
    until the criterion holds; the step between the last failing and the first passing
    :math:`\lambda` is then halved ``refine`` times in :math:`\log\lambda`, keeping a passing
    lower end. For linear Tikhonov problems solved exactly, :math:`\chi^2(\theta_\lambda)` is
    nondecreasing in :math:`\lambda` (and :math:`\Phi` nonincreasing), so the admissible
    :math:`\lambda` form an interval ending at :math:`\lambda^*` and the result satisfies
    :math:`\lambda^*\,r^{-1} < \lambda \le \lambda^*` with :math:`r` that final bracket ratio
    (at most ``factor ** 2**-refine``). Otherwise the result still passes while a
    :math:`\lambda` at most :math:`r` times larger fails, and ``message`` notes the
    non-monotone points.

    The caller runs its solver in ``solve``, including any warm start: calls come in
    decreasing :math:`\lambda` along the ladder, then alternate inside the final bracket, so
    starting from the solution of the nearest :math:`\lambda` tried so far works well.

    Parameters
    ----------
    solve : callable
        ``solve(lam) -> (theta, chi2, phi)``: the minimizer of :math:`\chi^2/M + \lambda\Phi`
        for ``lam`` :math:`= \lambda`, its whitened misfit :math:`\chi^2` (dimensionless, the
        sum over all :math:`M` measurements) and :math:`\Phi(\theta)` (units of :math:`\Phi`).
    n_measurements : int
        :math:`M`.
    lam_max, lam_min : float
        Search range of :math:`\lambda` (units: one over the units of :math:`\Phi`),
        ``0 < lam_min < lam_max``. ``lam_max`` should over-smooth: there
        :math:`\lambda\Phi` dominates :math:`\chi^2/M`.
    tau : float, optional
        Safety factor :math:`\tau \ge 1` (dimensionless). 1 fits to the expected noise level;
        slightly larger (1.05–1.1) guards against an underestimated :math:`\sigma` and small
        model errors.
    factor : float, optional
        Largest ratio between consecutive :math:`\lambda` of the ladder, > 1.
    refine : int, optional
        Bisection steps in :math:`\log\lambda` after the ladder brackets :math:`\lambda^*`.

    Returns
    -------
    ParameterChoice
        ``rule="discrepancy"``, ``target`` :math:`=\tau M` and ``theta`` the solution at the
        chosen :math:`\lambda`. If no :math:`\lambda` down to ``lam_min`` meets the criterion
        (model error larger than the noise, or ``lam_min`` too large), ``reached`` is False
        and the choice is the tried :math:`\lambda` of smallest :math:`\chi^2`. If ``lam_max``
        already meets it, the admissible range is not bracketed from above. Both cases, and a
        non-monotone sweep, also raise a :class:`RuntimeWarning`.
    """
    _check_count(n_measurements)
    if not (np.isfinite(lam_max) and np.isfinite(lam_min) and 0 < lam_min < lam_max):
        raise ValueError(f"need 0 < lam_min < lam_max (finite), got lam_min={lam_min}, "
                         f"lam_max={lam_max}")
    if not tau >= 1:
        raise ValueError(f"tau must be >= 1 (chi2 <= tau*M with M the noise level), got {tau}")
    if not factor > 1:
        raise ValueError(f"factor must be > 1 (ratio between ladder steps), got {factor}")
    if int(refine) != refine or refine < 0:
        raise ValueError(f"refine must be a non-negative integer, got {refine}")
    target = tau * n_measurements
    tried: dict[float, tuple[float, float]] = {}

    def evaluate(lam: float):
        theta, chi2, phi = solve(lam)
        chi2, phi = float(chi2), float(phi)
        if not (np.isfinite(chi2) and chi2 >= 0 and np.isfinite(phi) and phi >= 0):
            raise ValueError(f"solve({lam:.6g}) returned chi2={chi2}, phi={phi}; both must be "
                             "finite and >= 0 (did the solver diverge at this lambda?)")
        tried[lam] = (chi2, phi)
        return theta, chi2

    n_ladder = math.ceil(math.log(lam_max / lam_min) / math.log(factor) - 1e-9) + 1
    lower = upper = None  # largest passing and smallest failing lambda so far
    smallest_chi2 = math.inf
    for lam in map(float, np.geomspace(lam_max, lam_min, n_ladder)):
        theta, chi2 = evaluate(lam)
        if chi2 <= target:
            lower, chosen_theta = lam, theta
            break
        upper = lam
        if chi2 < smallest_chi2:
            smallest_chi2, closest, closest_theta = chi2, lam, theta
    notes = []
    if lower is None:
        notes.append(f"the discrepancy chi2 <= {target:.6g} was not reached down to "
                     f"lambda={lam_min:.3g} (model error larger than the noise, sigma "
                     "underestimated, or lam_min too large); chose the smallest chi2")
        lower, chosen_theta = closest, closest_theta
        reached = False
    elif upper is None:
        notes.append(f"lam_max={lam_max:.3g} already meets the discrepancy: the largest "
                     "admissible lambda may be larger; increase lam_max")
        reached = True
    else:
        for _ in range(int(refine)):
            middle = math.sqrt(lower * upper)
            theta, chi2 = evaluate(middle)
            if chi2 <= target:
                lower, chosen_theta = middle, theta
            else:
                upper = middle
        reached = True
    lams = np.array(sorted(tried))
    chi2 = np.array([tried[lam][0] for lam in lams])
    phi = np.array([tried[lam][1] for lam in lams])
    notes += _monotonicity_notes(lams, chi2, phi)
    index = int(np.flatnonzero(lams == lower)[0])
    summary = (f"discrepancy principle: lambda={lower:.6g}, chi2/M="
               f"{chi2[index] / n_measurements:.4g} (target tau={tau:g}) after {lams.size} "
               "solves")
    return _finish("discrepancy", index, reached, summary, notes, lams, chi2, phi,
                   n_measurements=int(n_measurements), target=target, theta=chosen_theta)


def l_curve(lams, chi2, phi, *, n_measurements: int | None = None) -> ParameterChoice:
    r"""Corner of the L-curve: the sweep point of largest curvature of
    :math:`(\log\chi^2, \log\Phi)`.

    The points are ordered by increasing :math:`\lambda`; along them :math:`\chi^2` grows and
    :math:`\Phi` falls, and the corner turns counter-clockwise in the
    :math:`(\log\chi^2, \log\Phi)` plane. The curvature at a point is the signed Menger
    curvature :math:`2\,(b-a)\times(c-b) / (|b-a|\,|c-b|\,|c-a|)` (one over the radius of the
    circle through the point :math:`b` and its neighbours :math:`a, c`), so four points
    already give two candidates; a point equal to the one before it is skipped. Rescaling
    :math:`\chi^2` or :math:`\Phi` by a constant shifts the curve and does not move the
    corner. The points are taken as given: where unconverged solves make nearly equal points
    jitter (at the flat ends of a wide sweep), a false sharp bend can win; such jitter usually
    breaks the monotonicity of :math:`\chi^2` or :math:`\Phi`, which ``message`` reports.

    Parameters
    ----------
    lams : array_like
        Swept :math:`\lambda > 0`, distinct, any order (units: one over the units of
        :math:`\Phi`).
    chi2 : array_like
        Whitened misfit :math:`\chi^2(\theta_\lambda) > 0` at each (dimensionless).
    phi : array_like
        :math:`\Phi(\theta_\lambda) > 0` at each (units of :math:`\Phi`).
    n_measurements : int, optional
        :math:`M`, recorded for plots of :math:`\chi^2/M`.

    Returns
    -------
    ParameterChoice
        ``rule="l-curve"``, with ``curvature`` (NaN at the ends and at repeated points). If no
        point has positive curvature the sweep has no corner (range too narrow, or all on one
        arm): ``reached`` is False, the choice is the point of largest curvature anyway, and a
        :class:`RuntimeWarning` is raised.
    """
    if n_measurements is not None:
        _check_count(n_measurements)
    columns = [np.asarray(v, dtype=np.float64) for v in (lams, chi2, phi)]
    if any(c.ndim != 1 for c in columns) or len({c.size for c in columns}) != 1:
        raise ValueError("lams, chi2 and phi must be 1-D arrays of one length, got shapes "
                         f"{[c.shape for c in columns]}")
    if columns[0].size < MIN_L_CURVE_POINTS:
        raise ValueError(f"the L-curve needs at least {MIN_L_CURVE_POINTS} points, got "
                         f"{columns[0].size}; sweep more lambda values")
    for name, c in zip(("lams", "chi2", "phi"), columns, strict=True):
        if not np.all(np.isfinite(c) & (c > 0)):
            raise ValueError(f"{name} must be finite and > 0 (the L-curve is drawn in logs), "
                             f"got {c.tolist()}")
    order = np.argsort(columns[0])
    lams, chi2, phi = (c[order] for c in columns)
    if np.any(np.diff(lams) == 0):
        raise ValueError(f"lams must be distinct, got {lams.tolist()}")
    x, y = np.log(chi2), np.log(phi)
    kept = [0]
    for i in range(1, lams.size):
        if (x[i], y[i]) != (x[kept[-1]], y[kept[-1]]):
            kept.append(i)
    if len(kept) < 3:
        raise ValueError(f"only {len(kept)} of the {lams.size} points differ on the L-curve "
                         "(the solutions do not change); sweep a wider lambda range")
    a, b, c = (np.stack([x[kept[s]], y[kept[s]]]) for s in (slice(None, -2), slice(1, -1),
                                                             slice(2, None)))
    ab, bc, ac = b - a, c - b, c - a
    cross = ab[0] * bc[1] - ab[1] * bc[0]
    curvature = np.full(lams.size, np.nan)
    curvature[kept[1:-1]] = 2 * cross / (np.hypot(*ab) * np.hypot(*bc) * np.hypot(*ac))
    index = int(np.nanargmax(curvature))
    reached = bool(curvature[index] > 0)
    notes = []
    if not reached:
        notes.append("no point bends like the corner of an L (no positive curvature): widen "
                     "the lambda range; chose the point of largest curvature")
    elif index in (kept[1], kept[-2]):
        notes.append("the largest curvature is at the first or last interior point: the corner"
                     " may lie beyond the sweep; extend the lambda range")
    notes += _monotonicity_notes(lams, chi2, phi)
    summary = (f"L-curve: lambda={lams[index]:.6g}, curvature {curvature[index]:.3g} "
               f"among {lams.size} points")
    return _finish("l-curve", index, reached, summary, notes, lams, chi2, phi,
                   n_measurements=n_measurements, curvature=curvature)


def _check_count(n_measurements) -> None:
    if int(n_measurements) != n_measurements or n_measurements < 1:
        raise ValueError(f"n_measurements must be a positive integer (the number of measured "
                         f"values M), got {n_measurements}")


def _monotonicity_notes(lams, chi2, phi) -> list[str]:
    """Notes where chi2 falls or Phi grows from one lambda to the next larger one."""
    notes = []
    for name, values, sign in (("chi2", chi2, 1), ("phi", phi, -1)):
        step = sign * np.diff(values)
        bad = np.flatnonzero(step < -MONOTONE_RTOL * np.abs(values[:-1]))
        if bad.size:
            where = ", ".join(f"{lams[k]:.3g}->{lams[k + 1]:.3g}" for k in bad)
            notes.append(f"{name} is not {'non-decreasing' if sign > 0 else 'non-increasing'}"
                         f" in lambda (at {where}): solves not converged or different local "
                         "minima; the choice rests on the points as given")
    return notes


def _finish(rule, index, reached, summary, notes, lams, chi2, phi, **fields) -> ParameterChoice:
    message = "; ".join([summary, *notes])
    if notes:
        warnings.warn(message, RuntimeWarning, stacklevel=3)
    return ParameterChoice(rule=rule, index=index, reached=reached, message=message, lams=lams,
                           chi2=chi2, phi=phi, **fields)
