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
``A - B``, ``c * A``, ``-A``, ``A ** p``, ``A.T``, and the stacks :func:`~operators.vstack` and
:func:`~operators.block_diag` (:mod:`operators.combinators`); every one returns an operator,
linear when all its parts are, and linearizes each part once per point (:mod:`operators.algebra`).

**Where the pieces live.** This module holds the base classes and the operators their own
methods return: :class:`Jacobian`, :class:`Adjoint` and :class:`Identity`. The combinations
(:mod:`operators.algebra`) and the wrappers of pylops operators and of JAX or torch functions
(:mod:`operators.adapters`) import this module and never the reverse: they :func:`register`
themselves here, and the methods build them through that registry, which also keeps them
importable from here (``operators.base.Composition``).

**Shapes are checked.** An input must have the operator's shape (``dims`` for ``x`` and ``v``,
``dimsd`` for ``w``); a linear operator also takes the flat vector of as many elements, the
convention of pylops' ``matvec``. Anything else raises a ``ValueError`` naming the operator, the
expected and the given shape; so does an implementation whose result has the wrong shape.

**Precision.** An operator of dtype float64 evaluates (value, Jacobian products, adjoint and
``linearize``, a subclass's own included) inside :func:`~operators.jax_precision.precision`.
"""

from __future__ import annotations

import functools
import numbers
import types

import numpy as np

from operators.jax_map import JaxMap
from operators.jax_precision import precision
from operators.pylops_import import pylops

#: What :func:`register` received, by name.
_registered = types.SimpleNamespace()


def register(obj):
    """Make ``obj``, a class or function of a module that imports this one, available to the
    methods of :class:`Operator` and importable from here as ``operators.base.<name>``.

    Parameters
    ----------
    obj : type or callable
        Registered under its ``__name__``; returned unchanged (use as a decorator).
    """
    setattr(_registered, obj.__name__, obj)
    return obj


def __getattr__(name):
    """A registered name (:func:`register`), as an attribute of this module."""
    try:
        return getattr(_registered, name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def _shape(dims) -> tuple[int, ...]:
    return (int(dims),) if np.isscalar(dims) else tuple(int(d) for d in dims)


def _size(shape) -> int:
    return int(np.prod(shape, dtype=np.int64))


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

    def jax_map(self) -> JaxMap | None:
        """This operator as a function JAX can trace (:class:`JaxMap`), or None (the default)
        for an operator that has none: programs that need one then use its NumPy methods.
        Its arrays are placed on JAX's device at every call; call it once per program."""
        return None

    def _forward(self, x):
        raise NotImplementedError(f"{self.name} does not implement _forward")

    def _jvp(self, x, v):
        raise NotImplementedError(f"{self.name} does not implement _jvp")

    def _vjp(self, x, w):
        raise NotImplementedError(f"{self.name} does not implement _vjp")

    # -- construction from frameworks ------------------------------------------------------
    @staticmethod
    def from_jax(fun, dims, dimsd, dtype=np.float64, name=None) -> Operator:
        """Wrap a JAX function; see :class:`~operators.adapters.JaxOperator`."""
        return _registered.JaxOperator(fun, dims, dimsd, dtype=dtype, name=name)

    @staticmethod
    def from_torch(fun, dims, dimsd, dtype=np.float64, device=None, name=None) -> Operator:
        """Wrap a torch function; see :class:`~operators.adapters.TorchOperator`."""
        return _registered.TorchOperator(fun, dims, dimsd, dtype=dtype, device=device,
                                         name=name)

    # -- algebra ----------------------------------------------------------------------------
    def __matmul__(self, other):
        if isinstance(other, pylops.LinearOperator) and not isinstance(other, Operator):
            other = _registered.aslinearoperator(other)
        if isinstance(other, Operator):
            return _registered._linear_if_possible(_registered.Composition(self, other))
        if self.linear:
            return pylops.LinearOperator.dot(self, other)
        raise TypeError(
            f"{self.name} is nonlinear: evaluate it as F(x), not F @ x "
            f"(got {type(other).__name__})"
        )

    def __add__(self, other):
        if not isinstance(other, Operator):
            return NotImplemented
        return _registered._linear_if_possible(_registered.Sum([self, other]))

    def __sub__(self, other):
        if not isinstance(other, Operator):
            return NotImplemented
        return self + (-1.0) * other

    def __neg__(self):
        return (-1.0) * self

    def __mul__(self, other):
        if isinstance(other, numbers.Number):
            return _registered._linear_if_possible(_registered.Scaled(self, other))
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
        return Jacobian(self, x, self(x), derivative=self)

    def _matvec(self, x):
        return self(np.reshape(x, self.dims)).ravel()

    def _rmatvec(self, y):
        return self.adjoint(np.reshape(y, self.dimsd)).ravel()


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
