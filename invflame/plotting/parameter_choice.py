r"""The choice of the regularization weight :math:`\lambda`: its sweep drawn as an L-curve.

Draws a :class:`solvers.ParameterChoice` (from :func:`solvers.discrepancy_principle` or
:func:`solvers.l_curve`, where the scales of :math:`\chi^2`, :math:`\Phi` and :math:`\lambda`
are defined) on a figure of its own, without pyplot's global state.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from invflame.atomic_files import write_atomic
from solvers import ParameterChoice

TITLES = {"discrepancy": "discrepancy principle", "l-curve": "L-curve"}
"""Figure title by :attr:`solvers.ParameterChoice.rule`."""


def plot_l_curve(choice: ParameterChoice, path, *,
                 phi_label: str = r"regularizer $\Phi(\theta)$ [units of $\Phi$]") -> Path:
    r"""Draw the sweep of ``choice`` as an L-curve (log–log) to a PNG, the choice marked.

    The horizontal axis is :math:`\chi^2/M` (dimensionless, 1 at the noise level) when
    :math:`M` is known, else :math:`\chi^2`; the discrepancy level :math:`\tau M`, if any, is a
    dashed vertical line. Each point is labelled with its :math:`\lambda`.

    Parameters
    ----------
    choice : solvers.ParameterChoice
        Result of :func:`solvers.discrepancy_principle` or :func:`solvers.l_curve`.
    path : str or Path
        Output PNG, written atomically; its folder is created if missing.
    phi_label : str, optional
        Vertical axis label with the units of :math:`\Phi` (e.g. ``"Φ, mean squared
        gradient [K²/m²]"``).

    Returns
    -------
    Path
        ``path``.
    """
    scale = 1.0 if choice.n_measurements is None else 1.0 / choice.n_measurements
    misfit = choice.chi2 * scale
    fig = Figure(figsize=(6.0, 4.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.loglog(misfit, choice.phi, "o-", color="0.3", ms=4, label="tried λ")
    for lam, u, v in zip(choice.lams, misfit, choice.phi, strict=True):
        ax.annotate(f"{lam:.2g}", (u, v), xytext=(4, 3), textcoords="offset points",
                    fontsize=7, color="0.35")
    if choice.target is not None:
        ax.axvline(choice.target * scale, color="tab:blue", ls="--",
                   label=f"discrepancy level χ² = τM = {choice.target:.4g}")
    i = choice.index
    ax.loglog(misfit[i], choice.phi[i], "*", color="red", ms=16,
              label=f"chosen λ = {choice.lam:.3g}" + ("" if choice.reached else " (flagged)"))
    xlabel = "whitened misfit χ²" if choice.n_measurements is None else (
        f"whitened misfit per measurement χ²/M (M = {choice.n_measurements})")
    ax.set(xlabel=xlabel + " [dimensionless]", ylabel=phi_label, title=TITLES[choice.rule])
    ax.legend(fontsize=8)
    return write_atomic(path, lambda handle: fig.savefig(handle, format="png", dpi=120,
                                                         bbox_inches="tight"))
