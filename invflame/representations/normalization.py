"""The fixed normalization shared by representations, regularizers and solvers.

Solvers and regularizers see *normalized* fields :math:`u_c = f_c / s_c`, one fixed reference
scale per field, so that temperature (K) and mole fractions (dimensionless) have comparable
magnitudes and one weight λ serves all fields:

=========  =============  ==========================================
field      scale s_c      typical normalized range in a flame
=========  =============  ==========================================
T          1000 K         0.3 (ambient) – 2.0
X_CO2      0.1            0 – 1
X_H2O      0.1            0 – 2
X_CH4      0.1            0 – 10 at a fuel inlet
=========  =============  ==========================================

The scales are constants, never derived from data, so that results of different runs are
comparable.
"""

from __future__ import annotations

import numpy as np

FIELD_NAMES = ("T", "CO2", "H2O", "CH4")
SCALES = np.array([1000.0, 0.1, 0.1, 0.1])
"""Reference scale per field: K for temperature, dimensionless for mole fractions."""


def per_field(values, shape) -> np.ndarray:
    """One value per field ``(4,)`` broadcast to fields of shape ``shape`` = ``(4, ...)``
    (a read-only view), e.g. bounds or scales on a grid ``(4, nx, ny, nz)``."""
    values = np.asarray(values)
    if values.shape != (4,) or len(shape) < 1 or shape[0] != 4:
        raise ValueError(f"per_field takes 4 values (T, CO2, H2O, CH4) and a fields shape "
                         f"(4, ...); got values of shape {values.shape} and shape {shape}")
    return np.broadcast_to(values.reshape((4,) + (1,) * (len(shape) - 1)), shape)


def _scales(ndim: int) -> np.ndarray:
    return per_field(SCALES, (4,) + (1,) * (ndim - 1))


def normalize(fields: np.ndarray) -> np.ndarray:
    """Physical fields ``(4, ...)`` (T in K, mole fractions) → normalized fields."""
    fields = np.asarray(fields)
    return fields / _scales(fields.ndim).astype(fields.dtype)


def denormalize(normalized: np.ndarray) -> np.ndarray:
    """Normalized fields ``(4, ...)`` → physical fields (T in K, mole fractions)."""
    normalized = np.asarray(normalized)
    return normalized * _scales(normalized.ndim).astype(normalized.dtype)


def physical_bounds(t_min: float, t_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper physical bounds per field: T in [t_min, t_max] K, 0 ≤ X ≤ 1."""
    if not 0 < t_min < t_max:
        raise ValueError(f"temperature bounds must satisfy 0 < t_min < t_max (K), got "
                         f"{t_min}, {t_max}")
    return np.array([t_min, 0.0, 0.0, 0.0]), np.array([t_max, 1.0, 1.0, 1.0])
