"""EmissionRTE forward: slab solutions, limits, float32 in thin and thick regions, input checks
(every backend against the reference: ``test_rte_backends.py``)."""

import numpy as np
import pytest
from rte_reference import random_rays, reference_radiance, synthetic_sigma

from operators.base import precision
from operators.rte import EmissionRTE, RTETables, emission_radiance
from operators.rte.planck import BOLTZMANN, planck
from operators.tabulated import PiecewiseCubic

ETA, NODES, SIGMA = synthetic_sigma()
COEF = PiecewiseCubic(NODES, SIGMA).coef
P = 101325.0


def tables(dtype=np.float64, planck_mode="exact"):
    return RTETables.from_spline(ETA, NODES, COEF, P, dtype, planck_mode)


def kappa(temperature, fractions):
    """Absorption coefficient (n_eta,) in 1/m of a homogeneous gas, from the reference spline."""
    sigma = PiecewiseCubic(NODES, SIGMA)(np.asarray(temperature, float))  # (3, n_eta) cm^2
    return np.asarray(fractions) @ sigma * P / (BOLTZMANN * temperature) * 1e-4


def slab_rays(states, lengths):
    """One ray through consecutive homogeneous slabs (nearest the camera first)."""
    fields = np.array([[s[0] for s in states]] + [[s[1][i] for s in states] for i in range(3)])
    return fields[:, None, :], np.asarray(lengths, float)[None, :]


HOT = (1800.0, (0.1, 0.2, 0.0))
COLD = (600.0, (0.05, 0.02, 0.0))


@pytest.mark.usefixtures("x64")
def test_homogeneous_slab_matches_closed_form():
    fields, lengths = slab_rays([HOT], [0.3])
    radiance = np.asarray(emission_radiance(tables(), fields, lengths))[0]
    expected = planck(ETA, HOT[0]) * -np.expm1(-kappa(*HOT) * 0.3)
    np.testing.assert_allclose(radiance, expected, rtol=1e-12)


@pytest.mark.usefixtures("x64")
def test_slab_cut_into_segments_equals_one_segment():
    one = emission_radiance(tables(), *slab_rays([HOT], [0.3]))
    cut = emission_radiance(tables(), *slab_rays([HOT] * 5, [0.01, 0.1, 0.04, 0.1, 0.05]))
    np.testing.assert_allclose(cut, one, rtol=1e-12)


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("order", [(HOT, COLD), (COLD, HOT)])
def test_two_slabs_in_both_orders(order):
    (near, far), (l_near, l_far) = order, (0.2, 0.35)
    radiance = np.asarray(emission_radiance(tables(), *slab_rays([near, far], [l_near, l_far])))
    t_near = np.exp(-kappa(*near) * l_near)
    expected = (planck(ETA, near[0]) * (1 - t_near)
                + t_near * planck(ETA, far[0]) * (1 - np.exp(-kappa(*far) * l_far)))
    np.testing.assert_allclose(radiance[0], expected, rtol=1e-12)
    swapped = np.asarray(emission_radiance(tables(), *slab_rays([far, near], [l_far, l_near])))
    assert np.max(np.abs(swapped - radiance)) > 1e-3 * radiance.max()


def test_transparent_gas_emits_nothing():
    fields, lengths = slab_rays([(1500.0, (0.0, 0.0, 0.3))] * 3, [0.2, 0.3, 0.1])
    for dtype in (np.float32, np.float64):
        with precision(dtype):
            radiance = np.asarray(emission_radiance(tables(dtype, "table"), fields, lengths))
        assert np.all(radiance == 0.0)


def test_optically_thick_gas_shows_the_segment_nearest_the_camera():
    thick = (900.0, (0.5, 0.5, 0.0))
    fields, lengths = slab_rays([thick, HOT], [1e4, 0.5])
    for dtype, rtol in ((np.float64, 1e-12), (np.float32, 1e-6)):
        with precision(dtype):
            radiance = np.asarray(emission_radiance(tables(dtype), fields, lengths))[0]
        np.testing.assert_allclose(radiance, planck(ETA, thick[0]), rtol=rtol)


def test_float32_stays_accurate_in_thin_and_thick_spectral_regions():
    fields, lengths = random_rays(n_rays=5, n_seg=12, seed=3)
    for scale in (1e-4, 1.0, 30.0):  # optically thin ... thick
        f = fields.copy()
        f[1:] *= scale
        expected = reference_radiance(ETA, NODES, SIGMA, f, lengths, P)
        radiance = np.asarray(emission_radiance(tables(np.float32, "table"), f, lengths))
        np.testing.assert_allclose(radiance, expected, rtol=1e-5)


def test_operator_shapes_dtype_and_skipped_species():
    _, lengths = random_rays(n_rays=4, n_seg=6)
    rte = EmissionRTE(ETA, NODES, COEF, lengths)
    assert rte.dims == (4, 4, 6) and rte.dimsd == (4, ETA.size)
    assert rte.dtype == np.float32
    assert rte.tables.species == (0, 1)  # CH4 has zero cross-section here


@pytest.mark.usefixtures("x64")
def test_bad_inputs_are_reported():
    with pytest.raises(ValueError, match="coef must have shape"):
        RTETables.from_spline(ETA, NODES, COEF[:, :-1], P)
    with pytest.raises(ValueError, match="planck must be"):
        RTETables.from_spline(ETA, NODES, COEF, P, planck="fast")
    with pytest.raises(ValueError, match="fields must have shape"):
        emission_radiance(tables(), np.ones((3, 2, 4)), np.ones((2, 4)))
    with pytest.raises(ValueError, match="lengths must have shape"):
        emission_radiance(tables(), np.ones((4, 2, 4)), np.ones((2, 5)))


def test_float64_tables_outside_64_bit_mode_are_refused_not_rounded():
    """Without JAX's 64-bit mode, JAX would compute float64 tables' kernel in float32."""
    fields, lengths = slab_rays([HOT], [0.3])
    with pytest.raises(ValueError, match=r"64-bit mode is off here.*operators.precision"):
        emission_radiance(tables(), fields, lengths)
    with precision(np.float64):
        assert emission_radiance(tables(), fields, lengths).dtype == np.float64


@pytest.mark.usefixtures("x64")
def test_operator_from_prepared_tables_equals_the_one_from_splines():
    fields, lengths = random_rays(n_rays=5, n_seg=7, seed=4)
    prepared = tables(np.float64, "table")
    rte = EmissionRTE.from_tables(prepared, lengths, batch_rays=2)
    from_splines = EmissionRTE(ETA, NODES, COEF, lengths, P, np.float64, "table", batch_rays=2)
    assert rte.tables is prepared and rte.dtype == np.float64 and rte.dims == from_splines.dims
    np.testing.assert_array_equal(rte(fields), from_splines(fields))
    np.testing.assert_array_equal(rte(fields), emission_radiance(prepared, fields, lengths, 2))
    with pytest.raises(TypeError, match="RTETables.from_spline"):
        EmissionRTE.from_tables(COEF, lengths)
