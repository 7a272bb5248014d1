"""Checkpoint files: everything needed to resume a run exactly where it stopped.

A checkpoint is one ``.npz`` file holding the parameters, the gradient at them, the solver's
state arrays (Adam moments, Gauss–Newton damping, dual variables...) and a JSON header (solver
name and options, seed, iteration, history, elapsed time). It is written to a temporary file in
the same folder, synced, then renamed over the target, so a crash never leaves a torn file.
Randomness needs no saved generator state: each iteration draws from
``numpy.random.default_rng([seed, iteration, ...])``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FORMAT = "invflame-solver-checkpoint/1"
_STATE = "state."


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
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"x": np.asarray(x),
              "meta": np.array(json.dumps({"format": FORMAT, **meta}, default=_plain))}
    if grad is not None:
        arrays["grad"] = np.asarray(grad)
    arrays.update({_STATE + k: np.asarray(v) for k, v in state.items()})
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as f:
        np.savez(f, **arrays)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    return path


def load_checkpoint(path) -> CheckpointData:
    """Read a checkpoint written by :func:`save_checkpoint`."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no checkpoint at {path}")
    with np.load(path, allow_pickle=False) as f:
        meta = json.loads(str(f["meta"]))
        if meta.get("format") != FORMAT:
            raise ValueError(f"{path} is not a solver checkpoint (format {meta.get('format')!r},"
                             f" expected {FORMAT!r})")
        state = {k[len(_STATE):]: f[k] for k in f.files if k.startswith(_STATE)}
        grad = f["grad"] if "grad" in f.files else None
        return CheckpointData(meta, f["x"], grad, state)
