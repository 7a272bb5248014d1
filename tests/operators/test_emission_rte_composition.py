"""EmissionRTE with cross-sections that depend on each species' own mole fraction: values
against a reference that interpolates with ``np.interp``, dot and Taylor tests, float32."""

import numpy as np
import pytest
from rte_reference import formal_solution, synthetic_sigma

import operators as op
from operators.base import precision
from operators.rte import EmissionRTE, RTETables, emission_radiance
from operators.rte.blocks import fraction_weights
from operators.rte.planck import BOLTZMANN, planck
from operators.tabulated import PiecewiseCubic

P = 101325.0
#: CO2 linear in its fraction (two nodes), H2O on four nodes, CH4 without lines.
FRACTION_NODES = ((0.0, 1.0), (0.0, 0.1, 0.3, 1.0), (0.0,))


def composition_sigma(n_eta=30):
    """Cross-sections (n_T, 7 columns, n_eta): one column per species and fraction node, each
    node's lines of its own strength, so that the interpolation shows."""
    eta, nodes, base = synthetic_sigma(n_eta=n_eta)
    factors = [(1.0, 1.6), (0.7, 1.0, 1.5, 2.4), (0.0,)]
    columns = [base[:, s] * f for s, species in enumerate(factors) for f in species]
    wiggle = 1.0 + 0.3 * np.sin(np.arange(len(columns))[:, None] * eta[None, :] / 7.0)
    return eta, nodes, np.stack(columns, axis=1) * wiggle[None]


ETA, NODES, SIGMA = composition_sigma()
SPLINE = PiecewiseCubic(NODES, SIGMA)


def reference_radiance(fields, lengths):
    """The reference formal solution (:func:`rte_reference.formal_solution`) with the
    cross-sections interpolated in each species' own mole fraction by ``np.interp`` (constant
    beyond the nodes), segment by segment."""
    first = np.cumsum([0, *map(len, FRACTION_NODES)])
    tau = np.zeros(lengths.shape + (ETA.size,))
    for r, k in np.ndindex(lengths.shape):
        temperature = fields[0, r, k]
        columns = SPLINE(temperature)
        for s, nodes in enumerate(FRACTION_NODES):
            x = fields[1 + s, r, k]
            own = columns[first[s]:first[s + 1]]
            sigma = np.array([np.interp(x, nodes, own[:, j]) for j in range(ETA.size)])
            tau[r, k] += x * P / (BOLTZMANN * temperature) * sigma * 1e-4 * lengths[r, k]
    with precision(np.float64):
        return formal_solution(planck(ETA, fields[0][..., None]), tau)


def mid_interval_rays(n_rays=4, n_seg=5, seed=3):
    """Fields whose mole fractions lie inside node intervals (the map is smooth there), T in
    K, lengths in m, and a direction that keeps every fraction inside its interval."""
    rng = np.random.default_rng(seed)
    fields = np.zeros((4, n_rays, n_seg))
    fields[0] = rng.uniform(400.0, 2300.0, (n_rays, n_seg))
    fields[1] = rng.uniform(0.02, 0.2, (n_rays, n_seg))
    fields[2] = rng.choice([0.05, 0.2, 0.6], (n_rays, n_seg))
    lengths = rng.uniform(0.01, 0.05, (n_rays, n_seg))
    direction = rng.uniform(-1.0, 1.0, fields.shape)
    direction[0] *= 30.0
    direction[1] *= 0.01
    direction[2] *= 0.03
    direction[3] = 0.0
    return fields, lengths, direction


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize(("sweeps", "planck_mode", "rtol"), [
    ("xla", "exact", 1e-10),
    ("numba", "table", 2e-7),  # Numba's sweeps take the Planck spline, accurate to 1e-7
])
def test_radiance_interpolates_in_each_species_own_fraction(sweeps, planck_mode, rtol):
    fields, lengths, _ = mid_interval_rays()
    fields[2, 0, :] = [0.0, 0.1, 0.3, 1.0, 0.95]  # on the nodes and at the ends
    tables = RTETables.from_spline(ETA, NODES, SPLINE.coef, P, np.float64, planck_mode,
                                   fraction_nodes=FRACTION_NODES)
    assert tables.fraction_nodes == FRACTION_NODES[:2]  # CH4 has no lines
    ours = emission_radiance(tables, fields, lengths, sweeps=sweeps)
    np.testing.assert_allclose(ours, reference_radiance(fields, lengths), rtol=rtol)


@pytest.mark.parametrize("planck_mode", ["exact", "table"])
def test_dot_and_taylor_tests_through_the_composition(planck_mode):
    fields, lengths, direction = mid_interval_rays()
    rte = EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, np.float64, planck_mode,
                      batch_rays=3, fraction_nodes=FRACTION_NODES)
    dot = op.jacobian_dottest(rte, fields, rtol=1e-12)
    assert dot.passed, dot
    taylor = op.taylor_test(rte, fields, direction, h0=1.0)
    assert taylor.passed, taylor
    assert abs(taylor.rate0 - 1) < 0.05 and taylor.rate1 > 1.9
    # the H2O derivative is the interpolated cross-section's: it changes across a node
    w = np.ones(rte.dimsd)
    below, above = fields.copy(), fields.copy()
    below[2], above[2] = 0.0999, 0.1001
    assert not np.allclose(rte.vjp(below, w)[2], rte.vjp(above, w)[2], rtol=1e-2)


def test_float32_agrees_with_float64():
    fields, lengths, _ = mid_interval_rays(seed=8)
    values = [EmissionRTE(ETA, NODES, SPLINE.coef, lengths, P, dtype, "table",
                          fraction_nodes=FRACTION_NODES)(fields) for dtype in (np.float32,
                                                                               np.float64)]
    np.testing.assert_allclose(values[0], values[1], rtol=2e-5)


def test_fraction_weights_and_bad_nodes():
    lower, weight = fraction_weights((0.0, 0.1, 0.3), np.array([-0.1, 0.0, 0.05, 0.3, 0.9]))
    np.testing.assert_array_equal(lower, [0, 0, 0, 1, 1])
    np.testing.assert_allclose(weight, [0.0, 0.0, 0.5, 1.0, 1.0])
    with pytest.raises(ValueError, match="increasing mole fractions"):
        RTETables.from_spline(ETA, NODES, SPLINE.coef, P, fraction_nodes=((0.0, 1.0),
                                                                          (0.3, 0.1, 0.0, 1.0),
                                                                          (0.0,)))
    with pytest.raises(ValueError, match="7 columns but fraction_nodes name 6"):
        RTETables.from_spline(ETA, NODES, SPLINE.coef, P,
                              fraction_nodes=((0.0, 1.0), (0.0, 0.1, 1.0), (0.0,)))
