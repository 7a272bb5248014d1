"""The blocks of the emission kernel's tables: composition intervals and spectral points.

:class:`~operators.rte.tables.RTETables` holds one block of rows per temperature interval and
combination of the species' mole-fraction intervals, and may hold several spectral points per
bin (module notes of :mod:`operators.rte.tables`). Here: the checks of the nodes and of the
points' bins, the gas slots of each block, and where a segment's fractions fall (the same code
for NumPy and JAX).
"""

from __future__ import annotations

import itertools

import numpy as np


def check_fraction_nodes(fraction_nodes, n_columns: int) -> tuple[tuple[float, ...], ...]:
    """Mole-fraction nodes per field, checked against the columns of the coefficients."""
    if fraction_nodes is None:
        return tuple((0.0,) for _ in range(n_columns))
    nodes = tuple(tuple(float(x) for x in np.atleast_1d(f)) for f in fraction_nodes)
    for f, field in enumerate(nodes):
        steps = np.diff(field)
        if not field or min(field) < 0 or max(field) > 1 or np.any(steps <= 0):
            raise ValueError(f"fraction_nodes of field {f} must be increasing mole fractions in "
                             f"[0, 1], got {field}")
    if sum(map(len, nodes)) != n_columns:
        raise ValueError(f"coef has {n_columns} columns but fraction_nodes name "
                         f"{sum(map(len, nodes))} (one column per field and node)")
    return nodes


def check_point_bin(point_bin, n_points: int) -> np.ndarray:
    """The bin of every point, checked (default: a bin per point)."""
    if point_bin is None:
        return np.arange(n_points)
    point_bin = np.asarray(point_bin)
    steps = np.diff(point_bin)
    if point_bin.shape != (n_points,) or not np.issubdtype(point_bin.dtype, np.integer) \
            or point_bin[0] != 0 or np.any((steps != 0) & (steps != 1)):
        raise ValueError(f"point_bin must give each of the {n_points} points its bin: integers "
                         "from 0, non-decreasing by steps of 0 or 1")
    return point_bin


def block_slots(columns):
    """The gas slots of every composition block: per block, the coefficient columns of each
    slot, species by species (one slot for a species of one node, two, the nodes below and
    above, for the others); blocks enumerate the species' node intervals, the last species
    fastest, as :func:`composition_block` numbers them."""
    choices = [[c] if c.size == 1 else [c[i:i + 2] for i in range(c.size - 1)] for c in columns]
    return list(itertools.product(*choices))


def fraction_weights(nodes, fraction, xp=np):
    """The node interval of each mole fraction and its weight on the interval's upper node.

    Linear interpolation between the nodes, the end value beyond them.

    Parameters
    ----------
    nodes : sequence of float, length >= 2
        Increasing mole fractions.
    fraction : array
        Mole fractions (dimensionless).
    xp : module
        ``numpy`` or ``jax.numpy``.

    Returns
    -------
    lower : integer array, the index of the interval's lower node (0 … len(nodes) - 2).
    weight : array in [0, 1], shaped as ``fraction``.
    """
    at = xp.asarray(nodes, dtype=fraction.dtype)
    lower = xp.clip(xp.searchsorted(at, fraction, side="right") - 1, 0, len(nodes) - 2)
    weight = xp.clip((fraction - at[lower]) / (at[lower + 1] - at[lower]), 0.0, 1.0)
    return lower, weight


def interpolate_fraction(values, nodes, fraction) -> np.ndarray:
    """Values given at a species' fraction nodes, interpolated linearly at its mole fractions
    (NumPy; the kernel does the same through its gas slots).

    Parameters
    ----------
    values : ndarray, shape (..., len(nodes), n)
        One row per node.
    nodes : sequence of float
        Increasing mole fractions; with one node, its row whatever the fraction.
    fraction : array_like, shape (...)
        Mole fractions (dimensionless), broadcast against the leading axes of ``values``.

    Returns
    -------
    ndarray, shape (..., n)
    """
    if len(nodes) == 1:
        return values[..., 0, :]
    lower, weight = fraction_weights(nodes, np.asarray(fraction, dtype=np.float64))
    pick = np.take_along_axis(values, np.stack([lower, lower + 1], -1)[..., None], -2)
    return pick[..., 0, :] + weight[..., None] * (pick[..., 1, :] - pick[..., 0, :])


def composition_block(fraction_nodes, lowers, xp=np):
    """The composition block of segments: the species' node intervals numbered together.

    Parameters
    ----------
    fraction_nodes : tuple of tuple of float
        :attr:`RTETables.fraction_nodes`.
    lowers : sequence of integer arrays
        Per species with two or more nodes, in order, the interval of :func:`fraction_weights`.
    xp : module
        ``numpy`` or ``jax.numpy``.

    Returns
    -------
    block : integer array (0 for tables without composition dependence).
    """
    block, intervals = 0, [len(f) - 1 for f in fraction_nodes if len(f) > 1]
    for lower, n in zip(lowers, intervals, strict=True):
        block = block * n + lower
    return xp.asarray(block)


def n_composition_blocks(fraction_nodes) -> int:
    """Number of composition blocks per temperature interval."""
    return int(np.prod([len(f) - 1 for f in fraction_nodes if len(f) > 1], dtype=int))
