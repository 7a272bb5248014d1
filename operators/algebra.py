r"""The chain-rule algebra of operators: ``A @ B``, ``A + B``, ``c * A`` and their kin.

:class:`Composition`, :class:`Sum` and :class:`Scaled` are what the operators of
:class:`~operators.base.Operator` (``@``, ``+``, ``-``, ``*``, unary ``-``, ``**``) build;
:class:`_Combination` is the common ground of every operator assembled from parts applied to
one input, the stacks of :mod:`operators.combinators` included. A combination linearizes each
part once per point: the Jacobian of ``A + B`` at ``x`` is the sum of the parts' Jacobians at
``x``, built once, and so on for every combinator; it is linear when all its parts are.

This module imports :mod:`operators.base`, never the other way round: its classes register
themselves with :func:`operators.base.register`, through which the base class's methods build
them and ``operators.base.Composition`` (and so on) stays importable.

:func:`linearize_together` linearizes several chains of compositions that end in the same
factors (a data map and a regularizer after one reparameterization) with those factors once.
"""

from __future__ import annotations

from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np

from operators.base import Jacobian, JaxMap, LinearOperator, Operator, _size, register


def _jacobian_from(op: Operator, x, value, derivative: LinearOperator) -> Jacobian:
    """The Jacobian of ``op`` at ``x`` applied through an already assembled linear map."""
    return Jacobian(op, x, value, derivative=derivative)


def _push(op: Operator, x, v):
    """:math:`J_{op}(x) v` (``x`` unused, and may be None, when ``op`` is linear)."""
    return op(v) if op.linear else op.jvp(x, v)


def _pull(op: Operator, x, w):
    r""":math:`J_{op}(x)^\mathsf{T} w` (``x`` unused, and may be None, when ``op`` is linear)."""
    return op.adjoint(w) if op.linear else op.vjp(x, w)


@register
class Composition(Operator):
    r"""``outer @ inner``: :math:`x \mapsto \text{outer}(\text{inner}(x))`, chain rule.

    The inner output is reshaped to the outer input when the two shapes differ in layout but
    not in size (checked here, once).
    """

    def __init__(self, outer: Operator, inner: Operator):
        if _size(outer.dims) != _size(inner.dimsd):
            raise ValueError(
                f"cannot compose {outer.name} (input {outer.dims}) after {inner.name} "
                f"(output {inner.dimsd}): sizes differ"
            )
        dtype = np.result_type(outer.dtype, inner.dtype)
        super().__init__(inner.dims, outer.dimsd, dtype=dtype,
                         name=f"({outer.name} @ {inner.name})")
        self.outer, self.inner = outer, inner
        self.parts = (outer, inner)

    def _mid(self, y):
        return np.reshape(y, self.outer.dims)

    def jax_map(self) -> JaxMap | None:
        """The two parts' maps composed, when both have one; the outer part's domain is
        checked at the inner part's value, computed on the host by the inner operator (cheap
        for a diagonal before the emission map, as a voxel problem has it)."""
        outer, inner = self.outer.jax_map(), self.inner.jax_map()
        if outer is None or inner is None:
            return None
        mid = self.outer.dims

        def function(args, x):
            return outer.function(args[0], jnp.reshape(inner.function(args[1], x), mid))

        def check(x):
            if inner.check is not None:
                inner.check(x)
            if outer.check is not None:
                outer.check(self._mid(self.inner(x)))

        checked = inner.check is not None or outer.check is not None
        return JaxMap(function, (outer.args, inner.args), check if checked else None)

    def _forward(self, x):
        return self.outer(self._mid(self.inner(x)))

    def _inner_value(self, x):
        return None if self.outer.linear else self._mid(self.inner(x))

    def _jvp(self, x, v):
        return _push(self.outer, self._inner_value(x), self._mid(_push(self.inner, x, v)))

    def _vjp(self, x, w):
        inner_w = np.reshape(_pull(self.outer, self._inner_value(x), w), self.inner.dimsd)
        return _pull(self.inner, x, inner_w)

    def linearize(self, x) -> Jacobian:
        r"""Both parts linearized once: :math:`J = J_\text{outer}(\text{inner}(x))\,
        J_\text{inner}(x)`."""
        x = self._as_input(x)
        return _linearize_after(self, x, self.outer, self.inner.linearize(x))[1]


def _linearize_after(op: Operator, x, outer: Operator, j_inner: Jacobian):
    """``(J_outer, J_op)`` at ``x`` for ``op`` = ``outer`` after an inner map whose Jacobian
    at ``x`` (with its value) is ``j_inner``: the outer linearized at the inner's value."""
    j_outer = outer.linearize(np.reshape(j_inner.value, outer.dims))
    return j_outer, _jacobian_from(op, x, j_outer.value,
                                   _linear_if_possible(Composition(j_outer, j_inner)))


def _factors(op: Operator) -> list[Operator]:
    """The factors of a chain of compositions, outermost first (``[op]`` if it is none).

    A Jacobian assembled from others is seen as its ``derivative``, and ``c * (A @ B)`` as
    ``(c * A) @ B``.
    """
    if isinstance(op, Jacobian) and op.derivative is not None:
        factors = _factors(op.derivative)
        return factors if len(factors) > 1 else [op]
    combination = op.combination if isinstance(op, _LinearView) else op
    if isinstance(combination, Composition):
        return _factors(combination.outer) + _factors(combination.inner)
    if isinstance(combination, Scaled):
        outermost, *rest = _factors(combination.parts[0])
        return [combination.scale * outermost, *rest] if rest else [op]
    return [op]


def _compose(factors: Sequence[Operator]) -> Operator:
    """``factors[0] @ factors[1] @ ...``, innermost first composed."""
    out = factors[-1]
    for factor in reversed(factors[:-1]):
        out = factor @ out
    return out


def _common_factor(ops: Sequence[Operator]):
    r"""Operators on one input split as :math:`F_i = A_i \circ P` with :math:`P` the innermost
    factors they all end in (the same objects, :func:`_factors`), each :math:`A_i` keeping
    at least one factor of its own.

    Parameters
    ----------
    ops : sequence of Operator
        Two or more operators with the same input shape.

    Returns
    -------
    tuple of (list of Operator, Operator), or None
        ``(outers, inner)``: ``ops[i]`` is ``outers[i] @ inner``; None when they share no
        factor (or there is one operator).
    """
    if len(ops) < 2:
        return None
    chains = [_factors(op) for op in ops]
    most = min(len(c) for c in chains) - 1
    shared = 0
    while shared < most and all(c[-1 - shared] is chains[0][-1 - shared] for c in chains):
        shared += 1
    if shared == 0:
        return None
    return [_compose(c[:-shared]) for c in chains], _compose(chains[0][-shared:])


def _pull_through(inner: Operator, cotangents, dims):
    r""":math:`P^\mathsf{T} \sum_i w_i`, shaped ``dims``, for cotangents :math:`w_i` of the
    output of a shared inner factor :math:`P` (``inner``, linear)."""
    w = sum(np.reshape(wi, inner.dimsd) for wi in cotangents)
    return np.reshape(inner.adjoint(w), dims)


def linearize_together(ops: Sequence[Operator], x):
    r"""Operators on one input linearized at ``x``, their common innermost factors once.

    When every operator of ``ops`` is a chain of compositions ending in the same factors
    :math:`P` (the same objects: :math:`F_i = A_i \circ P`, e.g. a data map and a regularizer
    after one reparameterization), :math:`P` is evaluated and linearized once, and a sum of
    the operators' pullbacks passes through :math:`J_P^\mathsf{T}` once:
    :math:`\sum_i J_{F_i}^\mathsf{T} w_i = J_P^\mathsf{T} \sum_i J_{A_i}^\mathsf{T} w_i`.
    Otherwise each operator is linearized on its own.

    Parameters
    ----------
    ops : sequence of Operator
        Operators with the same input shape.
    x : ndarray
        The point, shape ``ops[0].dims``.

    Returns
    -------
    jacobians : list of Jacobian
        :math:`J_{F_i}(x)`, each with its ``.value`` :math:`F_i(x)`; those of operators with
        common factors are :math:`J_{A_i} J_P` with the one :math:`J_P`, so a
        :class:`~operators.combinators.VStack` of them applies :math:`J_P` once too.
    pull : callable
        ``pull(ws, scales)`` is :math:`\sum_i c_i J_{F_i}(x)^\mathsf{T} w_i` for cotangents
        ``ws`` shaped as the operators' outputs (None for a term left out) and real scales
        :math:`c_i`, shape ``ops[0].dims``; each scale multiplies its term's pullback (through
        the shared factors: before :math:`J_P^\mathsf{T}`), as a caller computing the terms one
        by one would.
    """
    split = _common_factor(ops)
    if split is None:
        jacobians = [op.linearize(x) for op in ops]
        return jacobians, lambda ws, scales: sum(
            c * np.reshape(j.adjoint(w), ops[0].dims)
            for j, w, c in zip(jacobians, ws, scales, strict=True) if w is not None)
    outers, inner = split
    x = ops[0]._as_input(x)
    j_inner = inner.linearize(x)
    j_outers, jacobians = zip(*(_linearize_after(op, x, outer, j_inner)
                                for op, outer in zip(ops, outers, strict=True)), strict=True)

    def pull(ws, scales):
        return _pull_through(j_inner, (c * j.adjoint(w) for j, w, c
                                       in zip(j_outers, ws, scales, strict=True)
                                       if w is not None), ops[0].dims)

    return list(jacobians), pull


class _Combination(Operator):
    """An operator assembled from ``parts`` applied to (pieces of) one input.

    Subclasses say how the input is handed to the parts (:meth:`_inputs`), how the parts'
    outputs are assembled (:meth:`_assemble`) and the adjoints of both (:meth:`_cotangents`,
    :meth:`_gather`); value, Jacobian products and the once-per-point linearization follow.
    """

    parts: tuple[Operator, ...]

    def _rebuild(self, parts: Sequence[Operator]) -> Operator:
        """The same combination of other operators (e.g. of the parts' Jacobians)."""
        raise NotImplementedError

    def _inputs(self, x) -> list:
        return [np.reshape(x, p.dims) for p in self.parts]

    def _gather(self, grads) -> np.ndarray:
        return sum(np.reshape(g, self.dims) for g in grads)

    def _assemble(self, outputs) -> np.ndarray:
        raise NotImplementedError

    def _cotangents(self, w) -> list:
        raise NotImplementedError

    def _forward(self, x):
        return self._assemble([p(xi) for p, xi in zip(self.parts, self._inputs(x), strict=True)])

    def _jvp(self, x, v):
        return self._assemble([_push(p, xi, vi) for p, xi, vi in
                               zip(self.parts, self._inputs(x), self._inputs(v), strict=True)])

    def _vjp(self, x, w):
        xs = [None] * len(self.parts) if x is None else self._inputs(x)
        return self._gather([_pull(p, xi, wi) for p, xi, wi in
                             zip(self.parts, xs, self._cotangents(w), strict=True)])

    def linearize(self, x) -> Jacobian:
        """Each part linearized once at its input; the Jacobian is the same combination of
        the parts' Jacobians."""
        x = self._as_input(x)
        jacobians = [p.linearize(xi) for p, xi in zip(self.parts, self._inputs(x), strict=True)]
        value = self._assemble([j.value for j in jacobians])
        return _jacobian_from(self, x, value, _linear_if_possible(self._rebuild(jacobians)))


@register
class Sum(_Combination):
    """``A + B + ...`` of operators with inputs and outputs of the same sizes (the shapes of
    the first)."""

    def __init__(self, ops: Sequence[Operator]):
        ops = list(ops)
        first = ops[0]
        for op in ops[1:]:
            if _size(op.dims) != _size(first.dims) or _size(op.dimsd) != _size(first.dimsd):
                raise ValueError(
                    f"cannot add {first.name} ({first.dims} -> {first.dimsd}) and {op.name} "
                    f"({op.dims} -> {op.dimsd}): sizes differ"
                )
        super().__init__(first.dims, first.dimsd, dtype=np.result_type(*[o.dtype for o in ops]),
                         name="(" + " + ".join(o.name for o in ops) + ")")
        self.parts = tuple(ops)

    def _rebuild(self, parts):
        return Sum(parts)

    def _assemble(self, outputs):
        return sum(np.reshape(y, self.dimsd) for y in outputs)

    def _cotangents(self, w):
        return [np.reshape(w, p.dimsd) for p in self.parts]


@register
class Scaled(_Combination):
    """``c * A`` for a real scalar ``c``."""

    def __init__(self, op: Operator, scale: float):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=f"{scale:g}*{op.name}")
        self.scale = float(scale)
        self.parts = (op,)

    def _rebuild(self, parts):
        return Scaled(parts[0], self.scale)

    def _assemble(self, outputs):
        return self.scale * outputs[0]

    def _cotangents(self, w):
        return [self.scale * w]


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


@register
def _linear_if_possible(op: Operator) -> Operator:
    """A combination (``op.parts``: the operators it combines) as a linear operator when every
    part is linear, else unchanged."""
    return _LinearView(op) if all(p.linear for p in op.parts) else op
