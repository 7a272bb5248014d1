"""EmissionRTE derivatives: dot and Taylor tests, linearize, float32 against float64, memory
(every backend's derivatives against the reference: ``test_rte_backends.py``)."""

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from rte_reference import check_derivatives, random_rays, synthetic_sigma

from operators.rte import EmissionRTE, RTETables, emission_radiance
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)
SPLINE = PiecewiseCubic(NODES, SIGMA)
P = 101325.0
# directions scaled like the fields: kelvins for T, percent-level for mole fractions


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
