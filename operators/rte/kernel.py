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
fraction :math:`f_{v,k}` (:mod:`operators.rte.tables`), with :math:`I` in W/(m²·sr·cm⁻¹),
:math:`\kappa` in m⁻¹, :math:`N` in molecules/m³ and the
absorption cross-sections :math:`\sigma_s` in cm²/molecule (the :math:`10^{-4}` converts
them to m²). :math:`\sigma_s(\eta, T)` is a cubic spline in :math:`T` per wavenumber
(:class:`operators.tabulated.PiecewiseCubic` coefficients), so the model is C² in
:math:`T`; :math:`B_\eta` is Planck's law (:mod:`operators.rte.planck`), exact or as a spline in
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

**Two implementations** of the sweeps (:func:`~operators.rte.dispatch.choose_sweeps`): JAX's
(:mod:`operators.rte.sweeps_xla`), lowered by XLA for any backend, and, the default on one CPU
device, the same three sweeps compiled by Numba (the forward-mode one written out, not JAX's),
one ray at a time with its spectra in cache, called by XLA on its own buffers (FFI calls,
:mod:`operators.rte.sweeps_numba`, :mod:`operators.rte.numba_targets`,
:mod:`operators.rte.xla_ffi`); XLA's CPU backend writes each intermediate spectrum of a ray
batch to memory instead. ``docs/performance.md`` has the measured costs.

Entries of a ray after its last segment of non-zero length are padding: they contribute
nothing, and their cotangents are zero.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp

from operators.jax_precision import check_precision
from operators.rte.batches import batch_rays_for
from operators.rte.dispatch import choose_sweeps, radiance, radiance_forward_mode
from operators.rte.tables import RTETables


def _on_bins(kernel, tables: RTETables, fields, lengths, background=None):
    """``kernel`` (a radiance on the tables' spectral points) per bin: the background given per
    bin is taken at each of its points, the radiance averaged over each bin's points."""
    if not tables.binned:
        return kernel(tables, fields, lengths, background)
    if background is not None:
        background = background[..., tables.point_bin]
    at_points = kernel(tables, fields, lengths, background) * tables.point_weight
    return jnp.zeros(at_points.shape[:-1] + (tables.n_bins,), at_points.dtype
                     ).at[..., tables.point_bin].add(at_points)


_radiance_jit = jax.jit(lambda batch_rays, sweeps, *args: _on_bins(
    partial(radiance, batch_rays, sweeps), *args), static_argnums=(0, 1))


def radiance_kernel(batch_rays: int, forward_mode: bool = False, sweeps: str | None = None):
    """The kernel as a JAX function ``radiance(tables, fields, lengths, background=None)``,
    unchecked.

    For building maps around the kernel (:class:`operators.rte.operator.KernelOperator`):
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
    kernel = radiance_forward_mode if forward_mode else radiance
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
        (call inside :func:`operators.precision`; :class:`~operators.rte.operator.EmissionRTE`
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
    kernel = partial(_on_bins, partial(radiance_forward_mode, batch_rays, sweeps), tables)
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

