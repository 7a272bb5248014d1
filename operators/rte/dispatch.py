"""Which sweeps compute the emission kernel, and the kernel differentiable in either mode.

The sweeps (forward, forward-mode and reverse) have two implementations: JAX's
(:mod:`operators.rte.sweeps_xla`), lowered by XLA for any backend, and Numba's for CPUs
(:mod:`operators.rte.sweeps_numba`). :func:`choose_sweeps` picks one; :func:`radiance` is the
kernel on the tables' spectral points, reverse-mode differentiable through a custom VJP that
runs the chosen reverse sweep, and :func:`radiance_forward_mode` the same radiance,
differentiable in forward mode.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp

from operators.rte.sweeps_numba import (
    cotangents_numba,
    radiance_numba,
    radiance_numba_forward_mode,
)
from operators.rte.sweeps_xla import cotangents_xla, radiance_xla
from operators.rte.tables import RTETables

#: The implementations of the sweeps (forward, forward-mode and reverse): JAX's, lowered by
#: XLA for any backend, and the Numba ones for CPUs (:mod:`operators.rte.numba_targets`, which
#: need the Planck spline; with the exact Planck law the XLA ones run).
SWEEPS = ("xla", "numba")


def choose_sweeps(name: str | None = None) -> str:
    """The sweeps to use: ``name`` checked, or by default ``"numba"`` where JAX runs on one
    CPU device (at the paper's size its JVP took 0.24–0.26, its VJP 0.19–0.21 and its forward
    0.64–0.68 of the time of XLA's in two runs of ``benchmarks/bench_rte.py``,
    ``docs/performance.md``)
    and ``"xla"`` elsewhere: on other backends, and on several CPU devices in one process,
    whose devices would call the Numba sweeps at once, each call spreading over all the cores
    itself (``numba.prange``), and where Numba's threading layer of last resort (workqueue,
    where neither OpenMP nor TBB is installed) aborts on concurrent calls.

    Raises
    ------
    ValueError
        For a name not in :data:`SWEEPS`.
    """
    if name is None:
        one_cpu = jax.default_backend() == "cpu" and jax.local_device_count() == 1
        return "numba" if one_cpu else "xla"
    if name not in SWEEPS:
        raise ValueError(f"unknown sweeps {name!r}; choose one of {SWEEPS}")
    return name


def _numba(sweeps: str, tables: RTETables) -> bool:
    """Whether the Numba sweeps run: chosen, and the Planck spline (they have no exact law)."""
    return sweeps == "numba" and tables.planck == "table"


def _forward(batch_rays, sweeps, tables, fields, lengths, background=None):
    """The radiance by the chosen sweeps (:func:`choose_sweeps`), not differentiable."""
    if _numba(sweeps, tables):
        return radiance_numba(tables, fields, lengths, background)
    return radiance_xla(batch_rays, tables, fields, lengths, background)


@partial(jax.custom_vjp, nondiff_argnums=(0, 1))
def radiance(batch_rays, sweeps, tables, fields, lengths, background=None):
    """The radiance (n_rays, n_points) in W/(m²·sr·cm⁻¹) on the tables' spectral points by
    the ``sweeps`` (``batch_rays`` rays per batch of the XLA ones), reverse-mode
    differentiable: its custom VJP runs the reverse sweep (the tables get zero cotangents)."""
    return _forward(batch_rays, sweeps, tables, fields, lengths, background)


def _radiance_fwd(batch_rays, sweeps, tables, fields, lengths, background=None):
    value = _forward(batch_rays, sweeps, tables, fields, lengths, background)
    return value, (tables, fields, lengths, value, background)


def _radiance_bwd(batch_rays, sweeps, residuals, cotangent):
    tables, fields, lengths, value, background = residuals
    cotangents = (cotangents_numba if _numba(sweeps, tables)
                  else partial(cotangents_xla, batch_rays))
    return (jax.tree_util.tree_map(jnp.zeros_like, tables),
            *cotangents(tables, fields, lengths, value, cotangent, background is not None))


radiance.defvjp(_radiance_fwd, _radiance_bwd)


def radiance_forward_mode(batch_rays, sweeps, tables, fields, lengths, background=None):
    """:func:`radiance`, differentiable in forward mode: JAX's JVP through the XLA sweep, or
    the Numba forward-mode sweep as custom JVP
    (:func:`operators.rte.sweeps_numba.radiance_numba_forward_mode`)."""
    if _numba(sweeps, tables):
        return radiance_numba_forward_mode(tables, fields, lengths, background)
    return radiance_xla(batch_rays, tables, fields, lengths, background)
