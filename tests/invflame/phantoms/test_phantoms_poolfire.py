"""The packaged OpenFOAM pool fire and the phantom registry."""

import time

import numpy as np
import pytest

from invflame.geometry import VoxelGrid
from invflame.phantoms import PHANTOMS, make_phantom, poolfire


def test_poolfire_loads_fast_with_provenance():
    start = time.perf_counter()
    field = poolfire()
    elapsed = time.perf_counter() - start
    assert elapsed < 1.0, f"loading the packaged pool fire took {elapsed:.2f} s"
    assert field.grid == VoxelGrid.poolfire(60)
    assert field.values.dtype == np.float32
    meta = field.metadata
    assert meta["solver"] == "fireFoam" and meta["time"] == 0.9
    assert "1912" in meta["version"]
    assert meta["species"] == ["O2", "H2O", "CH4", "CO2", "N2"]
    assert field.T.min() == pytest.approx(300.0, abs=1.0)
    assert 1100 < field.T.max() < 1400
    # fuel enters through the 0.2 m square inlet at the floor, centred
    ix, iy, iz = np.unravel_index(np.argmax(field.X("CH4")), field.grid.shape)
    x, y, z = field.grid.centres()[ix, iy, iz]
    assert abs(x) < 0.1 and abs(z) < 0.1 and y < 0.05


def test_poolfire_resampled():
    field = poolfire(VoxelGrid.poolfire(30))
    assert field.grid.shape == (30, 30, 30)
    assert field.metadata["resampled_from"] == [60, 60, 60]
    assert 300 <= field.T.min() and field.T.max() < poolfire().T.max()


def test_registry_by_name():
    assert set(PHANTOMS) == {"poolfire", "synthetic"}
    field = make_phantom("synthetic", grid=VoxelGrid.poolfire(8))
    assert field.metadata["source"] == "synthetic"
    with pytest.raises(KeyError, match="choose one of"):
        make_phantom("candle")
