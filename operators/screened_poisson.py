r"""The inverse of a screened Laplacian on a grid, :math:`(c_f I + a\,D^\mathsf{T} D)^{-1}`,
exactly and in :math:`O(N \log N)`.

With :math:`D = (D_x, D_y, D_z)` the forward differences of :mod:`operators.derivatives` (the
last difference along each axis zero), :math:`D_d^\mathsf{T} D_d` is the Neumann Laplacian of
axis :math:`d`, diagonal in the orthonormal type-II cosine basis with eigenvalues
:math:`(4/\Delta_d^2)\sin^2(\pi k / 2 n_d)`, :math:`k = 0 \dots n_d - 1` (Strang, SIAM Review 41,
1999). The operator solves :math:`(c_f - a\nabla^2) u = v` per field :math:`f` by a cosine
transform, a division and the inverse transform (:func:`scipy.fft.dctn`): symmetric and positive
definite for :math:`c_f > 0`, a preconditioner for objectives whose curvature is a quadratic
smoothness penalty (the voxel grid's Tikhonov term) on top of a nearly diagonal data term.
"""

from __future__ import annotations

import numpy as np
from scipy.fft import dctn, idctn

from operators.base import LinearOperator
from operators.derivatives import _check_dims, _spacing


class ScreenedPoissonSolve(LinearOperator):
    r""":math:`v \mapsto (c_f I + a\,D^\mathsf{T} D)^{-1} v` on ``(n_fields, nx, ny, nz)``
    fields (self-adjoint).

    Parameters
    ----------
    dims : tuple of 4 int
        ``(n_fields, nx, ny, nz)``.
    spacing : float or tuple of 3 float
        Grid spacing in m, as for :func:`operators.Gradient`.
    weight : float
        :math:`a \ge 0`, the weight of :math:`D^\mathsf{T} D` (units of :math:`c` times m²).
    shift : float or array_like of n_fields floats
        :math:`c_f > 0`, per field or one for all.
    dtype : numpy dtype, optional
        Operator dtype (default float64).
    """

    def __init__(self, dims, spacing, weight: float, shift, dtype=np.float64):
        dims = _check_dims(dims)
        shift = np.broadcast_to(np.asarray(shift, dtype=np.float64), (dims[0],))
        if not (np.isfinite(weight) and weight >= 0):
            raise ValueError(f"weight must be a finite number >= 0, got {weight}")
        if not np.all(np.isfinite(shift) & (shift > 0)):
            raise ValueError(f"shift must be finite and positive per field, got {shift}")
        eigenvalues = sum(
            (4.0 / step**2) * np.sin(np.pi * np.arange(n) / (2 * n)).reshape(
                [n if axis == a else 1 for a in range(3)]) ** 2
            for axis, (n, step) in enumerate(zip(dims[1:], _spacing(spacing), strict=True)))
        self.weight = float(weight)
        self.shift = shift
        self.inverse_eigenvalues = 1.0 / (shift.reshape(-1, 1, 1, 1) + weight * eigenvalues)
        super().__init__(dims, dims, dtype=dtype, name="ScreenedPoissonSolve")

    def power(self, x, p: float = 1.0) -> np.ndarray:
        r""":math:`(c_f I + a\,D^\mathsf{T} D)^{-p} x` in float64: the operator for
        ``p = 1``, its square root for 1/2, the screened Laplacian itself for -1.

        Parameters
        ----------
        x : array_like, shape ``dims``
            Fields.
        p : float, optional
            The power (default 1).
        """
        spectrum = dctn(np.asarray(x, np.float64), type=2, axes=(1, 2, 3), norm="ortho")
        return idctn(spectrum * self.inverse_eigenvalues ** p, type=2, axes=(1, 2, 3),
                     norm="ortho")

    def _forward(self, x):
        return self.power(x).astype(np.result_type(x, self.dtype), copy=False)

    def _adjoint(self, y):
        return self._forward(y)
