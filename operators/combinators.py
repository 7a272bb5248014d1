"""Stacks of operators on one input (:func:`vstack`) and block-diagonal operators on the parts
of one input (:func:`block_diag`), with the chain rule of :mod:`operators.rules`.

Each is linear (a :class:`operators.base.LinearOperator`) when all its blocks are, and
linearizes each block once per point. A stack of linear blocks that end in the same factors
applies those once.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from operators.algebra import _common_factor, _pull_through
from operators.base import Operator, _Combination, _linear_if_possible
from operators.protocol import _size


def _stacked_shape(shapes: Sequence[tuple[int, ...]]) -> tuple[int, ...]:
    """``(n, *shape)`` when all blocks share a shape, else the flat concatenated size."""
    if all(s == shapes[0] for s in shapes):
        return (len(shapes), *shapes[0])
    return (sum(_size(s) for s in shapes),)


def _split(x: np.ndarray, shapes: Sequence[tuple[int, ...]]) -> list[np.ndarray]:
    sizes = [_size(s) for s in shapes]
    parts = np.split(np.ravel(x), np.cumsum(sizes)[:-1])
    return [p.reshape(s) for p, s in zip(parts, shapes, strict=True)]


def _join(parts: Sequence[np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
    return np.concatenate([np.ravel(p) for p in parts]).reshape(shape)


def _check_blocks(ops, what):
    ops = list(ops)
    if not ops:
        raise ValueError(f"{what} needs at least one operator")
    bad = [type(op).__name__ for op in ops if not isinstance(op, Operator)]
    if bad:
        raise TypeError(f"{what} blocks must be operators.Operator (wrap pylops operators with "
                        f"operators.aslinearoperator); got {', '.join(bad)}")
    return ops


class VStack(_Combination):
    r"""Vertical stack :math:`x \mapsto (A_1(x), \dots, A_n(x))` of operators on one input.

    The output has shape ``(n, *dimsd)`` when all blocks share ``dimsd``, else it is the flat
    concatenation of the blocks' outputs (:meth:`split` and :meth:`join` convert).

    Linear blocks that end in the same factors :math:`P` (the same objects:
    :math:`A_i = B_i P`, e.g. the Jacobians of a data map and a regularizer after one
    reparameterization, from :func:`operators.linearize_together`) apply :math:`P` once:
    :math:`x \mapsto (B_1 P x, \dots, B_n P x)`, and the adjoint
    :math:`P^\mathsf{T} \sum_i B_i^\mathsf{T} y_i`.
    """

    def __init__(self, ops: Sequence[Operator], name: str | None = None):
        ops = _check_blocks(ops, "VStack")
        if any(op.dims != ops[0].dims for op in ops):
            raise ValueError("VStack blocks must share their input shape: got "
                             + ", ".join(str(op.dims) for op in ops))
        super().__init__(ops[0].dims, _stacked_shape([op.dimsd for op in ops]),
                         dtype=np.result_type(*[op.dtype for op in ops]),
                         name=name or "VStack[" + ", ".join(op.name for op in ops) + "]")
        self.parts = tuple(ops)
        self._factored = _common_factor(ops) if all(op.linear for op in ops) else None

    def split(self, y) -> list[np.ndarray]:
        """An output of the stack as its blocks, each shaped like its operator's ``dimsd``."""
        return _split(self._as_output(y, "y"), [op.dimsd for op in self.parts])

    def join(self, blocks) -> np.ndarray:
        """Blocks shaped like the operators' ``dimsd`` as one output of the stack."""
        blocks = [op._as_output(b, "block") for op, b in zip(self.parts, blocks, strict=True)]
        return _join(blocks, self.dimsd)

    def _rebuild(self, parts):
        return VStack(parts, name=self.name)

    def _forward(self, x):
        if self._factored is None:
            return super()._forward(x)
        outers, inner = self._factored
        y = inner(np.reshape(x, inner.dims))
        return self._assemble([outer(np.reshape(y, outer.dims)) for outer in outers])

    def _jvp(self, x, v):
        return super()._jvp(x, v) if self._factored is None else self._forward(v)

    def _vjp(self, x, w):
        if self._factored is None:
            return super()._vjp(x, w)
        outers, inner = self._factored
        return _pull_through(inner, (outer.adjoint(wi) for outer, wi
                                     in zip(outers, self._cotangents(w), strict=True)),
                             self.dims)

    def _assemble(self, outputs):
        return _join(outputs, self.dimsd)

    def _cotangents(self, w):
        return _split(w, [op.dimsd for op in self.parts])


class BlockDiag(_Combination):
    """Block-diagonal operator: block ``i`` acts on part ``i`` of the input.

    Input and output have shape ``(n, *dims)`` / ``(n, *dimsd)`` when all blocks share their
    shapes (e.g. one operator per field), else flat concatenations.
    """

    def __init__(self, ops: Sequence[Operator], name: str | None = None):
        ops = _check_blocks(ops, "BlockDiag")
        super().__init__(_stacked_shape([op.dims for op in ops]),
                         _stacked_shape([op.dimsd for op in ops]),
                         dtype=np.result_type(*[op.dtype for op in ops]),
                         name=name or "BlockDiag[" + ", ".join(op.name for op in ops) + "]")
        self.parts = tuple(ops)

    def _rebuild(self, parts):
        return BlockDiag(parts, name=self.name)

    def _inputs(self, x):
        return _split(x, [op.dims for op in self.parts])

    def _gather(self, grads):
        return _join(grads, self.dims)

    def _assemble(self, outputs):
        return _join(outputs, self.dimsd)

    def _cotangents(self, w):
        return _split(w, [op.dimsd for op in self.parts])



def vstack(ops: Sequence[Operator], name: str | None = None) -> Operator:
    """Stack operators vertically (:class:`VStack`); linear if all blocks are.

    Parameters
    ----------
    ops : sequence of Operator
        Blocks sharing their input shape.
    name : str, optional
        Label for messages.
    """
    return _linear_if_possible(VStack(ops, name=name))


def block_diag(ops: Sequence[Operator], name: str | None = None) -> Operator:
    """Block-diagonal combination (:class:`BlockDiag`); linear if all blocks are.

    Parameters
    ----------
    ops : sequence of Operator
        Blocks, each acting on its own part of the input.
    name : str, optional
        Label for messages.
    """
    return _linear_if_possible(BlockDiag(ops, name=name))

