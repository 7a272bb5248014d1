"""RowMean: the mean over groups of rows, exact in the dot test, and its size checks."""

import numpy as np
import pytest

import operators as op


def test_row_mean_is_exact_in_the_dot_test():
    mean = op.RowMean(5, 4, 3)
    x = np.arange(60.0).reshape(20, 3)
    np.testing.assert_allclose(mean(x), x.reshape(5, 4, 3).mean(axis=1))
    assert op.dottest(mean, rtol=1e-13).passed


@pytest.mark.parametrize("bad", [0, -4, 2.5, True])
def test_row_mean_rejects_bad_sizes(bad):
    with pytest.raises(ValueError, match="positive integer"):
        op.RowMean(3, bad, 2)
