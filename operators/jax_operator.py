"""The JAX side of :class:`operators.adapters.JaxOperator`: a JAX function and its derivatives on
NumPy arrays."""

from __future__ import annotations

import jax

from operators.interop import to_jax, to_numpy


class JaxFunction:
    """``fun(x) -> y`` in JAX, with :func:`jax.jvp` and :func:`jax.vjp`, all jit-compiled once.

    Parameters
    ----------
    fun : callable
        JAX-traceable function of one array.
    dtype : numpy dtype
        Dtype the inputs are cast to before calling ``fun``.
    """

    def __init__(self, fun, dtype):
        self.dtype = dtype
        self._f = jax.jit(fun)
        self._jvp = jax.jit(lambda x, v: jax.jvp(fun, (x,), (v,))[1])
        self._vjp = jax.jit(lambda x, w: jax.vjp(fun, x)[1](w)[0])
        self._value_and_pullback = jax.jit(lambda x: jax.vjp(fun, x))
        self._pull = jax.jit(lambda pullback, w: pullback(w)[0])

    def _in(self, x):
        return to_jax(x, dtype=self.dtype)

    def forward(self, x):
        """``fun(x)`` as a NumPy array."""
        return to_numpy(self._f(self._in(x)))

    def jvp(self, x, v):
        """:math:`J(x) v` as a NumPy array."""
        return to_numpy(self._jvp(self._in(x), self._in(v)))

    def vjp(self, x, w):
        r""":math:`J(x)^\mathsf{T} w` as a NumPy array."""
        return to_numpy(self._vjp(self._in(x), self._in(w)))

    def pullback(self, x):
        """``(fun(x), v -> J v, w -> Jᵀ w)`` from one forward pass, keeping JAX's pullback."""
        xj = self._in(x)
        value, pullback = self._value_and_pullback(xj)
        return (to_numpy(value),
                lambda v: to_numpy(self._jvp(xj, self._in(v))),
                lambda w: to_numpy(self._pull(pullback, self._in(w))))
