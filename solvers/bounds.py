r"""Box bounds :math:`l \le \theta \le u`: the projection onto them and the projected gradient,
for NumPy and JAX arrays alike (inside a compiled program too), so that a step computed on
JAX's device (:mod:`solvers.compiled_objective`) is bounded by the same code as on the host.
"""

from __future__ import annotations

import numpy as np

from operators.functionals import namespace


def compact(array) -> np.ndarray:
    """The smallest array that broadcasts to ``array``: its axes of stride 0 (those of a
    :func:`numpy.broadcast_to` view, e.g. one bound per field of a grid) kept at length 1.

    Parameters
    ----------
    array : array_like
        E.g. a bound as :class:`solvers.Problem` holds it.

    Returns
    -------
    ndarray
        A view of ``array`` with as many axes.
    """
    array = np.asarray(array)
    return array[tuple(slice(0, 1) if stride == 0 else slice(None)
                       for stride in array.strides)]


def project(x, lower, upper):
    """``x`` clipped to ``[lower, upper]``.

    Parameters
    ----------
    x : ndarray or jax.Array
        Parameters, in their units.
    lower, upper : array or None
        Bounds broadcastable to ``x``, same units; None for no bound on that side.

    Returns
    -------
    ndarray or jax.Array
        ``x`` itself when both bounds are None, else a new array of ``x``'s kind.
    """
    if lower is None and upper is None:
        return x
    return namespace(x).clip(x, lower, upper)


def projected_gradient(x, grad, lower, upper):
    """The gradient with its components that push out of an active bound set to zero.

    A component is zeroed where ``x`` is at (or beyond) its lower bound and the gradient is
    positive (a descent step would lower it further), or at its upper bound and the gradient
    is negative. Its norm vanishes at a minimizer over the box.

    Parameters
    ----------
    x : ndarray or jax.Array
        Parameters.
    grad : ndarray or jax.Array
        Gradient of the objective at ``x``, same shape.
    lower, upper : array or None
        Bounds as in :func:`project`.

    Returns
    -------
    ndarray or jax.Array
        A new array of ``grad``'s kind and dtype.
    """
    xp = namespace(grad)
    outward = False
    if lower is not None:
        outward = outward | ((x <= lower) & (grad > 0))
    if upper is not None:
        outward = outward | ((x >= upper) & (grad < 0))
    return xp.where(outward, xp.zeros((), grad.dtype), grad)
