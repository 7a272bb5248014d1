r"""Thermal emission along rays through a piecewise-homogeneous absorbing gas.

Each ray is cut into segments, nearest the camera first, with uniform temperature :math:`T_k`
(K), mole fractions :math:`X_{s,k}` and length :math:`\Delta s_k` (m). The formal solution of
the radiative transfer equation without scattering and without background is

.. math::

    I(\eta) = \sum_k B_\eta(T_k)\,(1 - t_k)\,P_k, \qquad
    t_k = e^{-\tau_k}, \qquad P_k = \prod_{j<k} t_j, \qquad
    \tau_k = \kappa_k \Delta s_k,

    \kappa_k(\eta) = \sum_s X_{s,k}\, N(T_k, p)\, \sigma_s(\eta, T_k) \cdot 10^{-4},
    \qquad N = \frac{p}{k_B T},

with :math:`I` in W/(m²·sr·cm⁻¹), :math:`\kappa` in m⁻¹, :math:`N` in molecules/m³ and the
absorption cross-sections :math:`\sigma_s` in cm²/molecule (the :math:`10^{-4}` converts
them to m²). :math:`\sigma_s(\eta, T)` is a cubic spline in :math:`T` per wavenumber
(:class:`operators.tabulated.PiecewiseCubic` coefficients), so the model is C² in
:math:`T`; :math:`B_\eta` is Planck's law (:mod:`operators.planck`), exact or as a spline in
:math:`T` on refined nodes (``planck="table"``, relative error below ``planck_rtol``).

**Forward sweep.** The kernel runs from the far end of each ray to the camera,
:math:`I \leftarrow t_k I + B_k (1 - t_k)`, so one array of state per ray batch is updated in
one fused pass over the spectra per segment.

**Derivatives.** With :math:`P_k = \prod_{j<k} t_j` and
:math:`I_{\le k} = \sum_{m \le k} B_m (1 - t_m) P_m`,

.. math::

    \frac{\partial I}{\partial B_k} = (1 - t_k) P_k, \qquad
    \frac{\partial I}{\partial \tau_k} = t_k P_k B_k - (I - I_{\le k}),

so the reverse sweep (a custom VJP) re-runs the segments in camera order, accumulating
:math:`P_k` and :math:`I_{\le k}`, and needs only the final :math:`I` and arrays of one ray
batch's spectra: no per-segment spectra are stored. The sums over wavenumber that turn these
into cotangents of the per-segment weights are batched matrix-vector products; JAX then
carries them to :math:`(T_k, X_{s,k}, \Delta s_k)` through the (scalar, per-segment)
weights. Forward-mode derivatives (JVPs) run JAX's forward mode through the forward sweep,
with the same memory.

**Layout.** Rays are sorted by their number of segments and processed in batches
(``batch_rays``, sized from a memory budget), each batch sweeping only as many segments as
its longest ray, so padding costs little. All species' spline coefficients and those of
:math:`B` sit in one table per temperature interval, ``(n_intervals, n_coef, n_eta)``;
per segment, :math:`\tau` and :math:`B` are sums of gathered table rows times per-segment
weights (:math:`X_s \Delta s / T` times powers of the offset in the interval).
Coefficients are pre-scaled by :math:`p \cdot 10^{-4}/k_B` and written in the interval's
normalized offset :math:`u \in [0, 1]`, so float32 evaluation stays well inside its range.
``benchmarks/bench_rte.py`` times the kernel against a bare exponential.

Entries of a ray after its last segment of non-zero length are padding: they contribute
nothing, and their cotangents are zero.
"""

from __future__ import annotations

import dataclasses
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from operators.base import Jacobian, Operator
from operators.interop import to_jax, to_numpy
from operators.planck import BOLTZMANN, planck, planck_table

DEFAULT_MEMORY_BUDGET = {"cpu": 8 * 2**20, "gpu": 2**30}
"""Default working memory of one ray batch in bytes, per JAX backend: on a CPU a batch's
spectra should stay in the caches (8 MiB: about 40 rays of 1876 wavenumbers in float32), on
a GPU a batch should fill the device (1 GiB); other backends use the GPU figure."""


@partial(jax.tree_util.register_dataclass,
         data_fields=["nodes", "inv_width", "coef", "wavenumber"],
         meta_fields=["species", "n_species", "planck"])
@dataclasses.dataclass(frozen=True)
class RTETables:
    """Spectral tables of the emission kernel, prepared from absorption splines.

    Build with :meth:`from_spline`. A JAX pytree: its arrays travel as arguments of jitted
    functions (no large constants baked into compiled code).

    Attributes
    ----------
    nodes : jax.Array, shape (m,)
        Temperature nodes in K (those of the cross-sections, refined for Planck's law when
        ``planck == "table"``).
    inv_width : jax.Array, shape (m - 1,)
        Inverse interval widths in 1/K.
    coef : jax.Array, shape (m - 1, n_coef, n_eta)
        Per interval, the coefficients of :math:`u^3, u^2, u, 1` (``u`` the normalized offset
        in the interval) of :math:`\\sigma_s p 10^{-4}/k_B` (K/m) for each absorbing species
        in ``species`` order, then (``planck == "table"``) of :math:`B_\\eta` in
        W/(m²·sr·cm⁻¹).
    wavenumber : jax.Array, shape (n_eta,)
        Wavenumbers in cm⁻¹.
    species : tuple of int
        Indices (0-based, among the mole-fraction fields) of the species with a non-zero
        cross-section; the others are skipped.
    n_species : int
        Number of mole-fraction fields (the kernel input has ``1 + n_species`` fields).
    planck : {"table", "exact"}
        How :math:`B_\\eta(T)` is evaluated.
    """

    nodes: jax.Array
    inv_width: jax.Array
    coef: jax.Array
    wavenumber: jax.Array
    species: tuple[int, ...]
    n_species: int
    planck: str

    @classmethod
    def from_spline(cls, wavenumber, temperatures, coef, pressure: float = 101325.0,
                    dtype=np.float32, planck: str = "table",
                    planck_rtol: float = 1e-7) -> RTETables:
        """Prepare the kernel tables from cubic-spline coefficients of cross-sections.

        Parameters
        ----------
        wavenumber : array_like, shape (n_eta,)
            Wavenumbers in cm⁻¹.
        temperatures : array_like, shape (n_T,)
            Spline nodes in K, strictly increasing.
        coef : array_like, shape (4, n_T - 1, n_species, n_eta)
            :class:`~operators.tabulated.PiecewiseCubic` coefficients of the cross-sections
            :math:`\\sigma_s(\\eta, T)` in cm²/molecule: on interval ``i``,
            :math:`\\sigma = \\sum_j c_{j,i} (T - T_i)^{3-j}`.
        pressure : float, optional
            Total pressure in Pa (default 101325).
        dtype : numpy dtype, optional
            float32 (default, fast) or float64.
        planck : {"table", "exact"}, optional
            Planck's law as a spline on refined nodes (default, one polynomial instead of an
            exponential per spectral point) or evaluated exactly.
        planck_rtol : float, optional
            Relative accuracy of the Planck spline between the first and last node.
        """
        wavenumber = np.asarray(wavenumber, dtype=np.float64)
        temperatures = np.asarray(temperatures, dtype=np.float64)
        coef = np.asarray(coef, dtype=np.float64)
        n_t, n_eta = temperatures.size, wavenumber.size
        if wavenumber.ndim != 1:
            raise ValueError(f"wavenumber must be 1-D (cm-1), got shape {wavenumber.shape}")
        if coef.ndim != 4 or coef.shape[0] != 4 or coef.shape[1] != n_t - 1 \
                or coef.shape[3] != n_eta:
            raise ValueError(
                f"coef must have shape (4, n_T - 1, n_species, n_eta) = (4, {n_t - 1}, "
                f"n_species, {n_eta}) for {n_t} temperature nodes and {n_eta} wavenumbers; "
                f"got {coef.shape}"
            )
        if not pressure > 0:
            raise ValueError(f"pressure must be positive (Pa), got {pressure}")
        if planck not in ("table", "exact"):
            raise ValueError(f"planck must be 'table' or 'exact', got {planck!r}")
        if np.dtype(dtype) not in (np.float32, np.float64):
            raise ValueError(f"dtype must be float32 or float64, got {np.dtype(dtype)}")
        species = tuple(int(s) for s in np.flatnonzero(np.any(coef != 0, axis=(0, 1, 3))))
        if planck == "table":
            nodes, b_coef = planck_table(wavenumber, temperatures, rtol=planck_rtol)
        else:
            nodes = temperatures
        sigma = _restrict(temperatures, coef[:, :, list(species)], nodes)
        scale = pressure * 1e-4 / BOLTZMANN
        parts = [sigma * scale * _powers_of_width(nodes, sigma.ndim)]
        if planck == "table":
            parts.append(b_coef[:, :, None] * _powers_of_width(nodes, b_coef.ndim + 1))
        # (4, m - 1, k, n_eta) blocks -> (m - 1, k * 4, n_eta), species-major
        table = np.concatenate([p.transpose(1, 2, 0, 3) for p in parts], axis=1)
        table = table.reshape(nodes.size - 1, -1, n_eta)
        return cls(jnp.asarray(nodes, dtype), jnp.asarray(1.0 / np.diff(nodes), dtype),
                   jnp.asarray(table, dtype), jnp.asarray(wavenumber, dtype),
                   species, int(coef.shape[2]), planck)

    @property
    def dtype(self):
        """Floating-point type of the tables (and of the kernel's arithmetic)."""
        return self.coef.dtype

    @property
    def n_eta(self) -> int:
        """Number of wavenumbers."""
        return self.wavenumber.shape[0]


def _restrict(nodes, coef, fine):
    """Coefficients of a piecewise cubic on ``nodes`` re-expanded on the refinement ``fine``.

    Both in powers of the offset from the left node, highest first; ``coef`` has shape
    ``(4, len(nodes) - 1, ...)``.
    """
    index = np.clip(np.searchsorted(nodes, fine[:-1], side="right") - 1, 0, nodes.size - 2)
    c = coef[:, index]
    x = (fine[:-1] - nodes[index]).reshape((-1,) + (1,) * (coef.ndim - 2))
    return np.stack([
        c[0],
        3 * c[0] * x + c[1],
        (3 * c[0] * x + 2 * c[1]) * x + c[2],
        ((c[0] * x + c[1]) * x + c[2]) * x + c[3],
    ])


def _powers_of_width(nodes, ndim):
    """``width**(3 - j)`` shaped to scale coefficients ``(4, m - 1, ...)`` to offsets in [0, 1]."""
    width = np.diff(nodes)
    return (width[None, :] ** np.arange(3, -1, -1)[:, None]).reshape((4, -1) + (1,) * (ndim - 2))


# -- per-segment weights and one segment's spectra --------------------------------------------
def _interval(tables: RTETables, temperature):
    """Index of the temperature interval of each segment (clamped to the end intervals)."""
    nodes = tables.nodes
    return jnp.clip(jnp.searchsorted(nodes, temperature, side="right") - 1, 0,
                    nodes.shape[0] - 2)


def _segment_weights(tables: RTETables, index, temperature, fractions, length):
    """Weights of the table rows in the optical depth and in the Planck radiance.

    For segments shaped ``s`` (``temperature``, ``length``; ``fractions`` is
    ``(n_absorbing, *s)``): ``w_tau`` ``(*s, 4 n_absorbing)``, the coefficients of the rows
    ``X_s Δs / T · u^(3-j)`` (the table rows carry ``σ p 10⁻⁴/k_B``), and ``w_emit``, the
    powers ``u^(3-j)`` ``(*s, 4)`` for the Planck table or the temperature ``(*s, 1)`` for
    the exact law.
    """
    u = (temperature - tables.nodes[index]) * tables.inv_width[index]
    powers = jnp.stack([u**3, u**2, u, jnp.ones_like(u)], axis=-1)
    amount = fractions * (length / temperature)
    w_tau = jnp.moveaxis(amount[..., None] * powers, 0, -2)
    w_tau = w_tau.reshape(w_tau.shape[:-2] + (-1,))
    w_emit = powers if tables.planck == "table" else temperature[..., None]
    return w_tau, w_emit


def _spectra(tables: RTETables, index, w_tau, w_emit):
    """Optical depth and Planck radiance (r, n_eta) of one segment of each ray of a batch.

    One gather per table row: XLA fuses these into the elementwise sums.
    """
    n_tau = w_tau.shape[-1]
    tau = sum(w_tau[:, c, None] * tables.coef[index, c] for c in range(n_tau))
    if tables.planck == "table":
        emission = sum(w_emit[:, j, None] * tables.coef[index, n_tau + j] for j in range(4))
    else:
        emission = planck(tables.wavenumber, w_emit)
    return tau, emission


def _spectra_cotangent(tables: RTETables, index, w_tau, w_emit, g_tau, g_emit):
    """Cotangents of ``w_tau`` and ``w_emit`` from those of ``tau`` and ``B`` (r, n_eta).

    The sums over wavenumber are batched matrix-vector products.
    """
    n_tau = w_tau.shape[-1]
    contract = partial(jnp.einsum, "rn,rcn->rc", precision=jax.lax.Precision.HIGHEST)
    d_tau = contract(g_tau, tables.coef[index, :n_tau])
    if tables.planck == "table":
        d_emit = contract(g_emit, tables.coef[index, n_tau:])
    else:
        slope = jax.jvp(partial(planck, tables.wavenumber), (w_emit,),
                        (jnp.ones_like(w_emit),))[1]
        d_emit = jnp.sum(g_emit * slope, axis=-1, keepdims=True)
    return d_tau, d_emit


@jax.custom_jvp
def _transmission(tau):
    """Transmittance :math:`e^{-\tau}` and absorptance :math:`1 - e^{-\tau}`, both accurate.

    float64 uses ``expm1``; float32 a series below :math:`\tau = 0.1` (truncation below
    2e-8) and :math:`1 - e^{-\tau}` above (rounding below 6e-7), cheaper than ``expm1``.
    """
    t = jnp.exp(-tau)
    if tau.dtype == jnp.float64:
        return t, -jnp.expm1(-tau)
    series = 1.0 - tau / 6.0
    for n in (5.0, 4.0, 3.0, 2.0):
        series = 1.0 - tau / n * series
    return t, jnp.where(tau < 0.1, tau * series, 1.0 - t)


@_transmission.defjvp
def _transmission_jvp(primals, tangents):
    (tau,), (dtau,) = primals, tangents
    t, a = _transmission(tau)
    return (t, a), (-t * dtau, t * dtau)


def _sweep(tables: RTETables, index, w_tau, w_emit, n_segments):
    """Radiance (r, n_eta) of one ray batch, from the far end of the rays to the camera.

    ``I ← t_k I + B_k (1 - t_k)`` for ``k = n_segments - 1, …, 0``: one array of state, one
    fused pass over the spectra per segment.
    """
    zeros = jnp.zeros((index.shape[-1], tables.n_eta), tables.dtype)

    def step(j, radiance):
        k = n_segments - 1 - j
        tau, emission = _spectra(tables, index[k], w_tau[k], w_emit[k])
        transmittance, absorptance = _transmission(tau)
        return transmittance * radiance + emission * absorptance

    return jax.lax.fori_loop(0, n_segments, step, zeros)


def _sweep_vjp(tables: RTETables, index, w_tau, w_emit, n_segments, radiance, cotangent):
    """Cotangents of one batch's weights, camera side first, from ``∂I/∂τ_k`` and ``∂I/∂B_k``."""
    zeros = jnp.zeros_like(radiance)

    def step(k, carry):
        partial_sum, transmittance, d_w_tau, d_w_emit = carry
        tau, emission = _spectra(tables, index[k], w_tau[k], w_emit[k])
        t, a = _transmission(tau)
        absorbed = transmittance * a
        partial_sum = partial_sum + emission * absorbed
        transmittance = transmittance * t
        g_tau = cotangent * (transmittance * emission - (radiance - partial_sum))
        d_tau, d_emit = _spectra_cotangent(tables, index[k], w_tau[k], w_emit[k], g_tau,
                                           cotangent * absorbed)
        d_w_tau = jax.lax.dynamic_update_index_in_dim(d_w_tau, d_tau, k, 0)
        d_w_emit = jax.lax.dynamic_update_index_in_dim(d_w_emit, d_emit, k, 0)
        return partial_sum, transmittance, d_w_tau, d_w_emit

    init = (zeros, zeros + 1, jnp.zeros_like(w_tau), jnp.zeros_like(w_emit))
    return jax.lax.fori_loop(0, n_segments, step, init)[2:]


def _batch_radiance(tables: RTETables, temperature, fractions, length, n_segments):
    index = _interval(tables, temperature)
    return _sweep(tables, index,
                  *_segment_weights(tables, index, temperature, fractions, length), n_segments)


def _batch_cotangent(tables: RTETables, temperature, fractions, length, n_segments, radiance,
                     cotangent):
    index = _interval(tables, temperature)
    weights, to_fields = jax.vjp(partial(_segment_weights, tables, index),
                                 temperature, fractions, length)
    return to_fields(_sweep_vjp(tables, index, *weights, n_segments, radiance, cotangent))


# -- rays sorted and cut into batches ---------------------------------------------------------
def _ray_order(lengths, batch_rays):
    """Permutation sorting rays by segment count, and each batch's largest count."""
    n_rays, n_seg = lengths.shape
    count = jnp.max(jnp.where(lengths != 0, jnp.arange(1, n_seg + 1), 0), axis=1)
    order = jnp.argsort(count, stable=True)
    n_batches = -(-n_rays // batch_rays)
    padded = jnp.zeros(n_batches * batch_rays, count.dtype).at[:n_rays].set(count[order])
    return order, padded.reshape(n_batches, batch_rays).max(axis=1)


def _segment_batches(x, order, batch_rays, fill):
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


def _spectra_batches(x, order, batch_rays):
    """Spectra ``(n_rays, n_eta)`` -> ``(n_batches, batch_rays, n_eta)``, rays permuted."""
    pad = _n_batches(order, batch_rays) * batch_rays - order.shape[0]
    x = jnp.pad(x[order], ((0, pad), (0, 0)))
    return x.reshape(-1, batch_rays, x.shape[-1])


def _from_batches(x, order):
    """Inverse of :func:`_spectra_batches`."""
    x = x.reshape(-1, x.shape[-1])[: order.shape[0]]
    return jnp.zeros_like(x).at[order].set(x)


def _n_batches(order, batch_rays):
    return -(-order.shape[0] // batch_rays)


def _batched_inputs(tables: RTETables, fields, lengths, order, batch_rays):
    fractions = fields[1 + np.asarray(tables.species, dtype=int)]
    return (_segment_batches(fields[0], order, batch_rays, 1.0),
            _segment_batches(fractions, order, batch_rays, 0.0),
            _segment_batches(lengths, order, batch_rays, 0.0))


def _radiance_impl(batch_rays, tables, fields, lengths):
    order, n_segments = _ray_order(lengths, batch_rays)
    batches = _batched_inputs(tables, fields, lengths, order, batch_rays)
    out = jax.lax.map(lambda b: _batch_radiance(tables, *b), (*batches, n_segments))
    return _from_batches(out, order)


@partial(jax.custom_vjp, nondiff_argnums=(0,))
def _radiance(batch_rays, tables, fields, lengths):
    return _radiance_impl(batch_rays, tables, fields, lengths)


def _radiance_fwd(batch_rays, tables, fields, lengths):
    radiance = _radiance_impl(batch_rays, tables, fields, lengths)
    return radiance, (tables, fields, lengths, radiance)


def _radiance_bwd(batch_rays, residuals, cotangent):
    tables, fields, lengths, radiance = residuals
    order, n_segments = _ray_order(lengths, batch_rays)
    batches, to_inputs = jax.vjp(
        lambda f, s: _batched_inputs(tables, f, s, order, batch_rays), fields, lengths)
    spectra = tuple(_spectra_batches(a, order, batch_rays) for a in (radiance, cotangent))
    grads = jax.lax.map(lambda b: _batch_cotangent(tables, *b), (*batches, n_segments, *spectra))
    d_fields, d_lengths = to_inputs(grads)
    return jax.tree_util.tree_map(jnp.zeros_like, tables), d_fields, d_lengths


_radiance.defvjp(_radiance_fwd, _radiance_bwd)
_radiance_jit = jax.jit(_radiance, static_argnums=0)


def batch_rays_for(tables: RTETables, n_rays: int, memory_budget: int | None = None) -> int:
    """Rays per batch so that one batch's working arrays fit in ``memory_budget`` bytes.

    A batch holds about ``16 + n_coef`` spectra per ray in the reverse sweep (radiance,
    cotangent, partial sums, transmittance, the segment's optical depth, Planck radiance,
    gathered coefficients and their products).

    Parameters
    ----------
    tables : RTETables
        Kernel tables (give ``n_eta``, ``n_coef`` and the dtype).
    n_rays : int
        Number of rays (the batch never exceeds it).
    memory_budget : int, optional
        Bytes (default :data:`DEFAULT_MEMORY_BUDGET` for the default JAX backend).
    """
    if memory_budget is None:
        memory_budget = DEFAULT_MEMORY_BUDGET.get(jax.default_backend(),
                                                  DEFAULT_MEMORY_BUDGET["gpu"])
    budget = int(memory_budget)
    per_ray = tables.n_eta * tables.dtype.itemsize * (16 + tables.coef.shape[1])
    return int(max(1, min(n_rays, budget // per_ray)))


def emission_radiance(tables: RTETables, fields, lengths, batch_rays: int | None = None):
    """Spectral radiance leaving each ray's near end: the emission kernel, a JAX function.

    Differentiable in reverse mode with a memory-lean custom VJP (w.r.t. ``fields`` and
    ``lengths``; the tables get zero cotangents) and in forward mode through
    :func:`emission_radiance_jvp`. jit-compatible (``batch_rays`` must be static).

    Parameters
    ----------
    tables : RTETables
        Prepared spectral tables (:meth:`RTETables.from_spline`).
    fields : jax.Array, shape (1 + n_species, n_rays, n_seg)
        Per segment temperature in K, then mole fractions (dimensionless), segments nearest
        the camera first. Temperatures must be positive, also on padding.
    lengths : jax.Array, shape (n_rays, n_seg)
        Segment lengths in m; zero on padding.
    batch_rays : int, optional
        Rays per batch (default from :func:`batch_rays_for`).

    Returns
    -------
    jax.Array, shape (n_rays, n_eta)
        Spectral radiance in W/(m²·sr·cm⁻¹), in the tables' dtype.
    """
    fields, lengths = _check_inputs(tables, fields, lengths)
    if batch_rays is None:
        batch_rays = batch_rays_for(tables, lengths.shape[0])
    return _radiance_jit(int(batch_rays), tables, fields, lengths)


def emission_radiance_jvp(tables: RTETables, fields, lengths, d_fields, d_lengths,
                          batch_rays: int | None = None):
    """Radiance and its directional derivative (forward mode), memory as the forward.

    Parameters
    ----------
    tables, fields, lengths, batch_rays
        As in :func:`emission_radiance`.
    d_fields, d_lengths : jax.Array
        Tangents, shaped as ``fields`` and ``lengths``.

    Returns
    -------
    radiance, d_radiance : jax.Array, shape (n_rays, n_eta)
        In W/(m²·sr·cm⁻¹) and W/(m²·sr·cm⁻¹) per unit of the tangent.
    """
    fields, lengths = _check_inputs(tables, fields, lengths)
    if batch_rays is None:
        batch_rays = batch_rays_for(tables, lengths.shape[0])
    d_fields = jnp.asarray(d_fields, tables.dtype)
    d_lengths = jnp.asarray(d_lengths, tables.dtype)
    return _radiance_jvp_jit(int(batch_rays), tables, fields, lengths, d_fields, d_lengths)


@partial(jax.jit, static_argnums=0)
def _radiance_jvp_jit(batch_rays, tables, fields, lengths, d_fields, d_lengths):
    return jax.jvp(partial(_radiance_impl, batch_rays, tables), (fields, lengths),
                   (d_fields, d_lengths))


def _check_inputs(tables: RTETables, fields, lengths):
    fields = jnp.asarray(fields, tables.dtype)
    lengths = jnp.asarray(lengths, tables.dtype)
    n_fields = 1 + tables.n_species
    if fields.ndim != 3 or fields.shape[0] != n_fields:
        raise ValueError(
            f"fields must have shape ({n_fields}, n_rays, n_seg) (T, then {tables.n_species} "
            f"mole fractions); got {fields.shape}"
        )
    if lengths.shape != fields.shape[1:]:
        raise ValueError(
            f"lengths must have shape (n_rays, n_seg) = {fields.shape[1:]} to match fields; "
            f"got {lengths.shape}"
        )
    return fields, lengths


class EmissionRTE(Operator):
    r"""Emission radiative transfer along fixed rays, a nonlinear operator.

    Maps per-segment fields ``(1 + n_species, n_rays, n_seg)`` — temperature (K) and mole
    fractions (dimensionless), field order (T, CO2, H2O, CH4) — to spectral radiance
    ``(n_rays, n_eta)`` in W/(m²·sr·cm⁻¹); see the module docstring for the model. ``jvp``
    and ``vjp`` are the exact derivatives of the discrete forward map.

    Parameters
    ----------
    wavenumber : array_like, shape (n_eta,)
        Wavenumbers in cm⁻¹.
    temperatures : array_like, shape (n_T,)
        Temperature nodes in K of the cross-section splines.
    coef : array_like, shape (4, n_T - 1, n_species, n_eta)
        :class:`~operators.tabulated.PiecewiseCubic` coefficients of the cross-sections in
        cm²/molecule.
    lengths : array_like, shape (n_rays, n_seg)
        Segment lengths in m, nearest the camera first; zero on padding.
    pressure : float, optional
        Total pressure in Pa (default 101325).
    dtype : numpy dtype, optional
        float32 (default) or float64.
    planck : {"table", "exact"}, optional
        See :meth:`RTETables.from_spline`.
    memory_budget : int, optional
        Bytes for one batch of rays (default :data:`DEFAULT_MEMORY_BUDGET`, per backend);
        ignored when ``batch_rays`` is given.
    batch_rays : int, optional
        Rays per batch.

    Attributes
    ----------
    tables : RTETables
    lengths : jax.Array, shape (n_rays, n_seg)
    batch_rays : int
    kernel : callable
        ``kernel(fields, lengths) -> radiance``: :func:`emission_radiance` on these tables,
        a differentiable JAX function taking new segment lengths (m) at every call. Inside
        another jitted function prefer :func:`emission_radiance` with the tables as an
        argument, so they are not compiled in as constants.
    """

    def __init__(self, wavenumber, temperatures, coef, lengths, pressure: float = 101325.0,
                 dtype=np.float32, planck: str = "table", memory_budget: int | None = None,
                 batch_rays: int | None = None):
        tables = RTETables.from_spline(wavenumber, temperatures, coef, pressure, dtype, planck)
        lengths = np.asarray(lengths)
        if lengths.ndim != 2:
            raise ValueError(f"lengths must have shape (n_rays, n_seg) in m, got {lengths.shape}")
        n_rays, n_seg = lengths.shape
        super().__init__((1 + tables.n_species, n_rays, n_seg), (n_rays, tables.n_eta),
                         dtype=dtype, name="EmissionRTE")
        self.tables = tables
        self.lengths = to_jax(lengths, dtype=self.dtype)
        self.batch_rays = int(batch_rays or batch_rays_for(tables, n_rays, memory_budget))
        self.kernel = partial(emission_radiance, self.tables, batch_rays=self.batch_rays)

    def _in(self, x):
        return to_jax(x, dtype=self.dtype)

    def _forward(self, x):
        return to_numpy(_radiance_jit(self.batch_rays, self.tables, self._in(x), self.lengths))

    def _jvp(self, x, v):
        return to_numpy(_radiance_jvp_jit(self.batch_rays, self.tables, self._in(x), self.lengths,
                                          self._in(v), jnp.zeros_like(self.lengths))[1])

    def _vjp(self, x, w):
        return to_numpy(_fields_vjp_jit(self.batch_rays, self.tables, self._in(x), self.lengths,
                                        self._in(w)))

    def linearize(self, x) -> Jacobian:
        xj = self._in(self._as_input(x))
        value, pullback = jax.vjp(
            lambda f: _radiance_jit(self.batch_rays, self.tables, f, self.lengths), xj)
        return Jacobian(
            self, to_numpy(xj), to_numpy(value),
            jvp=lambda v: self._jvp(xj, v),
            vjp=lambda w: to_numpy(pullback(self._in(w))[0]),
        )


@partial(jax.jit, static_argnums=0)
def _fields_vjp_jit(batch_rays, tables, fields, lengths, cotangent):
    return jax.vjp(lambda f: _radiance(batch_rays, tables, f, lengths), fields)[1](cotangent)[0]
