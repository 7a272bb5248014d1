"""Generated 12C16O2 lines against the HITRAN validation slice in ../shared/linedata."""

import numpy as np
import pytest

from invflame.spectroscopy import co2_lines
from invflame.spectroscopy.co2_validation import format_report, validate_against_par
from invflame.spectroscopy.line_parameters import line_intensity


@pytest.fixture(scope="module")
def comparison(shared_linedata):
    return validate_against_par(shared_linedata / "CO2_HITRAN_691.4-692.7_validation.par")


def _first_bands(c, J_max=60):
    """Matched lines of 01101←00001, 02201/10002/10001←01101 and 03301←02201 up to J''."""
    v = co2_lines.levels()
    bands = {
        (v[up].hitran_v, v[lo].hitran_v)
        for up, lo in [
            ("01101", "00001"),
            ("02201", "01101"),
            ("10002", "01101"),
            ("10001", "01101"),
            ("03301", "02201"),
        ]
    }
    ref = c.reference
    j = c.matched[:, 1]
    return np.array(
        [
            (ref.V_upper[k], ref.V_lower[k]) in bands and int(ref.Q_lower[k][6:9]) <= J_max
            for k in j
        ],
        dtype=bool,
    )


def test_strong_lines_are_matched(comparison):
    S = comparison.reference.S296
    strong = np.flatnonzero(S > 1e-24)
    assert np.isin(strong, comparison.matched[:, 1]).mean() >= 0.95


def test_positions_of_fundamental_and_first_hot_bands(comparison):
    first = _first_bands(comparison)
    assert first.sum() >= 5
    assert np.abs(comparison.position_error()[first]).max() < 0.01


def test_intensities_of_fundamental_and_first_hot_bands(comparison):
    first = _first_bands(comparison)
    for T in (296.0, 1000.0):
        ratio = comparison.intensity_ratio(T)[first]
        assert np.all((ratio > 0.9) & (ratio < 1.1))


def test_intensities_of_all_matched_strong_lines(comparison):
    strong = comparison.reference.S296[comparison.matched[:, 1]] > 1e-26
    ratio = comparison.intensity_ratio(1000.0)[strong]
    assert np.all((ratio > 0.8) & (ratio < 1.35))


def test_total_slice_intensity_at_flame_temperatures(comparison):
    # the missing high hot bands (v2 >= 6, 14401, 22202, ...) grow with temperature
    assert comparison.total_ratio(1000.0) == pytest.approx(1.0, abs=0.12)
    assert comparison.total_ratio(1500.0) == pytest.approx(1.0, abs=0.25)


def test_temperature_scaling_is_identity_at_296(comparison):
    ref = comparison.reference
    np.testing.assert_allclose(line_intensity(ref, 296.0), ref.S296, rtol=1e-12)


def test_report_lists_totals(comparison):
    text = format_report(comparison, max_rows=5)
    assert "total intensity at 1000 K" in text and "total intensity at 1500 K" in text
