"""[soot] reconstruct: soot volume fraction as a fifth reconstructed field; [grid]: the box."""

import numpy as np
import pytest
import xarray as xr

from invflame.errors import ConfigError
from invflame.experiments import config, runner
from invflame.export import read_run_fields
from invflame.field import Field
from invflame.geometry import VoxelGrid, paper_rig
from invflame.geometry.rig_file import write_rig
from invflame.representations.voxel import VoxelRepresentation

pytestmark = pytest.mark.filterwarnings("ignore:discrepancy principle:RuntimeWarning")
SMALL = {"truth": {"source": "synthetic"}, "rig": {"pixels": 6, "rays_per_pixel": 4},
         "spectrum": {"min": 660.0, "max": 690.0, "step": 0.2},
         "data": {"inverse_crime": True}, "noise": {"kind": "nesr", "nesr": 1e-4}}


def test_soot_and_grid_keys_are_checked():
    cfg = config.validate({})
    assert cfg["soot"] == {"reconstruct": False, "max": 1e-5}
    assert config.reconstruction_grid(cfg) == VoxelGrid.poolfire(30)
    moved = config.validate({"grid": {"lower": [1.0, 0.0, 1.0], "upper": [1.4, 0.8, 1.4],
                                      "cells": [4, 8, 4]}})
    assert config.reconstruction_grid(moved) == VoxelGrid((1.0, 0.0, 1.0), (1.4, 0.8, 1.4),
                                                          (4, 8, 4))
    for bad, words in [
            ({"grid": {"cells": [1, 4, 4]}}, "'grid.cells' must be [nx, ny, nz] with at least 2"),
            ({"grid": {"cells": [4, 4]}}, "'grid.cells' must be a list of 3 integers"),
            ({"grid": {"upper": [0.5, -0.1, 0.5]}}, "'grid.upper' = [0.5, -0.1, 0.5] m must "
                                                    "exceed 'grid.lower'"),
            ({"grid": {"cells": [4, 4, 4]}, "truth": {"grid": 8}}, "give them in one place"),
            ({"soot": {"reconstruct": True}, "representation": {"kind": "neural-field"}},
             "'soot.reconstruct' = true needs 'representation.kind' = 'voxel'"),
            ({"soot": {"reconstruct": True}, "truth": {"soot": 2e-5}},
             "'truth.soot' = 2e-05 exceeds 'soot.max' = 1e-05"),
            ({"soot": {"max": 0.0}}, "'soot.max' must be in (0, 0.001]")]:
        with pytest.raises(ConfigError) as err:
            config.validate(bad)
        assert words in str(err.value)


def test_a_rig_file_must_see_the_moved_box(tmp_path):
    rig = write_rig(paper_rig(VoxelGrid.poolfire(8), n_pixels=3), tmp_path / "rig.toml")
    with pytest.raises(ConfigError, match=r"'rig.file' = .* looks away from the grid \[5.0"):
        config.validate({"rig": {"file": str(rig)},
                         "grid": {"lower": [5.0, 5.0, 5.0], "upper": [6.0, 6.0, 6.0]}})


def test_a_box_outside_the_truth_is_named(tmp_path):
    cfg = config.validate({**SMALL, "grid": {"lower": [0.0, 0.5, 0.0], "upper": [1.0, 1.5, 1.0],
                                             "cells": [3, 3, 3]},
                           "solver": {"iterations": 1}})
    with pytest.raises(ConfigError, match=r"'grid.lower'..'grid.upper' = .* reaches outside "
                                          r"the truth 'synthetic'"):
        runner.run_experiment(cfg, tmp_path / "run", progress=False)


def test_a_truth_with_soot_is_resampled_and_saved_with_it(tmp_path):
    cfg = config.validate({**SMALL, "truth": {"source": "synthetic", "soot": 2e-6}})
    native = runner.load_truth(cfg)
    assert native.names[-1] == "soot" and native.soot.max() == pytest.approx(2e-6)
    coarse = native.resample(VoxelGrid.poolfire(6))
    # a volume fraction is averaged by volume: the soot volume is kept (voxels 1000x larger)
    assert coarse.soot.sum(dtype=np.float64) * 1000 == pytest.approx(
        native.soot.sum(dtype=np.float64), rel=1e-4)
    assert Field.load(coarse.save(tmp_path / "f.npz")).names == coarse.names
    assert coarse.gas.names == Field.names and coarse.gas.with_soot(coarse.soot).names[-1] == "soot"
    assert runner.load_truth(config.validate(SMALL)).soot is None  # soot-free unless asked
    with pytest.raises(ValueError, match=r"soot volume fraction must lie in \[0, 1\)"):
        coarse.with_soot(np.full(coarse.grid.shape, -1e-7))


def test_voxel_bounds_hold_the_soot_volume_fraction():
    cfg = config.validate({**SMALL, "grid": {"cells": [4, 4, 4]},
                           "soot": {"reconstruct": True, "max": 2e-5}})
    scene = runner.build_scene(cfg)
    assert scene.field_shape == (5, 4, 4, 4)
    representation = runner.make_representation(cfg, scene)
    assert isinstance(representation, VoxelRepresentation)
    fields = representation.fields(representation.upper)
    assert fields[4].max() == pytest.approx(2e-5) and representation.fields(
        representation.lower)[4].min() == 0.0
    start = runner.initial_fields(cfg, None, scene, runner.measure(cfg, scene,
                                                                    runner.load_truth(cfg)))
    assert start.shape == (5, 4, 4, 4) and np.all(start[4] == 0)  # no soot to start with


def test_soot_is_reconstructed_where_the_truth_has_it(tmp_path):
    """A soot layer in the synthetic plume, seen by 4 cameras of 6 x 6 pixels, is found in
    the voxel that holds it, and scored."""
    cfg = config.validate({**SMALL, "truth": {"source": "synthetic", "soot": 4e-6},
                           "grid": {"cells": [5, 6, 5]}, "soot": {"reconstruct": True},
                           "representation": {"parameters": "fields"},
                           "regularizer": {"kind": "none"}, "init": {"calibrate": False},
                           "solver": {"name": "adam", "iterations": 60,
                                      "options": {"lr": 0.05}}})
    summary = runner.run_experiment(cfg, tmp_path / "run", progress=False)
    chi2 = summary["chi2_per_measurement"]
    assert chi2["final"] < 0.01 * chi2["initial"]
    assert summary["mse"]["soot"] < summary["mse_initial"]["soot"]
    fields = read_run_fields(tmp_path / "run")
    truth, found = fields["truth"].soot, fields["reconstruction"].soot
    assert fields["start"].soot.max() == 0.0
    sooty = truth > 0.2 * truth.max()
    assert found[sooty].mean() > 100 * found[truth == 0].mean()
    assert np.corrcoef(truth.ravel(), found.ravel())[0, 1] > 0.8
    with xr.open_dataset(tmp_path / "run" / "fields.nc") as exported:
        assert {"truth_f_v", "start_f_v", "reconstruction_f_v"} <= set(exported.data_vars)
