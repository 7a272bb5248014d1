"""Elementwise multiplication by a fixed array, keeping its shape as the operator's shape."""

from __future__ import annotations

import numpy as np

from operators.base import JaxMap, LinearOperator, precision
from operators.interop import to_jax


class Diagonal(LinearOperator):
    r""":math:`x \mapsto d \odot x` for a fixed real array :math:`d` (self-adjoint).

    Parameters
    ----------
    diagonal : array_like
        The weights :math:`d`; their shape is the operator's input and output shape.
    dtype : numpy dtype, optional
        Default: the dtype of ``diagonal``.
    name : str, optional
        Label for messages.
    """

    def __init__(self, diagonal, dtype=None, name: str = "Diagonal"):
        diagonal = np.asarray(diagonal)
        dtype = diagonal.dtype if dtype is None else np.dtype(dtype)
        self.diagonal = diagonal.astype(dtype)
        super().__init__(diagonal.shape, diagonal.shape, dtype=dtype, name=name)

    def jax_map(self) -> JaxMap:
        with precision(self.dtype):
            return JaxMap(lambda d, x: d * x, to_jax(self.diagonal, self.dtype))

    def _forward(self, x):
        return self.diagonal * x

    def _adjoint(self, y):
        return self.diagonal * y
