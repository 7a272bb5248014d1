"""The forward model's validation: its independent HAPI reference and the measures it prints."""

import hapi_reference
import numpy as np
import validate_forward

from operators.ils import ILSConvolution
from operators.rte.planck import planck


def test_the_reference_planck_law_is_invflames():
    eta = hapi_reference.bin_centres()
    for temperature in (300.0, 1500.0, 2500.0):
        np.testing.assert_allclose(hapi_reference.planck(eta, temperature),
                                   planck(eta, temperature), rtol=1e-12)


def test_hapi_and_invflame_cross_sections_of_the_same_lines_agree(tmp_path, monkeypatch):
    """H2O at 1500 K, x = 0.12: with the same shift convention the two line-by-line codes agree
    to a small part of the forward model's 0.3 % band acceptance."""
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path))
    band, worst, _ = hapi_reference.compare_cross_sections("H2O", 1500.0, 0.12)["invflame's own"]
    assert abs(band) < 1e-3 and worst < 2e-3


def test_the_measures_of_a_known_difference():
    eta = hapi_reference.bin_centres()
    reference = planck(eta, 1200.0) * (0.5 + 0.4 * np.sin(eta))
    model = reference * 1.01
    model[:25] *= 1.02 / 1.01  # the first 1 cm-1 window 2 % off
    measures = validate_forward.compare(model, reference, eta, ILSConvolution(eta, 1))
    assert 0.01 < measures["band"] < 0.02  # every bin 1 % off, 25 of them 2 %
    np.testing.assert_allclose([measures["wide_median"], measures["wide_max"]], [0.01, 0.02],
                               rtol=1e-9)
    assert measures["wide_at"] == eta[:25].mean()
    assert 0.01 - 1e-9 < measures["ils_median"] <= measures["ils_max"] < 0.02
