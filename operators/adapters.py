"""Operators from other libraries: pylops and scipy linear operators, JAX and torch functions.

:func:`aslinearoperator` wraps a pylops (or scipy) linear operator; :class:`JaxOperator` and
:class:`TorchOperator` turn a framework function into an :class:`~operators.base.Operator`
whose derivatives come from the framework (:mod:`operators.jax_operator`,
:mod:`operators.torch_operator`). torch is imported only when a :class:`TorchOperator` is built.

This module imports :mod:`operators.base`, never the other way round: what it defines registers
itself with :func:`operators.base.register`, through which ``Operator.from_jax``,
``Operator.from_torch`` and ``A @ pylops_op`` build it and ``operators.base.JaxOperator`` (and so
on) stays importable.
"""

from __future__ import annotations

import numpy as np

from operators.base import Jacobian, JaxMap, LinearOperator, Operator, register
from operators.jax_operator import JaxFunction
from operators.pylops_import import pylops


class _PylopsWrapper(LinearOperator):
    def __init__(self, op: pylops.LinearOperator, name: str | None = None):
        super().__init__(getattr(op, "dims", (op.shape[1],)),
                         getattr(op, "dimsd", (op.shape[0],)),
                         dtype=op.dtype, name=name or getattr(op, "name", None) or "pylops")
        self.op = op

    def _forward(self, x):
        return np.asarray(self.op.matvec(x.ravel())).reshape(self.dimsd)

    def _adjoint(self, y):
        return np.asarray(self.op.rmatvec(y.ravel())).reshape(self.dims)


@register
def aslinearoperator(op, name: str | None = None) -> LinearOperator:
    """Any pylops (or scipy) linear operator as an :class:`operators.LinearOperator`.

    Parameters
    ----------
    op : pylops.LinearOperator or scipy.sparse.linalg.LinearOperator
        Operator with ``matvec``/``rmatvec`` (and ideally ``dims``/``dimsd``).
    name : str, optional
        Label for reprs and messages.
    """
    if isinstance(op, LinearOperator):
        return op
    return _PylopsWrapper(pylops.aslinearoperator(op), name=name)


class _FunctionOperator(Operator):
    """An operator whose value and derivatives come from a framework function.

    ``function`` offers ``forward(x)``, ``jvp(x, v)``, ``vjp(x, w)`` and ``pullback(x) ->
    (value, jvp, vjp)`` on NumPy arrays (see :mod:`operators.jax_operator` and
    :mod:`operators.torch_operator`).
    """

    def __init__(self, function, dims, dimsd, dtype, name):
        super().__init__(dims, dimsd, dtype=dtype, name=name)
        self.function = function

    def _forward(self, x):
        return self.function.forward(x)

    def _jvp(self, x, v):
        return self.function.jvp(x, v)

    def _vjp(self, x, w):
        return self.function.vjp(x, w)

    def linearize(self, x) -> Jacobian:
        """One forward pass, keeping the framework's pullback for the vjp."""
        x = self._as_input(x)
        value, jvp, vjp = self.function.pullback(x)
        return Jacobian(self, x, self._result(value, self.dimsd, "forward"), jvp=jvp, vjp=vjp)


@register
class JaxOperator(_FunctionOperator):
    """An :class:`~operators.base.Operator` from a JAX function ``fun(x) -> y``.

    ``jvp`` and ``vjp`` come from :func:`jax.jvp` and :func:`jax.vjp`; all three are jit-compiled
    once per operator. ``linearize`` runs the forward pass once and keeps JAX's pullback, so a
    solver's value and gradient cost one forward and one reverse pass. Its :meth:`jax_map` is
    ``fun`` itself, so that it takes part in compiled programs such as
    :mod:`solvers.compiled_objective`.

    Parameters
    ----------
    fun : callable
        JAX-traceable function from an array of shape ``dims`` to one of shape ``dimsd``.
    dims, dimsd : tuple of int
        Input and output shapes; the function's output shape is checked against ``dimsd``.
    dtype : numpy dtype, optional
        Dtype the input is cast to before calling ``fun`` (default float64, computed in JAX's
        64-bit mode inside :func:`~operators.base.precision`).
    name : str, optional
        Label for messages.
    """

    def __init__(self, fun, dims, dimsd, dtype=np.float64, name=None):
        super().__init__(JaxFunction(fun, dtype), dims, dimsd, dtype,
                         name or getattr(fun, "__name__", "jax"))
        self.fun = fun

    def jax_map(self) -> JaxMap:
        return JaxMap(lambda _, x: self.fun(x))


@register
class TorchOperator(_FunctionOperator):
    """An :class:`~operators.base.Operator` from a torch function ``fun(x) -> y``.

    ``jvp`` and ``vjp`` come from :func:`torch.func.jvp` and :func:`torch.func.vjp`; torch is
    imported when the first such operator is built.

    Parameters
    ----------
    fun : callable
        Function from a tensor of shape ``dims`` to one of shape ``dimsd``.
    dims, dimsd : tuple of int
        Input and output shapes; the function's output shape is checked against ``dimsd``.
    dtype : numpy dtype, optional
        float32 or float64 (default); the input tensor gets the matching torch dtype.
    device : str or torch.device, optional
        Where ``fun`` runs (default: torch's default device, the CPU unless
        :func:`torch.set_default_device` chose another).
    name : str, optional
        Label for messages.
    """

    def __init__(self, fun, dims, dimsd, dtype=np.float64, device=None, name=None):
        from operators.torch_operator import TorchFunction

        super().__init__(TorchFunction(fun, dtype, device), dims, dimsd, dtype,
                         name or getattr(fun, "__name__", "torch"))
        self.device = self.function.device
