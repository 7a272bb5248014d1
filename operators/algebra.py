r"""Chains of compositions that end in the same factors, linearized with those factors once.

:func:`linearize_together` linearizes several chains of compositions that end in the same
factors (a data map and a regularizer after one reparameterization) with those factors once;
:func:`_common_factor` finds the factors, for it and for the stacks of
:mod:`operators.combinators`. The combinations themselves (:class:`~operators.base.Composition`,
:class:`~operators.base.Sum`, :class:`~operators.base.Scaled`) are defined in
:mod:`operators.base`, whose operators' ``@``, ``+`` and ``*`` build them; this module imports
that one.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from operators.base import (
    Composition,
    Jacobian,
    Operator,
    Scaled,
    _linearize_after,
    _LinearView,
)


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
