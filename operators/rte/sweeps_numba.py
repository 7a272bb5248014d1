"""The emission kernel's Numba sweeps for CPUs, called from JAX.

Each sweep of :mod:`operators.rte.numba_targets` (forward, forward-mode, reverse) runs as an
XLA FFI call on XLA's own buffers (:mod:`operators.rte.xla_ffi`), its operands made by JAX from
the fields and lengths (:mod:`operators.rte.weights`); JAX carries the derivatives of the
weights to the fields and lengths. The sweeps need the Planck spline (``planck="table"``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from operators.rte.batches import segment_counts
from operators.rte.numba_targets import target
from operators.rte.tables import RTETables
from operators.rte.weights import locate, segment_weights


def _numba_weights(tables: RTETables, fields):
    """Each segment's block of table rows, and the map ``(fields, lengths) -> (amount,
    offset)`` to the weights the Numba sweeps take (differentiable by JAX)."""
    species = 1 + np.asarray(tables.species, dtype=int)
    block, interval = locate(tables, fields[0], fields[species])
    return block, lambda f, s: segment_weights(tables, interval, f[0], f[species], s)[:2]


def _n_gas(tables: RTETables, amount) -> int:
    return amount.shape[-1] - int(tables.soot)


def _spectra_shape(tables: RTETables, lengths):
    return jax.ShapeDtypeStruct((lengths.shape[0], tables.n_points), tables.dtype)


def _background(tables: RTETables, background):
    """The background as the sweeps take it: one zero row for none."""
    return jnp.zeros((1, tables.n_points), tables.dtype) if background is None else background


def _numba_sweep(kind, results, tables: RTETables, index, amount, offset, lengths, *operands):
    """Sweep ``kind`` of :mod:`operators.rte.numba_targets` run by XLA on its buffers (an FFI
    call, :func:`operators.rte.numba_targets.target`), with the operands every sweep takes made
    from ``index``, ``amount``, ``offset`` and ``lengths``, then ``operands``; returns the
    arrays shaped as ``results``."""
    counts = segment_counts(lengths)
    order = jnp.argsort(-counts, stable=True)
    name = target(kind, _n_gas(tables, amount), amount.shape[-1], tables.dtype)
    call = jax.ffi.ffi_call(name, results, vmap_method="sequential")
    return call(tables.coef, index.astype(jnp.int32), amount, offset,
                counts.astype(jnp.int32), order.astype(jnp.int32), *operands)


def radiance_numba(tables: RTETables, fields, lengths, background):
    """The radiance by the forward sweep of :mod:`operators.rte.numba_targets`."""
    index, weights = _numba_weights(tables, fields)
    amount, offset = weights(fields, lengths)
    return _numba_sweep("forward", _spectra_shape(tables, lengths), tables, index, amount,
                        offset, lengths, _background(tables, background))


def cotangents_numba(tables: RTETables, fields, lengths, radiance, cotangent, has_background):
    """Cotangents of the fields, lengths and background (None without one) by the reverse
    sweep of :mod:`operators.rte.numba_targets`, the weights' cotangents carried to the fields
    and lengths by JAX."""
    index, weights = _numba_weights(tables, fields)
    (amount, offset), to_inputs = jax.vjp(weights, fields, lengths)
    n_tau = amount.shape[-1]
    n_rays = lengths.shape[0] if has_background else 0
    shapes = (jax.ShapeDtypeStruct(amount.shape[:-1] + (n_tau + 1,), tables.dtype),
              jax.ShapeDtypeStruct((n_rays, tables.n_points), tables.dtype))
    d_weights, transmittance = _numba_sweep("reverse", shapes, tables, index, amount, offset,
                                            lengths, radiance, cotangent)
    d_fields, d_lengths = to_inputs((d_weights[..., :n_tau], d_weights[..., n_tau]))
    return d_fields, d_lengths, cotangent * transmittance if has_background else None



@jax.custom_jvp
def radiance_numba_forward_mode(tables, fields, lengths, background=None):
    """The radiance by the forward sweep, differentiable in forward mode: its custom JVP is
    the forward-mode sweep."""
    return radiance_numba(tables, fields, lengths, background)


@radiance_numba_forward_mode.defjvp
def _radiance_numba_jvp(primals, tangents):
    """Radiance and tangent in one Numba sweep; the tables are held fixed (their tangents,
    zero wherever the kernel is used, are not read)."""
    tables, fields, lengths, background = primals
    _, d_fields, d_lengths, d_background = tangents
    index, weights = _numba_weights(tables, fields)
    (amount, offset), (d_amount, d_offset) = jax.jvp(weights, (fields, lengths),
                                                     (d_fields, d_lengths))
    shape = _spectra_shape(tables, lengths)
    return _numba_sweep("forward_mode", (shape, shape), tables, index, amount, offset, lengths,
                        _background(tables, background), d_amount, d_offset,
                        _background(tables, d_background))

