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
f_v        1e-6           0 – 10 (:data:`SOOT_MAX`) where soot is reconstructed
=========  =============  ==========================================

The scales are constants, never derived from data, so that results of different runs are
comparable.
"""

from __future__ import annotations

import numpy as np

FIELD_NAMES = ("T", "CO2", "H2O", "CH4")
SCALES = np.array([1000.0, 0.1, 0.1, 0.1])
"""Reference scale per field: K for temperature, dimensionless for mole fractions."""

SOOT_SCALE = 1e-6
"""Reference scale of the soot volume fraction, the fifth field when soot is reconstructed
(dimensionless: 1 ppm, a lightly sooting flame)."""

SOOT_MAX = 1e-5
"""Default upper bound of a reconstructed soot volume fraction (dimensionless, 10 ppm: above
the peak of laminar methane and ethylene flames, about 0.1–10 ppm)."""


def per_field(values, shape) -> np.ndarray:
    """One value per field ``(n,)`` broadcast to fields of shape ``shape`` = ``(n, ...)``
    (a read-only view), e.g. bounds or scales on a grid ``(n, nx, ny, nz)``; ``n`` is 4
    (T, CO2, H2O, CH4) or 5 (and the soot volume fraction)."""
    values = np.asarray(values)
    if values.shape not in ((4,), (5,)) or len(shape) < 1 or shape[0] != values.size:
        raise ValueError(f"per_field takes 4 values (T, CO2, H2O, CH4) and a fields shape "
                         f"(4, ...), or 5 of each with soot; got values of shape "
                         f"{values.shape} and shape {shape}")
    return np.broadcast_to(values.reshape((values.size,) + (1,) * (len(shape) - 1)), shape)


def field_scales(n_fields: int = 4) -> np.ndarray:
    """The scales :data:`SCALES`, with :data:`SOOT_SCALE` appended for 5 fields."""
    if n_fields not in (4, 5):
        raise ValueError(f"fields are 4 (T, CO2, H2O, CH4) or 5 (and soot), got {n_fields}")
    return np.append(SCALES, SOOT_SCALE)[:n_fields]


def _scales(fields: np.ndarray) -> np.ndarray:
    scales = field_scales(len(fields))
    return per_field(scales, (scales.size,) + (1,) * (fields.ndim - 1)).astype(fields.dtype)


def normalize(fields: np.ndarray) -> np.ndarray:
    """Physical fields ``(4, ...)`` (T in K, mole fractions; a fifth: the soot volume
    fraction) → normalized fields."""
    fields = np.asarray(fields)
    return fields / _scales(fields)


def denormalize(normalized: np.ndarray) -> np.ndarray:
    """Normalized fields ``(4, ...)`` or ``(5, ...)`` → physical fields (T in K, mole
    fractions, soot volume fraction)."""
    normalized = np.asarray(normalized)
    return normalized * _scales(normalized)


def physical_bounds(t_min: float, t_max: float,
                    soot_max: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper physical bounds per field: T in [t_min, t_max] K, 0 ≤ X ≤ 1, and with
    ``soot_max`` a fifth field, the soot volume fraction in [0, soot_max] (dimensionless)."""
    if not 0 < t_min < t_max:
        raise ValueError(f"temperature bounds must satisfy 0 < t_min < t_max (K), got "
                         f"{t_min}, {t_max}")
    lower, upper = np.array([t_min, 0.0, 0.0, 0.0]), np.array([t_max, 1.0, 1.0, 1.0])
    if soot_max is None:
        return lower, upper
    if not 0 < soot_max < 1:
        raise ValueError(f"soot_max must lie in (0, 1) (a volume fraction), got {soot_max}")
    return np.append(lower, 0.0), np.append(upper, soot_max)
