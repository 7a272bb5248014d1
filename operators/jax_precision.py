"""The precision JAX computes in: float64 in a context, without changing the process's setting.

JAX computes in float32 unless its 64-bit mode is on; an operator of dtype float64 turns the
mode on around its own computations (:func:`precision`), and code that must not silently
compute float64 inputs in float32 refuses to run outside it (:func:`check_precision`).
"""

from __future__ import annotations

import contextlib

import jax
import numpy as np


def precision(dtype):
    """Context in which JAX computes in ``dtype``: float64 turns on x64 inside it only.

    Parameters
    ----------
    dtype : numpy dtype
        float64 enables JAX's 64-bit mode for the duration of the context; any other dtype
        leaves the process setting as it is.
    """
    if np.dtype(dtype) == np.float64:
        return jax.enable_x64(True)
    return contextlib.nullcontext()


def check_precision(dtype, what: str) -> None:
    """Refuse to compute ``what`` in float64 where JAX would silently compute in float32.

    Parameters
    ----------
    dtype : numpy dtype
        The dtype ``what`` computes in.
    what : str
        Names the computation in the message.

    Raises
    ------
    ValueError
        For float64 while JAX's 64-bit mode is off here, saying how to turn it on.
    """
    if np.dtype(dtype) == np.float64 and not jax.config.jax_enable_x64:
        raise ValueError(
            f"{what} is float64, but JAX's 64-bit mode is off here, so JAX would compute in "
            "float32: call it inside `with operators.precision(numpy.float64):` (the "
            "operators' own methods do), or turn the mode on for the process with "
            "jax.config.update('jax_enable_x64', True)")
