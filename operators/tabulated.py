"""Smooth interpolation of tabulated functions of one variable.

Physics kernels need tabulated quantities (e.g. absorption cross-sections on temperature
nodes) evaluated at arbitrary arguments with continuous first and second derivatives, so that
Jacobians and Taylor tests see no kinks. :class:`PiecewiseCubic` holds the per-interval
polynomial coefficients of a cubic spline through the nodes and evaluates them with NumPy or
JAX, whichever the argument is.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from scipy.interpolate import CubicSpline


class PiecewiseCubic:
    r"""Cubic spline :math:`f(x)` through tabulated values, C² in :math:`x`.

    On interval :math:`[x_i, x_{i+1}]`,
    :math:`f(x) = c_0 (x - x_i)^3 + c_1 (x - x_i)^2 + c_2 (x - x_i) + c_3`.
    Outside the nodes the end polynomials continue (smooth extrapolation); keep
    arguments inside ``[nodes[0], nodes[-1]]`` where accuracy matters.

    Parameters
    ----------
    nodes : array_like, shape (n,)
        Strictly increasing abscissae, n ≥ 2 (any unit; the argument uses the same).
    values : array_like, shape (n, ...)
        Tabulated values; trailing axes are interpolated independently.
    bc_type : str, optional
        End condition passed to :class:`scipy.interpolate.CubicSpline`
        (default ``"not-a-knot"``).

    Attributes
    ----------
    nodes : ndarray, shape (n,)
    coef : ndarray, shape (4, n - 1, ...)
        Polynomial coefficients per interval, highest power first.
    """

    def __init__(self, nodes, values, bc_type: str = "not-a-knot"):
        nodes = np.asarray(nodes, dtype=np.float64)
        values = np.asarray(values)
        if nodes.ndim != 1 or nodes.size < 2:
            raise ValueError(f"nodes must be 1-D with at least 2 entries, got shape {nodes.shape}")
        if not np.all(np.diff(nodes) > 0):
            raise ValueError("nodes must be strictly increasing")
        if values.shape[:1] != nodes.shape:
            raise ValueError(
                f"values must have the node axis first: got values {values.shape} "
                f"for {nodes.size} nodes"
            )
        self.nodes = nodes
        self.coef = CubicSpline(nodes, values, axis=0, bc_type=bc_type).c

    @property
    def value_shape(self) -> tuple[int, ...]:
        """Shape of one tabulated value (the trailing axes of ``values``)."""
        return self.coef.shape[2:]

    def interval(self, x):
        """Interval index and offset ``x - nodes[index]`` for each argument.

        Parameters
        ----------
        x : array_like
            Arguments (NumPy or JAX array, any shape).

        Returns
        -------
        index : int array, same shape as ``x``
        offset : array, same shape as ``x``
        """
        xp = jnp if isinstance(x, jax.Array) else np
        nodes = xp.asarray(self.nodes, dtype=x.dtype) if xp is jnp else self.nodes
        index = xp.clip(xp.searchsorted(nodes, x, side="right") - 1, 0, self.nodes.size - 2)
        return index, x - nodes[index]

    def __call__(self, x, derivative: int = 0):
        """Evaluate the spline or one of its first two derivatives.

        Parameters
        ----------
        x : array_like
            Arguments, NumPy or JAX array of any shape ``s``.
        derivative : {0, 1, 2}
            Order of the derivative with respect to ``x``.

        Returns
        -------
        array, shape ``s + value_shape``
            NumPy in, NumPy out; JAX in, JAX out (jit-compatible).
        """
        is_jax = isinstance(x, jax.Array)
        xp = jnp if is_jax else np
        x = xp.asarray(x)
        index, dx = self.interval(x)
        coef = xp.asarray(self.coef, dtype=x.dtype) if is_jax else self.coef
        c = coef[:, index]
        dx = dx.reshape(dx.shape + (1,) * len(self.value_shape))
        if derivative == 0:
            return ((c[0] * dx + c[1]) * dx + c[2]) * dx + c[3]
        if derivative == 1:
            return (3 * c[0] * dx + 2 * c[1]) * dx + c[2]
        if derivative == 2:
            return 6 * c[0] * dx + 2 * c[1]
        raise ValueError(f"derivative must be 0, 1 or 2, got {derivative}")
