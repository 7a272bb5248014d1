r"""The objective's curvature per group of parameters, for the preconditioners of
``preconditioned-lbfgs``.

A voxel grid groups its parameters by field, a network by weight tensor; for each group
:math:`g` the mean Gauss–Newton curvature per parameter,

.. math:: c_g = \frac{\mathrm{tr}(J_g^\mathsf{T} J_g) + a\,\mathrm{tr}(R_g^\mathsf{T} R_g)}{N_g},

with :math:`J_g` the Jacobian of the (whitened) forward map restricted to the group, :math:`R_g`
that of the regularizer's inner operator and :math:`a` the weight of its quadratic model
(:func:`quadratic_weight`), is estimated by Hutchinson's estimator: for a Rademacher vector
:math:`v` on the group, :math:`E\|Jv\|^2 = \mathrm{tr}(J_g^\mathsf{T} J_g)`.
"""

from __future__ import annotations

import numpy as np

import operators as op


def quadratic_weight(regularizer, lam: float, x0) -> float:
    r"""The weight :math:`a` of :math:`a\|R\theta\|^2`, the quadratic model of
    :math:`\lambda\,g(R\theta)` at ``x0``, for a regularizer with an outer ``functional``
    :math:`g` and an inner ``op`` :math:`R` (an :class:`operators.Composite` or a
    :class:`solvers.Regularizer`, whose ``op`` may be nonlinear).

    :math:`a = \lambda s` for the squared L2 norm :math:`s\|\cdot\|^2`; for the L1 norm
    :math:`s\sum|\cdot|`, :math:`a = \lambda s / (2\tau)` with :math:`\tau` the median of the
    nonzero :math:`|R x_0|` (at least the norm's smoothing; 1 if all are zero): the curvature of
    the quadratic that touches :math:`|t|` at :math:`|t| = \tau`.
    """
    functional = regularizer.functional
    weight = lam * functional.scale
    if isinstance(functional, op.L1):
        differences = np.abs(np.asarray(regularizer.op(np.asarray(x0)), np.float64)).ravel()
        moving = differences[differences > 0]
        weight /= 2.0 * max(float(np.median(moving)) if moving.size else 1.0,
                            functional.smoothing)
    return weight


def by_field(dims) -> np.ndarray:
    """Groups of a voxel grid's parameters ``(n_fields, nx, ny, nz)``: the field of each."""
    return np.broadcast_to(np.arange(dims[0]).reshape(-1, *[1] * (len(dims) - 1)), tuple(dims))


def group_curvature(forward: op.Operator, x, groups, probes: int = 2, seed: int = 0,
                    regularizer: op.Operator | None = None, weight: float = 0.0) -> np.ndarray:
    """The mean curvature :math:`c_g` of the misfit (and of a weighted regularizer) per
    parameter of each group, by Hutchinson's estimator (the module docstring).

    Parameters
    ----------
    forward : operators.Operator
        From parameters to data (whitened: then per unit of the parameters squared).
    x : ndarray
        The point, ``forward.dims``.
    groups : ndarray of int
        The group of each parameter, ``0 .. G-1``, shape ``forward.dims``; every group must
        hold a parameter.
    probes : int, optional
        Jacobian-vector products per group (default 2).
    seed : int, optional
        Of the probes.
    regularizer : operators.Operator, optional
        The regularizer's inner operator :math:`R`, added with ``weight`` :math:`a`.
    weight : float, optional
        :math:`a` (default 0).

    Returns
    -------
    ndarray, shape (G,)
        Positive; a group nothing sees (curvature 0) gets the smallest curvature of the groups
        seen (1 if none is).
    """
    groups = np.asarray(groups)
    dims = tuple(forward.dims)
    if groups.shape != dims:
        raise ValueError(f"groups must have the parameters' shape {dims}; got {groups.shape}")
    sizes = np.bincount(groups.ravel())
    if np.any(sizes == 0):
        raise ValueError(f"groups {np.flatnonzero(sizes == 0).tolist()} hold no parameter")
    rng = np.random.default_rng(seed)
    curvature = np.zeros(len(sizes))
    for group, size in enumerate(sizes):
        for _ in range(probes):
            v = np.zeros(dims, forward.dtype)
            v[groups == group] = rng.choice(np.array([-1.0, 1.0], forward.dtype), size)
            total = _squared_norm(forward.jvp(x, v))
            if regularizer is not None and weight:
                total += weight * _squared_norm(regularizer.jvp(x, v))
            curvature[group] += total / (probes * size)
    seen = curvature > 0
    return np.where(seen, curvature, curvature[seen].min() if seen.any() else 1.0)


def _squared_norm(values) -> float:
    flat = np.asarray(values, np.float64).ravel()
    return float(flat @ flat)
