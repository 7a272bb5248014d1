r"""Do the spectra ask for a more compact start? A third calibrated number, its shape.

Usage: python studies/start_compactness.py --truth runs/validation/<flame>.npz

The calibrated start (:func:`invflame.experiments.calibration.calibrate_start`) scales the
band tomography's progress field :math:`s_0` by an amplitude :math:`a` and fits the state
relation's temperature factor :math:`h`. Its hot volume comes out above the truth's. This
fits one more number to the spectra, by Nelder–Mead on the full line-by-line model from the
calibrated :math:`(a, h)`, in one of two forms that would make the start more compact if the
spectra asked for it:

- ``power``: :math:`s = a\,m\,(s_0/m)^{p}` (:math:`m` the peak of :math:`s_0`; :math:`p > 1`
  narrows the flame, :math:`p < 1` widens it), fitted in :math:`\log p` within
  :math:`[1/2, 4]`;
- ``offset``: :math:`s = a \max(s_0 - c\,m, 0)/(1 - c)` (the faint flanks removed), :math:`c`
  within :math:`[0, 0.6]`.

For each start it prints MSE_T, MSE_CO2 and the hot-volume ratio against the truth (a
diagnosis on the tuning half, not a choice) and χ²/M against the study's data.
"""

import argparse

import numpy as np
from scipy.optimize import minimize

from invflame.experiments.calibration import AMPLITUDE_RANGE, calibrate_start
from invflame.experiments.method_problem import method_problem
from invflame.experiments.metrics import field_scores
from invflame.experiments.parameters import state_relation
from invflame.representations.whitening import noise_weights

FORMS = {"power": (np.log(2.0), (np.log(0.5), np.log(4.0))), "offset": (0.1, (0.0, 0.6))}
"""Each form's simplex step and bounds of its third number (log p, or c)."""

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="start_compactness", description=__doc__.split("\n")[0])
    parser.add_argument("--truth", required=True)
    args = parser.parse_args()
    setup = method_problem("VG/Tikh.", args.truth, settings={("init", "calibrate"): False})
    scene, measurement, start = setup.scene, setup.measurement, setup.start
    relation = state_relation(setup.cfg, scene)
    sigma = measurement.sigma if measurement.noisy else None
    weights = noise_weights(sigma, measurement.data.shape)

    def chi2(fields) -> float:
        residual = (scene.simulate(fields) - measurement.data) * weights
        return float(np.sum(residual ** 2)) / np.count_nonzero(weights)

    def report(label: str, fields, numbers: str) -> None:
        scores = field_scores(setup.truth, fields)
        print(f"| {label} | {scores['mse']['T']:.5f} | {scores['mse']['CO2']:.5f} | "
              f"{scores['hot_volume_ratio']:.2f} | {chi2(fields):.4g} | {numbers} |", flush=True)

    print(f"{args.truth}: the study's data and band tomography (quick preset)")
    print("| start | MSE_T | MSE_CO2 | hot vol. | χ²/M | fitted |")
    print("|---|---:|---:|---:|---:|---|")
    report("band tomography", start, "")
    calibrated = calibrate_start(scene, measurement.data, start, relation, sigma)
    report("calibrated (a, h)", calibrated.fields,
           f"a {calibrated.amplitude:.3f}, h {calibrated.factor:.3f}")
    s0 = relation.invert(start[:4])[0]
    peak = float(s0.max())

    def shaped(form: str, log_amplitude: float, factor: float, shape: float) -> np.ndarray:
        if form == "power":
            s = peak * (s0 / peak) ** np.exp(shape)
        else:
            s = np.maximum(s0 - shape * peak, 0.0) / (1.0 - shape)
        s = np.minimum(np.exp(log_amplitude) * s, relation.progress_max)
        return np.concatenate([np.stack(relation.states(s, factor)), start[4:]]
                              ).astype(start.dtype)

    for form, (step, bounds) in FORMS.items():
        x0 = np.array([np.log(calibrated.amplitude), calibrated.factor, 0.0])
        result = minimize(lambda x, form=form: chi2(shaped(form, *x)), x0, method="Nelder-Mead",
                          bounds=[np.log(AMPLITUDE_RANGE), relation.factor_range, bounds],
                          options={"xatol": 0.01, "fatol": 1e-4 * calibrated.chi2_after,
                                   "initial_simplex": [x0, x0 + [0.3, 0, 0], x0 + [0, 0.3, 0],
                                                       x0 + [0, 0, step]]})
        log_a, h, shape = result.x
        third = f"p {np.exp(shape):.3f}" if form == "power" else f"c {shape:.3f}"
        report(f"calibrated + {form}", shaped(form, *result.x),
               f"a {np.exp(log_a):.3f}, h {h:.3f}, {third}")
