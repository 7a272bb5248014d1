r"""Operators between array shapes, possibly nonlinear, with the chain rule built in.

An :class:`Operator` :math:`F: \mathbb{R}^{\text{dims}} \to \mathbb{R}^{\text{dimsd}}` evaluates
``F(x)``, its Jacobian-vector product ``F.jvp(x, v)`` :math:`= J_F(x) v`, its vector-Jacobian
product ``F.vjp(x, w)`` :math:`= J_F(x)^\mathsf{T} w`, and ``F.linearize(x)``, the Jacobian at
``x`` as a matrix-free :class:`LinearOperator` that also carries the value ``F(x)``.

There is one way to write an operator, on arrays already shaped ``dims`` / ``dimsd``:

- a nonlinear one implements ``_forward(x)``, ``_jvp(x, v)`` and ``_vjp(x, w)`` (and may
  override ``linearize`` to share work between the value and the derivatives);
- a linear one (:class:`LinearOperator`) implements ``_forward(x)`` and ``_adjoint(y)``; the
  base class derives the Jacobian products and pylops' flat ``_matvec`` / ``_rmatvec`` from
  them, so pylops solvers, :func:`pylops.utils.dottest` and pyproximal take it unchanged.
  ``A.H`` is the adjoint as an operator and ``A.adjoint(y)`` applies it.

The algebra follows the chain rule: ``A @ B`` (composition, ``B`` applied first), ``A + B``,
``A - B``, ``c * A``, ``-A``, ``A ** p``, ``A.T``, and the stacks
:func:`~operators.combinators.vstack` and :func:`~operators.combinators.block_diag`
(:mod:`operators.combinators`); every one returns an operator, linear when all its parts
are. A combination linearizes each part once per point: the Jacobian of ``A + B`` at ``x``
is the sum of the parts' Jacobians at ``x``, built once, and so on for every combinator.

**Shapes are checked.** An input must have the operator's shape (``dims`` for ``x`` and ``v``,
``dimsd`` for ``w``); a linear operator also takes the flat vector of as many elements, the
convention of pylops' ``matvec``. Anything else raises a ``ValueError`` naming the operator, the
expected and the given shape; so does an implementation whose result has the wrong shape.

**Precision.** An operator of dtype float64 evaluates (value, Jacobian products, adjoint and
``linearize``, a subclass's own included) inside :func:`precision`, so that JAX computes in
float64 there without turning on ``jax_enable_x64`` for the whole process.
"""

from __future__ import annotations

import contextlib
import functools
import numbers
from collections.abc import Sequence

import jax
import numpy as np

from operators.jax_operator import JaxFunction
from operators.pylops_import import pylops


def _shape(dims) -> tuple[int, ...]:
    return (int(dims),) if np.isscalar(dims) else tuple(int(d) for d in dims)


def _size(shape) -> int:
    return int(np.prod(shape, dtype=np.int64))


def precision(dtype):
    """Context in which JAX computes in ``dtype``: float64 turns on x64 inside it only.

    Parameters
    ----------
    dtype : numpy dtype
        float64 enables JAX's 64-bit mode for the duration of the context; any other dtype
        leaves the process setting as it is.
    """
    if np.dtype(dtype) == np.float64:
        return jax.enable_x64(True)
    return contextlib.nullcontext()


class Operator:
    """A differentiable map from arrays of shape ``dims`` to arrays of shape ``dimsd``.

    Subclasses implement ``_forward(x)``, ``_jvp(x, v)`` and ``_vjp(x, w)`` on arrays already
    shaped ``dims`` / ``dimsd``; they may override ``linearize`` to share work between the
    value and the derivatives.

    Parameters
    ----------
    dims : int or tuple of int
        Input shape.
    dimsd : int or tuple of int
        Output shape.
    dtype : numpy dtype, optional
        Floating-point type of inputs and outputs (default float64).
    name : str, optional
        Label used in error messages and reprs.
    """

    linear = False

    def __init_subclass__(cls, **kwargs):
        """A subclass's own ``linearize`` runs inside :func:`precision` too."""
        super().__init_subclass__(**kwargs)
        if "linearize" in vars(cls):
            own = vars(cls)["linearize"]

            @functools.wraps(own)
            def linearize(self, x):
                with precision(self.dtype):
                    return own(self, x)

            cls.linearize = linearize

    def __init__(self, dims, dimsd, dtype=np.float64, name: str | None = None):
        self.dims = _shape(dims)
        self.dimsd = _shape(dimsd)
        self.dtype = np.dtype(dtype)
        self.name = name or type(self).__name__

    # -- shapes -----------------------------------------------------------------------------
    def _checked(self, x, shape: tuple[int, ...], what: str) -> np.ndarray:
        """``x`` as an array of ``shape``; flat accepted for linear operators (pylops)."""
        x = np.asarray(x)
        if x.shape == shape:
            return x
        if self.linear and x.ndim == 1 and x.size == _size(shape):
            return x.reshape(shape)
        flat = f" (or flat, {_size(shape)} elements)" if self.linear else ""
        raise ValueError(f"{self.name}: {what} expected shape {shape}{flat}, got shape "
                         f"{x.shape}; reshape or transpose it to {shape}")

    def _as_input(self, x, what: str = "x") -> np.ndarray:
        return self._checked(x, self.dims, what)

    def _as_output(self, w, what: str = "w") -> np.ndarray:
        return self._checked(w, self.dimsd, what)

    def _result(self, y, shape: tuple[int, ...], what: str) -> np.ndarray:
        y = np.asarray(y)
        if y.shape != shape:
            raise ValueError(f"{self.name}: {what} returned shape {y.shape}, but the operator "
                             f"declares {shape}; fix the function or the declared shape")
        return y

    # -- evaluation -------------------------------------------------------------------------
    def __call__(self, x) -> np.ndarray:
        """Evaluate ``F(x)``; ``x`` shaped ``dims``, returns shape ``dimsd``."""
        x = self._as_input(x)
        with precision(self.dtype):
            return self._result(self._forward(x), self.dimsd, "forward")

    def jvp(self, x, v) -> np.ndarray:
        r"""Jacobian-vector product :math:`J_F(x)\,v`, shape ``dimsd``."""
        x, v = self._as_input(x), self._as_input(v, "v")
        with precision(self.dtype):
            return self._result(self._jvp(x, v), self.dimsd, "jvp")

    def vjp(self, x, w) -> np.ndarray:
        r"""Vector-Jacobian product :math:`J_F(x)^\mathsf{T} w`, shape ``dims``."""
        x, w = self._as_input(x), self._as_output(w)
        with precision(self.dtype):
            return self._result(self._vjp(x, w), self.dims, "vjp")

    def linearize(self, x) -> Jacobian:
        """The Jacobian at ``x`` as a linear operator; ``.value`` holds ``F(x)``."""
        x = self._as_input(x)
        return Jacobian(self, x, self(x))

    def _forward(self, x):
        raise NotImplementedError(f"{self.name} does not implement _forward")

    def _jvp(self, x, v):
        raise NotImplementedError(f"{self.name} does not implement _jvp")

    def _vjp(self, x, w):
        raise NotImplementedError(f"{self.name} does not implement _vjp")

    # -- construction from frameworks ------------------------------------------------------
    @staticmethod
    def from_jax(fun, dims, dimsd, dtype=np.float64, name=None) -> Operator:
        """Wrap a JAX function; see :class:`JaxOperator`."""
        return JaxOperator(fun, dims, dimsd, dtype=dtype, name=name)

    @staticmethod
    def from_torch(fun, dims, dimsd, dtype=np.float64, device="cpu", name=None) -> Operator:
        """Wrap a torch function; see :class:`TorchOperator`."""
        return TorchOperator(fun, dims, dimsd, dtype=dtype, device=device, name=name)

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
        if isinstance(other, numbers.Number):
            return _linear_if_possible(Scaled(self, other))
        return NotImplemented

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

    def __repr__(self) -> str:
        return f"<{self.name}: {self.dims} -> {self.dimsd}, {self.dtype}>"


class LinearOperator(Operator, pylops.LinearOperator):
    r"""A linear :class:`Operator` that is also a :class:`pylops.LinearOperator`.

    Subclasses implement ``_forward(x)`` on arrays shaped ``dims`` and ``_adjoint(y)`` on arrays
    shaped ``dimsd``. ``A(x)``, ``A.jvp(x, v)`` (:math:`= A v`), ``A.vjp(x, w)``
    (:math:`= A^\mathsf{H} w`, ``x`` ignored), ``A.adjoint(y)``, ``A.H`` and pylops'
    ``matvec``/``rmatvec`` all derive from those two methods.
    """

    linear = True

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        flat = [m for m in ("_matvec", "_rmatvec") if m in vars(cls)]
        if flat:
            raise TypeError(f"{cls.__name__} defines {' and '.join(flat)}: a LinearOperator "
                            "implements _forward(x) and _adjoint(y) on shaped arrays, and the "
                            "base class derives pylops' flat methods from them")

    def __init__(self, dims, dimsd, dtype=np.float64, name: str | None = None):
        Operator.__init__(self, dims, dimsd, dtype=dtype, name=name)
        pylops.LinearOperator.__init__(
            self, dtype=self.dtype, dims=self.dims, dimsd=self.dimsd, name=self.name
        )

    def _adjoint(self, y):
        raise NotImplementedError(f"{self.name} does not implement _adjoint")

    def adjoint(self, y=None):
        r""":math:`A^\mathsf{H} y` (``y`` shaped ``dimsd``), or the adjoint operator ``A.H``
        when ``y`` is omitted (as pylops' ``adjoint()``)."""
        if y is None:
            return Adjoint(self)
        y = self._as_output(y, "y")
        with precision(self.dtype):
            return self._result(self._adjoint(y), self.dims, "adjoint")

    H = property(adjoint)

    def transpose(self):
        r""":math:`A^\mathsf{T}`, which for a real operator is the adjoint ``A.H``."""
        if np.issubdtype(self.dtype, np.complexfloating):
            raise TypeError(f"{self.name} is complex: use the adjoint A.H; A.T is only "
                            "defined for real operators")
        return Adjoint(self)

    T = property(transpose)

    def jvp(self, x, v) -> np.ndarray:
        """The operator applied to ``v`` (``x`` is ignored: the Jacobian is the operator)."""
        return self(v)

    def vjp(self, x, w) -> np.ndarray:
        """The adjoint applied to ``w`` (``x`` is ignored: the Jacobian is the operator)."""
        return self.adjoint(w)

    def _jvp(self, x, v):
        return self._forward(v)

    def _vjp(self, x, w):
        return self._adjoint(w)

    def linearize(self, x) -> Jacobian:
        """The operator itself as its Jacobian at ``x``, with ``.value`` :math:`= A x`."""
        x = self._as_input(x)
        return Jacobian(self, x, self(x), jvp=self, vjp=self.adjoint)

    def _matvec(self, x):
        return self(np.reshape(x, self.dims)).ravel()

    def _rmatvec(self, y):
        return self.adjoint(np.reshape(y, self.dimsd)).ravel()


class Identity(LinearOperator):
    """The identity on arrays of shape ``dims`` (``A ** 0``)."""

    def __init__(self, dims, dtype=np.float64):
        super().__init__(dims, dims, dtype=dtype, name="I")

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
        ``v -> J v`` and ``w -> Jᵀ w`` on arrays shaped ``dims``/``dimsd`` (e.g. a linear
        operator and its ``adjoint``); default to ``op.jvp(x, ·)`` and ``op.vjp(x, ·)``.
    """

    def __init__(self, op: Operator, x, value=None, jvp=None, vjp=None):
        super().__init__(op.dims, op.dimsd, dtype=op.dtype, name=f"J[{op.name}]")
        self.op = op
        self.x = x
        self.value = value
        self._apply_jvp = (lambda v: op.jvp(x, v)) if jvp is None else jvp
        self._apply_vjp = (lambda w: op.vjp(x, w)) if vjp is None else vjp

    def _forward(self, v):
        return np.asarray(self._apply_jvp(v))

    def _adjoint(self, w):
        return np.asarray(self._apply_vjp(w))


def _jacobian_from(op: Operator, x, value, derivative: LinearOperator) -> Jacobian:
    """The Jacobian of ``op`` at ``x`` applied through an already assembled linear map."""
    return Jacobian(op, x, value, jvp=derivative, vjp=derivative.adjoint)


def _push(op: Operator, x, v):
    """:math:`J_{op}(x) v` (``x`` unused, and may be None, when ``op`` is linear)."""
    return op(v) if op.linear else op.jvp(x, v)


def _pull(op: Operator, x, w):
    r""":math:`J_{op}(x)^\mathsf{T} w` (``x`` unused, and may be None, when ``op`` is linear)."""
    return op.adjoint(w) if op.linear else op.vjp(x, w)


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
        j_inner = self.inner.linearize(x)
        j_outer = self.outer.linearize(self._mid(j_inner.value))
        return _jacobian_from(self, x, j_outer.value,
                              _linear_if_possible(Composition(j_outer, j_inner)))


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


def _linear_if_possible(op: Operator) -> Operator:
    """A combination (``op.parts``: the operators it combines) as a linear operator when every
    part is linear, else unchanged."""
    return _LinearView(op) if all(p.linear for p in op.parts) else op



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


class JaxOperator(_FunctionOperator):
    """An :class:`Operator` from a JAX function ``fun(x) -> y``.

    ``jvp`` and ``vjp`` come from :func:`jax.jvp` and :func:`jax.vjp`; all three are jit-compiled
    once per operator. ``linearize`` runs the forward pass once and keeps JAX's pullback, so a
    solver's value and gradient cost one forward and one reverse pass.

    Parameters
    ----------
    fun : callable
        JAX-traceable function from an array of shape ``dims`` to one of shape ``dimsd``.
    dims, dimsd : tuple of int
        Input and output shapes; the function's output shape is checked against ``dimsd``.
    dtype : numpy dtype, optional
        Dtype the input is cast to before calling ``fun`` (default float64, computed in JAX's
        64-bit mode inside :func:`precision`).
    name : str, optional
        Label for messages.
    """

    def __init__(self, fun, dims, dimsd, dtype=np.float64, name=None):
        super().__init__(JaxFunction(fun, dtype), dims, dimsd, dtype,
                         name or getattr(fun, "__name__", "jax"))


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
        Where ``fun`` runs (default CPU).
    name : str, optional
        Label for messages.
    """

    def __init__(self, fun, dims, dimsd, dtype=np.float64, device="cpu", name=None):
        from operators.torch_operator import TorchFunction

        super().__init__(TorchFunction(fun, dtype, device), dims, dimsd, dtype,
                         name or getattr(fun, "__name__", "torch"))
        self.device = self.function.device

