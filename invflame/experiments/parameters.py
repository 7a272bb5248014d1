"""A run's representation of the flame fields on its scene, its starting parameters and the
physical fields they give."""

from __future__ import annotations

import numpy as np

from invflame.representations.neural import NeuralCentresRepresentation, NeuralFieldRepresentation
from invflame.representations.normalization import physical_bounds
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene


def make_representation(cfg: dict, scene: Scene):
    """The representation named by ``representation.kind`` on the scene."""
    settings, kind = cfg["representation"], cfg["representation"]["kind"]
    network = {"n_frequencies": settings["frequencies"], "hidden": settings["hidden"],
               "depth": settings["depth"], "seed": cfg["seed"]}
    if kind == "neural-field":
        return NeuralFieldRepresentation(scene, n_coarse=settings["coarse_samples"],
                                         n_fine=settings["fine_samples"],
                                         batch_rays=settings["rays_per_batch"], **network)
    if kind == "neural-centres":
        return NeuralCentresRepresentation(scene, **network)
    return VoxelRepresentation(scene.grid, scene.operator, temperature_range=_t_range(scene),
                               soot_max=cfg["soot"]["max"],
                               tv_smoothing=cfg["regularizer"]["tv_smoothing"])


def starting_parameters(cfg: dict, representation, start: np.ndarray, progress: bool):
    """Parameters of the starting fields: normalized voxels, or networks pretrained on them."""
    if representation.kind == "voxel":
        return representation.initial_parameters(start)
    return representation.initial_parameters(
        start, iterations=cfg["representation"]["pretrain_iterations"], seed=cfg["seed"],
        progress=progress)


def physical_fields(scene: Scene, fields: np.ndarray) -> np.ndarray:
    """Fields clipped to the physical bounds, mole fractions scaled to sum to at most 1; a
    soot volume fraction (fifth field) clipped to [0, 1)."""
    lower, upper = physical_bounds(*_t_range(scene), np.nextafter(1.0, 0.0)
                                   if len(fields) == 5 else None)
    fields = np.clip(fields, lower[:, None, None, None], upper[:, None, None, None])
    fractions = fields[1:4]
    fractions /= np.maximum(fractions.sum(axis=0), 1.0)  # a network may exceed sum(X) = 1
    return fields


def _t_range(scene: Scene) -> tuple[float, float]:
    return float(scene.table.temperatures[0]), float(scene.table.temperatures[-1])
