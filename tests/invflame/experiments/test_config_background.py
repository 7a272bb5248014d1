"""[background] in a configuration: its keys, their checks, and the scene and data it makes."""

import numpy as np
import pytest

from invflame.background import BlackbodyWall, MeasuredBackground
from invflame.background_file import write_background
from invflame.errors import ConfigError
from invflame.experiments import config, runner
from invflame.phantoms import make_phantom
from operators.rte.planck import planck

SMALL = {"truth": {"source": "synthetic", "grid": 4}, "rig": {"pixels": 3, "rays_per_pixel": 1},
         "spectrum": {"min": 660.0, "max": 690.0, "step": 0.1},
         "data": {"rays_per_pixel": 1, "step_divisor": 1}, "noise": {"kind": "none"}}


def test_defaults_and_refusals():
    assert config.validate({})["background"] == {"kind": "none", "temperature": 300.0,
                                                 "emissivity": 1.0, "file": ""}
    for bad, words in [({"kind": "wall"}, "'background.kind' = 'wall' is not allowed"),
                       ({"emissivity": 1.2}, "'background.emissivity' must be in (0, 1]"),
                       ({"temperature": 0.0}, "'background.temperature' (K) must be"),
                       ({"kind": "file", "file": "missing.nc"}, "needs 'background.file'")]:
        with pytest.raises(ConfigError) as err:
            config.validate({"background": bad})
        assert words in str(err.value)


def test_a_wall_reaches_the_scene_and_the_synthetic_data():
    cfg = config.validate({**SMALL, "background": {"kind": "blackbody", "temperature": 500.0,
                                                   "emissivity": 0.8}})
    scene = runner.build_scene(cfg)
    assert scene.background == BlackbodyWall(500.0, 0.8)
    measurement = runner.measure(cfg, scene, make_phantom("synthetic"))
    assert measurement.provenance["background"] == {"kind": "blackbody", "temperature_K": 500.0,
                                                    "emissivity": 0.8}
    air = np.stack([np.full(scene.grid.shape, 300.0), *np.zeros((3, *scene.grid.shape))])
    bare = scene.with_background(None)
    assert bare.background is None and np.all(bare.simulate(air) == 0)
    # the wall through empty air: its radiance through the instrument, in every pixel
    wall = scene.ils(np.tile(0.8 * planck(scene.wavenumber, 500.0), (scene.n_rays, 1)))
    np.testing.assert_allclose(scene.simulate(air), wall, rtol=1e-5)


def test_a_background_file_from_the_configuration(tmp_path):
    eta = np.linspace(650.0, 700.0, 6)
    path = write_background(MeasuredBackground(eta, np.full((4, 6), 0.2)), tmp_path / "bg.nc")
    cfg = config.validate({**SMALL, "background": {"kind": "file", "file": str(path)}})
    scene = runner.build_scene(cfg)
    np.testing.assert_allclose(scene.background.on_grid(scene.wavenumber, 4), 0.2)


def test_a_soot_layer_in_the_truth_is_seen_in_the_synthetic_data():
    plain = config.validate(SMALL)
    sooty = config.validate({**SMALL, "truth": {**SMALL["truth"], "soot": 1e-6}})
    scene = runner.build_scene(plain)
    clean = runner.measure(plain, scene, runner.load_truth(plain))
    with_soot = runner.measure(sooty, scene, runner.load_truth(sooty))
    assert clean.provenance["soot_peak_volume_fraction"] == 0.0
    assert with_soot.provenance["soot_peak_volume_fraction"] == 1e-6
    assert scene.soot is None  # the reconstruction models gas only
    change = np.abs(with_soot.data - clean.data).max()
    assert change > 1e-3 * np.abs(clean.data).max()
    with pytest.raises(ConfigError, match=r"'truth.soot' must be in \[0, 0.001\]"):
        config.validate({"truth": {"soot": 0.1}})
