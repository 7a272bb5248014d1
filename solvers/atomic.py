"""Files written atomically and ``.npz`` files read with errors that name them.

:func:`write_atomic` fills a uniquely named temporary file in the destination folder, syncs it
and renames it over the destination, so a crash or a second writer never leaves a torn file
and two writers never share a temporary file. :func:`read_npz` reads every array of an
``.npz`` file at once and turns a truncated, empty or foreign file into a
:class:`CorruptFileError` that names the file and says what to do. Checkpoints
(:mod:`solvers.checkpoint`) and every file of the ``invflame`` application go through them.
"""

from __future__ import annotations

import os
import tempfile
import zipfile
import zlib
from pathlib import Path

import numpy as np


class CorruptFileError(ValueError):
    """A file exists but cannot be read back (truncated, empty, not what it should be)."""


def write_atomic(path, write) -> Path:
    """Create ``path`` atomically: ``write(binary_stream)`` fills a temporary file with a unique
    name in the same folder, which then replaces ``path`` with the permissions the umask gives
    new files.

    Parameters
    ----------
    path : str or os.PathLike
        Destination; parent folders are created.
    write : callable
        Writes the content to the binary stream it is given.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    OSError
        If the system refuses a step (no space, no permission); one that names no file (a
        full disk found at the flush) is raised again naming ``path``. The file that was at
        ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates the file private (0600)
        os.replace(tmp, path)
    except OSError as err:
        Path(tmp).unlink(missing_ok=True)
        if err.filename or not err.errno:
            raise
        raise OSError(err.errno, err.strerror, str(path)) from err
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_npz(path, what: str = "file", fix: str = "delete it and write it again") -> dict:
    """Every array of an ``.npz`` file, read at once (no pickles).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str, optional
        What the file is, for the message (e.g. ``"checkpoint"``).
    fix : str, optional
        What to do about a damaged file, for the message.

    Returns
    -------
    dict of str -> ndarray

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    CorruptFileError
        If the file is empty, truncated or not an ``.npz`` archive; the message names the path.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no {what} at {path}")
    try:
        data = np.load(path, allow_pickle=False)
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError("a single .npy array, not an .npz archive")
        with data:
            return {name: data[name] for name in data.files}
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError, KeyError) as err:
        size = path.stat().st_size
        reason = "an empty file" if size == 0 else f"{size} bytes, unreadable: {err}"
        raise CorruptFileError(f"{what} {path} is damaged or incomplete ({reason}); {fix}"
                               ) from err
