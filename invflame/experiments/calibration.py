r"""Two numbers of a data-driven start fitted to the spectra: its amplitude and its heat.

The band-tomography start (:mod:`invflame.experiments.data_start`) solves a linear, optically
thin problem and maps its emission density to gas states through a state relation whose
temperature rise is assumed. Both choices bias it in one direction over the whole flame:
non-negativity and smoothing spread the peaks and lower them, saturated lines lower the band
integral, and the assumed rise sets how many products the gas holds per kelvin. On the
packaged pool fire (quick preset) the start's spectra misfit the data by χ²/M ≈ 10⁴.

:func:`calibrate_start` keeps the start's shape and fits two global numbers to the measured
spectra with the full nonlinear line-by-line model: an amplitude :math:`a` of the progress
field and the temperature factor :math:`h` of the state relation
(:class:`~invflame.representations.state_relation.StateRelation`),

.. math:: \min_{a,\,h}\; \chi^2\big(\mathrm{states}(\min(a\,s_0,\ s_\max),\ h)\big),

by Nelder–Mead on :math:`(\log a, h)` inside the relation's bounds. Each evaluation is one
forward simulation. No truth enters. Where the flame's products per kelvin differ from the
assumed rise, :math:`h` is what the spectra say of it: on the packaged pool fire (quick honest
scene, data as ``invflame study`` makes them) it took 42 simulations to find
:math:`a` = 1.47 and :math:`h` = 1.54, against the truth's median :math:`h` of 1.52 (the
relation's inverse over its gas with over 1 % of CO₂ + H₂O), and the misfit fell from
χ²/M = 10 659 to 163 (``invflame study`` logs the numbers of each run; ``python
studies/fit_diagnosis.py`` scores both starts).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from invflame.representations.state_relation import StateRelation
from invflame.representations.whitening import noise_weights

AMPLITUDE_RANGE = (0.25, 4.0)
"""Bounds of the amplitude :math:`a` of the progress field (dimensionless)."""


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate_start`.

    Attributes
    ----------
    fields : ndarray, shape of the start
        The calibrated start: T in K, mole fractions of CO2, H2O, CH4 (and the start's soot).
    amplitude : float
        :math:`a`, the factor on the start's progress (dimensionless).
    factor : float
        :math:`h`, the state relation's temperature factor (dimensionless).
    chi2_before, chi2_after : float
        Misfit per measured value of the start and of the calibrated start (noise-weighted
        when the noise is known, else in (W/(m²·sr·cm⁻¹))²).
    evaluations : int
        Forward simulations spent.
    """

    fields: np.ndarray
    amplitude: float
    factor: float
    chi2_before: float
    chi2_after: float
    evaluations: int

    def as_dict(self) -> dict:
        """Plain numbers, for JSON and logs."""
        return {"amplitude": self.amplitude, "factor": self.factor,
                "chi2_per_value_before": self.chi2_before,
                "chi2_per_value_after": self.chi2_after, "evaluations": self.evaluations}


def calibrate_start(scene, data, start, relation: StateRelation, sigma=None,
                    tolerance: float = 0.01) -> Calibration:
    r"""Fit the amplitude :math:`a` and temperature factor :math:`h` of a start to the data.

    Parameters
    ----------
    scene : invflame.scene.Scene
        The reconstruction scene (:meth:`~invflame.scene.Scene.simulate`).
    data : ndarray, shape (n_pixels, n_out)
        Measured spectra in W/(m²·sr·cm⁻¹).
    start : ndarray, shape (4, nx, ny, nz) or (5, nx, ny, nz)
        Starting fields (T in K, mole fractions; a fifth, the soot volume fraction, is kept
        as it is); their progress :math:`s_0` is ``relation.invert(start[:4])[0]``.
    relation : StateRelation
        Gives the states and the bounds of :math:`s` and :math:`h`.
    sigma : float or array_like, optional
        Noise standard deviation in W/(m²·sr·cm⁻¹) (``inf`` for a masked value); None: an
        unweighted misfit.
    tolerance : float, optional
        Of :math:`\log a` and :math:`h` (dimensionless) for the simplex (default 0.01).

    Returns
    -------
    Calibration
    """
    data, start = np.asarray(data), np.asarray(start)
    weights = noise_weights(sigma, data.shape)
    weights = np.ones(data.shape) if weights is None else weights
    counted = max(int(np.count_nonzero(weights)), 1)
    progress = relation.invert(start[:4])[0]
    low, high = relation.factor_range
    evaluations = 0

    def fields_at(log_amplitude, factor):
        s = np.minimum(np.exp(log_amplitude) * progress, relation.progress_max)
        return np.concatenate([np.stack(relation.states(s, factor)), start[4:]]
                              ).astype(start.dtype)

    def chi2(fields):
        return float(np.sum(np.square((scene.simulate(fields) - data) * weights))) / counted

    def misfit(point):
        nonlocal evaluations
        evaluations += 1
        return chi2(fields_at(*point))

    before = chi2(start)
    x0 = np.array([0.0, min(max(1.0, low), high)])
    result = minimize(misfit, x0, method="Nelder-Mead",
                      bounds=[np.log(AMPLITUDE_RANGE), (low, high)],
                      options={"xatol": tolerance, "fatol": 1e-4 * before,
                               "initial_simplex": [x0, x0 + [np.log(2.0), 0.0],
                                                   [x0[0], min(x0[1] + 0.5, high)]]})
    log_amplitude, factor = (float(v) for v in result.x)
    return Calibration(fields_at(log_amplitude, factor), float(np.exp(log_amplitude)), factor,
                       before, float(result.fun), evaluations)
