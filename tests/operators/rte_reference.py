r"""The reference formal solution of the emission RTE, and small synthetic tables and rays, for
tests only.

The reference is the formal solution as it reads,
:math:`I = \sum_k B_k (1 - t_k) P_k + P_n I_\mathrm{bg}` with :math:`P_k = \prod_{j<k} t_j`, in
plain JAX on whole (ray, segment, wavenumber) arrays: cumulative products of the segments'
transmittances, no batching, no custom derivative, in float64; JAX differentiates it. The
cross-sections are the spline :class:`operators.tabulated.PiecewiseCubic` through their values
at the temperature nodes, as the kernel's tables take them. Every backend of the kernel is
tested against it (``test_rte_backends.py``).
"""

import jax.numpy as jnp
import numpy as np

import operators as op
from operators.base import precision
from operators.rte.planck import BOLTZMANN, planck, planck_table
from operators.tabulated import PiecewiseCubic


def formal_solution(emission, tau, background=None):
    """Radiance (n_rays, n_eta) leaving the near end of rays of homogeneous segments.

    Parameters
    ----------
    emission : (n_rays, n_seg, n_eta) Planck radiance of each segment in W/(m²·sr·cm⁻¹),
        segments nearest the camera first
    tau : (n_rays, n_seg, n_eta) optical depth of each segment
    background : (n_rays, n_eta) radiance behind each ray's far end, or None
    """
    through = jnp.cumprod(jnp.exp(-tau), axis=1)  # P_{k+1}: in front of segment k + 1
    before = jnp.concatenate([jnp.ones_like(through[:, :1]), through[:, :-1]], axis=1)  # P_k
    radiance = jnp.sum(emission * -jnp.expm1(-tau) * before, axis=1)
    return radiance if background is None else radiance + through[:, -1] * background


def reference_radiance(wavenumber, temperatures, sigma, fields, lengths, pressure=101325.0,
                       background=None, soot=None, planck_mode="exact"):
    """Spectral radiance (n_rays, n_eta) in W/(m²·sr·cm⁻¹), computed in float64 (JAX's 64-bit
    mode inside): a JAX function of ``fields``, ``lengths`` and ``background``, to be
    differentiated inside :func:`operators.precision` of float64.

    Parameters
    ----------
    wavenumber : (n_eta,) cm⁻¹
    temperatures : (n_T,) K, spline nodes
    sigma : (n_T, n_species, n_eta) cross-sections at the nodes in cm²/molecule
    fields : (1 + n_species, n_rays, n_seg) T in K and mole fractions, then, with ``soot``,
        the soot volume fraction
    lengths : (n_rays, n_seg) m; the entries after a ray's last non-zero length are padding,
        which counts for nothing, in the value and in the derivatives
    pressure : Pa
    background : (n_rays, n_eta) W/(m²·sr·cm⁻¹) behind each ray, or None
    soot : the Rayleigh constant C of the soot's absorption C f_v eta 10^2 in m⁻¹, or None
    planck_mode : "exact", Planck's law, or "table", its not-a-knot cubic spline in T through
        the nodes :func:`operators.rte.planck.planck_table` refines (those of the kernel's
        Planck table)
    """
    with precision(np.float64):
        eta = jnp.asarray(wavenumber, jnp.float64)
        fields = jnp.asarray(fields, jnp.float64)
        lengths = jnp.asarray(lengths, jnp.float64)
        n_species = sigma.shape[1]
        temperature = fields[0]
        density = pressure / (BOLTZMANN * temperature)  # molecules / m^3
        cross = PiecewiseCubic(temperatures, sigma)(temperature)  # (r, k, s, eta) cm^2
        kappa = (jnp.einsum("srk,rkse->rke", fields[1:1 + n_species], cross)
                 * (density * 1e-4)[..., None])
        if soot is not None:
            kappa = kappa + soot * fields[1 + n_species][..., None] * eta * 1e2
        n_seg = lengths.shape[1]
        counts = jnp.max(jnp.where(lengths != 0, jnp.arange(1, n_seg + 1), 0), axis=1)
        real = jnp.arange(n_seg) < counts[:, None]
        tau = kappa * jnp.where(real, lengths, 0.0)[..., None]
        if planck_mode == "table":
            nodes, _ = planck_table(wavenumber, temperatures)
            spline = PiecewiseCubic(nodes, planck(wavenumber[None, :], nodes[:, None]))
            emission = spline(temperature)
        else:
            emission = planck(eta, temperature[..., None])
        if background is not None:
            background = jnp.asarray(background, jnp.float64)
        return formal_solution(emission, tau, background)


def synthetic_sigma(n_eta=50, temperatures=(300.0, 700.0, 1200.0, 1800.0, 2500.0), seed=0,
                    zero_species=(2,)):
    """Small cross-section table with Lorentzian lines whose strength varies with T.

    Returns ``wavenumber`` (n_eta,) in cm⁻¹ over 650–725, ``temperatures`` (n_T,) in K and
    ``sigma`` (n_T, 3, n_eta) in cm²/molecule; the species in ``zero_species`` have σ = 0.
    """
    rng = np.random.default_rng(seed)
    wavenumber = np.linspace(650.0, 725.0, n_eta)
    temperatures = np.asarray(temperatures)
    sigma = np.zeros((temperatures.size, 3, n_eta))
    for s in range(3):
        if s in zero_species:
            continue
        centres = rng.uniform(650.0, 725.0, 6)
        strengths = rng.uniform(0.2, 1.0, 6)
        energies = rng.uniform(0.0, 3000.0, 6)  # lower-state energy, cm^-1
        for c, a, e in zip(centres, strengths, energies, strict=True):
            shape = 1.0 / (1.0 + ((wavenumber - c) / 1.5) ** 2)
            boltzmann = np.exp(-1.4388 * e * (1.0 / temperatures - 1.0 / 1000.0))
            strength = 1e-19 * a * boltzmann * 300.0 / temperatures
            sigma[:, s] += strength[:, None] * shape[None, :]
        sigma[:, s] += 2e-22
    return wavenumber, temperatures, sigma


def random_rays(n_rays=7, n_seg=9, seed=1, t_range=(350.0, 2300.0)):
    """Fields (4, n_rays, n_seg) and lengths (n_rays, n_seg) with ragged padding.

    Ray ``r`` has a random number of real segments (at least one); the rest has length 0 and
    repeats the temperature of the first segment.
    """
    rng = np.random.default_rng(seed)
    fields = np.empty((4, n_rays, n_seg))
    fields[0] = rng.uniform(*t_range, (n_rays, n_seg))
    fields[1] = rng.uniform(0.0, 0.15, (n_rays, n_seg))
    fields[2] = rng.uniform(0.0, 0.2, (n_rays, n_seg))
    fields[3] = rng.uniform(0.0, 0.05, (n_rays, n_seg))
    lengths = rng.uniform(0.005, 0.03, (n_rays, n_seg))
    counts = rng.integers(1, n_seg + 1, n_rays)
    counts[0] = n_seg
    pad = np.arange(n_seg) >= counts[:, None]
    lengths[pad] = 0.0
    fields[0][pad] = np.broadcast_to(fields[0][:, :1], pad.shape)[pad]
    return fields, lengths


def physical_direction(fields, seed=4):
    """A Taylor-test direction along which ``fields + h·direction`` stays physical for h ≤ 1:
    T moves by up to 30 K, each mole or volume fraction by up to half its own value (the
    emission operator refuses negative fractions)."""
    shape = np.random.default_rng(seed).uniform(-1.0, 1.0, fields.shape)
    return np.concatenate([30.0 * shape[:1], 0.5 * fields[1:] * shape[1:]])


def check_derivatives(rte, fields, rtol):
    """Assert the exact derivatives of ``rte`` at ``fields``: the Jacobian's dot test within
    ``rtol`` and a Taylor test along :func:`physical_direction` with rates 1 and 2."""
    dot = op.jacobian_dottest(rte, fields, rtol=rtol)
    assert dot.passed, dot
    taylor = op.taylor_test(rte, fields, physical_direction(fields), h0=1.0)
    assert taylor.passed, taylor
    assert abs(taylor.rate0 - 1) < 0.05 and taylor.rate1 > 1.9
