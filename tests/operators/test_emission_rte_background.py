"""Emission kernel in front of a background: I = I_flame + tau_ray I_bg, its derivatives, a slab."""

import numpy as np
import pytest
from rte_reference import check_derivatives, random_rays, synthetic_sigma

from operators.rte import EmissionRTE
from operators.rte.planck import BOLTZMANN, planck
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma(n_eta=40)
SPLINE = PiecewiseCubic(NODES, SIGMA)
P = 101325.0


def wall(n_rays, seed=3):
    """A different grey-body background per ray, W/(m2 sr cm-1)."""
    rng = np.random.default_rng(seed)
    return rng.uniform(0.3, 0.9, (n_rays, 1)) * planck(ETA, rng.uniform(300, 900, (n_rays, 1)))


def test_no_background_leaves_the_numbers_unchanged():
    fields, lengths = random_rays(n_rays=5, n_seg=6, seed=12)
    plain = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float32, "table")
    zero = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float32, "table",
                       background=np.zeros(ETA.size))
    assert plain.background is None
    np.testing.assert_array_equal(plain(fields), zero(fields))


@pytest.mark.parametrize("planck_mode", ["exact", "table"])
def test_jacobian_dot_and_taylor_tests_with_background(planck_mode):
    fields, lengths = random_rays(n_rays=5, n_seg=7, seed=13)
    rte = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float64, planck_mode,
                      batch_rays=2, background=wall(5))
    check_derivatives(rte, fields, rtol=1e-10)


@pytest.mark.parametrize("planck_mode", ["exact", "table"])
def test_uniform_slab_in_front_of_a_black_body_wall(planck_mode):
    r"""B(T)(1 - e^{-kappa L}) + e^{-kappa L} eps B(T_wall) for a slab of uniform gas."""
    sigma = np.broadcast_to(SIGMA[2:3], SIGMA.shape).copy()  # cross-sections constant in T
    spline = PiecewiseCubic(NODES, sigma)
    temperature, x_co2, length, n_seg = 1400.0, 0.08, 0.3, 12
    t_wall, emissivity = 650.0, 0.85
    fields = np.zeros((4, 1, n_seg))
    fields[0], fields[1] = temperature, x_co2
    lengths = np.full((1, n_seg), length / n_seg)
    background = emissivity * planck(ETA, t_wall)
    rte = EmissionRTE(ETA, NODES, spline.coef, lengths, P, np.float64, planck_mode,
                      background=background)
    kappa = x_co2 * P / (BOLTZMANN * temperature) * sigma[0, 0] * 1e-4  # m-1
    transmittance = np.exp(-kappa * length)
    expected = planck(ETA, temperature) * (1 - transmittance) + transmittance * background
    assert np.ptp(transmittance) > 0.3  # optically thin and thick wavenumbers both
    rtol = 1e-12 if planck_mode == "exact" else 1e-6  # the Planck spline's tolerance
    np.testing.assert_allclose(rte(fields)[0], expected, rtol=rtol)


def test_bad_background_shape_is_named():
    fields, lengths = random_rays(n_rays=3, n_seg=4)
    with pytest.raises(ValueError, match=r"background must have shape \(n_rays, n_eta\)"):
        EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float64, background=np.ones(3))
