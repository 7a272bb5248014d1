r"""A problem's objective and its gradient as compiled JAX programs.

When the forward map :math:`F`, the regularizer's operator :math:`K` and its functional
:math:`g` all have JAX forms (:meth:`operators.Operator.jax_map`; :meth:`operators.Functional.terms`
for a functional that sums terms per element, such as :class:`~operators.SquaredL2` and
:class:`~operators.L1`), the loss of a :class:`~solvers.problem.Problem`

.. math:: L(\theta) = \|F(\theta) - d\|_2^2 + \lambda\, g(K(\theta))

and its gradient :math:`2 J_F^\mathsf{T}(F(\theta) - d) + \lambda J_K^\mathsf{T} \nabla
g(K(\theta))` run as two jitted programs on JAX's device: the host sends :math:`\theta` and
receives the loss, and the gradient when it is asked for. The operators' own methods, which
:meth:`~solvers.problem.Problem.evaluate` uses otherwise, cross between NumPy and JAX at every
operator (on a GPU, a copy to and from the device each time) and compute the regularizer on the
host.

What is the same on both paths:

- **Sums.** Squares and the functional's terms are summed over the last axis on the device, in
  the parameters' dtype, and those sums in float64 on the host: float32 parameters give the
  loss to about 1e-7, relative, as the NumPy path, which sums every element in float64.
- **The functional's gradient** is its own :meth:`~operators.Functional.grad`, not JAX's
  derivative of its terms: exact TV's subgradient of :math:`|t|` is 0 at 0, where JAX's
  derivative of ``abs`` is 1. (XLA flushes subnormal numbers to zero, NumPy keeps them: where
  a difference of float32 fields is subnormal, below 1.2e-38 in magnitude, exact TV's
  subgradient there is 0 on one path and ±1 on the other, both subgradients.)
- **The domain.** Each operator's check (:attr:`operators.JaxMap.check`, e.g. the
  temperatures the absorption tables cover) runs on the host at every point, before the
  program; a point outside raises the operator's own ``ValueError``.

The point and the gradient stay on the device (``Evaluation.point``,
``Evaluation.native_grad``): Adam's step (:mod:`solvers.adam`) and the history's projected
gradient norm (:meth:`CompiledObjective.projected_gradient_norm`) run there too, with the
bounds copied to the device once (:attr:`CompiledObjective.bounds`), and the host receives the
new point, once per iteration, and numbers. ``Evaluation.grad`` copies the gradient to the host
when something asks for it (a checkpoint, a line search's inner product).

The Jacobians themselves (``Evaluation.forward_jacobian``), which Gauss–Newton and PDHG apply
many times per iteration, come from the operators' methods only.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from operators import Composite, Functional, JaxMap, Operator, precision
from operators.interop import to_jax, to_numpy
from solvers.bounds import compact, projected_gradient


def _sums_terms(functional: Functional) -> bool:
    """Whether ``functional`` gives its terms per element (:meth:`Functional.terms`)."""
    return type(functional).terms is not Functional.terms


def _row_total(rows) -> float:
    """The device's sums over the last axis, summed in float64 on the host."""
    return float(np.asarray(to_numpy(rows), dtype=np.float64).sum())


class CompiledObjective:
    r""":math:`\|F(\theta) - d\|_2^2 + \lambda g(K(\theta))` and its gradient as compiled
    JAX programs; build it with :meth:`CompiledObjective.of`.

    Parameters
    ----------
    forward : operators.base.JaxMap
        :math:`F`.
    data : ndarray
        :math:`d`, shape of :math:`F`'s output.
    regularizer : operators.Composite or None
        :math:`g \circ K`; its functional must give :meth:`~operators.Functional.terms`.
    regularizer_map : operators.base.JaxMap or None
        :math:`K` (None without a regularizer).
    dims : tuple of int
        Shape of :math:`\theta`.
    dtype : numpy dtype
        Of :math:`\theta`, the data and the programs.
    bounds : pair of array or None, optional
        The problem's lower and upper bounds on :math:`\theta` (None: unbounded on that side).

    Attributes
    ----------
    bounds : pair of jax.Array or None
        The bounds on JAX's device, for steps computed there (broadcastable to :attr:`dims`:
        a bound per field is copied as one number per field).
    """

    def __init__(self, forward: JaxMap, data, regularizer: Composite | None,
                 regularizer_map: JaxMap | None, dims, dtype, bounds=(None, None)):
        self.dims = tuple(dims)
        self.dtype = np.dtype(dtype)
        self.checks = [m.check for m in (forward, regularizer_map)
                       if m is not None and m.check is not None]
        self.scale = 1.0 if regularizer is None else regularizer.functional.scale
        functional = None if regularizer is None else regularizer.functional
        with precision(self.dtype):
            self.args = (forward.args, to_jax(data, self.dtype),
                         None if regularizer_map is None else regularizer_map.args)
            self.bounds = tuple(None if b is None else to_jax(compact(b), self.dtype)
                                for b in bounds)

        def value_and_pullback(args, x, lam):
            forward_args, d, regularizer_args = args

            def maps(x):
                y = forward.function(forward_args, x)
                k = None if regularizer_map is None else regularizer_map.function(
                    regularizer_args, x)
                return y, k

            (y, k), pullback = jax.vjp(maps, x)
            r = y - d
            misfit_rows = jnp.sum(r * r, axis=-1)
            if k is None:
                return misfit_rows, None, pullback, (2 * r, None)
            return (misfit_rows, jnp.sum(functional.terms(k), axis=-1), pullback,
                    (2 * r, lam * functional.grad(k)))

        self._value_and_pullback = jax.jit(value_and_pullback)
        self._pull = jax.jit(lambda pullback, cotangent: pullback(cotangent)[0])
        self._projected_norm = jax.jit(
            lambda x, g, bounds: jnp.linalg.norm(projected_gradient(x, g, *bounds)))

    @classmethod
    def of(cls, forward: Operator, data, regularizer: Composite | None, bounds=(None, None)
           ) -> CompiledObjective | None:
        """The compiled objective of a forward map, its data and a regularizer (with the
        parameters' bounds), or None when one of them has no JAX form (then the operators' own
        methods serve)."""
        forward_map = forward.jax_map()
        if forward_map is None:
            return None
        regularizer_map = None
        if regularizer is not None:
            if not _sums_terms(regularizer.functional):
                return None
            regularizer_map = regularizer.op.jax_map()
            if regularizer_map is None:
                return None
        return cls(forward_map, data, regularizer, regularizer_map, forward.dims, forward.dtype,
                   bounds)

    def __call__(self, x: np.ndarray, lam: float):
        r"""The loss's parts at ``x`` (shape :attr:`dims`, checked by the operators' domains)
        and the gradient's function.

        Returns
        -------
        misfit : float
            :math:`\|F(x) - d\|_2^2`.
        regularizer : float
            :math:`g(K(x))`, unweighted (0 without a regularizer).
        point : jax.Array
            ``x`` on JAX's device.
        grad : callable
            ``grad()`` is :math:`\nabla L(x)` for weight ``lam``, a JAX array of shape
            :attr:`dims` on JAX's device, from one reverse pass.
        """
        for check in self.checks:
            check(x)
        with precision(self.dtype):
            point = to_jax(x, self.dtype)
            misfit_rows, regularizer_rows, pullback, cotangent = self._value_and_pullback(
                self.args, point, lam)
        regularizer = 0.0 if regularizer_rows is None else (
            self.scale * _row_total(regularizer_rows))

        def grad():
            with precision(self.dtype):
                return self._pull(pullback, cotangent).reshape(self.dims)

        return _row_total(misfit_rows), regularizer, point, grad

    def projected_gradient_norm(self, point, grad) -> float:
        r""":math:`\|\cdot\|_2` of :func:`solvers.bounds.projected_gradient` with
        :attr:`bounds`, computed on JAX's device.

        Parameters
        ----------
        point, grad : jax.Array or ndarray
            A point and the objective's gradient there, shape :attr:`dims`.
        """
        with precision(self.dtype):
            return float(self._projected_norm(point, grad, self.bounds))
