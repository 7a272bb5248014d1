"""Is the truth a minimizer? The objective of finished voxel runs at their start, at the truth
and at their reconstruction.

Usage: python studies/objective_at_truth.py RUN [RUN ...]

For each run folder (of ``invflame run``, ``study`` or ``studies/lambda_sweep.py``, a voxel
representation with a truth) it rebuilds the run's problem from its ``config.toml`` and its
recorded data (``data.npz``: measured spectra and noise σ) and evaluates the objective
χ² + λMΦ (the runner's weighting,
:func:`~invflame.experiments.regularization.configured_problem`) at three points: the start
(``initial.npz``), the truth averaged onto the grid (``truth.npz``, mapped to the run's
parameters: for the state relation its progress and temperature factor by
:meth:`StateRelation.invert`, clipped to the bounds, the factor of its ambient air, which no
datum sees, filled smoothly from the gas around it; "truth" means the representable field
nearest to it) and the reconstruction (the solver's last parameters, from the run's
``checkpoint.npz``). It prints χ²/M, Φ, the objective and
MSE_T of each point against the truth. A reconstruction whose objective lies far below the
truth's fits what the grid cannot represent (the truth's χ²/M measures that model error): a
solver that reaches the objective's minimum then moves away from the truth, whatever its
speed.
"""

import argparse
from pathlib import Path

import numpy as np

import solvers
from invflame.atomic_files import read_json
from invflame.experiments import config, runner
from invflame.experiments.metrics import normalized_mse
from invflame.experiments.parameters import make_representation
from invflame.experiments.regularization import configured_problem
from invflame.field import Field
from invflame.measurement import Measurement


def smooth_air_factor(theta: np.ndarray, sweeps: int = 500) -> np.ndarray:
    """State-relation parameters with the temperature factor of ambient air (progress below
    1e-3, where :meth:`StateRelation.invert` sets 1) replaced by the harmonic fill of the
    gas's: Jacobi sweeps of the six-neighbour mean, the grid's faces mirrored."""
    theta = np.array(theta, dtype=np.float64)
    air = theta[0] < 1e-3
    factor = theta[1]
    for _ in range(sweeps):
        padded = np.pad(factor, 1, mode="edge")
        mean = sum(np.roll(padded, shift, axis)[1:-1, 1:-1, 1:-1]
                   for axis in range(3) for shift in (1, -1)) / 6.0
        factor = np.where(air, mean, factor)
    theta[1] = factor
    return theta


def rows(folder: Path):
    """``(label, χ²/M, Φ, objective, MSE_T)`` at the start, the truth and the reconstruction
    of the run in ``folder``."""
    cfg = config.validate(config.load(folder / "config.toml"))
    summary = read_json(folder / "summary.json")
    scene = runner.build_scene(cfg)
    representation = make_representation(cfg, scene)
    if representation.kind != "voxel":
        raise SystemExit(f"{folder}: a {representation.kind} run; this study takes voxel runs")
    recorded = np.load(folder / "data.npz")
    measurement = Measurement(recorded["measured"], recorded["sigma"], summary["noisy_data"],
                              {"source": str(folder / "data.npz")})
    m = measurement.n_measurements
    problem = configured_problem(cfg, scene, representation, measurement, summary["lambda"])
    truth = Field.load(folder / "truth.npz").values
    points = {"start": representation.initial_parameters(
                  Field.load(folder / "initial.npz").values),
              "truth": smooth_air_factor(representation.initial_parameters(truth)),
              "reconstruction": solvers.load_checkpoint(folder / "checkpoint.npz").x}
    for label, x in points.items():
        evaluation = problem.evaluate(x)
        fields = representation.fields(x)
        yield (label, evaluation.misfit / m, evaluation.regularizer, evaluation.loss,
               normalized_mse(truth, fields)["T"])


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="objective_at_truth")
    parser.add_argument("runs", type=Path, nargs="+")
    args = parser.parse_args()
    print("| run | point | χ²/M | Φ | objective | MSE_T |")
    print("|---|---|---:|---:|---:|---:|")
    for run in args.runs:
        for label, chi2, phi, loss, mse in rows(run):
            print(f"| {run} | {label} | {chi2:.4g} | {phi:.4g} | {loss:.4g} | {mse:.5f} |",
                  flush=True)
