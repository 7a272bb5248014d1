"""An absorption table's ``.npz`` file: its arrays, their content hash, written atomically and
read back checked."""

from __future__ import annotations

import hashlib

import numpy as np

from invflame.atomic_files import read_npz, write_atomic
from invflame.errors import InputDataError

#: The arrays of a saved table, in the order its content hash covers them.
ARRAYS = ("species", "wavenumber", "pressure", "temperatures", "sigma", "self_fraction",
          "nodes_per_species", "points_per_bin", "bin_width")


def content_hash(arrays: dict) -> str:
    """SHA-256 of a saved table's arrays (names, dtypes, shapes and bytes)."""
    digest = hashlib.sha256()
    for name in ARRAYS:
        array = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def write_table(path, arrays: dict, key: str) -> None:
    """Write ``arrays`` (those of :data:`ARRAYS`), the cache ``key`` and their content hash to
    an ``.npz`` file (atomic: temporary file, then rename)."""
    arrays = {**arrays, "key": np.array(key)}
    arrays["content_hash"] = np.array(content_hash(arrays))
    write_atomic(path, lambda stream: np.savez(stream, **arrays))


def read_table(path, key: str | None = None) -> dict:
    """The arrays of a file written by :func:`write_table`, checked.

    Parameters
    ----------
    path : str or Path
    key : str, optional
        The key the file must hold (a cache lookup); default: any.

    Raises
    ------
    CorruptFileError
        If the file is empty, truncated or not an ``.npz`` archive.
    InputDataError
        If it lacks entries, its arrays fail the stored hash, it holds another key, or a
        cache lookup (``key`` given) finds no hash to check.
    """
    fix = "delete it (a cached table is rebuilt on the next run)"
    data = read_npz(path, "absorption table", fix)
    missing = sorted(set(ARRAYS) - set(data))
    if missing:
        raise InputDataError(f"absorption table {path} lacks {missing}; {fix}")
    if key is not None and "content_hash" not in data:  # the cache writes one with its key
        raise InputDataError(f"absorption table {path} holds no content hash, so its arrays "
                             f"cannot be checked; {fix}")
    if "content_hash" in data and str(data["content_hash"]) != content_hash(data):
        raise InputDataError(f"absorption table {path} fails its content hash (the arrays "
                             f"were changed after it was written); {fix}")
    if key is not None and str(data.get("key", "")) != key:
        raise InputDataError(f"absorption table {path} was built from other inputs (key "
                             f"{str(data.get('key', ''))[:24] or 'none'}, expected "
                             f"{key[:24]}); {fix}")
    return data
