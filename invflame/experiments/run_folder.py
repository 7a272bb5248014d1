"""Output folders of runs: checked before use, locked while written, marked until complete.

:func:`check_output_folder` refuses a path that is a file or lies under one, before anything
is computed (the command line checks ``--out`` so). :class:`RunLock` holds ``.lock`` (the
writer's process id) in a run folder while a run writes it: a second writer gets an
:class:`~invflame.errors.OutputError` naming the folder and the holder's pid; the lock of a
process that no longer exists is taken over, with a warning. Where the system tells when a
process started (Linux ``/proc``), the lock records it too, so that a lock whose process id has
since been given to another process is recognized as stale.
While the lock is held the folder also holds :data:`INCOMPLETE`, which says that the outputs
beside it are partial; :meth:`RunLock.complete` removes it once every output is written, so a
folder left by a crash or a kill is marked as such.
"""

from __future__ import annotations

import logging
import os
import socket
import tempfile
from pathlib import Path

from invflame.atomic_files import write_text
from invflame.errors import OutputError

LOCK = ".lock"
"""Lock file of a run folder: the writing process's id, host name and start time (clock ticks
since boot, empty where unknown), one a line."""
INCOMPLETE = "INCOMPLETE"
"""Marker of a run folder whose outputs are partial (being written, or left by a crash)."""

logger = logging.getLogger(__name__)


def check_output_folder(path) -> Path:
    """``path`` as a :class:`~pathlib.Path` if it can be an output folder (a folder, or
    nothing yet), without creating it.

    Raises
    ------
    OutputError
        If ``path`` or one of its parents exists and is not a folder.
    """
    path = Path(path)
    for folder in (path, *path.parents):
        if folder.exists() and not folder.is_dir():
            where = "is a file" if folder == path else f"lies under the file {folder}"
            raise OutputError(f"output folder {path} {where}: give a folder path (--out DIR) "
                              "that is a folder or does not exist yet")
    return path


def output_folder(path) -> Path:
    """Create the output folder ``path`` (and its parents) after
    :func:`check_output_folder`; returns it as a :class:`~pathlib.Path`."""
    path = check_output_folder(path)
    path.mkdir(parents=True, exist_ok=True)
    return path


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
    link to a file that already holds this process's id and host) and writes
    :data:`INCOMPLETE`. On exit: releases the lock; :data:`INCOMPLETE` stays unless
    :meth:`complete` was called. A lock written on another host is never taken over (its
    process cannot be checked from here).

    Parameters
    ----------
    folder : str or os.PathLike
        The run folder.
    """

    def __init__(self, folder):
        self.folder = Path(folder)
        self.lock = self.folder / LOCK

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
        write_text(self.folder / INCOMPLETE,
                   "The outputs in this folder are partial: a run is writing them, or it was "
                   "interrupted. Continue it with --resume, or run it again.\n")
        return self

    def _take_over_if_stale(self) -> None:
        try:
            text = self.lock.read_text()
        except FileNotFoundError:  # released meanwhile: try again
            return
        pid_text, host, started = (text.split("\n") + ["", ""])[:3]
        pid, host = (int(pid_text) if pid_text.isdigit() else None), host.strip()
        here = socket.gethostname()
        if pid is not None and (_alive(pid, started.strip()) or host not in ("", here)):
            where = "" if host in ("", here) else f" on host {host}"
            raise OutputError(f"run folder {self.folder} is being written by process {pid}"
                              f"{where} (lock {self.lock}): wait for it to finish, stop it, or "
                              "choose another --out (remove the lock if that process is gone)")
        message = (f"taking over the lock {self.lock} of process "
                   f"{pid if pid is not None else repr(text)}, which no longer runs")
        logger.warning(message)
        self.lock.unlink(missing_ok=True)

    def complete(self) -> None:
        """Mark the folder's outputs complete (removes :data:`INCOMPLETE`)."""
        (self.folder / INCOMPLETE).unlink(missing_ok=True)

    def __exit__(self, *exc) -> None:
        self.lock.unlink(missing_ok=True)
