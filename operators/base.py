r"""Operators between array shapes, possibly nonlinear, with the chain rule built in.

An :class:`Operator` :math:`F: \mathbb{R}^{\text{dims}} \to \mathbb{R}^{\text{dimsd}}` evaluates
``F(x)``, its Jacobian-vector product ``F.jvp(x, v)`` :math:`= J_F(x) v`, its vector-Jacobian
product ``F.vjp(x, w)`` :math:`= J_F(x)^\mathsf{T} w`, and ``F.linearize(x)``, the Jacobian at
``x`` as a matrix-free :class:`LinearOperator` that also carries the value ``F(x)``.

A :class:`LinearOperator` is at once an :class:`Operator` (``jvp`` is the operator itself,
``vjp`` its adjoint) and a :class:`pylops.LinearOperator`, so pylops solvers,
:func:`pylops.utils.dottest` and pyproximal take it unchanged.

The algebra follows the chain rule: ``A @ B`` (composition, ``B`` applied first), ``A + B``,
``A - B``, ``c * A``, ``-A``, :class:`VStack` and :class:`BlockDiag`. A combination of linear
operators is linear again.

Arrays at this interface are NumPy arrays shaped ``dims`` (input) and ``dimsd`` (output); an
input of the right size but flat is reshaped. Framework operators (JAX, torch) convert at their
boundary through :mod:`operators.interop`.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np
import pylops


def _shape(dims) -> tuple[int, ...]:
    return (int(dims),) if np.isscalar(dims) else tuple(int(d) for d in dims)


class Operator:
    """A differentiable map from arrays of shape ``dims`` to arrays of shape ``dimsd``.

    Subclasses implement ``_forward(x)``, ``_jvp(x, v)`` and ``_vjp(x, w)`` on arrays already
    shaped ``dims`` / ``dimsd``; they may override ``linearize`` to share work between the
    value and the derivatives.

    Parameters
    ----------
    dims : tuple of int
        Input shape.
    dimsd : tuple of int
        Output shape.
    dtype : numpy dtype, optional
        Floating-point type of inputs and outputs (default float64).
    name : str, optional
        Label used in error messages and reprs.
    """

    linear = False

    def __init__(self, dims, dimsd, dtype=np.float64, name: str | None = None):
        self.dims = _shape(dims)
        self.dimsd = _shape(dimsd)
        self.dtype = np.dtype(dtype)
        self.name = name or type(self).__name__

    # -- evaluation -------------------------------------------------------------------------
    def _as_input(self, x, what: str = "x"):
        return _reshape_to(np.asarray(x), self.dims, f"{self.name} {what}")

    def _as_output(self, w, what: str = "w"):
        return _reshape_to(np.asarray(w), self.dimsd, f"{self.name} {what}")

    def __call__(self, x) -> np.ndarray:
        """Evaluate ``F(x)``; ``x`` shaped ``dims`` (or flat), returns shape ``dimsd``."""
        return self._forward(self._as_input(x))

    def jvp(self, x, v) -> np.ndarray:
        """Jacobian-vector product :math:`J_F(x)\\,v`, shape ``dimsd``.

        ``x`` may be ``None`` for an operator whose parts are all linear.
        """
        return self._jvp(self._point(x), self._as_input(v, "v"))

    def vjp(self, x, w) -> np.ndarray:
        """Vector-Jacobian product :math:`J_F(x)^\\mathsf{T} w`, shape ``dims``.

        ``x`` may be ``None`` for an operator whose parts are all linear.
        """
        return self._vjp(self._point(x), self._as_output(w))

    def _point(self, x):
        return None if x is None else self._as_input(x)

    def linearize(self, x) -> Jacobian:
        """The Jacobian at ``x`` as a linear operator; ``.value`` holds ``F(x)``."""
        x = self._as_input(x)
        return Jacobian(self, x, self._forward(x))

    def _forward(self, x):
        raise NotImplementedError(f"{self.name} does not implement _forward")

    def _jvp(self, x, v):
        raise NotImplementedError(f"{self.name} does not implement _jvp")

    def _vjp(self, x, w):
        raise NotImplementedError(f"{self.name} does not implement _vjp")

    # -- construction from frameworks ------------------------------------------------------
    @staticmethod
    def from_jax(fun, dims, dimsd, dtype=np.float64, name=None) -> Operator:
        """Wrap a JAX function; see :class:`operators.jax_operator.JaxOperator`."""
        from operators.jax_operator import JaxOperator

        return JaxOperator(fun, dims, dimsd, dtype=dtype, name=name)

    @staticmethod
    def from_torch(fun, dims, dimsd, dtype=np.float64, name=None) -> Operator:
        """Wrap a torch function; see :class:`operators.torch_operator.TorchOperator`."""
        from operators.torch_operator import TorchOperator

        return TorchOperator(fun, dims, dimsd, dtype=dtype, name=name)

    # -- algebra ----------------------------------------------------------------------------
    def __matmul__(self, other):
        if isinstance(other, pylops.LinearOperator) and not isinstance(other, Operator):
            other = aslinearoperator(other)
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
        return _linear_if_possible(Sum(self, other))

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
        if isinstance(other, numbers.Number):
            return _linear_if_possible(Scaled(self, other))
        return NotImplemented

    def __repr__(self) -> str:
        return f"<{self.name}: {self.dims} -> {self.dimsd}, {self.dtype}>"


def _reshape_to(x: np.ndarray, shape: tuple[int, ...], what: str) -> np.ndarray:
    if x.shape == shape:
        return x
    if x.size == int(np.prod(shape)):
        return x.reshape(shape)
    raise ValueError(f"{what}: expected shape {shape} (or {int(np.prod(shape))} elements), "
                     f"got {x.shape}")


class LinearOperator(Operator, pylops.LinearOperator):
    """A linear :class:`Operator` that is also a :class:`pylops.LinearOperator`.

    Subclasses implement ``_matvec`` and ``_rmatvec`` on flat vectors, as in pylops (the
    :func:`pylops.utils.decorators.reshaped` decorator gives them arrays shaped ``dims``).
    """

    linear = True

    def __init__(self, dims, dimsd, dtype=np.float64, name: str | None = None):
        Operator.__init__(self, dims, dimsd, dtype=dtype, name=name)
        pylops.LinearOperator.__init__(
            self, dtype=self.dtype, dims=self.dims, dimsd=self.dimsd, name=self.name
        )

    def _forward(self, x):
        return np.asarray(self._matvec(x.ravel())).reshape(self.dimsd)

    def _jvp(self, x, v):
        return self._forward(v)

    def _vjp(self, x, w):
        return np.asarray(self._rmatvec(w.ravel())).reshape(self.dims)

    def vjp(self, x, w) -> np.ndarray:
        """Adjoint applied to ``w`` (``x`` is ignored: the Jacobian is the operator)."""
        return self._vjp(None, self._as_output(w))

    def jvp(self, x, v) -> np.ndarray:
        """The operator applied to ``v`` (``x`` is ignored: the Jacobian is the operator)."""
        return self._forward(self._as_input(v, "v"))

    def adjoint_apply(self, w) -> np.ndarray:
        """:math:`A^\\mathsf{H} w` with ``w`` shaped ``dimsd``; returns shape ``dims``."""
        return self.vjp(None, w)

    def _adjoint(self):
        return Adjoint(self)


class Adjoint(LinearOperator):
    """The adjoint :math:`A^\\mathsf{H}` of a :class:`LinearOperator` (``A.H``)."""

    def __init__(self, op: LinearOperator):
        super().__init__(op.dimsd, op.dims, dtype=op.dtype, name=f"{op.name}.H")
        self.op = op

    def _matvec(self, x):
        return self.op._rmatvec(x)

    def _rmatvec(self, x):
        return self.op._matvec(x)


class Jacobian(LinearOperator):
    """Jacobian :math:`J_F(x)` of an operator at a point, applied through jvp/vjp.

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
        ``op.jvp(x, ·)`` and ``op.vjp(x, ·)``.
    """

    def __init__(self, op: Operator, x, value=None, jvp=None, vjp=None):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=f"J[{op.name}]")
        self.op = op
        self.x = x
        self.value = value
        self._apply_jvp = jvp or (lambda v: op.jvp(x, v))
        self._apply_vjp = vjp or (lambda w: op.vjp(x, w))

    def _matvec(self, v):
        return np.asarray(self._apply_jvp(v.reshape(self.dims))).ravel()

    def _rmatvec(self, w):
        return np.asarray(self._apply_vjp(w.reshape(self.dimsd))).ravel()


class Composition(Operator):
    """``outer @ inner``: :math:`x \\mapsto \\text{outer}(\\text{inner}(x))`, chain rule."""

    def __init__(self, outer: Operator, inner: Operator):
        if int(np.prod(outer.dims)) != int(np.prod(inner.dimsd)):
            raise ValueError(
                f"cannot compose {outer.name} (input {outer.dims}) after {inner.name} "
                f"(output {inner.dimsd}): sizes differ"
            )
        dtype = np.result_type(outer.dtype, inner.dtype)
        super().__init__(inner.dims, outer.dimsd, dtype=dtype,
                         name=f"({outer.name} @ {inner.name})")
        self.outer, self.inner = outer, inner
        self.parts = (outer, inner)

    def _forward(self, x):
        return self.outer(self.inner(x))

    def _inner_value(self, x):
        return None if self.outer.linear else self.inner(x)

    def _jvp(self, x, v):
        return self.outer.jvp(self._inner_value(x), self.inner.jvp(x, v))

    def _vjp(self, x, w):
        return self.inner.vjp(x, self.outer.vjp(self._inner_value(x), w))

    def linearize(self, x) -> Jacobian:
        j_inner = self.inner.linearize(x)
        j_outer = self.outer.linearize(j_inner.value)
        return Jacobian(
            self, self._as_input(x), j_outer.value,
            jvp=lambda v: j_outer.jvp(None, j_inner.jvp(None, v)),
            vjp=lambda w: j_inner.vjp(None, j_outer.vjp(None, w)),
        )


class Sum(Operator):
    """``A + B`` on the same input and output shapes."""

    def __init__(self, a: Operator, b: Operator):
        same_size = (np.prod(a.dims) == np.prod(b.dims)) and (np.prod(a.dimsd) == np.prod(b.dimsd))
        if not same_size:
            raise ValueError(
                f"cannot add {a.name} ({a.dims} -> {a.dimsd}) and {b.name} "
                f"({b.dims} -> {b.dimsd}): sizes differ"
            )
        super().__init__(a.dims, a.dimsd, dtype=np.result_type(a.dtype, b.dtype),
                         name=f"({a.name} + {b.name})")
        self.a, self.b = a, b
        self.parts = (a, b)

    def _forward(self, x):
        return self.a(x) + self.b(x).reshape(self.dimsd)

    def _jvp(self, x, v):
        return self.a.jvp(x, v) + self.b.jvp(x, v).reshape(self.dimsd)

    def _vjp(self, x, w):
        return self.a.vjp(x, w) + self.b.vjp(x, w).reshape(self.dims)


class Scaled(Operator):
    """``c * A`` for a real scalar ``c``."""

    def __init__(self, op: Operator, scale: float):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=f"{scale:g}*{op.name}")
        self.op, self.scale = op, float(scale)
        self.parts = (op,)

    def _forward(self, x):
        return self.scale * self.op(x)

    def _jvp(self, x, v):
        return self.scale * self.op.jvp(x, v)

    def _vjp(self, x, w):
        return self.scale * self.op.vjp(x, w)


def _stacked_shape(shapes: Sequence[tuple[int, ...]]) -> tuple[int, ...]:
    """``(n, *shape)`` when all blocks share a shape, else the flat concatenated size."""
    if all(s == shapes[0] for s in shapes):
        return (len(shapes), *shapes[0])
    return (int(sum(np.prod(s) for s in shapes)),)


def _split(x: np.ndarray, shapes: Sequence[tuple[int, ...]]) -> list[np.ndarray]:
    sizes = [int(np.prod(s)) for s in shapes]
    parts = np.split(x.ravel(), np.cumsum(sizes)[:-1])
    return [p.reshape(s) for p, s in zip(parts, shapes, strict=True)]


def _join(parts: Sequence[np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
    return np.concatenate([np.asarray(p).ravel() for p in parts]).reshape(shape)


class VStack(Operator):
    """Vertical stack :math:`x \\mapsto (A_1(x), \\dots, A_n(x))` of operators on one input.

    The output has shape ``(n, *dimsd)`` when all blocks share ``dimsd``, else it is the flat
    concatenation of the blocks' outputs.
    """

    def __init__(self, ops: Sequence[Operator], name: str | None = None):
        ops = list(ops)
        if not ops:
            raise ValueError("VStack needs at least one operator")
        if any(op.dims != ops[0].dims for op in ops):
            raise ValueError("VStack blocks must share their input shape: got "
                             + ", ".join(str(op.dims) for op in ops))
        super().__init__(ops[0].dims, _stacked_shape([op.dimsd for op in ops]),
                         dtype=np.result_type(*[op.dtype for op in ops]),
                         name=name or "VStack[" + ", ".join(op.name for op in ops) + "]")
        self.ops = ops
        self.parts = tuple(ops)

    def _forward(self, x):
        return _join([op(x) for op in self.ops], self.dimsd)

    def _jvp(self, x, v):
        return _join([op.jvp(x, v) for op in self.ops], self.dimsd)

    def _vjp(self, x, w):
        parts = _split(w, [op.dimsd for op in self.ops])
        return sum(op.vjp(x, p) for op, p in zip(self.ops, parts, strict=True))


class BlockDiag(Operator):
    """Block-diagonal operator: block ``i`` acts on part ``i`` of the input.

    Input and output have shape ``(n, *dims)`` / ``(n, *dimsd)`` when all blocks share their
    shapes (e.g. one operator per field), else flat concatenations.
    """

    def __init__(self, ops: Sequence[Operator], name: str | None = None):
        ops = list(ops)
        if not ops:
            raise ValueError("BlockDiag needs at least one operator")
        super().__init__(_stacked_shape([op.dims for op in ops]),
                         _stacked_shape([op.dimsd for op in ops]),
                         dtype=np.result_type(*[op.dtype for op in ops]),
                         name=name or "BlockDiag[" + ", ".join(op.name for op in ops) + "]")
        self.ops = ops
        self.parts = tuple(ops)

    def _parts(self, x):
        return _split(x, [op.dims for op in self.ops])

    def _forward(self, x):
        return _join([op(p) for op, p in zip(self.ops, self._parts(x), strict=True)], self.dimsd)

    def _jvp(self, x, v):
        return _join([op.jvp(p, q) for op, p, q in
                      zip(self.ops, self._parts(x), self._parts(v), strict=True)], self.dimsd)

    def _vjp(self, x, w):
        xs = self._parts(x) if x is not None else [None] * len(self.ops)
        ws = _split(w, [op.dimsd for op in self.ops])
        return _join([op.vjp(p, q) for op, p, q in zip(self.ops, xs, ws, strict=True)],
                     self.dims)


class _LinearView(LinearOperator):
    """A combination of linear operators seen as one :class:`LinearOperator`."""

    def __init__(self, op: Operator):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=op.name)
        self.op = op

    def _matvec(self, x):
        return self.op(x.reshape(self.dims)).ravel()

    def _rmatvec(self, y):
        return self.op.vjp(None, y.reshape(self.dimsd)).ravel()


def _linear_if_possible(op: Operator) -> Operator:
    """A combination (``op.parts``: the operators it combines) as a linear operator when every
    part is linear, else unchanged."""
    return _LinearView(op) if all(p.linear for p in op.parts) else op


def vstack(ops: Sequence[Operator], name: str | None = None) -> Operator:
    """Stack operators vertically (:class:`VStack`); linear if all blocks are."""
    return _linear_if_possible(VStack(ops, name=name))


def block_diag(ops: Sequence[Operator], name: str | None = None) -> Operator:
    """Block-diagonal combination (:class:`BlockDiag`); linear if all blocks are."""
    return _linear_if_possible(BlockDiag(ops, name=name))


class _PylopsWrapper(LinearOperator):
    def __init__(self, op: pylops.LinearOperator, name: str | None = None):
        super().__init__(getattr(op, "dims", (op.shape[1],)),
                         getattr(op, "dimsd", (op.shape[0],)),
                         dtype=op.dtype, name=name or getattr(op, "name", None) or "pylops")
        self.op = op

    def _matvec(self, x):
        return self.op.matvec(x)

    def _rmatvec(self, y):
        return self.op.rmatvec(y)


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
