"""One name per representation, from the configuration to the class and its problems."""

import warnings

import numpy as np
import pytest

from invflame.experiments import config as configuration
from invflame.representations import REPRESENTATIONS, Representation, VoxelRepresentation
from invflame.representations.normalization import SCALES, per_field


def test_configuration_kinds_are_the_classes_kinds():
    assert set(configuration.CHOICES[("representation", "kind")]) == set(REPRESENTATIONS)
    for kind, cls in REPRESENTATIONS.items():
        assert cls.kind == kind
        assert Representation in cls.__mro__  # inherits parameter_bytes


def test_voxel_problem_names_the_representation_kind(tiny_scene64, plume):
    rep = VoxelRepresentation(tiny_scene64.grid, tiny_scene64.operator)
    problem = rep.problem(tiny_scene64.simulate(plume), x0=rep.initial_parameters(plume))
    assert problem.metadata["representation"] == rep.kind == "voxel"


def test_former_names_are_read_with_a_warning_naming_the_new_ones():
    with pytest.warns(FutureWarning, match="'representation.layers' is now called "
                                           "'representation.depth'"):
        cfg = configuration.validate({"representation": {"kind": "neural-field", "layers": 2}})
    assert cfg["representation"]["depth"] == 2 and "layers" not in cfg["representation"]
    with pytest.warns(FutureWarning, match="'neural' is now called 'neural-field'"):
        cfg = configuration.validate({"representation": {"kind": "neural"}})
    assert cfg["representation"]["kind"] == "neural-field"


def test_current_names_raise_no_warning_and_both_names_at_once_are_refused():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cfg = configuration.validate({"representation": {"kind": "neural-centres", "depth": 3}})
    assert cfg["representation"]["depth"] == 3
    with pytest.raises(configuration.ConfigError, match="give only 'representation.depth'"):
        configuration.validate({"representation": {"layers": 2, "depth": 3}})


def test_parameter_bytes_is_the_memory_of_the_parameters():
    assert Representation.parameter_bytes(np.zeros(10, np.float32)) == 40
    assert VoxelRepresentation.parameter_bytes(np.zeros((2, 3), np.float64)) == 48


def test_per_field_broadcasts_one_value_per_field_and_refuses_other_shapes():
    grid = per_field(SCALES, (4, 2, 3, 5))
    assert grid.shape == (4, 2, 3, 5)
    for c in range(4):
        np.testing.assert_array_equal(grid[c], np.full((2, 3, 5), SCALES[c]))
    with pytest.raises(ValueError, match="4 values"):
        per_field(SCALES[:3], (4, 2, 2, 2))
    with pytest.raises(ValueError, match=r"fields shape \(4, \.\.\.\)"):
        per_field(SCALES, (3, 2, 2, 2))
