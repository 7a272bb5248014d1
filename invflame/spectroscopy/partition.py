"""Total internal partition sums Q(T) from TIPS.

Values come from HAPI's offline TIPS-2025 tables (``hapi.partitionSum``; Gamache et al. 2025,
JQSRT 345, 109568). Each (molecule, isotopologue) is tabulated once per process every 5 K over
its TIPS range and interpolated with a cubic spline in ln Q; the interpolation agrees with
``hapi.partitionSum`` to about 1e-7 relative between 200 and 2500 K.
"""

from __future__ import annotations

import contextlib
import functools
import io
import threading

import numpy as np
from scipy.interpolate import CubicSpline

_STEP = 5.0  # K
_IMPORT_LOCK = threading.Lock()


@functools.cache
def hapi_module():
    """The ``hapi`` module, imported once without its start-up banner on stdout."""
    with _IMPORT_LOCK, contextlib.redirect_stdout(io.StringIO()):
        import hapi
    return hapi


@functools.cache
def _tips_spline(molecule: int, isotopologue: int) -> CubicSpline:
    hapi = hapi_module()
    grid = hapi.TIPS_2025_ISOT_HASH.get((molecule, isotopologue))
    if grid is None:
        raise KeyError(
            f"TIPS has no partition function for molecule {molecule}, "
            f"isotopologue {isotopologue}"
        )
    t_min, t_max = float(np.min(grid)), float(np.max(grid))
    temperatures = np.append(np.arange(t_min, t_max, _STEP), t_max)
    q = np.asarray(hapi.partitionSum(molecule, isotopologue, temperatures.tolist()))
    return CubicSpline(temperatures, np.log(q))


def tips_range(molecule: int, isotopologue: int) -> tuple[float, float]:
    """Temperature range (K) over which TIPS tabulates Q for this isotopologue."""
    nodes = _tips_spline(int(molecule), int(isotopologue)).x
    return float(nodes[0]), float(nodes[-1])


def partition_function(molecule: int, isotopologue: int, temperature) -> np.ndarray:
    """Total internal partition sum Q(T) (dimensionless).

    Parameters
    ----------
    molecule, isotopologue : int
        HITRAN molecule and isotopologue numbers.
    temperature : array_like
        Temperatures in K, any shape.

    Returns
    -------
    ndarray, same shape as ``temperature``

    Raises
    ------
    ValueError
        If a temperature lies outside the TIPS range of the isotopologue.
    """
    spline = _tips_spline(int(molecule), int(isotopologue))
    temperature = np.asarray(temperature, dtype=np.float64)
    t_min, t_max = spline.x[0], spline.x[-1]
    if np.any(temperature < t_min) or np.any(temperature > t_max) or np.isnan(temperature).any():
        raise ValueError(
            f"temperature outside the TIPS range {t_min:g}-{t_max:g} K of molecule {molecule} "
            f"isotopologue {isotopologue}: got {temperature.min():g}-{temperature.max():g} K"
        )
    return np.exp(spline(temperature))
