"""ILSConvolution: lineshape, normalization, adjoint, edges."""

import numpy as np
import pytest

import operators as op
from operators.ils import triangular_ils

ETA = np.arange(650.0, 725.0 + 1e-9, 0.04)


def test_dot_test_and_shapes():
    ils = op.ILSConvolution(ETA, n_rays=9, resolution=8.0)
    assert ils.dims == (9, ETA.size)
    assert ils.out_wavenumber[0] == pytest.approx(658.0)
    assert np.allclose(np.diff(ils.out_wavenumber), 2.0)
    assert op.dottest(ils, rtol=1e-10).passed


def test_lineshape_has_unit_area_first_zero_and_fwhm():
    nu = np.linspace(-400, 400, 800_001)
    shape = triangular_ils(nu, 8.0)
    tails = 1.0 / (np.pi**2 * 400 / 8.0)  # mean sin^2 = 1/2 beyond 50 zeros on each side
    assert np.trapezoid(shape, nu) == pytest.approx(1.0 - tails, abs=2e-5)
    assert triangular_ils(8.0, 8.0) == pytest.approx(0.0, abs=1e-15)
    half = nu[shape >= shape.max() / 2]
    assert half[-1] - half[0] == pytest.approx(0.886 * 8.0, rel=2e-3)


def test_flat_spectrum_is_reproduced_and_a_line_keeps_its_area():
    ils = op.ILSConvolution(ETA, n_rays=1, resolution=8.0, out_wavenumber=np.arange(670, 706))
    np.testing.assert_allclose(ils(np.full((1, ETA.size), 2.5)), 2.5, rtol=1e-12)
    line = np.zeros((1, ETA.size))
    line[0, np.argmin(abs(ETA - 688.0))] = 1.0 / 0.04  # unit-area line at 688 cm-1
    out = ils(line)[0]
    # the window keeps ~98 % of the lineshape's area; renormalization lifts the peak by ~2 %
    assert out.argmax() == 688 - 670
    assert out.max() == pytest.approx(triangular_ils(0.0, 8.0), rel=0.03)
    nu = np.linspace(-60, 60, 240_001)
    shape = triangular_ils(nu, 8.0)
    seen = (nu >= 670 - 688.5) & (nu <= 705 - 687.5)  # output points at 1 cm-1 spacing
    window = (nu >= 650 - 688) & (nu <= 725 - 688)
    expected = np.trapezoid(shape * seen, nu) / np.trapezoid(shape * window, nu)
    assert out.sum() * 1.0 == pytest.approx(expected, rel=5e-3)


def test_bad_grids_are_rejected():
    with pytest.raises(ValueError, match="uniform"):
        op.ILSConvolution(np.r_[650, 651, 653.0], n_rays=1)
    with pytest.raises(ValueError, match="inside the line-by-line window"):
        op.ILSConvolution(ETA, n_rays=1, out_wavenumber=[640.0])
    with pytest.raises(ValueError, match="narrower"):
        op.ILSConvolution(ETA[:100], n_rays=1)


def test_irregular_measured_grid_passes_the_dot_test_and_keeps_flat_spectra():
    rng = np.random.default_rng(3)
    measured = np.sort(rng.uniform(662.0, 712.0, 17))  # a spectrometer's own, uneven samples
    ils = op.ILSConvolution(ETA, n_rays=5, resolution=8.0, out_wavenumber=measured)
    np.testing.assert_array_equal(ils.out_wavenumber, measured)
    assert ils.dtype == np.float64 and op.dottest(ils, rtol=1e-10).passed
    np.testing.assert_allclose(ils(np.full((5, ETA.size), 1.5)), 1.5, rtol=1e-12)
    # a decreasing grid measures the same spectra, in its own order
    reverse = op.ILSConvolution(ETA, n_rays=5, resolution=8.0, out_wavenumber=measured[::-1])
    x = rng.standard_normal(ils.dims)
    np.testing.assert_allclose(reverse(x), ils(x)[:, ::-1], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("grid, message", [
    ([670.0, 680.0, 680.0, 690.0], "point 2 \\(680 cm-1\\)"),
    ([670.0, 690.0, 680.0], "point 2 \\(680 cm-1\\)"),
    ([670.0, np.nan], "finite"),
    ([[670.0, 680.0]], "1-D"),
])
def test_measured_grids_that_are_not_monotone_are_named(grid, message):
    with pytest.raises(ValueError, match=message):
        op.ILSConvolution(ETA, n_rays=1, out_wavenumber=grid)
