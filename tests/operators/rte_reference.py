"""Float64 NumPy reference of the emission RTE and small synthetic tables, for tests only.

The reference follows the formal solution term by term: one ray at a time, one segment at a
time, exact Planck radiance and the cross-section spline evaluated by
:class:`operators.tabulated.PiecewiseCubic`.
"""

import numpy as np

import operators as op
from operators.planck import BOLTZMANN, planck
from operators.tabulated import PiecewiseCubic


def reference_radiance(wavenumber, temperatures, sigma, fields, lengths, pressure=101325.0):
    """Spectral radiance (n_rays, n_eta) in W/(m²·sr·cm⁻¹).

    Parameters
    ----------
    wavenumber : (n_eta,) cm⁻¹
    temperatures : (n_T,) K, spline nodes
    sigma : (n_T, n_species, n_eta) cross-sections at the nodes in cm²/molecule
    fields : (1 + n_species, n_rays, n_seg) T in K and mole fractions
    lengths : (n_rays, n_seg) m
    pressure : Pa
    """
    spline = PiecewiseCubic(temperatures, sigma)
    n_rays, n_seg = lengths.shape
    out = np.zeros((n_rays, wavenumber.size))
    for r in range(n_rays):
        transmittance = np.ones(wavenumber.size)
        for k in range(n_seg):
            temperature = fields[0, r, k]
            density = pressure / (BOLTZMANN * temperature)  # molecules / m^3
            kappa = np.zeros(wavenumber.size)
            for s in range(sigma.shape[1]):
                kappa += fields[1 + s, r, k] * density * spline(temperature)[s] * 1e-4
            t = np.exp(-kappa * lengths[r, k])
            out[r] += planck(wavenumber, temperature) * (1.0 - t) * transmittance
            transmittance = transmittance * t
    return out


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
