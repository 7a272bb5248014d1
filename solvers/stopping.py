"""Stopping rules shared by all solvers."""

from __future__ import annotations

from dataclasses import asdict, dataclass

DIVERGENCE = 1e3
"""A step whose objective exceeds the start's by more than this many times the start's
magnitude ends the run as diverged (:func:`diverged`) and keeps the iterate before. Above what
the study's runs do: Adam's first step at the honest study's learning rate raises the
objective of its networks 13- to 195-fold (``docs/validation.md``), and they go on from there;
a learning rate of 1e30 on bounded voxels raises it further at once."""


def diverged(start: float, loss: float) -> str | None:
    """Why an objective ``loss`` tells a run diverged from its ``start``, or None.

    Parameters
    ----------
    start, loss : float
        The objective at the starting point and at a new iterate (loss units).

    Returns
    -------
    str or None
        A reason when ``loss - start`` exceeds :data:`DIVERGENCE` times ``|start|`` (a start
        of 0 gives no scale: never).
    """
    if start != 0 and loss - start > DIVERGENCE * abs(start):
        return (f"the loss rose from {start:.6g} at the start to {loss:.6g}, more than "
                f"{DIVERGENCE:g} times its start")
    return None


def _check_tolerance(name, value):
    if value is not None and not value >= 0:
        raise ValueError(f"{name} must be None (off) or >= 0, got {value}")


@dataclass(frozen=True)
class StoppingRule:
    r"""When to stop; each rule is off when None.

    Parameters
    ----------
    max_iter : int
        Maximum number of iterations in total (a resumed run counts those done before).
    rtol_loss : float, optional
        Stop when :math:`|L_k - L_{k-w}| \le \text{rtol}\,|L_{k-w}|` with
        :math:`w` = ``loss_window``: the objective changed by less than ``rtol`` over the last
        :math:`w` iterations.
    rtol_x : float, optional
        Stop when :math:`\|\theta_k - \theta_{k-1}\| \le \text{rtol}\,\|\theta_{k-1}\|`.
    gtol : float, optional
        Stop when the norm of the projected gradient is at most ``gtol`` (loss units per
        parameter unit).
    time_budget : float, optional
        Wall-clock seconds one call to ``run`` may take; checked between iterations.
    loss_window : int, optional
        Iterations :math:`w` over which ``rtol_loss`` measures the change (default 1). First-order
        methods take many small steps: a window (e.g. 20) tells a plateau from a slow step.
    misfit_target : float, optional
        Stop when the misfit :math:`\|W(F(\theta) - d)\|^2` (loss units) is at most this
        value: the discrepancy principle as a stopping rule, which makes the iteration count
        the regularizer (Engl, Hanke & Neubauer, *Regularization of Inverse Problems*,
        Kluwer 1996). With the noise-weighted misfit :math:`\chi^2`, ``tau * M`` stops at
        :math:`\chi^2/M \le \tau`.
    """

    max_iter: int = 100
    rtol_loss: float | None = None
    rtol_x: float | None = None
    gtol: float | None = None
    time_budget: float | None = None
    loss_window: int = 1
    misfit_target: float | None = None

    def __post_init__(self):
        if int(self.max_iter) != self.max_iter or self.max_iter < 0:
            raise ValueError(f"max_iter must be a non-negative integer, got {self.max_iter}")
        if int(self.loss_window) != self.loss_window or self.loss_window < 1:
            raise ValueError(f"loss_window must be a positive integer, got {self.loss_window}")
        for name in ("rtol_loss", "rtol_x", "gtol", "time_budget", "misfit_target"):
            _check_tolerance(name, getattr(self, name))

    def as_dict(self) -> dict:
        """The rules as a plain dict."""
        return asdict(self)

    def budget_spent(self, iteration: int, call_seconds: float) -> str | None:
        """Reason to stop before the next iteration (iteration count or time), or None."""
        if iteration >= self.max_iter:
            return f"max_iter: reached {self.max_iter} iterations"
        if self.time_budget is not None and call_seconds >= self.time_budget:
            return f"time_budget: {call_seconds:.3g} s >= {self.time_budget:g} s"
        return None

    def converged(self, losses, step_ratio: float, grad_norm: float,
                  misfit: float = float("nan")) -> str | None:
        """Reason to stop after an iteration, or None.

        Parameters
        ----------
        losses : array_like
            Objective at every iteration so far, the starting point first and the new
            iterate last.
        step_ratio : float
            Relative change of the parameters in this iteration.
        grad_norm : float
            Norm of the projected gradient at the new iterate.
        misfit : float, optional
            The misfit term at the new iterate (NaN, the default, when unknown: a stochastic
            objective's).
        """
        if self.misfit_target is not None and misfit <= self.misfit_target:
            return f"misfit_target: misfit {misfit:.6g} <= {self.misfit_target:g}"
        if self.gtol is not None and grad_norm <= self.gtol:
            return f"gtol: gradient norm {grad_norm:.3e} <= {self.gtol:g}"
        w = self.loss_window
        if self.rtol_loss is not None and len(losses) > w:
            loss, before = losses[-1], losses[-1 - w]
            if abs(loss - before) <= self.rtol_loss * abs(before):
                over = "" if w == 1 else f" over {w} iterations"
                return f"rtol_loss: relative loss change{over} <= {self.rtol_loss:g}"
        if self.rtol_x is not None and step_ratio <= self.rtol_x:
            return f"rtol_x: relative parameter change {step_ratio:.3e} <= {self.rtol_x:g}"
        return None
