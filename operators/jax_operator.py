"""Operators defined by a JAX function, differentiated by JAX."""

from __future__ import annotations

import jax
import numpy as np

from operators.base import Jacobian, Operator
from operators.interop import to_jax, to_numpy


class JaxOperator(Operator):
    """An :class:`~operators.base.Operator` from a JAX function ``fun(x) -> y``.

    ``jvp`` and ``vjp`` come from :func:`jax.jvp` and :func:`jax.vjp`; all three are jit-compiled
    once per operator. ``linearize`` runs the forward pass once and keeps JAX's pullback, so a
    solver's value and gradient cost one forward and one reverse pass.

    Parameters
    ----------
    fun : callable
        JAX-traceable function from an array of shape ``dims`` to one of shape ``dimsd``.
    dims, dimsd : tuple of int
        Input and output shapes.
    dtype : numpy dtype, optional
        Dtype the input is cast to before calling ``fun`` (default float64; JAX needs
        ``jax_enable_x64`` for float64, which importing :mod:`operators` turns on).
    name : str, optional
        Label for messages.
    """

    def __init__(self, fun, dims, dimsd, dtype=np.float64, name=None):
        super().__init__(dims, dimsd, dtype=dtype, name=name or getattr(fun, "__name__", "jax"))
        self.fun = fun
        self._f = jax.jit(fun)
        self._jvp_fn = jax.jit(lambda x, v: jax.jvp(fun, (x,), (v,))[1])
        self._vjp_fn = jax.jit(lambda x, w: jax.vjp(fun, x)[1](w)[0])
        self._value_and_pullback = jax.jit(lambda x: jax.vjp(fun, x))
        self._pull = jax.jit(lambda pullback, w: pullback(w)[0])

    def _in(self, x):
        return to_jax(x, dtype=self.dtype)

    def _forward(self, x):
        return to_numpy(self._f(self._in(x)))

    def _jvp(self, x, v):
        return to_numpy(self._jvp_fn(self._in(x), self._in(v)))

    def _vjp(self, x, w):
        return to_numpy(self._vjp_fn(self._in(x), self._in(w)))

    def linearize(self, x) -> Jacobian:
        xj = self._in(self._as_input(x))
        value, pullback = self._value_and_pullback(xj)
        return Jacobian(
            self, to_numpy(xj), to_numpy(value),
            jvp=lambda v: to_numpy(self._jvp_fn(xj, self._in(v))),
            vjp=lambda w: to_numpy(self._pull(pullback, self._in(w))),
        )
