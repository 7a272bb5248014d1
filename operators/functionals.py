r"""Scalar functionals with gradients and proximal maps, and their composition with operators.

A :class:`Functional` :math:`f` offers ``f(x)``, ``f.grad(x)`` (where differentiable) and
``f.prox(x, tau)`` :math:`= \arg\min_z f(z) + \|z - x\|^2 / (2\tau)`; ``f.prox_dual(y, sigma)``
is the proximal map of :math:`\sigma f^*` by Moreau's identity, which primal–dual solvers use.
:class:`Composite` is :math:`g(K(x))` for an operator :math:`K`, linear or not: the one
"functional after operator" type, which :mod:`solvers` takes as a regularizer.

The regularizers of the flame problem are composites of the gradient operator:
``tikhonov(dims, spacing)`` is :math:`\Phi(f) = \sum_{d\in\{x,y,z\}} \mathrm{mean}((D_d f)^2)`
and ``total_variation(dims, spacing)`` is :math:`\Phi(f) = \sum_d \mathrm{mean}(|D_d f|)`
(anisotropic TV), the means taken over all fields and grid points.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from operators.base import Operator
from operators.derivatives import Gradient


def namespace(x):
    """The array namespace of ``x``: :mod:`jax.numpy` for a JAX array (or a tracer inside a
    compiled program), NumPy otherwise."""
    return jnp if isinstance(x, jax.Array) else np


class Functional:
    r"""A scalar function of an array, with gradient and proximal map.

    Values are summed in float64 whatever the array's precision; gradients and proximal maps
    keep the array's dtype. A functional that is a sum over the array's elements, :math:`f(x)
    = c \sum_i t(x_i)`, gives its terms :math:`t(x_i)` by :meth:`terms` and its gradient for
    NumPy and JAX arrays alike, so that a compiled program (:mod:`solvers.compiled_objective`)
    evaluates it on JAX's device.

    Parameters
    ----------
    scale : float, optional
        Positive weight :math:`c` multiplying the functional (default 1).
    """

    def __init__(self, scale: float = 1.0):
        if not scale > 0:
            raise ValueError(f"scale must be positive, got {scale}")
        self.scale = float(scale)

    def __call__(self, x) -> float:
        return self.scale * float(self.terms(np.asarray(x)).sum(dtype=np.float64))

    def terms(self, x):
        r"""The terms :math:`t(x_i)` of a functional :math:`c \sum_i t(x_i)`, shape of ``x``
        (NumPy or JAX, as ``x``), unscaled; ``NotImplementedError`` for one that is not such a
        sum."""
        raise NotImplementedError(f"{type(self).__name__} is not a sum of terms per element")

    def grad(self, x) -> np.ndarray:
        raise NotImplementedError

    def prox(self, x, tau: float) -> np.ndarray:
        raise NotImplementedError

    def prox_dual(self, y, sigma: float) -> np.ndarray:
        r"""Proximal map of :math:`\sigma f^*` (Moreau: :math:`y - \sigma\,
        \mathrm{prox}_{f/\sigma}(y/\sigma)`)."""
        return y - sigma * self.prox(y / sigma, 1.0 / sigma)


class SquaredL2(Functional):
    r""":math:`f(x) = c\,\|x - b\|_2^2` with optional offset :math:`b`."""

    def __init__(self, scale: float = 1.0, offset=None):
        super().__init__(scale)
        self.offset = None if offset is None else np.asarray(offset)

    def _residual(self, x):
        return x if self.offset is None else x - self.offset

    def terms(self, x):
        r = self._residual(x)
        return (r * r.conj()).real if np.iscomplexobj(r) else r * r

    def grad(self, x):
        """:math:`2c(x - b)`, NumPy or JAX as ``x``."""
        return 2.0 * self.scale * self._residual(namespace(x).asarray(x))

    def prox(self, x, tau: float) -> np.ndarray:
        b = 0.0 if self.offset is None else self.offset
        return (np.asarray(x) + 2.0 * tau * self.scale * b) / (1.0 + 2.0 * tau * self.scale)


class L1(Functional):
    r""":math:`f(x) = c\,\|x\|_1`, or with ``smoothing`` :math:`\varepsilon > 0` its Huber
    smoothing :math:`f(x) = c \sum_i h_\varepsilon(x_i)`, :math:`h_\varepsilon(t) =
    t^2/(2\varepsilon)` for :math:`|t| \le \varepsilon` and :math:`|t| - \varepsilon/2`
    beyond.

    Exact (:math:`\varepsilon = 0`), the gradient is the subgradient :math:`c\,\mathrm{sign}(x)`
    (0 at 0): gradient solvers see no cost in leaving a kink, and a quasi-Newton line search can
    fail where many :math:`x_i` sit at 0 (a flat field). Smoothed, :math:`f` is continuously
    differentiable, its gradient :math:`c\,\mathrm{clip}(x/\varepsilon, -1, 1)` is
    :math:`c/\varepsilon`-Lipschitz, and :math:`0 \le c\|x\|_1 - f(x) \le c\,n\varepsilon/2`.

    Parameters
    ----------
    scale : float, optional
        :math:`c > 0`.
    smoothing : float, optional
        :math:`\varepsilon \ge 0`, in the units of :math:`x` (default 0: exact).
    """

    def __init__(self, scale: float = 1.0, smoothing: float = 0.0):
        super().__init__(scale)
        if not (np.isfinite(smoothing) and smoothing >= 0):
            raise ValueError(f"smoothing must be a finite number >= 0, got {smoothing}")
        self.smoothing = float(smoothing)

    def terms(self, x):
        xp = namespace(x)
        a = xp.abs(x)
        if self.smoothing == 0:
            return a
        eps = self.smoothing
        return xp.where(a <= eps, a * a / (2 * eps), a - eps / 2)

    def grad(self, x):
        r""":math:`c\,\mathrm{sign}(x)` (0 at 0), or smoothed :math:`c\,\mathrm{clip}(x /
        \varepsilon, -1, 1)`; NumPy or JAX as ``x``."""
        xp = namespace(x)
        x = xp.asarray(x)
        if self.smoothing == 0:
            return self.scale * xp.sign(x)
        return self.scale * xp.clip(x / self.smoothing, -1.0, 1.0)

    def prox(self, x, tau: float) -> np.ndarray:
        x = np.asarray(x)
        t = tau * self.scale
        shrunk = np.sign(x) * np.maximum(np.abs(x) - t, 0.0)
        if self.smoothing == 0:
            return shrunk
        # inside |x| <= eps + t the minimizer lies in the quadratic part of h
        return np.where(np.abs(x) <= self.smoothing + t, x * self.smoothing / (self.smoothing + t),
                        shrunk)

    def prox_dual(self, y, sigma: float) -> np.ndarray:
        r"""Proximal map of :math:`\sigma f^*`: :math:`f^*(y) = \varepsilon y^2 / (2c)` on the
        box :math:`|y_i| \le c` (the projection onto it, independent of ``sigma``, when exact)."""
        y = np.asarray(y)
        return np.clip(y / (1.0 + sigma * self.smoothing / self.scale), -self.scale, self.scale)


class Composite(Functional):
    r""":math:`\Phi(x) = g(K(x))` for a functional :math:`g` and an operator :math:`K`.

    :math:`K` may be linear (a finite-difference gradient) or nonlinear (that gradient after a
    network); the gradient is :math:`J_K(x)^\mathsf{T} \nabla g(K(x))`.

    Parameters
    ----------
    functional : Functional
        Outer functional :math:`g` (e.g. :class:`SquaredL2` for Tikhonov, :class:`L1` for total
        variation).
    op : Operator
        Inner operator :math:`K`.
    """

    def __init__(self, functional: Functional, op: Operator):
        if not isinstance(functional, Functional):
            raise TypeError(f"the outer functional of g(K(x)) must be an operators.Functional,"
                            f" got {type(functional).__name__}")
        if not isinstance(op, Operator):
            raise TypeError(f"the inner operator of g(K(x)) must be an operators.Operator, got "
                            f"{type(op).__name__} (wrap pylops operators with "
                            "operators.aslinearoperator)")
        super().__init__(1.0)
        self.functional = functional
        self.op = op

    @property
    def quadratic(self) -> bool:
        """Whether :math:`g` is a squared L2 norm (Tikhonov-like)."""
        return isinstance(self.functional, SquaredL2)

    def __call__(self, x) -> float:
        return float(self.functional(self.op(x)))

    def grad(self, x) -> np.ndarray:
        jacobian = self.op.linearize(x)
        return jacobian.adjoint(self.functional.grad(jacobian.value))

    def prox(self, x, tau: float) -> np.ndarray:
        raise NotImplementedError(
            "the proximal map of f(Ax) has no closed form: split it in a primal-dual solver "
            "with prox_dual of the outer functional and the operator"
        )

    def __repr__(self) -> str:
        return f"Composite({type(self.functional).__name__} o {self.op.name})"


def tikhonov(dims, spacing=1.0, dtype=np.float64) -> Composite:
    r"""Tikhonov regularizer :math:`\sum_d \mathrm{mean}((D_d f)^2)` on ``(n_fields, nx, ny, nz)``.

    Parameters
    ----------
    dims : tuple of 4 int
        ``(n_fields, nx, ny, nz)``.
    spacing : float or tuple of 3 float
        Grid spacing in m (the differences are per metre).
    dtype : numpy dtype, optional
        Operator dtype.
    """
    grad = Gradient(dims, spacing, dtype)
    return Composite(SquaredL2(scale=1.0 / np.prod(dims)), grad)


def total_variation(dims, spacing=1.0, dtype=np.float64, smoothing: float = 0.0) -> Composite:
    r"""Anisotropic total variation :math:`\sum_d \mathrm{mean}(|D_d f|)`.

    Parameters
    ----------
    dims : tuple of 4 int
        ``(n_fields, nx, ny, nz)``.
    spacing : float or tuple of 3 float
        Grid spacing in m.
    dtype : numpy dtype, optional
        Operator dtype.
    smoothing : float, optional
        Huber smoothing :math:`\varepsilon` of each :math:`|D_d f|` (:class:`L1`), in the units
        of :math:`D_d f` (units of f per m); 0 (default) is exact TV.
    """
    grad = Gradient(dims, spacing, dtype)
    return Composite(L1(scale=1.0 / np.prod(dims), smoothing=smoothing), grad)
