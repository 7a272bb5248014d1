r"""How far the reconstruction model is from reality, estimated from prior flames.

A reconstruction scene is coarser than the flame it images: a voxel holds one temperature and
composition, a pixel a few sub-rays, the line-by-line grid a finite step. Data of a real (or
natively rendered) flame therefore differ from the model's prediction of the best voxel
field by a *model error* that no noise level accounts for, and the discrepancy principle with
:math:`\tau = 1` then asks for a fit the model cannot give (``docs/honest.md`` measures
:math:`\chi^2/M` = 320 for the pool fire's own truth averaged onto the quick grid).

The approximation-error approach (Kaipio & Somersalo, *Statistical and Computational Inverse
Problems*, Springer 2005, §7.4; Kaipio & Somersalo, J. Comput. Appl. Math. 198 (2007) 493–504)
estimates that error from flames drawn from a prior, never from the flame being
reconstructed: each prior flame is rendered on a grid twice as fine per axis as the
reconstruction's, with the synthesis' sub-rays and line-by-line step (``data.rays_per_pixel``,
``data.step_divisor``), and by the reconstruction model from its average on the
reconstruction grid. The mean whitened squared difference per measured value,

.. math:: \varepsilon = \frac{1}{M}\,\mathbb{E}\Big\|\frac{F_\text{fine}(f) -
   F(\bar f)}{\sigma}\Big\|^2,

adds to the noise's expected 1, so the discrepancy principle's safety factor becomes
:math:`\tau = 1 + \varepsilon` (``regularizer.tau = "model-error"``).

The prior (:func:`prior_flames`) is McCaffrey plumes (:func:`invflame.phantoms.synthetic_plume`)
of random heat release, pool size and turbulent perturbation, in the reconstruction box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from invflame.experiments.inputs import absorption_table
from invflame.experiments.measurement import synthesis_scene
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.measurement import Measurement
from invflame.phantoms import synthetic_plume
from invflame.scene import Scene

PRIOR_RANGES = {"heat_release_kw": (5.0, 25.0), "pool_size": (0.15, 0.30),
                "perturbation": (0.0, 0.5)}
"""Uniform ranges of the prior plumes' parameters: heat release in kW, side of the square
pool in m, relative amplitude of puffing and turbulence (dimensionless)."""


@dataclass(frozen=True)
class ModelError:
    r"""The model error per prior flame.

    Attributes
    ----------
    chi2_per_value : ndarray, shape (n_flames,)
        :math:`\|(F_\text{fine}(f) - F(\bar f))/\sigma\|^2 / M` of each prior flame
        (dimensionless).
    flames : list of dict
        Each flame's parameters (:data:`PRIOR_RANGES`, and its seed).
    relative_variance : ndarray, shape (n_out,)
        :math:`r(\nu)^2 = \sum (F_\text{fine}(f) - F(\bar f))^2 / \sum F(\bar f)^2` per
        output wavenumber, the sums over the prior flames and pixels (dimensionless): the
        model error as a fraction of the radiance (not in :meth:`as_dict`).
    """

    chi2_per_value: np.ndarray
    flames: list
    relative_variance: np.ndarray

    @property
    def level(self) -> float:
        r"""The mean :math:`\varepsilon` over the prior flames (dimensionless)."""
        return float(np.mean(self.chi2_per_value))

    @property
    def tau(self) -> float:
        r"""The discrepancy principle's factor :math:`1 + \varepsilon`."""
        return 1.0 + self.level

    def as_dict(self) -> dict:
        """Plain values, for JSON."""
        return {"tau": self.tau, "level": self.level,
                "chi2_per_value": [float(v) for v in self.chi2_per_value],
                "flames": self.flames}


def prior_flames(grid: VoxelGrid, n_flames: int, seed: int) -> list[tuple[dict, Field]]:
    """``n_flames`` plumes of random parameters (:data:`PRIOR_RANGES`) on ``grid``, each with
    its parameters (and the seed of its turbulence).

    Parameters
    ----------
    grid : VoxelGrid
        The grid to draw them on (m); the pool lies at the bottom of its box.
    n_flames : int
        How many, ≥ 1.
    seed : int
        Seed of the parameters and of each plume's turbulence.
    """
    if int(n_flames) != n_flames or n_flames < 1:
        raise ValueError(f"n_flames must be a positive integer, got {n_flames!r}")
    rng = np.random.default_rng(seed)
    flames = []
    for _ in range(int(n_flames)):
        drawn = {key: float(rng.uniform(*bounds)) for key, bounds in PRIOR_RANGES.items()}
        drawn["seed"] = int(rng.integers(2**31))
        flames.append((drawn, synthetic_plume(grid, **drawn)))
    return flames


def estimate_model_error(cfg: dict, scene: Scene, measurement: Measurement,
                         n_flames: int = 6, seed: int = 0, log=None,
                         flames: list[tuple[dict, Field]] | None = None) -> ModelError:
    """The model error of ``scene`` against the configured synthesis, from prior flames.

    Parameters
    ----------
    cfg : dict
        Validated configuration (``data.rays_per_pixel``, ``data.step_divisor``,
        ``spectrum.step``).
    scene : Scene
        The reconstruction's scene.
    measurement : Measurement
        Gives the noise σ per value (W/(m²·sr·cm⁻¹)); masked values (σ = inf) count for
        nothing and are not counted in :math:`M`.
    n_flames : int, optional
        Prior flames to average over.
    seed : int, optional
        Seed of the prior draws.
    log : callable, optional
        Receives one line per flame.
    flames : list of (dict, Field), optional
        Your own prior flames instead of :func:`prior_flames` (e.g. other realizations of a
        simulation, each with a description), on a grid finer than the reconstruction's that
        covers its box; ``n_flames`` and ``seed`` are then unused.
    """
    table = absorption_table(cfg, cfg["spectrum"]["step"] / cfg["data"]["step_divisor"])
    weight = np.broadcast_to(1.0 / np.asarray(measurement.sigma, np.float64),
                             measurement.data.shape)
    counted = np.isfinite(weight) & (weight > 0)
    values, described = [], []
    squared = signal = 0.0
    if flames is None:
        grid = scene.grid
        fine_grid = VoxelGrid(grid.lower, grid.upper, tuple(2 * n for n in grid.shape),
                              grid.up_axis)
        flames = prior_flames(fine_grid, n_flames, seed)
    for drawn, flame in flames:
        if flame.values.shape[0] != scene.field_shape[0]:
            raise ValueError(f"prior flame {drawn} has {flame.values.shape[0]} fields, the scene "
                             f"takes {scene.field_shape[0]} (give prior flames with soot to a "
                             "scene that reconstructs soot)")
        fine = synthesis_scene(scene, flame, table, cfg["data"]["rays_per_pixel"])
        model = scene.simulate(flame.resample(scene.grid).values)
        difference = fine.with_background(scene.background).simulate(flame.values) - model
        values.append(float(np.mean(np.square(difference * weight)[counted])))
        squared = squared + np.sum(np.square(difference), axis=0)
        signal = signal + np.sum(np.square(model), axis=0)
        described.append(drawn)
        if log is not None:
            log(f"model error of prior flame {len(values)}/{len(flames)} {drawn}: chi2/M "
                f"{values[-1]:.4g}")
    return ModelError(np.array(values), described, squared / signal)
