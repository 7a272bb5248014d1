"""A run's representation of the flame fields on its scene, its starting parameters and the
physical fields they give."""

from __future__ import annotations

import jax
import numpy as np
import torch

from invflame.representations.neural import NeuralCentresRepresentation, NeuralFieldRepresentation
from invflame.representations.normalization import physical_bounds
from invflame.representations.state_relation import StateRelation
from invflame.representations.subvoxel import SubvoxelEmission
from invflame.representations.voxel import VoxelRepresentation
from invflame.scene import Scene


def torch_device(name: str) -> str:
    """The torch device that ``representation.device`` names on this machine.

    Parameters
    ----------
    name : str
        ``"auto"``, ``"cpu"``, ``"cuda"`` or ``"cuda:N"``.

    Returns
    -------
    str
        ``"auto"`` resolved: ``"cuda"`` when JAX computes on a GPU and torch has CUDA, else
        ``"cpu"``; any other name as given.

    Raises
    ------
    ValueError
        For a CUDA device where torch has no CUDA or JAX no GPU (the networks hand their
        tensors to the emission kernel, which JAX runs, without a copy).
    """
    jax_on_gpu = jax.default_backend() == "gpu"
    if name == "auto":
        return "cuda" if jax_on_gpu and torch.cuda.is_available() else "cpu"
    if name.startswith("cuda") and not (jax_on_gpu and torch.cuda.is_available()):
        raise ValueError(
            f"representation.device = {name!r}, but here torch {torch.__version__} "
            f"{'has' if torch.cuda.is_available() else 'has no'} CUDA and JAX computes on "
            f"{jax.default_backend()}: both need the GPU (a CUDA build of torch and "
            "jax[cuda13]); or set device = 'auto' or 'cpu'")
    return name


def state_relation(cfg: dict, scene: Scene) -> StateRelation:
    """The methane state relation of a configuration: ``init.ambient``,
    ``init.temperature_rise`` (K), ``representation.factor_range``, and the scene's absorption
    table's highest temperature (K) as the hottest state."""
    return StateRelation(cfg["init"]["ambient"], cfg["init"]["temperature_rise"],
                         cfg["representation"]["factor_range"], _t_range(scene)[1])


def subvoxel_emission(cfg: dict, scene: Scene) -> SubvoxelEmission | None:
    """The sub-voxel emission model of ``representation.subvoxel_spread`` with the
    configuration's state relation; None when the spread is 0 or the representation is not
    voxels or a network at the voxel centres of the state relation's parameters."""
    settings = cfg["representation"]
    if settings["kind"] not in ("voxel", "neural-centres") \
            or settings["parameters"] != "state-relation" or settings["subvoxel_spread"] == 0:
        return None
    return SubvoxelEmission(state_relation(cfg, scene), settings["subvoxel_spread"])


def make_representation(cfg: dict, scene: Scene):
    """The representation named by ``representation.kind`` on the scene, parameterized as
    ``representation.parameters`` says; for the networks, torch's default device set to
    ``representation.device`` first (:func:`torch_device`)."""
    settings, kind = cfg["representation"], cfg["representation"]["kind"]
    relation = (state_relation(cfg, scene) if settings["parameters"] == "state-relation"
                else None)
    network = {"n_frequencies": settings["frequencies"], "hidden": settings["hidden"],
               "depth": settings["depth"], "grid_levels": settings["grid_levels"],
               "seed": cfg["seed"], "state_relation": relation}
    if kind != "voxel":
        device = torch.device(torch_device(settings["device"]))
        if device != torch.get_default_device():
            torch.set_default_device(device)
    if kind == "neural-field":
        return NeuralFieldRepresentation(scene, n_coarse=settings["coarse_samples"],
                                         n_fine=settings["fine_samples"],
                                         batch_rays=settings["rays_per_batch"], **network)
    if kind == "neural-centres":
        return NeuralCentresRepresentation(scene, **network,
                                           subvoxel=subvoxel_emission(cfg, scene))
    return VoxelRepresentation(scene.grid, scene.operator, temperature_range=_t_range(scene),
                               soot_max=cfg["soot"]["max"],
                               tv_smoothing=cfg["regularizer"]["tv_smoothing"],
                               state_relation=relation,
                               subvoxel=subvoxel_emission(cfg, scene))


def starting_parameters(cfg: dict, representation, start: np.ndarray, progress: bool):
    """Parameters of the starting fields: normalized voxels, or networks pretrained on them or
    offset by them (``representation.network_start``)."""
    if representation.kind == "voxel":
        return representation.initial_parameters(start)
    settings = cfg["representation"]
    return representation.initial_parameters(
        start, iterations=settings["pretrain_iterations"], seed=cfg["seed"], progress=progress,
        offset=settings["network_start"] == "offset")


def physical_fields(scene: Scene, fields: np.ndarray) -> np.ndarray:
    """Fields clipped to the physical bounds, mole fractions scaled to sum to at most 1; a
    soot volume fraction (fifth field) clipped to [0, 1)."""
    lower, upper = physical_bounds(*_t_range(scene), np.nextafter(1.0, 0.0)
                                   if len(fields) == 5 else None)
    fields = np.clip(fields, lower[:, None, None, None], upper[:, None, None, None])
    fractions = fields[1:4]
    fractions /= np.maximum(fractions.sum(axis=0), 1.0)  # a network may exceed sum(X) = 1
    return fields


def predicted_spectra(scene: Scene, representation, theta) -> np.ndarray:
    """The spectra the model predicts for parameters ``theta``, shape ``(n_rays, n_out)``
    in W/(m²·sr·cm⁻¹): the scene's simulation of the representation's rendered fields
    (:meth:`~invflame.representations.protocol.Representation.rendered_fields`), clipped to
    the physical bounds."""
    return scene.simulate(physical_fields(scene, representation.rendered_fields(theta)))


def _t_range(scene: Scene) -> tuple[float, float]:
    return float(scene.table.temperatures[0]), float(scene.table.temperatures[-1])
