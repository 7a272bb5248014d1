"""Atomic file writing: a half-written file never replaces a good one.

Every file invflame writes (fields, absorption tables, line lists, run outputs) goes through
:func:`write_atomic` (:func:`solvers.atomic.write_atomic`, the one writer that solver
checkpoints use too): the content fills a uniquely named temporary file in the destination
folder, which is flushed to disk and then renamed over the destination. :func:`read_npz` reads
an ``.npz`` file back and names the file when it is damaged.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from invflame.errors import InputDataError
from solvers.atomic import CorruptFileError, read_npz, write_atomic

__all__ = ["CorruptFileError", "read_json", "read_npz", "write_atomic", "write_csv",
           "write_json", "write_npz", "write_text"]


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
    """Read a JSON file written by :func:`write_json`.

    Raises
    ------
    CorruptFileError
        If the file is not valid UTF-8 JSON (the message names it).
    """
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise CorruptFileError(f"{path} is damaged or incomplete (not valid JSON: {err}); delete "
                               "it and write it again") from err


def read_netcdf(path, what: str):
    """Load a whole NetCDF-4 file into memory as an :class:`xarray.Dataset`.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file should be, for messages (e.g. "measurement file").

    Raises
    ------
    FileNotFoundError
        If there is no file at ``path``.
    InputDataError
        If the file cannot be read as NetCDF (the message names it and ``what``).
    """
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{what} not found: {path}")
    try:
        with xr.open_dataset(path, engine="netcdf4") as opened:
            return opened.load()
    except (OSError, ValueError) as err:
        raise InputDataError(f"{path}: not a NetCDF {what} ({err})") from err
