r"""Operators and their algebra: every class that a method of an operator builds.

An :class:`Operator` is the protocol of :mod:`operators.protocol` (``F(x)``, ``F.jvp(x, v)``,
``F.vjp(x, w)``, written as ``_forward``, ``_jvp`` and ``_vjp``, or ``_forward`` and
``_adjoint`` for a :class:`LinearOperator`) with the methods that return operators:
``F.linearize(x)``, the Jacobian at ``x`` as a matrix-free :class:`LinearOperator` that also
carries ``F(x)``; ``A.H``, ``A.T``; and the algebra, which follows the chain rule: ``A @ B``
(``B`` applied first), ``A + B``, ``A - B``, ``c * A``, ``-A``, ``A ** p`` and the stacks of
:mod:`operators.combinators`. Each returns an operator, linear when all its parts are, that
linearizes each part once per point.

**Why these classes share a module.** A method builds only the classes its module sees, and what
the methods of an operator build are operators: :class:`Jacobian`, :class:`Adjoint`,
:class:`Identity` (``A ** 0``), :class:`Composition`, :class:`Sum`, :class:`Scaled`, the wrapper
of a pylops operator (``A @ pylops_op``), :class:`JaxOperator` and :class:`TorchOperator`
(``Operator.from_jax`` / ``from_torch``). This module defines them all, with what builds
operators; what they compute on arrays is below it, in :mod:`operators.protocol` and
:mod:`operators.rules`. Imports run one way, from those to this module to the rest of
:mod:`operators`, and nothing registers itself anywhere.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np

from operators.jax_map import JaxMap
from operators.jax_operator import JaxFunction
from operators.jax_precision import precision as precision  # importable from here, as before
from operators.protocol import LinearOperatorProtocol, OperatorProtocol
from operators.pylops_import import pylops
from operators.rules import (
    CombinationRule,
    CompositionRule,
    FunctionRule,
    PylopsRule,
    ScaleRule,
    SumRule,
)


class Operator(OperatorProtocol):
    """A differentiable map from arrays of shape ``dims`` to arrays of shape ``dimsd``, with
    the methods that build operators: its Jacobian, its adjoint and the algebra.

    Constructed and subclassed as :class:`~operators.protocol.OperatorProtocol` (its
    parameters ``dims``, ``dimsd``, ``dtype`` and ``name``; ``_forward(x)``, ``_jvp(x, v)`` and
    ``_vjp(x, w)`` on arrays already shaped ``dims`` / ``dimsd``); a subclass may override
    ``linearize`` to share work between the value and the derivatives.
    """

    def linearize(self, x) -> Jacobian:
        """The Jacobian at ``x`` as a linear operator; ``.value`` holds ``F(x)``."""
        x = self._as_input(x)
        return Jacobian(self, x, self(x))

    @staticmethod
    def from_jax(fun, dims, dimsd, dtype=np.float64, name=None) -> Operator:
        """Wrap a JAX function; see :class:`JaxOperator`."""
        return JaxOperator(fun, dims, dimsd, dtype=dtype, name=name)

    @staticmethod
    def from_torch(fun, dims, dimsd, dtype=np.float64, device=None, name=None) -> Operator:
        """Wrap a torch function; see :class:`TorchOperator`."""
        return TorchOperator(fun, dims, dimsd, dtype=dtype, device=device, name=name)

    def __matmul__(self, other):
        if isinstance(other, pylops.LinearOperator) and not isinstance(other, Operator):
            other = _PylopsWrapper(pylops.aslinearoperator(other))
        if isinstance(other, Operator):
            return _linear_if_possible(Composition(self, other))
        if self.linear:
            return pylops.LinearOperator.dot(self, other)
        raise TypeError(
            f"{self.name} is nonlinear: evaluate it as F(x), not F @ x "
            f"(got {type(other).__name__})"
        )

    def __add__(self, other):
        if not isinstance(other, Operator):
            return NotImplemented
        return _linear_if_possible(Sum([self, other]))

    def __sub__(self, other):
        if not isinstance(other, Operator):
            return NotImplemented
        return self + (-1.0) * other

    def __neg__(self):
        return (-1.0) * self

    def __mul__(self, other):
        if isinstance(other, numbers.Number):
            return _linear_if_possible(Scaled(self, other))
        if self.linear and not isinstance(other, Operator):
            return pylops.LinearOperator.dot(self, other)
        return NotImplemented

    def __rmul__(self, other):
        return self * other if isinstance(other, numbers.Number) else NotImplemented

    def __pow__(self, p):
        """``F ** p``: ``F`` composed with itself ``p`` times (the identity for ``p = 0``)."""
        if isinstance(p, bool) or not isinstance(p, numbers.Integral) or p < 0:
            raise ValueError(f"{self.name} ** p needs an integer p >= 0, got {p!r}")
        if self.dims != self.dimsd:
            raise ValueError(f"{self.name} ** {p}: the operator maps {self.dims} to "
                             f"{self.dimsd}; powers need equal input and output shapes")
        if p == 0:
            return Identity(self.dims, dtype=self.dtype)
        result = self
        for _ in range(int(p) - 1):
            result = result @ self
        return result


class LinearOperator(Operator, LinearOperatorProtocol):
    r"""A linear :class:`Operator` that is also a :class:`pylops.LinearOperator`.

    Subclasses implement ``_forward(x)`` on arrays shaped ``dims`` and ``_adjoint(y)`` on arrays
    shaped ``dimsd``. ``A(x)``, ``A.jvp(x, v)`` (:math:`= A v`), ``A.vjp(x, w)``
    (:math:`= A^\mathsf{H} w`, ``x`` ignored), ``A.adjoint(y)``, ``A.H`` and pylops'
    ``matvec``/``rmatvec`` all derive from those two methods.
    """

    def adjoint(self, y=None):
        r""":math:`A^\mathsf{H} y` (``y`` shaped ``dimsd``), or the adjoint operator ``A.H``
        when ``y`` is omitted (as pylops' ``adjoint()``)."""
        return Adjoint(self) if y is None else super().adjoint(y)

    H = property(adjoint)

    def transpose(self):
        r""":math:`A^\mathsf{T}`, which for a real operator is the adjoint ``A.H``."""
        if np.issubdtype(self.dtype, np.complexfloating):
            raise TypeError(f"{self.name} is complex: use the adjoint A.H; A.T is only "
                            "defined for real operators")
        return Adjoint(self)

    T = property(transpose)

    def linearize(self, x) -> Jacobian:
        """The operator itself as its Jacobian at ``x``, with ``.value`` :math:`= A x`."""
        x = self._as_input(x)
        return Jacobian(self, x, self(x), derivative=self)


class Identity(LinearOperator):
    """The identity on arrays of shape ``dims`` (``A ** 0``)."""

    def __init__(self, dims, dtype=np.float64):
        super().__init__(dims, dims, dtype=dtype, name="I")

    def jax_map(self) -> JaxMap:
        return JaxMap(lambda _, x: x)

    def _forward(self, x):
        return x

    def _adjoint(self, y):
        return y


class Adjoint(LinearOperator):
    r"""The adjoint :math:`A^\mathsf{H}` of a :class:`LinearOperator` (``A.H``)."""

    def __init__(self, op: LinearOperator):
        super().__init__(op.dimsd, op.dims, dtype=op.dtype, name=f"{op.name}.H")
        self.op = op

    def _forward(self, y):
        return self.op.adjoint(y)

    def _adjoint(self, x):
        return self.op(x)

    def adjoint(self, y=None):
        r""":math:`(A^\mathsf{H})^\mathsf{H} y = A y`; ``A`` itself when ``y`` is omitted."""
        return self.op if y is None else super().adjoint(y)

    H = property(adjoint)


class Jacobian(LinearOperator):
    """Jacobian :math:`J_F(x)` of an operator at a point, with the value :math:`F(x)`.

    Parameters
    ----------
    op : Operator
        The operator :math:`F`.
    x : ndarray
        The linearization point, shape ``op.dims``.
    value : ndarray, optional
        :math:`F(x)` if already known (kept as ``.value``).
    jvp, vjp : callable, optional
        ``v -> J v`` and ``w -> Jᵀ w`` on arrays shaped ``dims``/``dimsd``; default to
        ``op.jvp(x, ·)`` and ``op.vjp(x, ·)``, or to ``derivative`` and its adjoint.
    derivative : LinearOperator, optional
        The Jacobian as an assembled linear operator (e.g. the chain-rule composition of the
        parts' Jacobians), kept as ``.derivative``: a stack of Jacobians that end in the same
        factors applies those once (:class:`~operators.combinators.VStack`).
    """

    def __init__(self, op: Operator, x, value=None, jvp=None, vjp=None,
                 derivative: LinearOperator | None = None):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=f"J[{op.name}]")
        self.op = op
        self.x = x
        self.value = value
        self.derivative = derivative
        if derivative is not None:
            jvp = derivative if jvp is None else jvp
            vjp = derivative.adjoint if vjp is None else vjp
        self._apply_jvp = (lambda v: op.jvp(x, v)) if jvp is None else jvp
        self._apply_vjp = (lambda w: op.vjp(x, w)) if vjp is None else vjp

    def _forward(self, v):
        return np.asarray(self._apply_jvp(v))

    def _adjoint(self, w):
        return np.asarray(self._apply_vjp(w))


class Composition(CompositionRule, Operator):
    r"""``outer @ inner``: :math:`x \mapsto \text{outer}(\text{inner}(x))`, chain rule
    (:class:`~operators.rules.CompositionRule`)."""

    def linearize(self, x) -> Jacobian:
        r"""Both parts linearized once: :math:`J = J_\text{outer}(\text{inner}(x))\,
        J_\text{inner}(x)`."""
        x = self._as_input(x)
        return _linearize_after(self, x, self.outer, self.inner.linearize(x))[1]


def _linearize_after(op: Operator, x, outer: Operator, j_inner: Jacobian):
    """``(J_outer, J_op)`` at ``x`` for ``op`` = ``outer`` after an inner map whose Jacobian
    at ``x`` (with its value) is ``j_inner``: the outer linearized at the inner's value."""
    j_outer = outer.linearize(np.reshape(j_inner.value, outer.dims))
    return j_outer, Jacobian(op, x, j_outer.value,
                             derivative=_linear_if_possible(Composition(j_outer, j_inner)))


class _Combination(CombinationRule, Operator):
    """An operator assembled from ``parts`` applied to (pieces of) one input
    (:class:`~operators.rules.CombinationRule`), linearized once per point."""

    def _rebuild(self, parts: Sequence[Operator]) -> Operator:
        """The same combination of other operators (e.g. of the parts' Jacobians)."""
        raise NotImplementedError

    def linearize(self, x) -> Jacobian:
        """Each part linearized once at its input; the Jacobian is the same combination of
        the parts' Jacobians."""
        x = self._as_input(x)
        jacobians = [p.linearize(xi) for p, xi in zip(self.parts, self._inputs(x), strict=True)]
        value = self._assemble([j.value for j in jacobians])
        return Jacobian(self, x, value, derivative=_linear_if_possible(self._rebuild(jacobians)))


class Sum(SumRule, _Combination):
    """``A + B + ...`` (:class:`~operators.rules.SumRule`)."""

    def _rebuild(self, parts):
        return Sum(parts)


class Scaled(ScaleRule, _Combination):
    """``c * A`` (:class:`~operators.rules.ScaleRule`)."""

    def _rebuild(self, parts):
        return Scaled(parts[0], self.scale)


class _LinearView(LinearOperator):
    """A combination of linear operators seen as one :class:`LinearOperator`.

    Attributes
    ----------
    combination : Operator
        The combination itself (e.g. a :class:`~operators.combinators.VStack`, for its
        ``split``/``join``).
    """

    def __init__(self, op: Operator):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=op.name)
        self.combination = op

    def _forward(self, x):
        return self.combination._forward(x)

    def _adjoint(self, y):
        return self.combination._vjp(None, y)


def _linear_if_possible(op: Operator) -> Operator:
    """A combination (``op.parts``: the operators it combines) as a linear operator when every
    part is linear, else unchanged."""
    return _LinearView(op) if all(p.linear for p in op.parts) else op


class _PylopsWrapper(PylopsRule, LinearOperator):
    """A pylops linear operator as ours (:func:`operators.aslinearoperator`, ``A @ op``)."""


class _FunctionOperator(FunctionRule, Operator):
    """An operator whose value and derivatives come from a JAX or torch function
    (:class:`~operators.rules.FunctionRule`)."""

    def linearize(self, x) -> Jacobian:
        """One forward pass, keeping the framework's pullback for the vjp."""
        x = self._as_input(x)
        value, jvp, vjp = self.function.pullback(x)
        return Jacobian(self, x, self._result(value, self.dimsd, "forward"), jvp=jvp, vjp=vjp)


class JaxOperator(_FunctionOperator):
    """An :class:`Operator` from a JAX function ``fun(x) -> y``.

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


class TorchOperator(_FunctionOperator):
    """An :class:`Operator` from a torch function ``fun(x) -> y``.

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
