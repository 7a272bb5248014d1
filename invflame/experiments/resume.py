"""Resuming a run folder safely: refuse one written under another configuration, truth,
data or code (:func:`check_resumable`, :func:`check_fingerprint`), unless forced; continue a
finished run to a raised iteration limit (:func:`continues_finished_run`) and refuse a limit
below the iterations already done (:func:`resumed_from`)."""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

import invflame
import solvers
from invflame.atomic_files import read_json
from invflame.errors import InputDataError
from invflame.experiments import config as configuration
from invflame.experiments.run_folder import CHECKPOINT, FINGERPRINT, SUMMARY
from invflame.field import Field
from invflame.measurement import Measurement

__all__ = ["FINGERPRINT", "FORCE_HINT", "check_fingerprint", "check_resumable",
           "checkpoint_of_this_run", "continues_finished_run", "resumed_from",
           "run_fingerprint"]

FORCE_HINT = "; --force (invflame run --resume --force) continues anyway and records it"


def _differences(a: dict, b: dict, where: str = "") -> list[str]:
    keys = sorted(set(a) | set(b))
    out = []
    for key in keys:
        path = f"{where}.{key}" if where else key
        if isinstance(a.get(key), dict) and isinstance(b.get(key), dict) and key != "options":
            out += _differences(a[key], b[key], path)
        elif a.get(key) != b.get(key):
            out.append(f"{path}: {a.get(key)!r} there, {b.get(key)!r} now")
    return out


def check_resumable(cfg: dict, folder, force: bool = False) -> list[str]:
    """Refuse to resume a run folder written under another configuration (a larger iteration
    limit is allowed: it continues the run).

    Parameters
    ----------
    cfg : dict
        Validated configuration of the resumed run.
    folder : str or Path
        The run folder.
    force : bool, optional
        Return the differences instead of refusing.

    Returns
    -------
    list of str
        Every changed key with its value there and now (empty when nothing changed).

    Raises
    ------
    ConfigError
        Naming every key whose value differs from the folder's ``config.toml`` (unless
        ``force``).
    """
    saved = Path(folder) / "config.toml"
    if not saved.is_file():
        return []
    changed = [d for d in _differences(configuration.load(saved), cfg)
               if not d.startswith("solver.iterations:")]
    return _refuse_unless_forced(folder, changed, force, "it was run with another configuration",
                                 "the same configuration")


def _below_done(folder, done: float, limit: int) -> configuration.ConfigError:
    """The refusal of a limit of ``limit`` epochs for a run that did ``done``."""
    return configuration.ConfigError(
        f"cannot resume {Path(folder)}: it has done {done:g} epochs, but 'solver.iterations' "
        f"= {limit} now stops it before them: set solver.iterations to at least {done:g} "
        "(higher continues the run), or start a new folder (invflame run --overwrite)")


def continues_finished_run(cfg: dict, folder) -> bool:
    """Whether resuming the finished run in ``folder`` continues it: its solver stopped at its
    iteration limit and ``solver.iterations`` is now higher. Otherwise its result stands (the
    same limit, or a stop before the limit by another rule, where a run with the new limit
    would have stopped too).

    Parameters
    ----------
    cfg : dict
        Validated configuration of the resumed run.
    folder : str or Path
        The run folder, holding ``summary.json``.

    Raises
    ------
    ConfigError
        If ``solver.iterations`` is below the epochs the run did, or the run is to continue
        but its checkpoint is gone.
    """
    summary = read_json(Path(folder) / SUMMARY)
    done, limit = summary["epochs"], cfg["solver"]["iterations"]
    if limit < done:
        raise _below_done(folder, done, limit)
    if not (limit > done and summary["stop_reason"].startswith("max_iter:")):
        return False
    if not (Path(folder) / CHECKPOINT).is_file():
        raise configuration.ConfigError(
            f"cannot continue {Path(folder)} to 'solver.iterations' = {limit}: its "
            f"{CHECKPOINT} is gone; start a new folder (invflame run --overwrite)")
    return True


def resumed_from(cfg: dict, folder, per_epoch: int, changed: list[str]) -> dict:
    """What a run resumed from the checkpoint in ``folder`` records in its summary.

    Parameters
    ----------
    cfg : dict
        Validated configuration of the resumed run.
    folder : str or Path
        The run folder, holding the checkpoint.
    per_epoch : int
        Solver iterations per epoch of the run's representation.
    changed : list of str
        What changed since the folder was written (:func:`check_resumable`,
        :func:`check_fingerprint`), resumed anyway with ``force``.

    Returns
    -------
    dict
        ``from_iteration`` (the checkpoint's solver iteration), ``exact`` (whether the solver
        resumes exactly from this checkpoint), ``forced`` and ``changed``.

    Raises
    ------
    ConfigError
        If ``solver.iterations`` is below the epochs of the checkpoint (the run would stop at
        once, past its own limit).
    CorruptFileError
        If the checkpoint is damaged or its header lacks an entry
        (:func:`solvers.checkpoint.read_run`).
    """
    solver = cfg["solver"]
    checkpoint = solvers.checkpoint.read_run(Path(folder) / CHECKPOINT)
    done = checkpoint.meta["iteration"]
    if done > solver["iterations"] * per_epoch:
        raise _below_done(folder, done / per_epoch, solver["iterations"])
    exact = solvers.get(solver["name"]).resumes_exactly(checkpoint.state)
    return {"from_iteration": done, "exact": exact,
            "forced": bool(changed), "changed": changed}


@contextmanager
def checkpoint_of_this_run(folder) -> Iterator[None]:
    """Run the solver resuming from the checkpoint of the run folder ``folder`` inside this
    context: a checkpoint that another solver, other options or another grid wrote (a file
    copied from another run) becomes an :class:`~invflame.errors.InputDataError` naming it and
    saying to start the run again.
    """
    try:
        yield
    except solvers.checkpoint.CheckpointMismatchError as err:
        raise InputDataError(f"{err.fact}: it belongs to another run; start this one again "
                             f"(invflame run --overwrite --out {folder})") from None


def _content_hash(*arrays) -> str:
    """SHA-256 of arrays' shapes, dtypes and bytes (hex)."""
    digest = hashlib.sha256()
    for array in arrays:
        array = np.ascontiguousarray(array)
        digest.update(f"{array.dtype.str}{array.shape}".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def run_fingerprint(cfg: dict, truth: Field | None, measurement: Measurement | None) -> dict:
    """What defines a run beside its configuration, for :func:`check_fingerprint`.

    Parameters
    ----------
    cfg : dict
        Validated configuration (its solver's ``Options`` dataclass is described).
    truth : Field or None
        Ground truth on the reconstruction grid.
    measurement : Measurement or None
        Measured spectra and noise σ; None leaves ``data sha256`` out (for a finished run
        whose simulated data follow from the rest and are not rendered again).

    Returns
    -------
    dict
        ``truth sha256`` and ``data sha256`` (content hashes of the truth's values and of the
        measured spectra with σ), ``invflame version`` (``invflame.__version__``) and
        ``solver options`` (the solver's options dataclass: each field with its type and
        default).
    """
    options = solvers.get(cfg["solver"]["name"]).Options
    return {
        "truth sha256": None if truth is None else _content_hash(truth.values),
        **({} if measurement is None else
           {"data sha256": _content_hash(measurement.data, measurement.sigma)}),
        "invflame version": invflame.__version__,
        "solver options": f"{options.__module__}.{options.__qualname__}("
                          + ", ".join(f"{f.name}: {f.type} = {f.default!r}"
                                      for f in dataclasses.fields(options)) + ")",
    }


def check_fingerprint(folder, fingerprint: dict, force: bool = False) -> list[str]:
    """Refuse to resume a run folder whose data, truth or code changed since it was written.

    Parameters
    ----------
    folder : str or Path
        The run folder; its ``fingerprint.json`` is compared. A folder holding results (a
        checkpoint or a summary) without one cannot be compared and is refused; one without
        results (a run stopped before its data were made) has nothing to compare.
    fingerprint : dict
        :func:`run_fingerprint` of the resumed run; only its entries are compared.
    force : bool, optional
        Return the differences instead of refusing.

    Returns
    -------
    list of str
        Each changed entry with its value there and now.

    Raises
    ------
    ConfigError
        Naming each changed entry (unless ``force``).
    """
    saved = Path(folder) / FINGERPRINT
    if saved.is_file():
        changed = _differences({k: v for k, v in read_json(saved).items() if k in fingerprint},
                               fingerprint)
    elif any((Path(folder) / name).is_file() for name in (SUMMARY, CHECKPOINT)):
        changed = [f"{FINGERPRINT} is missing, so the truth, data and code cannot be compared"]
    else:
        return []
    return _refuse_unless_forced(folder, changed, force,
                                 "what defines the run changed since it was written",
                                 "the same truth, data and code")


def _refuse_unless_forced(folder, changed: list[str], force: bool, why: str,
                          same: str) -> list[str]:
    """Raise a :class:`ConfigError` naming ``changed`` (unless empty or ``force``); return it."""
    if changed and not force:
        raise configuration.ConfigError(
            f"cannot resume {Path(folder)}: {why} (" + "; ".join(changed) + f"); resume with "
            f"{same}, or start a new folder (or redo it: invflame run --overwrite){FORCE_HINT}")
    return changed
