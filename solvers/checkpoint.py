"""Checkpoint files: everything needed to resume a run exactly where it stopped.

A checkpoint is one ``.npz`` file holding the parameters, the gradient at them, the solver's
state arrays (Adam moments, Gauss–Newton damping, dual variables...) and a JSON header (solver
name and options, seed, iteration, history, elapsed time). It is written to a uniquely named
temporary file in the same folder, synced, then renamed over the target
(:func:`solvers.atomic.write_atomic`), so a crash never leaves a torn file and two writers never
share a temporary file; a damaged file is reported with its path (:func:`load_checkpoint`).
Randomness needs no saved generator state: each iteration draws from
``numpy.random.default_rng([seed, iteration, ...])``.

The run loop (:mod:`solvers.base`) uses two calls: :func:`save_run` writes a run's state and
:func:`load_run` reads it back after checking that it belongs to the solver, the options and
the problem at hand.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from solvers.atomic import CorruptFileError, read_npz, write_atomic
from solvers.problem import Evaluation

FORMAT = "invflame-solver-checkpoint/1"
_STATE = "state."
_FIX = "delete it and start the run again without resuming"
HEADER = ("solver", "options", "seed", "iteration", "problem", "dims", "dtype", "elapsed",
          "history", "current")
"""The entries of the JSON header of a run's checkpoint (:func:`save_run`) besides
``format``."""


class CheckpointMismatchError(ValueError):
    """A readable checkpoint written by another solver, with other options or for another
    problem than the run that would resume from it.

    Parameters
    ----------
    fact : str
        What differs, naming the file.
    advice : str
        What to do; the message is ``"{fact}; {advice}"``.

    Attributes
    ----------
    fact : str
        What differs, for a caller that gives its own advice.
    """

    def __init__(self, fact: str, advice: str):
        super().__init__(f"{fact}; {advice}")
        self.fact = fact


@dataclass
class CheckpointData:
    """A loaded checkpoint.

    Attributes
    ----------
    meta : dict
        JSON header: ``solver``, ``options``, ``seed``, ``iteration``, ``problem``, ``dims``,
        ``dtype``, ``elapsed`` (s), ``history`` (columns), ``current`` (loss parts).
    x : ndarray
        Parameters at the checkpoint.
    grad : ndarray or None
        Objective gradient at ``x``.
    state : dict of ndarray
        The solver's state arrays.
    """

    meta: dict
    x: np.ndarray
    grad: np.ndarray | None
    state: dict[str, np.ndarray]

    def evaluation(self, dtype) -> Evaluation:
        """The objective's parts at ``x`` as saved, the gradient cast to ``dtype`` (None when
        the checkpoint holds no gradient: the caller evaluates it again)."""
        c = self.meta["current"]
        grad = None if self.grad is None else self.grad.astype(dtype)
        return Evaluation(c["loss"], c["misfit"], c["regularizer"], grad=grad,
                          sample=c["sample"])


def _plain(value):
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    raise TypeError(f"cannot store {type(value).__name__} in a checkpoint header")


def normalize(value):
    """``value`` as JSON would give it back (tuples become lists, NumPy numbers plain)."""
    return json.loads(json.dumps(value, default=_plain))


def save_checkpoint(path, meta: dict, x: np.ndarray, grad: np.ndarray | None,
                    state: dict[str, np.ndarray]) -> Path:
    """Write a checkpoint atomically; returns its path.

    Parameters
    ----------
    path : str or Path
        Target file (conventionally ``*.npz``); its folder is created if missing.
    meta : dict
        JSON-serializable header.
    x, grad : ndarray
        Parameters and the gradient there (``grad`` may be None).
    state : dict of ndarray
        Solver state arrays.
    """
    arrays = {"x": np.asarray(x),
              "meta": np.array(json.dumps({"format": FORMAT, **meta}, default=_plain))}
    if grad is not None:
        arrays["grad"] = np.asarray(grad)
    arrays.update({_STATE + k: np.asarray(v) for k, v in state.items()})
    return write_atomic(path, lambda stream: np.savez(stream, **arrays))


def load_checkpoint(path) -> CheckpointData:
    """Read a checkpoint written by :func:`save_checkpoint`.

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    CorruptFileError
        If the file is damaged (truncated, empty, garbage) or lacks the checkpoint's entries;
        the message names it and says to delete it and start the run again.
    ValueError
        If it is a readable ``.npz`` of another format.
    """
    path = Path(path)
    arrays = read_npz(path, "checkpoint", _FIX)
    try:
        meta = json.loads(str(arrays["meta"]))
        x = arrays["x"]
    except (KeyError, json.JSONDecodeError) as err:
        raise CorruptFileError(f"checkpoint {path} lacks its header or parameters ({err}); "
                               f"{_FIX}") from err
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        found = meta.get("format") if isinstance(meta, dict) else None
        raise ValueError(f"{path} is not a solver checkpoint (format {found!r}, expected "
                         f"{FORMAT!r})")
    state = {k[len(_STATE):]: v for k, v in arrays.items() if k.startswith(_STATE)}
    return CheckpointData(meta, x, arrays.get("grad"), state)


def save_run(path, run) -> Path:
    """Write a checkpoint of a run; returns its path.

    Parameters
    ----------
    path : str or Path
        Target file (``*.npz``).
    run : solvers.RunState
        The run: its solver (name, options, stopping rules, state arrays), problem, iterate,
        objective, history, seed and elapsed time are saved.
    """
    c = run.current
    meta = {
        "solver": run.solver.name, "options": normalize(run.solver.options.as_dict()),
        "stopping": run.solver.stopping.as_dict(), "seed": run.seed,
        "iteration": run.iteration, "problem": run.problem.name,
        "dims": list(run.problem.dims), "dtype": str(run.problem.dtype),
        "elapsed": run.elapsed, "history": run.history.as_dict(),
        "current": {"loss": c.loss, "misfit": c.misfit, "regularizer": c.regularizer,
                    "sample": c.sample},
    }
    grad = c.grad if c.has_grad else None
    return save_checkpoint(path, meta, run.x, grad, run.solver.state_to_arrays(run))


def read_run(path) -> CheckpointData:
    """Read a checkpoint written by :func:`save_run`, its header complete.

    Raises
    ------
    FileNotFoundError, CorruptFileError, ValueError
        As :func:`load_checkpoint`; :class:`CorruptFileError` also if the header lacks an
        entry of :data:`HEADER` (the message names the file and the entries).
    """
    ck = load_checkpoint(path)
    missing = [key for key in HEADER if key not in ck.meta]
    if missing:
        raise CorruptFileError(f"checkpoint {path} lacks the header entries {missing}; {_FIX}")
    return ck


def load_run(path, solver, problem) -> CheckpointData:
    """Read a checkpoint to resume ``solver`` on ``problem`` from it.

    Parameters
    ----------
    path : str or Path
        Checkpoint written by :func:`save_run`.
    solver : solvers.Solver
        The solver that continues the run (its stopping rules may differ from the
        checkpoint's, e.g. a larger ``max_iter``).
    problem : solvers.Problem
        The problem it continues on.

    Raises
    ------
    FileNotFoundError, CorruptFileError, ValueError
        As :func:`read_run`.
    CheckpointMismatchError
        If the checkpoint was written by another solver, with other options (each changed
        option is named with both values) or for parameters of another shape.
    """
    ck = read_run(path)
    meta = ck.meta
    if meta["solver"] != solver.name:
        raise CheckpointMismatchError(
            f"checkpoint {path} was written by solver {meta['solver']!r}, not {solver.name!r}",
            f"resume with solvers.get({meta['solver']!r}), or start a new run")
    saved, now = meta["options"], normalize(solver.options.as_dict())
    changed = [f"{k}: {saved.get(k)!r} in the checkpoint, {now.get(k)!r} now"
               for k in sorted(set(saved) | set(now)) if saved.get(k) != now.get(k)]
    if changed:
        raise CheckpointMismatchError(
            f"checkpoint {path} was written with other options of solver {solver.name!r} "
            f"({'; '.join(changed)})", "resume with the same options, or start a new run")
    if tuple(meta["dims"]) != problem.dims:
        raise CheckpointMismatchError(
            f"checkpoint {path} holds parameters of shape {tuple(meta['dims'])}, the "
            f"problem's are {problem.dims}",
            "resume on the problem it was written for, or start a new run")
    return ck
