"""Argument types of the command line: values checked when parsed, errors that name them.

Each function takes the argument's text and returns its value or raises
:class:`argparse.ArgumentTypeError`, which argparse reports as ``argument --NAME: MESSAGE``
with the usage line and exit status 2. :class:`Choices` holds the names an argument allows
when they come from a registry that is imported only once a name is checked or listed.

Building the parser imports nothing beyond the standard library and :mod:`invflame.errors`:
what checks a value (the run folders, the registries) is imported when a value is parsed.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Iterable, Sequence
from functools import cached_property
from pathlib import Path

from invflame.errors import OutputError


class Choices(Sequence):
    """The names an argument allows, read from ``load()`` the first time they are needed.

    As ``choices=`` of :meth:`argparse.ArgumentParser.add_argument`, the names are loaded when
    argparse checks a value against them or lists them in a help (``%(choices)s``), not when the
    parser is built. The argument needs a ``metavar``: without one, argparse lists the choices
    as soon as the argument is added.

    Parameters
    ----------
    load : callable
        Returns the names (e.g. ``lambda: sorted(PHANTOMS)``, importing the registry).
    """

    def __init__(self, load: Callable[[], Iterable[str]]):
        self._load = load

    @cached_property
    def names(self) -> list[str]:
        """The names, in the order ``load()`` gives them."""
        return list(self._load())

    def __getitem__(self, index):
        return self.names[index]

    def __len__(self) -> int:
        return len(self.names)

    def __contains__(self, name) -> bool:
        return name in self.names


def folder(text: str) -> Path:
    """An output folder: a folder, or a path where none exists yet (not a file, nor under one);
    not an empty path (which would name the current folder unawares)."""
    from invflame.experiments.run_folder import check_output_folder

    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path would write into the current folder: "
                                         "name the output folder (e.g. --out results/run)")
    try:
        return check_output_folder(text)
    except OutputError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive(text: str) -> float:
    """A finite number > 0 (a length in m, a resolution in cm⁻¹, a temperature in K)."""
    value = _number(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text}")
    return value


def count(text: str) -> int:
    """A positive integer (voxels per axis)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def amplitude(text: str) -> float:
    """A relative amplitude in [0, 1)."""
    value = _number(text)
    if not 0.0 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"must lie in [0, 1), got {text}")
    return value


def fraction(text: str) -> float:
    """A mole fraction in [0, 1]."""
    value = _number(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"a mole fraction must be in [0, 1], got {text}")
    return value


def png(text: str) -> Path:
    """An output image file: ``.png`` is appended to a name without a suffix; an existing
    folder is refused, and so is one that cannot hold the file (see :func:`folder`)."""
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{path} is a folder: give a file name, e.g. "
                                         f"{path / 'lines.png'}")
    path = path if path.suffix else path.with_suffix(".png")
    folder(str(path.parent))
    return path
