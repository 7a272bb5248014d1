"""The Numba reverse sweep for CPUs against JAX's, and its float32 exponential."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from rte_reference import random_rays, synthetic_sigma

from operators.base import precision
from operators.rte_kernel import REVERSE_SWEEPS, emission_radiance, reverse_sweep
from operators.rte_sweep_cpu import _exp_neg
from operators.rte_tables import RTETables, rayleigh_soot_constant
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)
COEF = PiecewiseCubic(NODES, SIGMA).coef


def gradients(tables, fields, lengths, background, reverse):
    """Gradients of a weighted sum of the radiance w.r.t. fields, lengths and background."""
    weights = np.random.default_rng(1).standard_normal((lengths.shape[0], ETA.size))

    def loss(f, s, b):
        return jnp.sum(weights * emission_radiance(tables, f, s, 3, b, reverse=reverse))

    args = (jnp.asarray(a, tables.dtype) for a in (fields, lengths, background))
    return jax.jit(jax.grad(loss, argnums=(0, 1, 2)))(*args)


def assert_same_gradients(xla, ours, rtol):
    """Each gradient within ``rtol`` of the XLA sweep's largest entry."""
    for a, b in zip(xla, ours, strict=True):
        assert np.max(np.abs(a - b)) <= rtol * np.max(np.abs(a))


@pytest.mark.parametrize("dtype, rtol", [(np.float64, 1e-12), (np.float32, 2e-6)])
@pytest.mark.parametrize("soot", [False, True])
def test_numba_sweep_gives_the_gradients_of_the_xla_sweep(dtype, rtol, soot):
    fields, lengths = random_rays(n_rays=7, n_seg=9, seed=5)
    if soot:
        fraction = np.random.default_rng(6).uniform(0.0, 5e-6, fields.shape[1:])
        fields = np.concatenate([fields, fraction[None]])
    tables = RTETables.from_spline(ETA, NODES, COEF, 101325.0, dtype, "table",
                                   soot=rayleigh_soot_constant() if soot else None)
    background = np.random.default_rng(2).uniform(0.0, 0.5, (7, ETA.size))
    xla = gradients(tables, fields, lengths, background, "xla")
    ours = gradients(tables, fields, lengths, background, "numba")
    assert_same_gradients(xla, ours, rtol)
    padding = np.arange(lengths.shape[1]) >= np.count_nonzero(lengths, axis=1)[:, None]
    assert padding.any() and not np.any(ours[0][:, padding]) and not np.any(ours[1][padding])
    assert not np.any(xla[1][padding])


def test_float64_stays_float64_with_64_bit_mode_in_the_callers_thread_only():
    """`precision(float64)` turns on JAX's 64-bit mode in the calling thread only; JAX runs the
    Numba sweep's host callback on a thread of its own, which must not round to float32."""
    fields, lengths = random_rays(n_rays=7, n_seg=9, seed=5)
    background = np.zeros((7, ETA.size))
    jax.config.update("jax_enable_x64", False)
    try:
        with precision(np.float64):
            tables = RTETables.from_spline(ETA, NODES, COEF, 101325.0, np.float64, "table")
            xla = gradients(tables, fields, lengths, background, "xla")
            ours = gradients(tables, fields, lengths, background, "numba")
    finally:
        jax.config.update("jax_enable_x64", True)
    assert all(a.dtype == b.dtype == np.float64 for a, b in zip(xla, ours, strict=True))
    assert_same_gradients(xla, ours, 1e-12)


def test_float32_exponential_is_within_four_units_in_the_last_place():
    x = np.concatenate([np.linspace(0, 1, 10_001), np.linspace(1, 80, 10_001)]).astype(
        np.float32)
    ours = np.array([_exp_neg(v) for v in x])
    exact = np.exp(-x.astype(np.float64))
    assert np.max(np.abs(ours - exact) / exact) < 4 * 2.0**-23


def test_the_reverse_sweep_defaults_to_numba_on_a_cpu_and_refuses_unknown_names():
    assert REVERSE_SWEEPS == ("xla", "numba")
    assert reverse_sweep() == ("numba" if jax.default_backend() == "cpu" else "xla")
    assert reverse_sweep("xla") == "xla"
    with pytest.raises(ValueError, match=r"unknown reverse sweep 'c'; choose one of"):
        reverse_sweep("c")
