r"""Means over consecutive rows: many samples of one measurement averaged into it.

For ``x`` of shape ``(n_groups · group, n_cols)``,

.. math:: (M x)_{g,c} = \frac{1}{m} \sum_{i=0}^{m-1} x_{g m + i,\, c}, \qquad
          (M^\mathsf{T} y)_{g m + i,\, c} = \frac{y_{g,c}}{m},

with :math:`m` = ``group``: e.g. the sub-ray spectra of a camera pixel averaged into the
pixel's spectrum (a pixel integrates the radiance over its footprint).
"""

from __future__ import annotations

import numpy as np

from operators.base import LinearOperator


class RowMean(LinearOperator):
    """Mean over groups of ``group`` consecutive rows: ``(n_groups·group, n_cols) → (n_groups,
    n_cols)``, any unit; the adjoint spreads each value, divided by ``group``, over its rows.

    Parameters
    ----------
    n_groups : int
        Number of output rows (e.g. pixels).
    group : int
        Rows averaged into one (e.g. sub-rays per pixel).
    n_cols : int
        Length of each row (e.g. wavenumbers).
    dtype : numpy dtype, optional
        float32 or float64 (default).
    """

    def __init__(self, n_groups: int, group: int, n_cols: int, dtype=np.float64):
        sizes = {"n_groups": n_groups, "group": group, "n_cols": n_cols}
        for name, value in sizes.items():
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ValueError(f"{name} must be a positive integer, got {value!r}")
        self.group = int(group)
        super().__init__((int(n_groups) * self.group, int(n_cols)), (int(n_groups), int(n_cols)),
                         dtype=dtype, name="RowMean")

    def _forward(self, x):
        n_groups, n_cols = self.dimsd
        return x.reshape(n_groups, self.group, n_cols).mean(axis=1)

    def _adjoint(self, y):
        n_groups, n_cols = self.dimsd
        spread = np.broadcast_to(y[:, None, :] / self.group, (n_groups, self.group, n_cols))
        return spread.reshape(self.dims)
