"""Generated 12C16O2 lines against the HITRAN validation slice in ../shared/linedata."""

import numpy as np
import pytest

from invflame.spectroscopy import co2_lines
from invflame.spectroscopy.co2_validation import format_report, validate_against_par
from invflame.spectroscopy.line_parameters import line_intensity


@pytest.fixture(scope="module")
def comparison(shared_linedata):
    return validate_against_par(shared_linedata / "CO2_HITRAN_691.4-692.7_validation.par")


FIRST_BANDS = [("01101", "00001"), ("02201", "01101"), ("10002", "01101"), ("10001", "01101")]
FIRST_BANDS += [("03301", "02201")]

# bands whose upper or both levels come from the extrapolated effective Hamiltonian
MODEL_BANDS = [("06601", "05501"), ("07701", "06601"), ("08801", "07701"), ("14401", "13301")]
MODEL_BANDS += [("14402", "13302"), ("15501", "14401"), ("15502", "14402"), ("22202", "21102")]
MODEL_BANDS += [("23302", "22202"), ("11111", "10011"), ("31102", "30002")]


def _first_bands(c, J_max=60, pairs=FIRST_BANDS):
    """Which matched lines belong to the (upper, lower) ``pairs`` with J'' up to ``J_max``."""
    v = co2_lines.levels()
    bands = {(v[up].hitran_v, v[lo].hitran_v) for up, lo in pairs}
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


def test_extrapolated_bands_positions_and_intensities(comparison):
    model = _first_bands(comparison, J_max=80, pairs=MODEL_BANDS)
    assert model.sum() >= 15
    # measured |dnu| <= 0.1 cm-1 except the bending ladder drifting with v2 (08801<-07701: -0.19)
    assert np.abs(comparison.position_error()[model]).max() < 0.25
    assert np.median(np.abs(comparison.position_error()[model])) < 0.06
    ratio = comparison.intensity_ratio(1500.0)[model]
    assert np.all((ratio > 0.9) & (ratio < 1.1))


def test_every_reference_band_with_flame_weight_is_generated(comparison):
    # the 7 unmatched reference lines are ℓ-resonance borrowed or Q lines beyond the window edge
    assert comparison.unmatched_share("reference", 1000.0) < 0.001
    assert comparison.unmatched_share("reference", 1500.0) < 0.002


def test_total_slice_intensity_at_flame_temperatures(comparison):
    # measured: 1.011 at 1000 K, 1.051 at 1500 K (edge lines of misplaced Q/R lines dominate)
    assert comparison.total_ratio(1000.0) == pytest.approx(1.0, abs=0.05)
    assert comparison.total_ratio(1500.0) == pytest.approx(1.0, abs=0.10)


def test_temperature_scaling_is_identity_at_296(comparison):
    ref = comparison.reference
    np.testing.assert_allclose(line_intensity(ref, 296.0), ref.S296, rtol=1e-12)


def test_report_lists_totals(comparison):
    text = format_report(comparison, max_rows=5)
    assert "total intensity at 1000 K" in text and "total intensity at 1500 K" in text
