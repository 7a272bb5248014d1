"""The fields a run starts from, by ``init.kind``: from the data, ambient air, or the paper's
noisy truth."""

from __future__ import annotations

import numpy as np

from invflame.experiments.calibration import calibrate_start
from invflame.experiments.data_start import band_tomography_start
from invflame.experiments.initialization import ambient, noisy_truth, with_soot_field
from invflame.experiments.parameters import state_relation
from invflame.field import Field
from invflame.measurement import Measurement
from invflame.scene import Scene


def initial_fields(cfg: dict, truth: Field, scene: Scene, measurement: Measurement,
                   log=None) -> np.ndarray:
    """Starting fields ``scene.field_shape`` on the reconstruction grid: from the data (band
    tomography, masked values left out; with ``init.calibrate`` its amplitude and the state
    relation's temperature factor then fitted to the measured values of the spectra,
    :func:`~invflame.experiments.calibration.calibrate_start`), ambient air, or the paper's
    noisy truth (``truth`` on the reconstruction grid). When the scene reconstructs soot, the
    data-driven and ambient starts hold none (f_v = 0), the noisy truth its soot with the same
    noise (none for a soot-free truth). ``log``, when given, receives a line on the
    calibration."""
    init = cfg["init"]
    if init["kind"] == "ambient":
        start = ambient(scene.grid.shape, init["ambient"])
    elif init["kind"] == "band-tomography":
        sigma = measurement.sigma if measurement.noisy else None
        start = band_tomography_start(scene, measurement.data, sigma=sigma,
                                      temperature_rise_st=init["temperature_rise"],
                                      ambient=init["ambient"],
                                      measured=measurement.measured
                                      ).astype(np.float32)
        if init["calibrate"]:
            calibration = calibrate_start(scene, measurement.data,
                                          with_soot_field(start, scene.soot_input),
                                          state_relation(cfg, scene),
                                          measurement.unweighted_sigma if sigma is None
                                          else sigma)
            start = calibration.fields
            if log is not None:
                log("start calibrated to the spectra: " + ", ".join(
                    f"{k} {v:.4g}" for k, v in calibration.as_dict().items()))
    else:
        start = noisy_truth(truth.values, init["noise"], seed=cfg["seed"])
    return with_soot_field(start, scene.soot_input)
