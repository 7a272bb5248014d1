"""The start's amplitude and temperature factor fitted to the spectra."""

import numpy as np
import pytest

from invflame.experiments.calibration import calibrate_start
from invflame.representations.state_relation import StateRelation

AIR = [300.0, 0.0, 0.0, 0.0]


@pytest.fixture(scope="module")
def relation():
    return StateRelation(AIR, factor_range=(0.3, 2.0))


@pytest.fixture(scope="module")
def progress(plume, relation):
    return relation.invert(plume)[0]


@pytest.mark.parametrize("amplitude, factor", [(1.6, 1.4), (0.7, 0.8)])
def test_the_two_numbers_that_made_the_data_are_found(tiny_scene64, relation, progress,
                                                      amplitude, factor):
    """Data of the start's shape at another amplitude and factor: both come back, and the
    misfit falls from the start's to nearly nothing."""
    made = np.stack(relation.states(np.minimum(amplitude * progress, relation.progress_max),
                                    factor))
    data = tiny_scene64.simulate(made)
    start = np.stack(relation.states(progress, 1.0))
    result = calibrate_start(tiny_scene64, data, start, relation, sigma=1e-3, tolerance=1e-3)
    assert result.amplitude == pytest.approx(amplitude, rel=0.02)
    assert result.factor == pytest.approx(factor, rel=0.02)
    assert result.chi2_after < 1e-3 * result.chi2_before
    assert result.fields.shape == start.shape
    assert set(result.as_dict()) == {"amplitude", "factor", "chi2_per_value_before",
                                     "chi2_per_value_after", "evaluations"}


def test_masked_values_count_for_nothing(tiny_scene64, relation, progress):
    made = np.stack(relation.states(progress, 1.3))
    data = tiny_scene64.simulate(made).copy()
    sigma = np.full(data.shape, 1e-3)
    data[:, :5] = 1e3  # nonsense where masked
    sigma[:, :5] = np.inf
    result = calibrate_start(tiny_scene64, data, np.stack(relation.states(progress)), relation,
                             sigma=sigma, tolerance=1e-3)
    assert result.factor == pytest.approx(1.3, rel=0.02)
