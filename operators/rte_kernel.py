r"""The emission kernel: thermal emission along rays through a piecewise-homogeneous gas.

Each ray is cut into segments, nearest the camera first, with uniform temperature :math:`T_k`
(K), mole fractions :math:`X_{s,k}` and length :math:`\Delta s_k` (m). The formal solution of
the radiative transfer equation without scattering, in front of a background of radiance
:math:`I_\mathrm{bg}(\eta)` (a wall or the sky behind the flame; zero when there is none), is

.. math::

    I(\eta) = \sum_k B_\eta(T_k)\,(1 - t_k)\,P_k + \tau_\mathrm{ray}\, I_\mathrm{bg},
    \qquad t_k = e^{-\tau_k}, \qquad P_k = \prod_{j<k} t_j, \qquad
    \tau_\mathrm{ray} = P_{n}, \qquad \tau_k = \kappa_k \Delta s_k,

    \kappa_k(\eta) = \sum_s X_{s,k}\, N(T_k, p)\, \sigma_s(\eta, T_k) \cdot 10^{-4},
    \qquad N = \frac{p}{k_B T},

plus, with soot, the Rayleigh continuum :math:`C f_{v,k}\, \eta \cdot 10^2` of the soot volume
fraction :math:`f_{v,k}` (:mod:`operators.rte_tables`), with :math:`I` in W/(m²·sr·cm⁻¹),
:math:`\kappa` in m⁻¹, :math:`N` in molecules/m³ and the
absorption cross-sections :math:`\sigma_s` in cm²/molecule (the :math:`10^{-4}` converts
them to m²). :math:`\sigma_s(\eta, T)` is a cubic spline in :math:`T` per wavenumber
(:class:`operators.tabulated.PiecewiseCubic` coefficients), so the model is C² in
:math:`T`; :math:`B_\eta` is Planck's law (:mod:`operators.planck`), exact or as a spline in
:math:`T` on refined nodes (``planck="table"``, relative error below ``planck_rtol``).

**Forward sweep.** The kernel runs from the far end of each ray to the camera,
:math:`I \leftarrow t_k I + B_k (1 - t_k)`, so one array of state per ray batch is updated in
one fused pass over the spectra per segment. The sweep starts from :math:`I = I_\mathrm{bg}`,
which the segments then attenuate by exactly the ray's transmittance :math:`\tau_\mathrm{ray}`.

**Derivatives.** With :math:`P_k = \prod_{j<k} t_j` and
:math:`I_{\le k} = \sum_{m \le k} B_m (1 - t_m) P_m`,

.. math::

    \frac{\partial I}{\partial B_k} = (1 - t_k) P_k, \qquad
    \frac{\partial I}{\partial \tau_k} = t_k P_k B_k - (I - I_{\le k}), \qquad
    \frac{\partial I}{\partial I_\mathrm{bg}} = \tau_\mathrm{ray},

(:math:`I - I_{\le k}`, everything behind segment :math:`k`, holds the transmitted background,
so the background enters the temperature and mole-fraction derivatives through
:math:`\tau_\mathrm{ray}` with no term of its own)
so the reverse sweep (a custom VJP) re-runs the segments in camera order, accumulating
:math:`P_k` and :math:`I_{\le k}`, and needs only the final :math:`I` and arrays of one ray
batch's spectra: no per-segment spectra are stored. Per segment, the optical depth is
:math:`\tau = \sum_s a_s \tilde\sigma_s(u)` with the amounts :math:`a_s = X_s \Delta s / T`
and the cubics :math:`\tilde\sigma_s` in the offset :math:`u` in the temperature interval,
and :math:`B = \tilde B(u)`; so the sums over wavenumber are taken of the physical spectra,
:math:`\sum_\eta g_\tau \tilde\sigma_s` per gas and one
:math:`\sum_\eta (g_\tau \partial_u\tau + g_B \partial_u B)` (``n_gas + 1`` sums per
segment, not one per spline coefficient, four per gas and four for :math:`B`); JAX then
carries them to :math:`(T_k, X_{s,k}, \Delta s_k)` through the scalar weights
:math:`(a_s, u)`. Forward-mode derivatives (JVPs) carry the tangents through the forward
sweep, with the same memory (JAX's forward mode through the XLA sweep).

**Two implementations** of the sweeps (:func:`choose_sweeps`): JAX's below, lowered by XLA for
any backend, and, the default on one CPU device, the same three sweeps compiled by Numba (the
forward-mode one written out, not JAX's), one ray at a time with its spectra in cache, called
by XLA on its own buffers (FFI calls, :mod:`operators.rte_sweep_cpu`,
:mod:`operators.xla_ffi`); XLA's CPU backend writes each intermediate spectrum of a ray batch to
memory instead. ``docs/performance.md`` has the measured costs.

**Layout** of the XLA sweeps. Rays are sorted by their number of segments and processed in
batches (:mod:`operators.rte_batches`), each batch sweeping only as many segments as its
longest ray.
Per segment, :math:`\tilde\sigma_s` and :math:`\tilde B` are Horner sums of gathered rows
of the spectral tables (:mod:`operators.rte_tables`), fused by XLA into the sweep.
``benchmarks/bench_rte.py`` times the kernel and its stages against a bare exponential.

Entries of a ray after its last segment of non-zero length are padding: they contribute
nothing, and their cotangents are zero.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from operators.base import check_precision
from operators.planck import planck
from operators.rte_batches import (
    batch_rays_for,
    batched_inputs,
    from_batches,
    ray_order,
    segment_counts,
    spectra_batches,
)
from operators.rte_blocks import composition_block, fraction_weights, n_composition_blocks
from operators.rte_sweep_cpu import target
from operators.rte_tables import RTETables


# -- per-segment weights and one segment's spectra --------------------------------------------
def _locate(tables: RTETables, temperature, fractions):
    """Each segment's block of table rows and its temperature interval (clamped to the end
    intervals); ``fractions`` as :func:`_segment_weights` takes them."""
    nodes = tables.nodes
    interval = jnp.clip(jnp.searchsorted(nodes, temperature, side="right") - 1, 0,
                        nodes.shape[0] - 2)
    lowers = [fraction_weights(f, fractions[s], jnp)[0]
              for s, f in enumerate(tables.fraction_nodes) if len(f) > 1]
    blocks = n_composition_blocks(tables.fraction_nodes)
    return interval * blocks + composition_block(tables.fraction_nodes, lowers, jnp), interval


def _segment_weights(tables: RTETables, interval, temperature, fractions, length):
    r"""The scalars per segment that the spectra depend on.

    For segments shaped ``s`` (``temperature`` in K, ``length`` in m, ``interval`` the
    temperature interval of :func:`_locate`; ``fractions`` is ``(n_absorbing, *s)``, the soot
    volume fraction last when the tables have soot): the amounts ``(*s, n_slots [+ 1])``, per
    gas slot :math:`X_s \Delta s / T` (m/K; the table rows carry :math:`\sigma p 10^{-4}/k_B`),
    split as :math:`X_s (1 - w_s)` and :math:`X_s w_s` between the nodes either side of a
    species with several fraction nodes (:func:`operators.rte_blocks.fraction_weights`), and
    the soot's :math:`f_v \Delta s` (m); the offset :math:`u \in [0, 1]` in the temperature
    interval ``(*s,)``; and the temperature ``(*s,)`` in K, which the exact Planck law takes.
    """
    offset = (temperature - tables.nodes[interval]) * tables.inv_width[interval]
    per_length = length / temperature
    amount = []
    for s, nodes in enumerate(tables.fraction_nodes):
        gas = fractions[s] * per_length
        if len(nodes) > 1:
            weight = fraction_weights(nodes, fractions[s], jnp)[1]
            amount += [gas - gas * weight, gas * weight]
        else:
            amount.append(gas)
    if tables.soot:
        amount.append(fractions[-1] * length)
    return jnp.stack(amount, axis=-1), offset, temperature


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
    :math:`g_B = \bar I\,\partial I/\partial B_k` (module notes), per segment the sums
    over wavenumber of :math:`g_\tau` times each row of ``tau`` give the amounts' cotangents,
    and that of :math:`g_\tau\,\partial\tau/\partial u + g_B\,\partial B/\partial u`
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
    block, interval = _locate(tables, temperature, fractions)
    return _sweep(tables, block,
                  *_segment_weights(tables, interval, temperature, fractions, length),
                  n_segments, background)


def _batch_cotangent(tables: RTETables, with_background: bool, temperature, fractions, length,
                     n_segments, radiance, cotangent):
    block, interval = _locate(tables, temperature, fractions)
    weights, to_fields = jax.vjp(partial(_segment_weights, tables, interval),
                                 temperature, fractions, length)
    d_weights, d_background = _sweep_vjp(tables, block, *weights, n_segments, radiance,
                                         cotangent)
    return to_fields(d_weights), d_background if with_background else None


# -- all rays: batches mapped, the reverse sweep as custom VJP --------------------------------
def _radiance_impl(batch_rays, tables, fields, lengths, background=None):
    order, n_segments = ray_order(lengths, batch_rays)
    batches = batched_inputs(tables, fields, lengths, order, batch_rays)
    if background is not None:
        background = spectra_batches(background, order, batch_rays)
    out = jax.lax.map(lambda b: _batch_radiance(tables, *b), (*batches, n_segments, background))
    return from_batches(out, order)


def _numba(sweeps: str, tables: RTETables) -> bool:
    """Whether the Numba sweeps run: chosen, and the Planck spline (they have no exact law)."""
    return sweeps == "numba" and tables.planck == "table"


def _forward(batch_rays, sweeps, tables, fields, lengths, background=None):
    """The radiance by the chosen sweeps (:func:`choose_sweeps`), not differentiable."""
    if _numba(sweeps, tables):
        return _radiance_numba(tables, fields, lengths, background)
    return _radiance_impl(batch_rays, tables, fields, lengths, background)


@partial(jax.custom_vjp, nondiff_argnums=(0, 1))
def _radiance(batch_rays, sweeps, tables, fields, lengths, background=None):
    return _forward(batch_rays, sweeps, tables, fields, lengths, background)


def _radiance_fwd(batch_rays, sweeps, tables, fields, lengths, background=None):
    radiance = _forward(batch_rays, sweeps, tables, fields, lengths, background)
    return radiance, (tables, fields, lengths, radiance, background)


def _radiance_bwd(batch_rays, sweeps, residuals, cotangent):
    tables, fields, lengths, radiance, background = residuals
    cotangents = (_cotangents_numba if _numba(sweeps, tables)
                  else partial(_cotangents_xla, batch_rays))
    return (jax.tree_util.tree_map(jnp.zeros_like, tables),
            *cotangents(tables, fields, lengths, radiance, cotangent, background is not None))


def _radiance_forward_mode(batch_rays, sweeps, tables, fields, lengths, background=None):
    """The radiance, differentiable in forward mode: JAX's JVP through the XLA sweep, or
    :func:`_radiance_tangent` (the Numba forward-mode sweep) as custom JVP."""
    if _numba(sweeps, tables):
        return _radiance_tangent(tables, fields, lengths, background)
    return _radiance_impl(batch_rays, tables, fields, lengths, background)


@jax.custom_jvp
def _radiance_tangent(tables, fields, lengths, background=None):
    return _radiance_numba(tables, fields, lengths, background)


@_radiance_tangent.defjvp
def _radiance_tangent_jvp(primals, tangents):
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


def _cotangents_xla(batch_rays, tables: RTETables, fields, lengths, radiance, cotangent,
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


# -- the Numba sweeps (operators.rte_sweep_cpu) as XLA FFI calls -----------------------------
def _numba_weights(tables: RTETables, fields):
    """Each segment's block of table rows, and the map ``(fields, lengths) -> (amount,
    offset)`` to the weights the Numba sweeps take (differentiable by JAX)."""
    species = 1 + np.asarray(tables.species, dtype=int)
    block, interval = _locate(tables, fields[0], fields[species])
    return block, lambda f, s: _segment_weights(tables, interval, f[0], f[species], s)[:2]


def _n_gas(tables: RTETables, amount) -> int:
    return amount.shape[-1] - int(tables.soot)


def _spectra_shape(tables: RTETables, lengths):
    return jax.ShapeDtypeStruct((lengths.shape[0], tables.n_points), tables.dtype)


def _background(tables: RTETables, background):
    """The background as the sweeps take it: one zero row for none."""
    return jnp.zeros((1, tables.n_points), tables.dtype) if background is None else background


def _numba_sweep(kind, results, tables: RTETables, index, amount, offset, lengths, *operands):
    """Sweep ``kind`` of :mod:`operators.rte_sweep_cpu` run by XLA on its buffers (an FFI
    call, :func:`operators.rte_sweep_cpu.target`), with the operands every sweep takes made
    from ``index``, ``amount``, ``offset`` and ``lengths``, then ``operands``; returns the
    arrays shaped as ``results``."""
    counts = segment_counts(lengths)
    order = jnp.argsort(-counts, stable=True)
    name = target(kind, _n_gas(tables, amount), amount.shape[-1], tables.dtype)
    call = jax.ffi.ffi_call(name, results, vmap_method="sequential")
    return call(tables.coef, index.astype(jnp.int32), amount, offset,
                counts.astype(jnp.int32), order.astype(jnp.int32), *operands)


def _radiance_numba(tables: RTETables, fields, lengths, background):
    """The radiance by the forward sweep of :mod:`operators.rte_sweep_cpu`."""
    index, weights = _numba_weights(tables, fields)
    amount, offset = weights(fields, lengths)
    return _numba_sweep("forward", _spectra_shape(tables, lengths), tables, index, amount,
                        offset, lengths, _background(tables, background))


def _cotangents_numba(tables: RTETables, fields, lengths, radiance, cotangent, has_background):
    """Cotangents of the fields, lengths and background (None without one) by the reverse
    sweep of :mod:`operators.rte_sweep_cpu`, the weights' cotangents carried to the fields
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


_radiance.defvjp(_radiance_fwd, _radiance_bwd)


# -- spectral points and bins -----------------------------------------------------------------
def _on_bins(radiance, tables: RTETables, fields, lengths, background=None):
    """``radiance`` (a kernel on the tables' spectral points) per bin: the background given per
    bin is taken at each of its points, the radiance averaged over each bin's points."""
    if not tables.binned:
        return radiance(tables, fields, lengths, background)
    if background is not None:
        background = background[..., tables.point_bin]
    at_points = radiance(tables, fields, lengths, background) * tables.point_weight
    return jnp.zeros(at_points.shape[:-1] + (tables.n_bins,), at_points.dtype
                     ).at[..., tables.point_bin].add(at_points)


_radiance_jit = jax.jit(lambda batch_rays, sweeps, *args: _on_bins(
    partial(_radiance, batch_rays, sweeps), *args), static_argnums=(0, 1))


#: The implementations of the sweeps (forward, forward-mode and reverse): JAX's, lowered by
#: XLA for any backend, and the Numba ones for CPUs (:mod:`operators.rte_sweep_cpu`, which need
#: the Planck spline; with the exact Planck law the XLA ones run).
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


def radiance_kernel(batch_rays: int, forward_mode: bool = False, sweeps: str | None = None):
    """The kernel as a JAX function ``radiance(tables, fields, lengths, background=None)``,
    unchecked.

    For building maps around the kernel (:class:`operators.emission_rte.KernelOperator`):
    inputs as in :func:`emission_radiance`, already in the tables' dtype.

    Parameters
    ----------
    batch_rays : int
        Rays per batch of the XLA sweeps (static).
    forward_mode : bool, optional
        False (default): reverse-mode differentiable through the memory-lean custom VJP (no
        forward mode: JAX cannot push tangents through a custom VJP). True: forward-mode
        differentiable (no reverse mode), by the forward-mode sweep (:func:`emission_radiance_jvp`).
        Both give the same radiance.
    sweeps : {"xla", "numba"}, optional
        The sweeps' implementation (default: :func:`choose_sweeps`).

    Returns
    -------
    callable
        ``radiance(tables, fields, lengths, background=None) -> (n_rays, n_eta)`` in
        W/(m²·sr·cm⁻¹).
    """
    kernel = _radiance_forward_mode if forward_mode else _radiance
    return partial(_on_bins, partial(kernel, int(batch_rays), choose_sweeps(sweeps)))


def emission_radiance(tables: RTETables, fields, lengths, batch_rays: int | None = None,
                      background=None, sweeps: str | None = None):
    """Spectral radiance leaving each ray's near end: the emission kernel, a JAX function.

    Differentiable in reverse mode with a memory-lean custom VJP (w.r.t. ``fields``,
    ``lengths`` and ``background``; the tables get zero cotangents) and in forward mode through
    :func:`emission_radiance_jvp`. jit-compatible (``batch_rays`` must be static).

    Parameters
    ----------
    tables : RTETables
        Prepared spectral tables (:meth:`RTETables.from_spline`).
    fields : jax.Array, shape (tables.n_fields, n_rays, n_seg)
        Per segment temperature in K, then mole fractions (dimensionless), then, when the
        tables have soot, the soot volume fraction (dimensionless); segments nearest the
        camera first. Temperatures must be positive, also on padding.
    lengths : jax.Array, shape (n_rays, n_seg)
        Segment lengths in m; zero on padding.
    batch_rays : int, optional
        Rays per batch of the XLA sweeps (default from :func:`batch_rays_for`).
    background : jax.Array, shape (n_rays, n_eta) or (n_eta,), optional
        Radiance behind each ray's far end in W/(m²·sr·cm⁻¹), seen through the ray's
        transmittance (default None: none, as zero but without the cost).
    sweeps : {"xla", "numba"}, optional
        The sweeps' implementation (default: :func:`choose_sweeps`); the same values to
        rounding.

    Returns
    -------
    jax.Array, shape (n_rays, n_eta)
        Spectral radiance in W/(m²·sr·cm⁻¹), in the tables' dtype.

    Raises
    ------
    ValueError
        For inputs of the wrong shape, and for float64 tables while JAX's 64-bit mode is off
        (call inside :func:`operators.precision`; :class:`~operators.emission_rte.EmissionRTE`
        does).
    """
    fields, lengths, background = _check_inputs(tables, fields, lengths, background)
    if batch_rays is None:
        batch_rays = batch_rays_for(tables, lengths.shape[0])
    return _radiance_jit(int(batch_rays), choose_sweeps(sweeps), tables, fields, lengths,
                         background)


def emission_radiance_jvp(tables: RTETables, fields, lengths, d_fields, d_lengths,
                          batch_rays: int | None = None, background=None,
                          sweeps: str | None = None):
    """Radiance and its directional derivative (forward mode), memory as the forward.

    Parameters
    ----------
    tables, fields, lengths, batch_rays, background, sweeps
        As in :func:`emission_radiance` (the background held fixed).
    d_fields, d_lengths : jax.Array
        Tangents, shaped as ``fields`` and ``lengths``.

    Returns
    -------
    radiance, d_radiance : jax.Array, shape (n_rays, n_eta)
        In W/(m²·sr·cm⁻¹) and W/(m²·sr·cm⁻¹) per unit of the tangent.

    Raises
    ------
    ValueError
        As :func:`emission_radiance`.
    """
    fields, lengths, background = _check_inputs(tables, fields, lengths, background)
    if batch_rays is None:
        batch_rays = batch_rays_for(tables, lengths.shape[0])
    d_fields = jnp.asarray(d_fields, tables.dtype)
    d_lengths = jnp.asarray(d_lengths, tables.dtype)
    return _radiance_jvp_jit(int(batch_rays), choose_sweeps(sweeps), tables, fields, lengths,
                             d_fields, d_lengths, background)


@partial(jax.jit, static_argnums=(0, 1))
def _radiance_jvp_jit(batch_rays, sweeps, tables, fields, lengths, d_fields, d_lengths,
                      background):
    kernel = partial(_on_bins, partial(_radiance_forward_mode, batch_rays, sweeps), tables)
    return jax.jvp(lambda f, s: kernel(f, s, background), (fields, lengths),
                   (d_fields, d_lengths))


def _check_inputs(tables: RTETables, fields, lengths, background=None):
    check_precision(tables.dtype, "the emission kernel on these tables")
    fields = jnp.asarray(fields, tables.dtype)
    lengths = jnp.asarray(lengths, tables.dtype)
    n_fields = tables.n_fields
    if fields.ndim != 3 or fields.shape[0] != n_fields:
        soot = ", then the soot volume fraction" if tables.soot else ""
        raise ValueError(
            f"fields must have shape ({n_fields}, n_rays, n_seg) (T, then {tables.n_species} "
            f"mole fractions{soot}); got {fields.shape}"
        )
    if lengths.shape != fields.shape[1:]:
        raise ValueError(
            f"lengths must have shape (n_rays, n_seg) = {fields.shape[1:]} to match fields; "
            f"got {lengths.shape}"
        )
    return fields, lengths, check_background(tables, background, lengths.shape[0])


def check_background(tables: RTETables, background, n_rays: int):
    """A background radiance as ``(n_rays, n_eta)`` in the tables' dtype (None stays None).

    Parameters
    ----------
    tables : RTETables
        Give ``n_eta`` and the dtype.
    background : array_like, shape (n_rays, n_eta) or (n_eta,), or None
        Radiance in W/(m²·sr·cm⁻¹) behind each ray, or one spectrum for all rays.
    n_rays : int
        Number of rays.

    Raises
    ------
    ValueError
        For another shape, naming the expected ones.
    """
    if background is None:
        return None
    background = jnp.asarray(background, tables.dtype)
    if background.shape not in ((tables.n_eta,), (n_rays, tables.n_eta)):
        raise ValueError(
            f"background must have shape (n_rays, n_eta) = {(n_rays, tables.n_eta)} or "
            f"(n_eta,) = ({tables.n_eta},) in W/(m2 sr cm-1); got {background.shape}"
        )
    return jnp.broadcast_to(background, (n_rays, tables.n_eta))

