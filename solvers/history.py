"""Per-iteration history and the result every solver returns."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: Columns every history has; solvers may add their own (step size, damping...).
COLUMNS = ("iteration", "loss", "misfit", "regularizer", "grad_norm", "time")


class History:
    r"""Table of per-iteration values, one row per iteration (row 0 is the starting point).

    Columns: ``iteration``; ``loss`` (objective), ``misfit`` (:math:`\|F(\theta)-d\|^2`),
    ``regularizer`` (:math:`\Phi(\theta)`, unweighted), ``grad_norm`` (norm of the projected
    gradient), ``time`` (wall seconds since the run began, s), plus solver-specific ones. A
    value a row does not have is NaN. ``history["loss"]`` is a NumPy array.
    """

    def __init__(self, columns: dict[str, list[float]] | None = None):
        self._data: dict[str, list[float]] = {c: [] for c in COLUMNS}
        if columns:
            lengths = {len(v) for v in columns.values()}
            if len(lengths) > 1:
                raise ValueError(f"history columns differ in length: {sorted(lengths)}")
            self._data.update({k: [float(v) for v in vals] for k, vals in columns.items()})

    def append(self, **row: float) -> None:
        """Add a row; unknown columns are created (earlier rows get NaN)."""
        n = len(self)
        for key in row:
            if key not in self._data:
                self._data[key] = [np.nan] * n
        for key, values in self._data.items():
            values.append(float(row.get(key, np.nan)))

    def __len__(self) -> int:
        return len(self._data["iteration"])

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self._data:
            raise KeyError(f"no history column {key!r}; columns are {', '.join(self.keys())}")
        values = np.asarray(self._data[key])
        return values.astype(int) if key == "iteration" else values

    def keys(self) -> list[str]:
        """Column names."""
        return list(self._data)

    def as_dict(self) -> dict[str, list[float]]:
        """Plain lists per column (JSON-serializable)."""
        return {k: list(v) for k, v in self._data.items()}

    def __repr__(self) -> str:
        return f"<History: {len(self)} rows, columns {', '.join(self.keys())}>"


CONVERGED = ("gtol:", "rtol_loss:", "rtol_x:", "misfit_target:", "converged:",
             "scipy L-BFGS-B: CONVERGENCE",
             "scipy L-BFGS-B: STOP: PROJECTED GRADIENT IS SUFFICIENTLY SMALL")
"""Beginnings of the stop reasons of a converged run: the stopping rules' tests
(:mod:`solvers.stopping`), a solver's own test, SciPy L-BFGS-B's convergence messages."""


DIVERGED = ("diverged:", "non-finite:")
"""Beginnings of the stop reasons of a diverged run: an objective risen a thousandfold
(:func:`solvers.stopping.diverged`) or a non-finite one (:meth:`solvers.base.Solver.loop`)."""


@dataclass(repr=False)
class Result:
    """What a solver run returns.

    Attributes
    ----------
    x : ndarray
        Final parameters, shape of the problem's parameters.
    history : History
        Per-iteration loss, data misfit, regularizer, gradient norm and wall time.
    stop_reason : str
        Why the run stopped (e.g. ``"max_iter: reached 100 iterations"``).
    iterations : int
        Number of iterations done (including those before a resume).
    solver : str
        Registry name of the solver.
    options : dict
        The solver's options, stopping rules included.
    problem : str
        The problem's name.
    seed : int
        Seed of the run's randomness.
    elapsed : float
        Wall time of all segments of the run, s.
    metadata : dict
        The problem's metadata.
    """

    x: np.ndarray
    history: History
    stop_reason: str
    iterations: int
    solver: str
    options: dict[str, Any]
    problem: str
    seed: int
    elapsed: float
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def loss(self) -> float:
        """Objective at :attr:`x` (last history row)."""
        return float(self.history["loss"][-1])

    @property
    def converged(self) -> bool:
        """Whether the run stopped because a convergence test passed (:data:`CONVERGED`), not
        at a limit, on a failed line search, a non-finite value or a callback's request."""
        return self.stop_reason.startswith(CONVERGED)

    @property
    def diverged(self) -> bool:
        """Whether the run stopped because its objective rose a thousandfold or became
        non-finite (:data:`DIVERGED`)."""
        return self.stop_reason.startswith(DIVERGED)

    def __repr__(self) -> str:
        return f"<Result {self}>"

    def __str__(self) -> str:
        return (f"{self.solver} on {self.problem}: {self.iterations} iterations, loss "
                f"{self.history['loss'][0]:.6g} -> {self.loss:.6g} in {self.elapsed:.3g} s "
                f"({self.stop_reason})")
