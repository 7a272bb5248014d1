r"""What an operator computes on arrays: the protocol every operator implements.

An operator :math:`F: \mathbb{R}^{\text{dims}} \to \mathbb{R}^{\text{dimsd}}` evaluates ``F(x)``,
its Jacobian-vector product ``F.jvp(x, v)`` :math:`= J_F(x) v` and its vector-Jacobian product
``F.vjp(x, w)`` :math:`= J_F(x)^\mathsf{T} w`. There is one way to write one, on arrays already
shaped ``dims`` / ``dimsd``:

- a nonlinear one implements ``_forward(x)``, ``_jvp(x, v)`` and ``_vjp(x, w)`` (and may
  override ``linearize`` to share work between the value and the derivatives);
- a linear one implements ``_forward(x)`` and ``_adjoint(y)``; :class:`LinearOperatorProtocol`
  derives the Jacobian products, ``A.adjoint(y)`` and pylops' flat ``_matvec`` / ``_rmatvec``
  from them, so pylops solvers, :func:`pylops.utils.dottest` and pyproximal take it unchanged.

**Why the protocol is a module of its own.** What returns an operator (``linearize``, ``A.H``,
``A @ B``, ``A + B``, ...) builds instances of subclasses of :class:`~operators.Operator`, so it
is defined with them in :mod:`operators.base`; what takes arrays and returns arrays needs none
of them and is defined here, below (as the combinations' arrays are, in :mod:`operators.rules`).
:class:`~operators.Operator` is :class:`OperatorProtocol` with the methods that build operators,
and this module imports no module of :mod:`operators` that defines an operator.

**Shapes are checked.** An input must have the operator's shape (``dims`` for ``x`` and ``v``,
``dimsd`` for ``w``); a linear operator also takes the flat vector of as many elements, the
convention of pylops' ``matvec``. Anything else raises a ``ValueError`` naming the operator, the
expected and the given shape; so does an implementation whose result has the wrong shape.

**Precision.** An operator of dtype float64 evaluates (value, Jacobian products, adjoint and
``linearize``, a subclass's own included) inside :func:`~operators.jax_precision.precision`.
"""

from __future__ import annotations

import functools

import numpy as np

from operators.jax_map import JaxMap
from operators.jax_precision import precision
from operators.pylops_import import pylops


def _shape(dims) -> tuple[int, ...]:
    return (int(dims),) if np.isscalar(dims) else tuple(int(d) for d in dims)


def _size(shape) -> int:
    return int(np.prod(shape, dtype=np.int64))


class OperatorProtocol:
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

    def __repr__(self) -> str:
        return f"<{self.name}: {self.dims} -> {self.dimsd}, {self.dtype}>"


class LinearOperatorProtocol(OperatorProtocol, pylops.LinearOperator):
    r"""A linear :class:`OperatorProtocol` that is also a :class:`pylops.LinearOperator`.

    Subclasses implement ``_forward(x)`` on arrays shaped ``dims`` and ``_adjoint(y)`` on arrays
    shaped ``dimsd``. ``A(x)``, ``A.jvp(x, v)`` (:math:`= A v`), ``A.vjp(x, w)``
    (:math:`= A^\mathsf{H} w`, ``x`` ignored), ``A.adjoint(y)`` and pylops'
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
        OperatorProtocol.__init__(self, dims, dimsd, dtype=dtype, name=name)
        pylops.LinearOperator.__init__(
            self, dtype=self.dtype, dims=self.dims, dimsd=self.dimsd, name=self.name
        )

    def _adjoint(self, y):
        raise NotImplementedError(f"{self.name} does not implement _adjoint")

    def adjoint(self, y):
        r""":math:`A^\mathsf{H} y`, ``y`` shaped ``dimsd``."""
        y = self._as_output(y, "y")
        with precision(self.dtype):
            return self._result(self._adjoint(y), self.dims, "adjoint")

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

    def _matvec(self, x):
        return self(np.reshape(x, self.dims)).ravel()

    def _rmatvec(self, y):
        return self.adjoint(np.reshape(y, self.dimsd)).ravel()
