"""Soot in the emission kernel: a Rayleigh continuum C f_v eta added to the gas, a fifth field."""

import numpy as np
import pytest
from rte_reference import check_derivatives, random_rays, reference_radiance, synthetic_sigma

from operators.rte import EmissionRTE, RTETables, emission_radiance
from operators.rte.planck import planck
from operators.rte.tables import rayleigh_soot_constant
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)
SPLINE = PiecewiseCubic(NODES, SIGMA)
P = 101325.0
C = rayleigh_soot_constant()


def sooty_rays(n_rays, n_seg, seed):
    """Gas fields of :func:`random_rays` with a soot volume fraction of a few ppm appended."""
    fields, lengths = random_rays(n_rays=n_rays, n_seg=n_seg, seed=seed)
    soot = np.random.default_rng(seed + 100).uniform(0.0, 5e-6, fields.shape[1:])
    return np.concatenate([fields, soot[None]]), lengths


def test_the_rayleigh_constant_of_a_given_refractive_index():
    n, k = 2.0, 1.0
    assert rayleigh_soot_constant(n, k) == pytest.approx(36 * np.pi * 2 / (5.0**2 + 16.0))
    assert 3.0 < C < 3.4  # Chang & Charalampopoulos near 675 cm-1
    with pytest.raises(ValueError, match="n > 0 and k > 0"):
        rayleigh_soot_constant(2.0, 0.0)


@pytest.mark.usefixtures("x64")
def test_soot_adds_its_continuum_to_the_gas_absorption():
    """A ray through soot alone is a grey-ish slab: B(T)(1 - exp(-C f_v eta 100 L))."""
    fields, lengths = sooty_rays(4, 5, seed=3)
    tables = RTETables.from_spline(ETA, NODES, SPLINE.coef, P, np.float64, "exact", soot=C)
    assert tables.n_fields == 5
    soot_only = fields.copy()
    soot_only[1:4] = 0.0
    soot_only[0] = 1500.0
    soot_only[4] = 4e-6
    path = lengths.sum(axis=1, keepdims=True)
    expected = planck(ETA, 1500.0) * -np.expm1(-C * 4e-6 * ETA * 1e2 * path)
    np.testing.assert_allclose(emission_radiance(tables, soot_only, lengths), expected,
                               rtol=1e-12)
    # without soot the gas alone, as the reference computes it
    sootless = np.concatenate([fields[:4], np.zeros_like(fields[4:])])
    np.testing.assert_allclose(emission_radiance(tables, sootless, lengths),
                               reference_radiance(ETA, NODES, SIGMA, fields[:4], lengths, P),
                               rtol=1e-12)


@pytest.mark.parametrize("planck_mode", ["exact", "table"])
def test_soot_field_dot_and_taylor_tests(planck_mode):
    fields, lengths = sooty_rays(5, 7, seed=9)
    rte = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float64, planck_mode,
                      batch_rays=2, soot=C)
    assert rte.dims == (5, 5, 7)
    check_derivatives(rte, fields, rtol=1e-10)


@pytest.mark.usefixtures("x64")
def test_soot_fields_are_required_and_the_constant_checked():
    fields, lengths = random_rays(n_rays=3, n_seg=4)
    tables = RTETables.from_spline(ETA, NODES, SPLINE.coef, P, np.float64, soot=C)
    with pytest.raises(ValueError, match=r"shape \(5, n_rays, n_seg\).*soot volume fraction"):
        emission_radiance(tables, fields, lengths)
    with pytest.raises(ValueError, match="positive Rayleigh constant"):
        RTETables.from_spline(ETA, NODES, SPLINE.coef, P, np.float64, soot=-1.0)
