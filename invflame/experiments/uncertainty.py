r"""Error bars of a finished voxel run: a posterior standard deviation per voxel and field.

:func:`run_uncertainty` rebuilds the run's problem from its folder (``config.toml``, the
measured spectra and noise σ of ``data.npz``, λ of ``summary.json``, the solver's last
parameters from ``checkpoint.npz``), takes the linearized posterior of its parameters at the
solution (:mod:`invflame.experiments.posterior`) and writes into the folder

====================== ======================================================================
``uncertainty.nc``     CF-style NetCDF (the layout of ``fields.nc``, :mod:`invflame.export`):
                       the reconstruction (and the truth, when the run has one) and
                       ``sigma_T`` [K], ``sigma_X_CO2``, ``sigma_X_H2O``, ``sigma_X_CH4`` [1]
                       (and ``sigma_f_v`` with soot), CF ``standard_error`` of each quantity
``uncertainty.png``    mid-plane cutaways of T beside σ_T (with a truth: the truth's T and
                       the z-score (T̂ − T)/σ_T too)
``uncertainty.json``   the settings, the eigenvalues kept, the cost, and with a truth the
                       calibration: the share of voxels, all and those above 500 K in the
                       truth, whose truth lies within ±1σ and ±2σ of the reconstruction
``uncertainty_z.png``  with a truth: histograms of the z-scores against N(0, 1)
====================== ======================================================================

**From parameters to fields.** Each voxel's fields follow from its own parameters only
(the state relation's progress and temperature factor, or normalized fields), so the
covariance of a voxel's fields is :math:`G\,\Sigma\,G^\mathsf{T}` with :math:`\Sigma` the
posterior covariance of that voxel's parameters (a 2 × 2 block for the state relation:
:meth:`~invflame.experiments.posterior.LaplacePosterior.voxel_covariance`) and :math:`G` the
Jacobian of its fields (:func:`voxel_jacobian`, exact, by JAX). The fields are those the run
reports (``reconstruction.npz``), the mean state of a voxel with a sub-voxel emission model.

**What σ covers.** The noise of the data, seen through the linearized forward map and the
regularizer's prior. It leaves out the model error (grid, sub-rays, line-by-line step):
the run's likelihood holds the noise σ only (the model error of
:mod:`invflame.experiments.model_error` enters the choice of λ, not the weights). Networks
get no σ: their Jacobians cost a pass over the data each (``linearizable`` is false) and
their weights have no prior of which the regularizer is the Hessian.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import xarray as xr

import operators as op
import solvers
from invflame.atomic_files import read_json, write_json
from invflame.errors import ConfigError
from invflame.experiments import config as configuration
from invflame.experiments.inputs import read_data
from invflame.experiments.parameters import make_representation
from invflame.experiments.posterior import LaplacePosterior, laplace_posterior
from invflame.experiments.regularization import configured_problem
from invflame.experiments.run_folder import CHECKPOINT, SUMMARY, RunLock
from invflame.experiments.runner import build_scene
from invflame.export import (
    QUANTITIES,
    fields_dataset,
    run_attributes,
    voxel_variable,
    write_dataset,
)
from invflame.field import SOOTY_FIELD_NAMES, Field
from invflame.measurement import Measurement
from invflame.representations.normalization import field_scales, per_field
from invflame.representations.voxel import relation_fields

NETCDF, FIGURE, REPORT, Z_FIGURE = ("uncertainty.nc", "uncertainty.png", "uncertainty.json",
                                    "uncertainty_z.png")
"""The files :func:`run_uncertainty` writes into a run folder."""

HOT = 500.0
"""Temperature in K above which a truth voxel counts as flame in the calibration."""

CALIBRATED = ("T", "CO2", "H2O")
"""Fields whose calibration is reported (the state relation's lean branch holds no CH₄)."""

GAUSSIAN_SHARES = {"within_1sigma": 0.6827, "within_2sigma": 0.9545}
"""Shares of a Gaussian within ±1σ and ±2σ, to compare the calibration with."""


def fields_map(representation) -> op.Operator:
    """The map from a voxel representation's parameters to the physical fields it reports
    (T in K, mole fractions, soot volume fraction), float64.

    Parameters
    ----------
    representation : VoxelRepresentation
    """
    dims, field_dims = representation.dims, representation.field_dims
    relation = representation.state_relation
    if relation is None:
        scales = per_field(field_scales(field_dims[0]), field_dims)
        return op.Diagonal(scales, dtype=np.float64, name="denormalize")
    return op.JaxOperator(lambda theta: relation_fields(relation, theta, jnp), dims,
                          field_dims, dtype=np.float64, name="state relation")


def voxel_jacobian(representation, theta) -> np.ndarray:
    r"""Each voxel's Jacobian of its fields by its parameters, :math:`G_{fp} = \partial
    f_f / \partial\theta_p`, shape ``(n_fields, n_parameters, nx, ny, nz)`` (field units per
    parameter unit): one JVP per parameter field, since a voxel's fields depend on its own
    parameters only.

    Parameters
    ----------
    representation : VoxelRepresentation
    theta : ndarray
        Parameters, ``representation.dims``.
    """
    mapping = fields_map(representation)
    theta = np.asarray(theta, np.float64).reshape(representation.dims)
    columns = []
    for p in range(theta.shape[0]):
        tangent = np.zeros_like(theta)
        tangent[p] = 1.0
        columns.append(mapping.jvp(theta, tangent))
    return np.stack(columns, axis=1)


def field_sigma(jacobian: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    r"""Standard deviations of the fields, :math:`\sqrt{\mathrm{diag}(G \Sigma G^\mathsf{T})}`
    per voxel, shape ``(n_fields, nx, ny, nz)`` (field units).

    Parameters
    ----------
    jacobian : ndarray, shape (n_fields, n_parameters, nx, ny, nz)
        :func:`voxel_jacobian`.
    covariance : ndarray, shape (n_parameters, n_parameters, nx, ny, nz)
        The posterior covariance of each voxel's parameters.
    """
    variance = np.einsum("fpxyz,pqxyz,fqxyz->fxyz", jacobian, covariance, jacobian)
    return np.sqrt(np.maximum(variance, 0.0))


def z_scores(truth: np.ndarray, estimate: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """``(estimate - truth) / sigma`` per value (dimensionless); 0 where both the error and σ
    are 0, ±inf where only σ is."""
    error = np.asarray(estimate, np.float64) - truth
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(error == 0, 0.0, error / sigma)


def calibration(truth: np.ndarray, estimate: np.ndarray, sigma: np.ndarray,
                hot: float = HOT) -> dict:
    """The share of voxels whose truth lies within ±1σ and ±2σ of the estimate.

    Parameters
    ----------
    truth, estimate, sigma : ndarray, shape (n_fields, nx, ny, nz)
        Fields in the order of :data:`invflame.field.SOOTY_FIELD_NAMES` (T in K first).
    hot : float, optional
        Voxels with a truth above ``hot`` K form the ``"hot"`` set (default :data:`HOT`).

    Returns
    -------
    dict
        ``{field: {"all" | "hot": {"voxels", "within_1sigma", "within_2sigma"}}}`` for each
        field of :data:`CALIBRATED` (a set without voxels has shares None), and
        ``"expected"``, the Gaussian's shares.
    """
    z = np.abs(z_scores(truth, estimate, sigma))
    sets = {"all": np.ones(truth.shape[1:], bool), "hot": truth[0] > hot}
    out = {"expected": GAUSSIAN_SHARES, "hot_threshold_K": hot}
    for name in CALIBRATED:
        field = z[SOOTY_FIELD_NAMES.index(name)]
        out[name] = {label: {"voxels": int(mask.sum()),
                             **{key: float(np.mean(field[mask] <= k)) if mask.any() else None
                                for k, key in enumerate(GAUSSIAN_SHARES, start=1)}}
                     for label, mask in sets.items()}
    return out


@dataclass
class RunProblem:
    """A finished voxel run's problem, rebuilt from its folder (:func:`rebuild_problem`).

    Attributes
    ----------
    representation : VoxelRepresentation
    problem : solvers.Problem
        The run's noise-weighted problem at its λ.
    theta : ndarray
        The solution's parameters.
    reconstruction : Field
        The reported fields (``reconstruction.npz``).
    truth : Field or None
        ``truth.npz``, when the run has one.
    summary : dict
        ``summary.json``.
    """

    representation: object
    problem: solvers.Problem
    theta: np.ndarray
    reconstruction: Field
    truth: Field | None
    summary: dict


def rebuild_problem(folder, progress: bool = False) -> RunProblem:
    """The problem of the finished run in ``folder``, as its solver saw it.

    Raises
    ------
    FileNotFoundError
        If the folder holds no finished run.
    ConfigError
        For a run that is not of voxels, whose misfit is not weighted by the noise
        (``regularizer.scaling = "paper"``) or whose data carry no noise σ.
    """
    folder = Path(folder)
    if not (folder / SUMMARY).is_file():
        raise FileNotFoundError(f"{folder} holds no {SUMMARY}: it is not the folder of a "
                                "finished run (invflame run writes one); give a run folder")
    cfg = configuration.load(folder / "config.toml")
    summary = read_json(folder / SUMMARY)
    kind, scaling = cfg["representation"]["kind"], cfg["regularizer"]["scaling"]
    if kind != "voxel":
        raise ConfigError(f"{folder}: representation.kind = {kind!r}; σ per voxel is computed "
                          "for voxel runs (a network's Jacobian costs a pass over the data "
                          "per product): run the method with representation.kind = 'voxel'")
    if scaling != "chi2" or not summary["noisy_data"]:
        why = (f"regularizer.scaling = {scaling!r} weighs the misfit without the noise" if
               scaling != "chi2" else "its data carry no noise σ (noise.kind = 'none')")
        raise ConfigError(f"{folder}: {why}, so its objective is no posterior: run it with "
                          "regularizer.scaling = 'chi2' on data with noise")
    scene = build_scene(cfg, measured=read_data(cfg), progress=progress)
    representation = make_representation(cfg, scene)
    recorded = np.load(folder / "data.npz")
    measurement = Measurement(recorded["measured"], recorded["sigma"], True,
                              {"source": str(folder / "data.npz")})
    reconstruction = Field.load(folder / "reconstruction.npz")
    if (folder / CHECKPOINT).is_file():
        theta = solvers.load_checkpoint(folder / CHECKPOINT).x
    else:  # the reported fields' parameters (ambient air's temperature factor then 1)
        theta = representation.initial_parameters(reconstruction.values)
    problem = configured_problem(cfg, scene, representation, measurement, summary["lambda"])
    truth = Field.load(folder / "truth.npz") if (folder / "truth.npz").is_file() else None
    return RunProblem(representation, problem, np.asarray(theta).reshape(problem.dims),
                      reconstruction, truth, summary)


def sigma_dataset(sigma: np.ndarray, fields: dict[str, Field], attributes: dict) -> xr.Dataset:
    """The field sets and their standard deviations as one CF-style dataset: the variables of
    :func:`invflame.export.fields_dataset` and ``sigma_<quantity>`` (same units) with the
    CF standard name modifier ``standard_error``.

    Parameters
    ----------
    sigma : ndarray, shape (n_fields, nx, ny, nz)
        Standard deviations (T in K, mole fractions, soot volume fraction).
    fields : dict of str to Field
        Field sets on the grid of ``sigma``.
    attributes : dict
        Global attributes.
    """
    dataset = fields_dataset(fields, attributes)
    for field_name, values in zip(SOOTY_FIELD_NAMES, sigma, strict=False):
        name, units, long_name, standard_name = QUANTITIES[field_name]
        attrs = {"units": units, "field_set": "sigma",
                 "long_name": f"posterior standard deviation of the {long_name}"}
        if standard_name is not None:
            attrs["standard_name"] = f"{standard_name} standard_error"
        dataset[f"sigma_{name}"] = voxel_variable(values, attrs)
    return dataset


def run_uncertainty(folder, rank: int = 100, oversampling: int = 10,
                    power_iterations: int = 1, prior_std: float = 1.0, seed: int = 0,
                    progress: bool = True) -> dict:
    """σ per voxel and field of the finished voxel run in ``folder``; writes the files of
    the module docstring into it (locked like a run writing it,
    :class:`~invflame.experiments.run_folder.RunLock`).

    Parameters
    ----------
    folder : str or os.PathLike
        A finished run folder of a voxel representation, noise-weighted (default).
    rank, oversampling, power_iterations, prior_std, seed
        Of :func:`~invflame.experiments.posterior.laplace_posterior`: eigenpairs kept (the
        cost grows with them, about ``(power_iterations + 2) * (rank + oversampling)``
        Hessian products), the floor's standard deviation in parameter units.
    progress : bool, optional
        Show progress bars.

    Returns
    -------
    dict
        The content of ``uncertainty.json``.
    """
    from invflame.plotting.uncertainty import plot_uncertainty, plot_z_scores

    folder = Path(folder)
    with RunLock(folder):
        run = rebuild_problem(folder, progress)
        start = time.perf_counter()
        posterior = laplace_posterior(run.problem, run.theta, rank, oversampling,
                                      power_iterations, prior_std, seed, progress)
        sigma = field_sigma(voxel_jacobian(run.representation, run.theta),
                            posterior.voxel_covariance())
        seconds = time.perf_counter() - start
        estimate = run.reconstruction.values
        report = describe(run, posterior, sigma, seconds,
                          {"rank": len(posterior.eigenvalues), "oversampling": oversampling,
                           "power_iterations": power_iterations, "prior_std": prior_std,
                           "seed": seed})
        sets = {"reconstruction": run.reconstruction} | (
            {} if run.truth is None else {"truth": run.truth})
        write_dataset(sigma_dataset(sigma, sets, run_attributes(folder)), folder / NETCDF)
        plot_uncertainty(run.reconstruction, sigma[0], run.truth, folder / FIGURE)
        if run.truth is not None:
            report["calibration"] = calibration(run.truth.values, estimate, sigma)
            z = z_scores(run.truth.values, estimate, sigma)
            plot_z_scores({name: z[SOOTY_FIELD_NAMES.index(name)] for name in CALIBRATED},
                          run.truth.T > HOT, folder / Z_FIGURE)
        write_json(folder / REPORT, report)
    return report


def describe(run: RunProblem, posterior: LaplacePosterior, sigma: np.ndarray,
             seconds: float, settings: dict) -> dict:
    """The content of ``uncertainty.json`` but the calibration: settings, prior, spectrum,
    parameters at a bound, σ_T quantiles (K) and the cost (s) beside the run's solve."""
    problem, prior = run.problem, posterior.prior
    at_bound = np.zeros(problem.dims, bool)
    for bound in (problem.lower, problem.upper):
        if bound is not None:
            at_bound |= run.theta == bound
    solve = (run.summary.get("stages") or {}).get("solve")
    return {
        "method": "linearized (Laplace) posterior, low rank plus diagonal "
                  "(invflame.experiments.posterior)",
        "settings": settings,
        "prior": {"regularizer": run.summary["config"]["regularizer"]["kind"],
                  "weight": prior.weight, "floor": prior.floor},
        "eigenvalues": posterior.eigenvalues.tolist(),
        "truncation": posterior.truncation,
        "parameters_at_bound": int(at_bound.sum()),
        "parameters": int(at_bound.size),
        "sigma_T_K": {f"q{q}": float(np.percentile(sigma[0], q)) for q in (5, 50, 95)},
        "seconds": seconds,
        "solve_seconds": solve,
        "seconds_per_solve_second": None if not solve else seconds / solve,
    }
