"""Atomic file writing: a half-written file never replaces a good one.

Every file invflame writes (fields, absorption tables, line lists, run outputs) goes through
:func:`write_atomic`: the content fills a temporary file in the destination folder, which is
flushed to disk and then renamed over the destination.
"""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path

import numpy as np


def write_atomic(path, write) -> Path:
    """Create ``path`` atomically: ``write(binary_stream)`` fills a temporary file in the same
    folder, which then replaces ``path`` with the permissions the umask gives new files.

    Parameters
    ----------
    path : str or os.PathLike
        Destination; parent folders are created.
    write : callable
        Writes the content to the binary stream it is given.
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
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return write_atomic(path, lambda handle: handle.write(text.encode()))


def write_npz(path, **arrays) -> Path:
    """Write arrays to a compressed ``.npz`` atomically."""
    return write_atomic(path, lambda handle: np.savez_compressed(handle, **arrays))


def write_json(path, data) -> Path:
    """Write ``data`` as indented JSON, atomically."""
    return write_text(path, json.dumps(data, indent=2, sort_keys=False) + "\n")


def write_csv(path, rows: list[dict]) -> Path:
    """Write a list of dicts (same keys) as CSV with a header row, atomically."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]) if rows else [])
    writer.writeheader()
    writer.writerows(rows)
    return write_text(path, buffer.getvalue())


def read_json(path):
    """Read a JSON file written by :func:`write_json`."""
    return json.loads(Path(path).read_text())
