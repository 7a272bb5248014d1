r"""The emission kernel's sweeps in JAX, lowered by XLA for any backend.

The forward sweep, its reverse (the cotangents of the custom VJP) and, through JAX's forward
mode of the forward sweep, the tangents (:mod:`operators.rte.kernel` has the maths). Rays are
sorted by their number of segments and processed in batches (:mod:`operators.rte.batches`),
each batch sweeping only as many segments as its longest ray. Per segment,
:math:`\tilde\sigma_s` and :math:`\tilde B` are Horner sums of gathered rows of the spectral
tables (:mod:`operators.rte.tables`), fused by XLA into the sweep.
``benchmarks/bench_rte.py`` times the kernel and its stages against a bare exponential.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp

from operators.rte.batches import (
    batched_inputs,
    from_batches,
    ray_order,
    segment_counts,
    spectra_batches,
)
from operators.rte.planck import planck
from operators.rte.tables import RTETables
from operators.rte.weights import locate, segment_weights


def _cubic(tables: RTETables, index, offset, row: int):
    """Value and offset derivative (r, n_eta) of the cubic in table rows ``row … row + 3``.

    One gather per row: XLA fuses them into the Horner sums.
    """
    c0, c1, c2, c3 = (tables.coef[index, row + j] for j in range(4))
    u = offset[:, None]
    return ((c0 * u + c1) * u + c2) * u + c3, (3 * c0 * u + 2 * c1) * u + c2


def _spectra(tables: RTETables, index, amount, offset, temperature):
    r"""Spectra (r, n_eta) of one segment of each ray of a batch and their derivatives.

    Returns
    -------
    tau : optical depth (dimensionless).
    rows : the spectra whose products with the amounts sum to ``tau``: per gas its
        cross-section row (K/m), then the soot row (m⁻¹).
    tau_offset : :math:`\partial\tau/\partial u` at fixed amounts.
    emission : Planck radiance :math:`B` in W/(m²·sr·cm⁻¹).
    emission_slope : :math:`\partial B/\partial u` (Planck table) or
        :math:`\partial B/\partial T` (exact law, per K).

    What a caller leaves unused, XLA does not compute.
    """
    n_gas = amount.shape[-1] - int(tables.soot)
    rows, tau, tau_offset = [], 0.0, 0.0
    for s in range(n_gas):
        value, slope = _cubic(tables, index, offset, 4 * s)
        rows.append(value)
        tau = tau + amount[:, s, None] * value
        tau_offset = tau_offset + amount[:, s, None] * slope
    if tables.soot:
        rows.append(tables.coef[index, 4 * n_gas])
        tau = tau + amount[:, n_gas, None] * rows[-1]
    if tables.planck == "table":
        emission, emission_slope = _cubic(tables, index, offset, amount.shape[-1] + 3 * n_gas)
    else:
        emission, emission_slope = jax.jvp(partial(planck, tables.wavenumber),
                                           (temperature[:, None],),
                                           (jnp.ones_like(temperature)[:, None],))
    return tau, rows, tau_offset, emission, emission_slope


@jax.custom_jvp
def _transmission(tau):
    r"""Transmittance :math:`e^{-\tau}` and absorptance :math:`1 - e^{-\tau}`, both accurate.

    float64 uses ``expm1``; float32 a series below :math:`\tau = 0.1` (truncation below
    2e-8) and :math:`1 - e^{-\tau}` above (rounding below 6e-7), cheaper than ``expm1``.
    """
    t = jnp.exp(-tau)
    if tau.dtype == jnp.float64:
        return t, -jnp.expm1(-tau)
    series = 1.0 - tau * (1 / 6)
    for n in (5, 4, 3, 2):  # multiplications by the reciprocals: no division per element
        series = 1.0 - tau * (1 / n) * series
    return t, jnp.where(tau < 0.1, tau * series, 1.0 - t)


@_transmission.defjvp
def _transmission_jvp(primals, tangents):
    (tau,), (dtau,) = primals, tangents
    t, a = _transmission(tau)
    return (t, a), (-t * dtau, t * dtau)


def _sweep(tables: RTETables, index, amount, offset, temperature, n_segments, background):
    """Radiance (r, n_eta) of one ray batch, from the far end of the rays to the camera.

    ``I ← t_k I + B_k (1 - t_k)`` for ``k = n_segments - 1, …, 0``, starting from the
    background (r, n_eta), or from zero when it is None: one array of state, one fused pass
    over the spectra per segment.
    """
    def step(j, radiance):
        k = n_segments - 1 - j
        tau, _, _, emission, _ = _spectra(tables, index[k], amount[k], offset[k],
                                          temperature[k])
        transmittance, absorptance = _transmission(tau)
        return transmittance * radiance + emission * absorptance

    if background is None:
        background = jnp.zeros((index.shape[-1], tables.n_points), tables.dtype)
    return jax.lax.fori_loop(0, n_segments, step, background)


def _sweep_vjp(tables: RTETables, index, amount, offset, temperature, n_segments, radiance,
               cotangent):
    r"""Cotangents of one batch's weights, camera side first, and of its background.

    With :math:`g_\tau = \bar I\,\partial I/\partial\tau_k` and
    :math:`g_B = \bar I\,\partial I/\partial B_k` (:mod:`operators.rte.kernel`), per segment
    the sums over wavenumber of :math:`g_\tau` times each row of ``tau`` give the amounts'
    cotangents, and that of :math:`g_\tau\,\partial\tau/\partial u + g_B\,\partial B/\partial u`
    the offset's (with the exact Planck law, :math:`g_B\,\partial B/\partial T` the
    temperature's): ``n_gas + 1`` reductions of fused products (one more for soot, one more
    with the exact Planck law), whatever the spline order.
    The background's cotangent is ``cotangent · τ_ray`` (``radiance`` includes the
    background).
    """
    n_tau = amount.shape[-1]
    table = tables.planck == "table"

    def step(k, carry):
        partial_sum, transmittance, d_weights = carry
        tau, rows, tau_offset, emission, emission_slope = _spectra(
            tables, index[k], amount[k], offset[k], temperature[k])
        t, a = _transmission(tau)
        absorbed = transmittance * a
        partial_sum = partial_sum + emission * absorbed
        transmittance = transmittance * t
        g_tau = cotangent * (transmittance * emission - (radiance - partial_sum))
        g_emit = cotangent * absorbed * emission_slope
        sums = [g_tau * row for row in rows]
        sums += [g_tau * tau_offset + g_emit] if table else [g_tau * tau_offset, g_emit]
        d_segment = jnp.stack([jnp.sum(x, axis=-1) for x in sums], axis=-1)
        d_weights = jax.lax.dynamic_update_index_in_dim(d_weights, d_segment, k, 0)
        return partial_sum, transmittance, d_weights

    zeros = jnp.zeros_like(radiance)
    n_sums = n_tau + (1 if table else 2)
    init = (zeros, zeros + 1, jnp.zeros(amount.shape[:-1] + (n_sums,), amount.dtype))
    _, transmittance, d_weights = jax.lax.fori_loop(0, n_segments, step, init)
    d_temperature = jnp.zeros_like(temperature) if table else d_weights[..., n_tau + 1]
    return ((d_weights[..., :n_tau], d_weights[..., n_tau], d_temperature),
            cotangent * transmittance)


def _batch_radiance(tables: RTETables, temperature, fractions, length, n_segments,
                    background=None):
    block, interval = locate(tables, temperature, fractions)
    return _sweep(tables, block,
                  *segment_weights(tables, interval, temperature, fractions, length),
                  n_segments, background)


def _batch_cotangent(tables: RTETables, with_background: bool, temperature, fractions, length,
                     n_segments, radiance, cotangent):
    block, interval = locate(tables, temperature, fractions)
    weights, to_fields = jax.vjp(partial(segment_weights, tables, interval),
                                 temperature, fractions, length)
    d_weights, d_background = _sweep_vjp(tables, block, *weights, n_segments, radiance,
                                         cotangent)
    return to_fields(d_weights), d_background if with_background else None


def radiance_xla(batch_rays, tables, fields, lengths, background=None):
    """The radiance (n_rays, n_points) by JAX's forward sweep, batch by batch
    (``batch_rays`` rays each); differentiable in forward mode."""
    order, n_segments = ray_order(lengths, batch_rays)
    batches = batched_inputs(tables, fields, lengths, order, batch_rays)
    if background is not None:
        background = spectra_batches(background, order, batch_rays)
    out = jax.lax.map(lambda b: _batch_radiance(tables, *b), (*batches, n_segments, background))
    return from_batches(out, order)


def cotangents_xla(batch_rays, tables: RTETables, fields, lengths, radiance, cotangent,
                   has_background):
    """Cotangents of the fields, lengths and background (None without one) by JAX's reverse
    sweep, batch by batch."""
    order, n_segments = ray_order(lengths, batch_rays)
    batches, to_inputs = jax.vjp(
        lambda f, s: batched_inputs(tables, f, s, order, batch_rays), fields, lengths)
    spectra = tuple(spectra_batches(a, order, batch_rays) for a in (radiance, cotangent))
    grads, d_background = jax.lax.map(
        lambda b: _batch_cotangent(tables, has_background, *b),
        (*batches, n_segments, *spectra))
    d_fields, d_lengths = to_inputs(grads)
    d_lengths = jnp.where(jnp.arange(lengths.shape[1]) < segment_counts(lengths)[:, None],
                          d_lengths, 0)  # a batch sweeps its rays' padding too: not theirs
    return d_fields, d_lengths, from_batches(d_background, order) if has_background else None

