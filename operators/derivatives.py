r"""Forward-difference derivatives :math:`D_x, D_y, D_z` and the stacked :class:`Gradient`.

On a grid of fields shaped ``(n_fields, nx, ny, nz)`` with spacings :math:`\Delta_x, \Delta_y,
\Delta_z` (m),

.. math:: (D_x f)_{c,i,j,k} = (f_{c,i+1,j,k} - f_{c,i,j,k}) / \Delta_x, \quad i < n_x - 1,

and :math:`(D_x f)_{c,n_x-1,j,k} = 0` (the last difference is zero), likewise along y and z.
The operators wrap :class:`pylops.FirstDerivative` (``kind="forward"``), whose adjoint is exact.
"""

from __future__ import annotations

import numpy as np

from operators.adapters import aslinearoperator
from operators.base import LinearOperator
from operators.combinators import vstack
from operators.pylops_import import pylops

_AXES = {"x": 1, "y": 2, "z": 3}


def _check_dims(dims) -> tuple[int, int, int, int]:
    dims = tuple(int(d) for d in dims)
    if len(dims) != 4 or min(dims) < 1:
        raise ValueError(
            f"dims must be (n_fields, nx, ny, nz) with positive sizes, got {dims}"
        )
    return dims


def _spacing(spacing) -> tuple[float, float, float]:
    spacing = (float(spacing),) * 3 if np.isscalar(spacing) else tuple(map(float, spacing))
    if len(spacing) != 3 or min(spacing) <= 0:
        raise ValueError(f"spacing must be a positive scalar or (dx, dy, dz) in m, got {spacing}")
    return spacing


def derivative(dims, axis: str, spacing=1.0, dtype=np.float64) -> LinearOperator:
    """Forward difference along one spatial axis of a ``(n_fields, nx, ny, nz)`` grid.

    Parameters
    ----------
    dims : tuple of 4 int
        ``(n_fields, nx, ny, nz)``.
    axis : {"x", "y", "z"}
        Direction of the difference.
    spacing : float or tuple of 3 float, optional
        Grid spacing in m, scalar or ``(dx, dy, dz)`` (default 1).
    dtype : numpy dtype, optional
        Operator dtype (default float64).

    Returns
    -------
    LinearOperator
        ``(n_fields, nx, ny, nz) -> (n_fields, nx, ny, nz)``, in units of 1/m times the field's.
    """
    dims = _check_dims(dims)
    if axis not in _AXES:
        raise ValueError(f"axis must be one of 'x', 'y', 'z', got {axis!r}")
    step = _spacing(spacing)[_AXES[axis] - 1]
    op = pylops.FirstDerivative(dims, axis=_AXES[axis], sampling=step, kind="forward",
                                edge=False, dtype=dtype)
    return aslinearoperator(op, name=f"D_{axis}")


def D_x(dims, spacing=1.0, dtype=np.float64) -> LinearOperator:  # noqa: N802
    """Forward difference along x; see :func:`derivative`."""
    return derivative(dims, "x", spacing, dtype)


def D_y(dims, spacing=1.0, dtype=np.float64) -> LinearOperator:  # noqa: N802
    """Forward difference along y; see :func:`derivative`."""
    return derivative(dims, "y", spacing, dtype)


def D_z(dims, spacing=1.0, dtype=np.float64) -> LinearOperator:  # noqa: N802
    """Forward difference along z; see :func:`derivative`."""
    return derivative(dims, "z", spacing, dtype)


def Gradient(dims, spacing=1.0, dtype=np.float64) -> LinearOperator:  # noqa: N802
    """The stacked forward differences :math:`(D_x, D_y, D_z)`.

    Parameters
    ----------
    dims : tuple of 4 int
        ``(n_fields, nx, ny, nz)``.
    spacing : float or tuple of 3 float, optional
        Grid spacing in m (default 1).
    dtype : numpy dtype, optional
        Operator dtype (default float64).

    Returns
    -------
    LinearOperator
        ``(n_fields, nx, ny, nz) -> (3, n_fields, nx, ny, nz)``, directions in order x, y, z.
    """
    return vstack([derivative(dims, a, spacing, dtype) for a in "xyz"], name="Gradient")
