"""Operators defined by a torch function, differentiated by :mod:`torch.func`."""

from __future__ import annotations

import numpy as np
import torch
from torch.func import jvp, vjp

from operators.base import Jacobian, Operator
from operators.interop import to_numpy, to_torch

_TORCH_DTYPES = {np.dtype(np.float32): torch.float32, np.dtype(np.float64): torch.float64}


class TorchOperator(Operator):
    """An :class:`~operators.base.Operator` from a torch function ``fun(x) -> y``.

    ``jvp`` and ``vjp`` come from :func:`torch.func.jvp` and :func:`torch.func.vjp`.

    Parameters
    ----------
    fun : callable
        Function from a tensor of shape ``dims`` to one of shape ``dimsd``.
    dims, dimsd : tuple of int
        Input and output shapes.
    dtype : numpy dtype, optional
        float32 or float64 (default); the input tensor gets the matching torch dtype.
    device : str or torch.device, optional
        Where ``fun`` runs (default CPU).
    name : str, optional
        Label for messages.
    """

    def __init__(self, fun, dims, dimsd, dtype=np.float64, device="cpu", name=None):
        super().__init__(dims, dimsd, dtype=dtype,
                         name=name or getattr(fun, "__name__", "torch"))
        if self.dtype not in _TORCH_DTYPES:
            raise ValueError(f"TorchOperator supports float32 and float64, got {self.dtype}")
        self.fun = fun
        self.device = torch.device(device)

    def _in(self, x):
        return to_torch(x, dtype=_TORCH_DTYPES[self.dtype], device=self.device)

    def _forward(self, x):
        with torch.no_grad():
            return to_numpy(self.fun(self._in(x)))

    def _jvp(self, x, v):
        return to_numpy(jvp(self.fun, (self._in(x),), (self._in(v),))[1])

    def _vjp(self, x, w):
        return to_numpy(vjp(self.fun, self._in(x))[1](self._in(w))[0])

    def linearize(self, x) -> Jacobian:
        xt = self._in(self._as_input(x))
        value, pullback = vjp(self.fun, xt)
        return Jacobian(
            self, to_numpy(xt), to_numpy(value),
            jvp=lambda v: to_numpy(jvp(self.fun, (xt,), (self._in(v),))[1]),
            vjp=lambda w: to_numpy(pullback(self._in(w))[0]),
        )
