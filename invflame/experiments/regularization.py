"""The regularizer's weight in a run: λ scaled as configured (``regularizer.scaling``, see
:mod:`invflame.experiments.runner`) or chosen from the data by the discrepancy principle, and
the run's problem at a weight."""

from __future__ import annotations

from pathlib import Path

import solvers
from invflame.atomic_files import write_json
from invflame.errors import ConfigError
from invflame.experiments.model_error import estimate_model_error
from invflame.measurement import Measurement
from invflame.scene import Scene


def regularizer_weight(cfg: dict, scene: Scene, measurement: Measurement, lam: float) -> float:
    """The solver's weight of the regularizer for a configured λ (*Weighting* in
    :mod:`invflame.experiments.runner`):
    λ·M under ``"chi2"`` scaling (:func:`solvers.problem_weight`), λ·R (pixels) under
    ``"paper"``."""
    if cfg["regularizer"]["scaling"] == "paper":
        return lam * scene.n_rays
    return solvers.problem_weight(lam, measurement.n_measurements)


def configured_problem(cfg: dict, scene: Scene, representation, measurement: Measurement,
                       lam: float, x0=None) -> solvers.Problem:
    """The run's inverse problem: ``representation``'s problem with the configured regularizer
    at λ on the configuration's scale (:func:`regularizer_weight`), the misfit weighted by
    the noise σ under ``"chi2"`` scaling, unweighted under ``"paper"``; masked values (σ =
    inf: bad pixels and wavenumbers, channels outside a camera's window) weigh 0 under both.

    Parameters
    ----------
    cfg : dict
        Validated configuration (``regularizer.kind``, ``regularizer.scaling``).
    scene : Scene
    representation : VoxelRepresentation, NeuralFieldRepresentation, ...
    measurement : Measurement
        Data and noise σ (W/(m²·sr·cm⁻¹)).
    lam : float
        λ, dimensionless on the configuration's scale.
    x0 : ndarray, optional
        Starting parameters.
    """
    reg = cfg["regularizer"]
    return representation.problem(
        measurement.data, regularizer=reg["kind"],
        lam=regularizer_weight(cfg, scene, measurement, lam), x0=x0,
        sigma=measurement.sigma if reg["scaling"] == "chi2" else measurement.unweighted_sigma)


def solver_options(cfg: dict, measurement: Measurement) -> dict:
    """The configured solver's options and stopping rules, with ``solver.stop_chi2`` as the
    misfit it stops at (:class:`solvers.stopping.StoppingRule`: χ² ≤ level·M).

    Raises
    ------
    ConfigError
        If ``solver.stop_chi2`` is set and the data carry no noise σ (noise-free synthetic
        data, or a measurement file without noise).
    """
    options, level = dict(cfg["solver"]["options"]), cfg["solver"]["stop_chi2"]
    if level > 0:
        if not measurement.noisy:
            raise ConfigError(f"'solver.stop_chi2' = {level!r} stops at a noise-weighted misfit "
                              "χ²/M, and these data have no noise σ (noise.kind = 'none', or a "
                              "measurement file without noise): set stop_chi2 = 0, or give the "
                              "data their noise")
        options["misfit_target"] = level * measurement.n_measurements
    return options


def choose_lambda(cfg: dict, scene: Scene, representation, measurement: Measurement, x0,
                  out: Path, log) -> solvers.ParameterChoice:
    """λ by Morozov's discrepancy principle (:func:`solvers.discrepancy_principle`).

    Every trial solves the configured problem from ``x0`` with the configured solver and
    stopping rules; the choice and all trials go to ``lambda_choice.json`` and
    ``l_curve.png`` in ``out``. With ``regularizer.tau = "model-error"``, τ is 1 plus the
    model error of ``scene`` estimated from prior flames
    (:func:`invflame.experiments.model_error.estimate_model_error`, written to
    ``model_error.json``).

    Parameters
    ----------
    cfg : dict
        Validated configuration (``regularizer.lambda_range``, ``regularizer.tau``).
    scene : Scene
        The reconstruction's scene.
    representation : VoxelRepresentation, NeuralFieldRepresentation, ...
        Gives the problem for each λ.
    measurement : Measurement
        Data and noise σ.
    x0 : ndarray
        Starting parameters of every trial.
    out : Path
        Output folder.
    log : callable
        Receives one line per trial.

    Raises
    ------
    ConfigError
        If the data carry no noise σ (noise-free synthetic data, or a measurement file
        without noise): the rule has nothing to compare the misfit with.
    """
    if not measurement.noisy:
        raise ConfigError("'regularizer.lambda' = 'discrepancy' needs data with a noise σ, and "
                          "these data have none (noise.kind = 'none', or a measurement file "
                          "without noise): give lambda a number, or the file its noise")
    from invflame.plotting.parameter_choice import plot_l_curve  # matplotlib, once a run draws

    reg, solver = cfg["regularizer"], cfg["solver"]
    m = measurement.n_measurements
    per_epoch = representation.iterations_per_epoch

    def solve_at(lam):
        problem = configured_problem(cfg, scene, representation, measurement, lam, x0)
        result = solvers.solve(problem, solver["name"],
                               max_iter=solver["iterations"] * per_epoch, seed=cfg["seed"],
                               **solver_options(cfg, measurement))
        final = problem.evaluate(result.x)
        log(f"lambda {lam:.4g}: chi2/M {final.misfit / m:.4g}, Phi {final.regularizer:.4g} "
            f"after {result.iterations} iterations ({result.stop_reason})")
        return result.x, final.misfit, final.regularizer

    tau = reg["tau"]
    if tau == "model-error":
        error = estimate_model_error(cfg, scene, measurement, seed=cfg["seed"], log=log)
        write_json(out / "model_error.json", error.as_dict())
        tau = error.tau
        log(f"model error from {error.chi2_per_value.size} prior flames: chi2/M {error.level:.4g}"
            f" (spread {error.chi2_per_value.min():.4g}-{error.chi2_per_value.max():.4g}); "
            f"tau = {tau:.4g}")
    low, high = reg["lambda_range"]
    choice = solvers.discrepancy_principle(solve_at, m, high, low, tau=tau, refine=2)
    write_json(out / "lambda_choice.json", choice.as_dict())
    plot_l_curve(choice, out / "l_curve.png")
    log(choice.message)
    return choice
