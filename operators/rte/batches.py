r"""Rays of the emission kernel sorted by length and cut into batches of one memory budget.

Rays are sorted by their number of segments (entries up to the last of non-zero length) and
processed in batches of ``batch_rays``, each batch sweeping only as many segments as its
longest ray, so padding costs little. Within a batch the rays are the last axis, so that one
segment of a batch is a contiguous slice. :func:`batch_rays_for` sizes the batches from a
memory budget.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from operators.rte.tables import RTETables

DEFAULT_MEMORY_BUDGET = {"cpu": 8 * 2**20, "gpu": 2**30}
"""Default working memory of one ray batch in bytes, per JAX backend: on a CPU a batch's
spectra should stay in the caches (8 MiB: about 40 rays of 1876 wavenumbers in float32), on
a GPU a batch should fill the device (1 GiB); other backends use the GPU figure."""


def batch_rays_for(tables: RTETables, n_rays: int, memory_budget: int | None = None) -> int:
    """Rays per batch so that one batch's working arrays fit in ``memory_budget`` bytes.

    A batch holds about ``16 + n_coef`` spectra per ray in the reverse sweep (radiance,
    cotangent, partial sums, transmittance, the segment's optical depth, Planck radiance,
    gathered coefficients and their products).

    Parameters
    ----------
    tables : RTETables
        Kernel tables (give ``n_points``, ``n_coef`` and the dtype).
    n_rays : int
        Number of rays (the batch never exceeds it).
    memory_budget : int, optional
        Bytes (default :data:`DEFAULT_MEMORY_BUDGET` for the default JAX backend).
    """
    if memory_budget is None:
        memory_budget = DEFAULT_MEMORY_BUDGET.get(jax.default_backend(),
                                                  DEFAULT_MEMORY_BUDGET["gpu"])
    budget = int(memory_budget)
    per_ray = tables.n_points * tables.dtype.itemsize * (16 + tables.coef.shape[1])
    return int(max(1, min(n_rays, budget // per_ray)))


def ray_order(lengths, batch_rays):
    """Permutation sorting rays by segment count, and each batch's largest count.

    Parameters
    ----------
    lengths : jax.Array, shape (n_rays, n_seg)
        Segment lengths in m; zero on padding.
    batch_rays : int
        Rays per batch.

    Returns
    -------
    order : jax.Array of int, shape (n_rays,)
        Ray indices by increasing segment count (stable).
    n_segments : jax.Array of int, shape (n_batches,)
        Segments to sweep in each batch of the sorted rays.
    """
    n_rays = lengths.shape[0]
    count = segment_counts(lengths)
    order = jnp.argsort(count, stable=True)
    n_batches = -(-n_rays // batch_rays)
    padded = jnp.zeros(n_batches * batch_rays, count.dtype).at[:n_rays].set(count[order])
    return order, padded.reshape(n_batches, batch_rays).max(axis=1)


def segment_counts(lengths):
    """Segments of each ray up to its last of non-zero length, shape ``(n_rays,)``."""
    return jnp.max(jnp.where(lengths != 0, jnp.arange(1, lengths.shape[1] + 1), 0), axis=1)


def segment_batches(x, order, batch_rays, fill):
    """Per-segment array ``(*lead, n_rays, n_seg)`` -> ``(n_batches, *lead, n_seg, batch)``.

    Rays are permuted by ``order``, padded with ``fill`` to whole batches and moved last, so
    that one segment of a batch is a contiguous slice.
    """
    axis = x.ndim - 2
    x = jnp.take(x, order, axis=axis)
    pad = [(0, 0)] * x.ndim
    pad[axis] = (0, _n_batches(order, batch_rays) * batch_rays - order.shape[0])
    x = jnp.pad(x, pad, constant_values=fill)
    x = x.reshape(x.shape[:axis] + (-1, batch_rays) + x.shape[axis + 1:])
    return jnp.moveaxis(jnp.moveaxis(x, axis + 1, -1), axis, 0)


def spectra_batches(x, order, batch_rays):
    """Spectra ``(n_rays, n_eta)`` -> ``(n_batches, batch_rays, n_eta)``, rays permuted."""
    pad = _n_batches(order, batch_rays) * batch_rays - order.shape[0]
    x = jnp.pad(x[order], ((0, pad), (0, 0)))
    return x.reshape(-1, batch_rays, x.shape[-1])


def from_batches(x, order):
    """Inverse of :func:`spectra_batches`."""
    x = x.reshape(-1, x.shape[-1])[: order.shape[0]]
    return jnp.zeros_like(x).at[order].set(x)


def _n_batches(order, batch_rays):
    return -(-order.shape[0] // batch_rays)


def batched_inputs(tables: RTETables, fields, lengths, order, batch_rays):
    """Temperature (K), the absorbing species' mole fractions and lengths (m) in batches.

    ``fields`` ``(1 + n_species, n_rays, n_seg)`` and ``lengths`` ``(n_rays, n_seg)`` become
    :func:`segment_batches` of each; padding rays get T = 1 K (any positive value) and zero
    mole fractions and lengths, so they emit nothing.
    """
    fractions = fields[1 + np.asarray(tables.species, dtype=int)]
    return (segment_batches(fields[0], order, batch_rays, 1.0),
            segment_batches(fractions, order, batch_rays, 0.0),
            segment_batches(lengths, order, batch_rays, 0.0))
