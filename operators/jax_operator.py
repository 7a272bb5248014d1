"""The JAX side of :class:`operators.base.JaxOperator`: a JAX function and its derivatives on
NumPy arrays."""

from __future__ import annotations

from collections.abc import Callable

import jax

from operators.interop import to_jax, to_numpy


class JaxFunction:
    """``fun(*args, x) -> y`` in JAX, with :func:`jax.jvp` and :func:`jax.vjp` in ``x``, all
    jit-compiled once.

    Parameters
    ----------
    fun : callable
        JAX-traceable function of the constant arguments ``args``, then of one array ``x``;
        its value and its reverse mode (:func:`jax.vjp`) are those of the :class:`JaxFunction`.
    dtype : numpy dtype
        Dtype the inputs are cast to before calling ``fun``.
    args : tuple, optional
        Constant arguments of ``fun`` (pytrees of arrays), passed at every call so that they
        are not compiled in as constants (default: none).
    forward_mode : callable, optional
        The same map as ``fun``, differentiable in forward mode, for the JVPs (default:
        ``fun``); for a ``fun`` whose reverse mode is a custom VJP, through which JAX cannot
        push tangents.

    Attributes
    ----------
    function : callable
        ``function(*args, x) -> y``, ``fun`` jitted.
    args : tuple
    """

    def __init__(self, fun: Callable, dtype, args: tuple = (),
                 forward_mode: Callable | None = None):
        tangent = fun if forward_mode is None else forward_mode
        self.dtype = dtype
        self.args = tuple(args)
        self.function = jax.jit(fun)
        self._jvp = jax.jit(lambda a, x, v: jax.jvp(lambda y: tangent(*a, y), (x,), (v,))[1])
        self._vjp = jax.jit(lambda a, x, w: jax.vjp(lambda y: fun(*a, y), x)[1](w)[0])
        self._value_and_pullback = jax.jit(lambda a, x: jax.vjp(lambda y: fun(*a, y), x))
        self._pull = jax.jit(lambda pullback, w: pullback(w)[0])

    def _in(self, x):
        return to_jax(x, dtype=self.dtype)

    def forward(self, x):
        """``fun(*args, x)`` as a NumPy array."""
        return to_numpy(self.function(*self.args, self._in(x)))

    def jvp(self, x, v):
        """:math:`J(x) v` as a NumPy array."""
        return to_numpy(self._jvp(self.args, self._in(x), self._in(v)))

    def vjp(self, x, w):
        r""":math:`J(x)^\mathsf{T} w` as a NumPy array."""
        return to_numpy(self._vjp(self.args, self._in(x), self._in(w)))

    def pullback(self, x):
        """``(fun(*args, x), v -> J v, w -> Jᵀ w)`` from one forward pass, keeping JAX's
        pullback."""
        xj = self._in(x)
        value, pullback = self._value_and_pullback(self.args, xj)
        return (to_numpy(value),
                lambda v: to_numpy(self._jvp(self.args, xj, self._in(v))),
                lambda w: to_numpy(self._pull(pullback, self._in(w))))
