"""The torch side of :class:`operators.base.TorchOperator`: a torch function and its
derivatives (:mod:`torch.func`) on NumPy arrays. Importing this module imports torch."""

from __future__ import annotations

import numpy as np
import torch
from torch.func import jvp, vjp

from operators.interop import TORCH_DTYPES, to_numpy, to_torch


class TorchFunction:
    """``fun(x) -> y`` on tensors, with :func:`torch.func.jvp` and :func:`torch.func.vjp`.

    Parameters
    ----------
    fun : callable
        Function of one tensor.
    dtype : numpy dtype
        float32 or float64: the tensors get the matching torch dtype.
    device : str, torch.device or None
        Where ``fun`` runs; None: torch's default device when the function is built (the CPU
        unless :func:`torch.set_default_device` chose another).
    """

    def __init__(self, fun, dtype, device):
        dtype = np.dtype(dtype)
        if dtype not in TORCH_DTYPES:
            raise ValueError(f"TorchOperator supports float32 and float64, got {dtype}")
        self.fun = fun
        self.dtype = TORCH_DTYPES[dtype]
        self.device = torch.get_default_device() if device is None else torch.device(device)

    def _in(self, x):
        return to_torch(x, dtype=self.dtype, device=self.device)

    def forward(self, x):
        """``fun(x)`` as a NumPy array."""
        with torch.no_grad():
            return to_numpy(self.fun(self._in(x)))

    def jvp(self, x, v):
        """:math:`J(x) v` as a NumPy array."""
        return to_numpy(jvp(self.fun, (self._in(x),), (self._in(v),))[1])

    def vjp(self, x, w):
        r""":math:`J(x)^\mathsf{T} w` as a NumPy array."""
        return to_numpy(vjp(self.fun, self._in(x))[1](self._in(w))[0])

    def pullback(self, x):
        """``(fun(x), v -> J v, w -> Jᵀ w)`` from one forward pass, keeping torch's pullback."""
        xt = self._in(x)
        value, pull = vjp(self.fun, xt)
        return (to_numpy(value),
                lambda v: to_numpy(jvp(self.fun, (xt,), (self._in(v),))[1]),
                lambda w: to_numpy(pull(self._in(w))[0]))
