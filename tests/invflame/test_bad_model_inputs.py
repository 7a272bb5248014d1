"""Bad input to the forward model through the Python API: fields outside the absorption
table's or physics' range, wrong shapes, geometry that sees nothing; each raises with a
message naming the quantity."""

import numpy as np
import pytest

from invflame.experiments.initialization import noisy_truth
from invflame.geometry import CameraRig, VoxelGrid, paper_rig
from invflame.geometry.camera import PinholeCamera
from invflame.phantoms import make_phantom
from invflame.scene import Scene


def fields(scene, t=1000.0, co2=0.1, h2o=0.2) -> np.ndarray:
    """Uniform fields on the scene's grid: T in K, mole fractions of CO2, H2O and no CH4."""
    return np.stack([np.full(scene.grid.shape, value) for value in (t, co2, h2o, 0.0)])


def missing_camera(scene):
    """A scene whose one camera looks away from the grid."""
    centre = scene.grid.centre
    away = PinholeCamera(centre + [3.0, 0.0, 0.0], centre + [6.0, 0.0, 0.0], [0.0, 1.0, 0.0],
                         0.5, (0.1, 0.1), (2, 2))
    return Scene(scene.grid, CameraRig((away,)), scene.table)


CASES = {
    "simulate T = 5000 K": (lambda s: s.simulate(fields(s, t=5000.0)), "T|temperature"),
    "simulate X_CO2 = -0.1": (lambda s: s.simulate(fields(s, co2=-0.1)), "CO2"),
    "simulate sum X > 1": (lambda s: s.simulate(fields(s, co2=0.6, h2o=0.6)),
                           "sum|mole fraction"),
    "simulate NaN T": (lambda s: s.simulate(fields(s, t=np.nan)), "NaN|T"),
    "simulate wrong shape": (lambda s: s.simulate(fields(s)[:3]), "shape"),
    "operator T = 0 K": (lambda s: s.operator(fields(s, t=0.0)), "temperature"),
    "operator T = 5000 K": (lambda s: s.operator(fields(s, t=5000.0)), "temperature|table"),
    "operator X_CO2 = -0.5": (lambda s: s.operator(fields(s, co2=-0.5)), "CO2"),
    "operator fields last": (lambda s: s.operator(np.moveaxis(fields(s), 0, -1)), "shape"),
    "jvp at T = -300 K": (lambda s: s.operator.jvp(fields(s, t=-300.0), fields(s)),
                          "temperature"),
    "vjp at NaN T": (lambda s: s.operator.vjp(fields(s, t=np.nan),
                                              np.zeros(s.operator.dimsd)), "NaN|T"),
    "linearize at X_H2O = 1.5": (lambda s: s.operator.linearize(fields(s, h2o=1.5)), "H2O"),
    "EmissionRTE at T = 5000 K": (lambda s: s.emission(
        s.sampling(fields(s)) * np.array([5.0, 1, 1, 1])[:, None, None]), "temperature|5000"),
    "EmissionRTE X_CO2 = -0.5": (lambda s: s.emission(
        s.sampling(fields(s)) - np.array([0, 0.6, 0, 0])[:, None, None]),
        "mole fraction|negative"),
    "rig that misses the grid": (missing_camera, "grid|camera"),
    "paper_rig inside the grid": (lambda s: paper_rig(s.grid, distance=0.2), "distance"),
}
"""Case → ``(call, match)``: ``call(scene)`` must raise a message that ``match`` finds."""


@pytest.mark.parametrize(("call", "match"), CASES.values(), ids=CASES.keys())
def test_bad_fields_and_geometry_are_named(tiny_scene, call, match):
    with pytest.raises(Exception, match=match):
        call(tiny_scene)


@pytest.mark.parametrize(("call", "match"), [
    (lambda: VoxelGrid((0, 0, 0), (-1, 1, 1), (4, 4, 4)), "upper|lower"),
    (lambda: VoxelGrid((0, 0, 0), (1, 1, 1), (0, 4, 4)), "shape"),
    (lambda: PinholeCamera([0.0, 5.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5, (0.1, 0.1),
                           (2, 2)), "up"),
    (lambda: noisy_truth(np.ones((4, 2, 2, 2)), -1.0, 0), "noise"),
    (lambda: make_phantom("candle"), "candle"),
], ids=["VoxelGrid upper below lower", "VoxelGrid zero cells", "camera looking along up",
        "noisy_truth negative noise", "unknown phantom"])
def test_bad_construction_arguments_are_named(call, match):
    with pytest.raises(Exception, match=match):
        call()
