"""Argument types of the command line: values checked when parsed, errors that name them.

Each function takes the argument's text and returns its value or raises
:class:`argparse.ArgumentTypeError`, which argparse reports as ``argument --NAME: MESSAGE``
with the usage line and exit status 2.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from invflame.errors import OutputError
from invflame.experiments.run_folder import check_output_folder


def folder(text: str) -> Path:
    """An output folder: a folder, or a path where none exists yet (not a file, nor under one)."""
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
    folder is refused."""
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{path} is a folder: give a file name, e.g. "
                                         f"{path / 'lines.png'}")
    path = path if path.suffix else path.with_suffix(".png")
    try:
        check_output_folder(path.parent)
    except OutputError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return path
