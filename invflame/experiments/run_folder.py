"""Output folders of runs: checked before use, locked while written, marked until complete.

:func:`check_output_folder` refuses a path that is a file or lies under one, before anything
is computed (the command line checks ``--out`` so). :func:`check_run_target` refuses a folder
whose files a new run would replace: one holding a run (finished or not) unless it is resumed
or overwritten on purpose, one holding files of the user's own unless overwritten on purpose.
:func:`finished_runs` finds the finished runs of a folder and reads back their files
(:func:`check_run_outputs`) before they are drawn or exported, naming the first damaged one.

:class:`RunLock` holds ``.lock`` (the writer's process id) in a run folder while a run writes
it: a second writer gets an :class:`~invflame.errors.OutputError` naming the folder and the
holder's pid; the lock of a process that no longer exists is taken over, with a warning, by
exactly one of the processes that find it. Where the system tells when a process started
(Linux ``/proc``), the lock records it too, so that a lock whose process id has since been
given to another process is recognized as stale.
While the lock is held the folder also holds :data:`INCOMPLETE`, which says that the outputs
beside it are partial; :meth:`RunLock.complete` removes it once every output is written, so a
folder left by a crash or a kill is marked as such.
"""

from __future__ import annotations

import csv
import fcntl
import logging
import os
import socket
import tempfile
import tomllib
from pathlib import Path

from invflame.atomic_files import CorruptFileError, read_json, read_npz, write_text
from invflame.errors import OutputError

LOCK = ".lock"
"""Lock file of a run folder: the writing process's id, host name and start time (clock ticks
since boot, empty where unknown), one a line."""
INCOMPLETE = "INCOMPLETE"
"""Marker of a run folder whose outputs are partial (being written, or left by a crash)."""
SUMMARY = "summary.json"
"""Metrics of a run, written last: a folder holding it (and not :data:`INCOMPLETE`) is finished."""
FINGERPRINT = "fingerprint.json"
"""What defines a run beside its configuration (:mod:`invflame.experiments.resume`)."""
CHECKPOINT = "checkpoint.npz"
"""The solver's state, written as it goes, from which ``--resume`` continues."""
RUN_MARKERS = (SUMMARY, FINGERPRINT, LOCK, INCOMPLETE)
"""Files that only a run writes: a folder holding one of them is a run folder."""

logger = logging.getLogger(__name__)


def check_output_folder(path) -> Path:
    """``path`` as a :class:`~pathlib.Path` if it can be an output folder (a folder, or
    nothing yet, under a folder this process may write in), without creating it.

    Raises
    ------
    OutputError
        If ``path`` or one of its parents exists and is not a folder, is a link to nothing,
        or if the nearest existing one is a folder this process may not write in.
    """
    path = Path(path)
    for folder in (path, *path.parents):
        where = "" if folder == path else f" lies under {folder}, which"
        if folder.is_symlink() and not folder.exists():
            raise OutputError(f"output folder {path}{where} is a link to {os.readlink(folder)}, "
                              "which does not exist: create that folder, or give another --out")
        if folder.exists() and not folder.is_dir():
            where = "is a file" if folder == path else f"lies under the file {folder}"
            raise OutputError(f"output folder {path} {where}: give a folder path (--out DIR) "
                              "that is a folder or does not exist yet")
        if folder.exists():
            if not os.access(folder, os.W_OK | os.X_OK):
                raise OutputError(f"output folder {path}{where} is a folder this user may not "
                                  "write in: give another --out, or make it writable")
            return path
    return path


def output_folder(path) -> Path:
    """Create the output folder ``path`` (and its parents) after
    :func:`check_output_folder`; returns it as a :class:`~pathlib.Path`.

    Raises
    ------
    OutputError
        As :func:`check_output_folder`, or if the system refuses to create the folder (the
        message gives its reason).
    """
    path = check_output_folder(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f"output folder {path} cannot be created ({err.strerror}): give "
                          "another --out") from None
    return path


def check_run_target(path, resume: bool = False, overwrite: bool = False) -> Path:
    """``path`` as a :class:`~pathlib.Path` if a run may write into it without destroying files
    it was not asked to replace; nothing is created or removed.

    A run may write into a folder that does not exist or is empty; into a run folder (one
    holding any of :data:`RUN_MARKERS`) when it continues that run (``resume``) or replaces
    it (``overwrite``); into any other folder only when ``overwrite``.

    Parameters
    ----------
    path : str or os.PathLike
        The output folder.
    resume : bool, optional
        The run continues the run in the folder.
    overwrite : bool, optional
        The run replaces the folder's run, or writes beside files of other origin (replacing
        those of the same names).

    Raises
    ------
    OutputError
        Naming the folder, what it holds and the options to proceed; also if ``path`` is a
        file or lies under one (:func:`check_output_folder`).
    """
    path = check_output_folder(path)
    held = sorted(entry.name for entry in path.iterdir()) if path.is_dir() else []
    if not held or overwrite:
        return path
    if any(name in held for name in RUN_MARKERS):
        if resume:
            return path
        state = ("a finished run (summary.json)" if SUMMARY in held and INCOMPLETE not in held
                 else "an unfinished run")
        raise OutputError(f"output folder {path} holds {state}: continue it with --resume, "
                          "replace its results with --overwrite, or choose another --out")
    shown = ", ".join(held[:5]) + (f" and {len(held) - 5} more" if len(held) > 5 else "")
    raise OutputError(f"output folder {path} holds files that no run wrote ({shown}): choose "
                      "another --out (a new or empty folder), or --overwrite to write the run "
                      "into it anyway (files of the same names are replaced)")


def finished_runs(folder, marker: str = SUMMARY) -> list[Path]:
    """The finished runs in ``folder``, their outputs read back (:func:`check_run_outputs`):
    the folder itself if it holds ``marker``, else its sub-folders that do (a comparison).

    Parameters
    ----------
    folder : str or os.PathLike
        The output folder of ``invflame run`` (a run), or of ``study``, ``reproduce`` or
        ``sweep`` (runs in sub-folders).
    marker : str, optional
        The file that a finished run holds and the caller needs.

    Raises
    ------
    NotADirectoryError
        If ``folder`` is not a folder.
    FileNotFoundError
        If neither the folder nor a sub-folder holds ``marker``.
    CorruptFileError
        Naming the first damaged output of a run.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise NotADirectoryError(f"{folder} is not a folder: give the output folder of "
                                 "'invflame run', 'study', 'sweep' or 'reproduce'")
    runs = [folder] if (folder / marker).is_file() else sorted(
        path.parent for path in folder.glob(f"*/{marker}"))
    if not runs:
        unfinished = " (it holds an unfinished run: continue it with invflame run --resume)" \
            if any((folder / name).exists() for name in RUN_MARKERS) else ""
        raise FileNotFoundError(f"{folder} holds no {marker}, nor do its sub-folders: no "
                                f"finished run{unfinished}")
    return [check_run_outputs(run) for run in runs]


def check_run_outputs(folder) -> Path:
    """Read back the outputs of the run folder ``folder`` (``.npz``, ``.json``, ``.toml`` and
    ``.csv`` files) before they are drawn or exported.

    Returns
    -------
    pathlib.Path
        ``folder``.

    Raises
    ------
    CorruptFileError
        Naming the first file that is damaged or incomplete, and what to do.
    """
    folder = Path(folder)
    fix = f"run it again (invflame run --overwrite --out {folder})"
    for path in sorted(folder.iterdir()):
        if path.suffix == ".npz":
            read_npz(path, "output", fix)
        elif path.suffix == ".json":
            read_json(path)
        elif path.suffix in (".toml", ".csv"):
            try:
                _check_text(path)
            except (ValueError, UnicodeDecodeError) as err:
                raise CorruptFileError(f"{path} is damaged or incomplete ({err}); {fix}") from err
    return folder


def _check_text(path: Path) -> None:
    """Parse a TOML file, or a CSV table (a header row, then at least one row as long);
    ValueError (or UnicodeDecodeError) if it cannot be."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".toml":
        tomllib.loads(text)
        return
    rows = list(csv.reader(text.splitlines()))
    if len(rows) < 2 or any(len(row) != len(rows[0]) for row in rows):
        raise ValueError("expected a header row, then rows of as many values")


def _started(pid: int) -> str:
    """When process ``pid`` started, in clock ticks since boot (``/proc/<pid>/stat`` field 22);
    empty where the system does not say (no ``/proc``) or no such process runs."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return ""
    return stat.rpartition(")")[2].split()[19]  # fields after the command name start at 3


def _alive(pid: int, started: str) -> bool:
    """Whether process ``pid`` runs and, if ``started`` is known, is the one that started then
    (not a later process given the same id)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        pass
    return not started or _started(pid) in ("", started)


class RunLock:
    """Exclusive writer of a run folder, as a context manager.

    On entry: creates the folder (:func:`output_folder`), takes ``.lock`` (atomically: a hard
    link to a file that already holds this process's id and host; a stale lock is removed
    first, by one process at a time, :meth:`_take_over_if_stale`) and writes
    :data:`INCOMPLETE`. On exit: releases the lock; :data:`INCOMPLETE` stays unless
    :meth:`complete` was called, or the folder held a finished run on entry whose
    :data:`SUMMARY` is still there unchanged (a refused ``--resume`` leaves a finished run
    finished). A lock written on another host is never taken over (its process cannot be
    checked from here).

    Parameters
    ----------
    folder : str or os.PathLike
        The run folder.
    """

    def __init__(self, folder):
        self.folder = Path(folder)
        self.lock = self.folder / LOCK
        self._finished = None  # the finished run's summary on entry: (mtime_ns, size)

    def __enter__(self) -> RunLock:
        output_folder(self.folder)
        fd, mine = tempfile.mkstemp(dir=self.folder, prefix=".lock.", suffix=".tmp")
        try:
            with os.fdopen(fd, "w") as handle:
                pid = os.getpid()
                handle.write(f"{pid}\n{socket.gethostname()}\n{_started(pid)}\n")
            while True:
                try:  # a hard link appears whole, with its content, or fails if taken
                    os.link(mine, self.lock)
                    break
                except FileExistsError:
                    self._take_over_if_stale()
        finally:
            os.unlink(mine)
        if not (self.folder / INCOMPLETE).exists():
            self._finished = _summary_stamp(self.folder)
        try:
            write_text(self.folder / INCOMPLETE,
                       "The outputs in this folder are partial: a run is writing them, or it "
                       "was interrupted. Continue it with invflame run --resume, or run it "
                       "again with --overwrite.\n")
        except BaseException:  # a full disk: the lock is not left behind
            self.lock.unlink()
            raise
        return self

    def _take_over_if_stale(self) -> None:
        """Remove the lock if its process no longer runs, else refuse.

        Every process that finds the lock opens it and waits for an exclusive ``flock`` on
        it: while one holds that, it checks that the file it opened is still the lock (no
        other process removed it meanwhile) and whose it is, and removes it if stale, so that
        of several processes finding one stale lock exactly one removes it; they then race
        for the lock again with :func:`os.link`, which one wins.
        """
        try:
            fd = os.open(self.lock, os.O_RDWR)  # NFS grants an exclusive flock to writers only
        except FileNotFoundError:  # released meanwhile: try again
            return
        except PermissionError as err:
            raise OutputError(f"cannot examine the lock {self.lock} of run folder {self.folder} "
                              f"({err}): it belongs to another user; remove it if its run is "
                              "over, or choose another --out") from err
        with os.fdopen(fd) as handle:
            fcntl.flock(handle, fcntl.LOCK_EX)  # released when the file is closed
            try:
                if os.stat(self.lock).st_ino != os.fstat(fd).st_ino:
                    return  # taken over and replaced meanwhile: try again
            except FileNotFoundError:
                return
            text = handle.read()
            pid_text, host, started = (text.split("\n") + ["", ""])[:3]
            pid, host = (int(pid_text) if pid_text.isdigit() else None), host.strip()
            here = socket.gethostname()
            if pid is not None and (_alive(pid, started.strip()) or host not in ("", here)):
                where = "" if host in ("", here) else f" on host {host}"
                raise OutputError(f"run folder {self.folder} is being written by process {pid}"
                                  f"{where} (lock {self.lock}): wait for it to finish, stop it, "
                                  "or choose another --out (remove the lock if that process is "
                                  "gone)")
            logger.warning(f"taking over the lock {self.lock} of process "
                           f"{pid if pid is not None else repr(text)}, which no longer runs")
            self.lock.unlink()

    def complete(self) -> None:
        """Mark the folder's outputs complete (removes :data:`INCOMPLETE`)."""
        (self.folder / INCOMPLETE).unlink(missing_ok=True)

    def __exit__(self, *exc) -> None:
        if self._finished is not None and _summary_stamp(self.folder) == self._finished:
            self.complete()
        self.lock.unlink(missing_ok=True)


def _summary_stamp(folder: Path) -> tuple[int, int] | None:
    """Modification time (ns) and size of a folder's :data:`SUMMARY`, or None without one."""
    try:
        stat = (folder / SUMMARY).stat()
    except FileNotFoundError:
        return None
    return stat.st_mtime_ns, stat.st_size
