"""What a run's summary says beside the solver's result: the protocol in words, the misfit per
measured value and the scores against a ground truth."""

from __future__ import annotations

import numpy as np

from invflame.experiments.metrics import field_scores, psnr
from invflame.measurement import Measurement


def protocol(cfg: dict, measurement: Measurement) -> dict[str, str]:
    """What made a result, in words: the start, the data, the noise, the weight λ, the
    unknowns and the forward model."""
    init, data, reg = cfg["init"], cfg["data"], cfg["regularizer"]
    calibrated = ("; amplitude and heat per product fitted to the spectra" if init["calibrate"]
                  else "")
    starts = {"band-tomography": "data-driven (band-integrated linear tomography + "
                                 f"Burke-Schumann state relation{calibrated}); knows nothing "
                                 "of the truth",
              "ambient": "ambient air; knows nothing of the truth",
              "noisy-truth": f"ground truth + {init['noise']:g} relative Gaussian noise (the "
                             "paper's protocol: starts from the answer)"}
    record = measurement.provenance
    if data["source"]:
        made = f"measured, read from {data['source']}"
    elif data["inverse_crime"]:
        made = "inverse crime: the reconstruction's own grid, sub-rays and line-by-line step"
    else:
        made = (f"truth on its {'x'.join(map(str, record['grid']))} grid, "
                f"{record['rays_per_pixel']} sub-rays/pixel, line-by-line step "
                f"{record['step_cm-1']:g} cm-1")
    noise = cfg["noise"]
    if not measurement.noisy and data["source"]:
        said = "unknown (the file holds no noise): the misfit is unweighted"
    elif not measurement.noisy:
        said = "none (noise-free data)"
    elif data["source"]:
        sigma = measurement.sigma[np.isfinite(measurement.sigma)]
        said = (f"from the file: sigma {sigma.min():.3g}-{sigma.max():.3g} W/(m2 sr cm-1); "
                f"{measurement.data.size - measurement.n_measurements} masked values")
    elif noise["kind"] == "snr":
        said = f"Gaussian, peak SNR {noise['snr']:g}"
    else:
        said = (f"Gaussian, NESR {noise['nesr']} W/(m2 sr cm-1) (peak SNR "
                f"{record['peak_snr']:.0f})")
    parameters = {"state-relation": "per point the methane state relation's progress and "
                                    "temperature factor",
                  "fields": "per point T and the mole fractions"}
    return {"start": starts[init["kind"]], "data": made, "noise": said,
            "lambda": f"{reg['lambda']} ({reg['scaling']} scaling)",
            "unknowns": parameters[cfg["representation"]["parameters"]],
            "model": forward_model(cfg["spectrum"])}


def forward_model(spectrum: dict) -> str:
    """The forward model's spectroscopy in words: broadening and spectral points."""
    broadening = {"local": "lines broadened and shifted by each point's own H2O and CO2 "
                           "fractions",
                  "fixed": "lines broadened at fixed X_CO2 = 0.1 and X_H2O = 0.2"}
    points = spectrum["points_per_bin"]
    inside = (f"up to {points} spectral points per {spectrum['step']:g} cm-1 bin where lines "
              "saturate inside it" if points > 1 else
              f"one optical depth per {spectrum['step']:g} cm-1 bin")
    return f"{broadening[spectrum['broadening']]}; {inside}"


def misfit_name(noisy: bool) -> str:
    """What :func:`chi2_per_value` is, in the words of the logs: χ²/M for data with a noise σ,
    the mean square misfit with its units for data without."""
    return "chi2/M" if noisy else "mean square misfit [(W/(m2 sr cm-1))^2]"


def chi2_per_value(simulated: np.ndarray, measurement: Measurement) -> float:
    r"""Noise-weighted misfit per measured value, :math:`\chi^2/M` (≈ 1 at the noise level;
    the plain mean squared misfit in (W/(m²·sr·cm⁻¹))² for noise-free data); masked values
    (σ = inf) left out."""
    residual = (simulated - measurement.data) / measurement.sigma
    return float(np.sum(residual.astype(np.float64) ** 2) / measurement.n_measurements)


def truth_scores(truth: np.ndarray, fields: np.ndarray, start: np.ndarray) -> dict:
    """The summary's scores against a ground truth (fields ``(4, nx, ny, nz)``: T in K, mole
    fractions, a fifth the soot volume fraction): those of
    :func:`~invflame.experiments.metrics.field_scores` for the result and, suffixed
    ``_initial``, for the start, and the result's PSNR in dB. Soot is scored (``"soot"``) only
    when both the truth and the result hold it."""
    scores, initial = field_scores(truth, fields), field_scores(truth, start)
    return {**scores, "mse_initial": initial["mse"], "mse_flame_initial": initial["mse_flame"],
            "hot_volume_ratio_initial": initial["hot_volume_ratio"],
            "psnr_db": psnr(truth, fields)}
