"""EmissionRTE derivatives: dot and Taylor tests, the custom VJP against plain autodiff, memory."""

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from rte_reference import check_derivatives, random_rays, synthetic_sigma

from operators.emission_rte import (
    EmissionRTE,
    RTETables,
    emission_radiance,
    emission_radiance_jvp,
)
from operators.planck import BOLTZMANN, planck
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)
SPLINE = PiecewiseCubic(NODES, SIGMA)
P = 101325.0
# directions scaled like the fields: kelvins for T, percent-level for mole fractions


def plain_radiance(fields, lengths):
    """Formal solution with whole (ray, segment, wavenumber) arrays, for JAX autodiff."""
    temperature = fields[0]
    sigma = SPLINE(temperature)  # (r, k, species, eta)
    density = P / (BOLTZMANN * temperature)
    kappa = jnp.einsum("srk,rkse->rke", fields[1:], sigma) * (density * 1e-4)[..., None]
    tau = kappa * lengths[..., None]
    before = jnp.cumsum(tau, axis=1) - tau
    emission = planck(jnp.asarray(ETA), temperature[..., None])
    return jnp.sum(emission * -jnp.expm1(-tau) * jnp.exp(-before), axis=1)


@pytest.mark.parametrize("planck_mode", ["exact", "table"])
def test_jacobian_dot_and_taylor_tests(planck_mode):
    fields, lengths = random_rays(n_rays=5, n_seg=7)
    rte = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float64, planck_mode,
                      batch_rays=2)
    check_derivatives(rte, fields, rtol=1e-12)


def test_linearize_keeps_value_and_matches_jvp_vjp():
    fields, lengths = random_rays(n_rays=4, n_seg=5)
    rte = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float64, "exact")
    jac = rte.linearize(fields)
    np.testing.assert_allclose(jac.value, rte(fields), rtol=1e-14)
    rng = np.random.default_rng(0)
    v, w = rng.standard_normal(rte.dims), rng.standard_normal(rte.dimsd)
    np.testing.assert_allclose(jac.matvec(v.ravel()), rte.jvp(fields, v).ravel(), rtol=1e-13)
    np.testing.assert_allclose(jac.rmatvec(w.ravel()), rte.vjp(fields, w).ravel(), rtol=1e-13)


@pytest.mark.usefixtures("x64")
def test_custom_vjp_equals_autodiff_of_the_plain_formulation():
    fields, lengths = random_rays(n_rays=6, n_seg=8, seed=5)
    lengths = np.where(lengths > 0, lengths, 0.004)  # every segment real: d/dlength defined
    tables = RTETables.from_spline(ETA, NODES, SPLINE.coef, P, np.float64, "exact")
    weights = jnp.asarray(np.random.default_rng(1).standard_normal((6, ETA.size)))

    def loss(radiance_fn, f, s):
        return jnp.sum(weights * radiance_fn(f, s))

    args = (jnp.asarray(fields), jnp.asarray(lengths))
    ours = jax.grad(lambda f, s: loss(lambda a, b: emission_radiance(tables, a, b, 4), f, s),
                    argnums=(0, 1))(*args)
    plain = jax.grad(lambda f, s: loss(plain_radiance, f, s), argnums=(0, 1))(*args)
    np.testing.assert_allclose(ours[0], plain[0], rtol=1e-10, atol=1e-12 * np.abs(plain[0]).max())
    np.testing.assert_allclose(ours[1], plain[1], rtol=1e-10)


@pytest.mark.usefixtures("x64")
def test_jvp_in_lengths_matches_autodiff():
    fields, lengths = random_rays(n_rays=3, n_seg=4, seed=2)
    lengths = lengths + 0.001
    tables = RTETables.from_spline(ETA, NODES, SPLINE.coef, P, np.float64, "exact")
    d_lengths = np.random.default_rng(3).uniform(0, 0.01, lengths.shape)
    zeros = np.zeros_like(fields)
    _, ours = emission_radiance_jvp(tables, fields, lengths, zeros, d_lengths)
    _, plain = jax.jvp(plain_radiance, (jnp.asarray(fields), jnp.asarray(lengths)),
                       (jnp.asarray(zeros), jnp.asarray(d_lengths)))
    np.testing.assert_allclose(ours, plain, rtol=1e-11)


def test_float32_gradient_is_close_to_float64():
    fields, lengths = random_rays(n_rays=4, n_seg=6, seed=7)
    w = np.random.default_rng(2).standard_normal((4, ETA.size))
    grads = []
    for dtype in (np.float32, np.float64):
        rte = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, dtype, "table")
        grads.append(rte.vjp(fields, w))
    assert np.all(grads[0][3] == 0) and np.all(grads[1][3] == 0)  # CH4: no cross-section
    scale = np.abs(grads[1][:3]).max(axis=(1, 2), keepdims=True)
    assert np.max(np.abs(grads[0][:3] - grads[1][:3]) / scale) < 1e-4


def test_xla_reverse_sweep_memory_does_not_grow_with_segments_times_wavenumbers():
    """Working memory of forward+VJP holds spectra per ray, not per segment (XLA's sweeps;
    the Numba ones hold one ray's spectra per core by construction)."""
    eta, nodes, sigma = synthetic_sigma(n_eta=1000)
    tables = RTETables.from_spline(eta, nodes, PiecewiseCubic(nodes, sigma).coef, P,
                                   np.float32, "table")
    n_rays = 32

    def temp_bytes(n_seg):
        def grad(f, s):
            radiance = partial(emission_radiance, tables, lengths=s, batch_rays=n_rays,
                               sweeps="xla")
            return jax.vjp(radiance, f)[1](jnp.ones((n_rays, eta.size), jnp.float32))[0]

        shapes = (jax.ShapeDtypeStruct((4, n_rays, n_seg), jnp.float32),
                  jax.ShapeDtypeStruct((n_rays, n_seg), jnp.float32))
        return jax.jit(grad).lower(*shapes).compile().memory_analysis().temp_size_in_bytes

    growth = temp_bytes(200) - temp_bytes(50)
    per_segment_spectra = n_rays * 150 * eta.size * 4
    assert growth < per_segment_spectra / 8
