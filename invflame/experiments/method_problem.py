"""One method of a study as a problem to solve by hand: its data, start, representation and
weighted objective, for studies and benchmarks that compare solvers or objectives on it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import solvers
from invflame.experiments import config, reproduce, runner
from invflame.experiments.metrics import field_scores
from invflame.experiments.parameters import make_representation, starting_parameters
from invflame.experiments.regularization import configured_problem
from invflame.field import Field
from invflame.geometry import VoxelGrid
from invflame.measurement import Measurement
from invflame.scene import Scene


@dataclass
class MethodProblem:
    """What a run of one method builds before its solver starts.

    Attributes
    ----------
    cfg : dict
        The validated configuration.
    scene : Scene
    truth : ndarray
        The truth averaged onto the reconstruction grid, ``scene.field_shape``.
    measurement : Measurement
        The data and their noise σ (W/(m²·sr·cm⁻¹)).
    start : ndarray
        The starting fields.
    representation : VoxelRepresentation or a neural representation
    x0 : ndarray
        The starting parameters.
    """

    cfg: dict
    scene: Scene
    truth: np.ndarray
    measurement: Measurement
    start: np.ndarray
    representation: object
    x0: np.ndarray

    def problem(self, lam: float | None = None, measurement: Measurement | None = None,
                x0=None) -> solvers.Problem:
        """The run's problem with the configured λ (or ``lam``, on the configuration's
        scale), its measurement (or ``measurement``, e.g. with another σ) and start (or
        ``x0``)."""
        return configured_problem(
            self.cfg, self.scene, self.representation,
            self.measurement if measurement is None else measurement,
            self.cfg["regularizer"]["lambda"] if lam is None else lam,
            self.x0 if x0 is None else x0)

    def scores(self, theta, cells=None) -> dict:
        """:func:`~invflame.experiments.metrics.field_scores` of parameters ``theta``
        against the truth, on the reconstruction grid or, with ``cells`` (voxels per axis,
        three ints), with both averaged onto that grid over the same box
        (:meth:`invflame.field.Field.resample`)."""
        truth, fields = self.truth, self.representation.fields(theta)
        if cells is not None:
            grid = self.scene.grid
            coarse = VoxelGrid(grid.lower, grid.upper, tuple(cells), grid.up_axis)
            truth, fields = (Field(grid, f).resample(coarse).values for f in (truth, fields))
        return field_scores(truth, fields)


def method_problem(method: str, truth: str = "poolfire", preset: str = "quick",
                   settings: dict | None = None) -> MethodProblem:
    """The honest-protocol run of ``method`` in ``preset`` on ``truth``, up to its solver.

    Parameters
    ----------
    method : str
        A key of :data:`~invflame.experiments.reproduce.METHODS`.
    truth : str, optional
        ``truth.source``: a phantom name or a field file.
    preset : str, optional
        ``"quick"`` (default) or ``"paper"``.
    settings : dict, optional
        ``{(section, key): value}`` set in the configuration before it is validated.
    """
    cfg = reproduce.method_config(preset, method, 0, "honest", truth)
    for (section, key), value in (settings or {}).items():
        cfg[section][key] = value
    cfg = config.validate(cfg)
    scene, native = runner.build_scene(cfg), runner.load_truth(cfg)
    on_grid = native.resample(scene.grid)
    measurement = runner.measure(cfg, scene, native, progress=False)
    start = runner.initial_fields(cfg, on_grid, scene, measurement)
    representation = make_representation(cfg, scene)
    x0 = starting_parameters(cfg, representation, start, progress=False)
    return MethodProblem(cfg, scene, on_grid.values, measurement, start, representation, x0)
