"""The absorption-table cache checks what it loads and rebuilds a bad file, saying so."""

import logging

import numpy as np
import pytest

from invflame.atomic_files import CorruptFileError
from invflame.errors import InputDataError
from invflame.spectroscopy.absorption_table import AbsorptionTable

GRID = 690.0 + 0.1 * np.arange(51)  # 690-695 cm-1
OTHER_GRID = 700.0 + 0.1 * np.arange(51)
NODES = [300.0, 1000.0, 1500.0]
LOGGER = "invflame.spectroscopy.absorption_table"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path))
    return tmp_path


def cached(h2o, grid=GRID):
    return AbsorptionTable.cached({"H2O": h2o}, wavenumber=grid, temperatures=NODES,
                                  progress=False)


def damage_truncate(path, h2o, cache):
    path.write_bytes(path.read_bytes()[:300])


def damage_empty(path, h2o, cache):
    path.write_bytes(b"")


def damage_garbage(path, h2o, cache):
    path.write_bytes(np.random.default_rng(0).bytes(2000))


def damage_other_window(path, h2o, cache):
    """A valid table of another window, copied under this one's hashed name."""
    other = cached(h2o, OTHER_GRID)
    (other_path,) = set(cache.glob("absorption-*.npz")) - {path}
    path.write_bytes(other_path.read_bytes())
    assert other.wavenumber[0] == 700.0


def damage_sigma(path, h2o, cache):
    """The arrays changed after writing: the stored content hash no longer fits."""
    data = dict(np.load(path))
    data["sigma"] = data["sigma"] * 2.0
    np.savez(path, **data)


def damage_zeros_without_hash(path, h2o, cache):
    """Zero cross-sections under the right key, with no hash to catch them."""
    data = dict(np.load(path))
    data["sigma"] = np.zeros_like(data["sigma"])
    del data["content_hash"]
    np.savez(path, **data)


@pytest.mark.parametrize("damage", [damage_truncate, damage_empty, damage_garbage,
                                    damage_other_window, damage_sigma,
                                    damage_zeros_without_hash])
def test_a_bad_cache_file_is_rebuilt_with_a_warning(h2o, cache, caplog, damage):
    good = cached(h2o)
    (path,) = cache.glob("absorption-*.npz")
    damage(path, h2o, cache)
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        again = cached(h2o)
    warnings = [r.getMessage() for r in caplog.records if r.name == LOGGER]
    assert len(warnings) == 1 and str(path) in warnings[0]
    assert warnings[0].startswith("rebuilding the cached absorption table")
    np.testing.assert_array_equal(again.sigma, good.sigma)
    np.testing.assert_array_equal(again.wavenumber, GRID)
    caplog.clear()  # the rebuilt file is good again: loaded silently, equal value by value
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        np.testing.assert_array_equal(cached(h2o).sigma, good.sigma)
    assert not caplog.records


def test_load_names_the_damaged_file(h2o, cache):
    cached(h2o)
    (path,) = cache.glob("absorption-*.npz")
    path.write_bytes(b"")
    with pytest.raises(CorruptFileError, match=f"absorption table {path} is damaged or "
                                               r"incomplete \(an empty file\); delete it"):
        AbsorptionTable.load(path)


def test_a_window_without_lines_is_refused(h2o):
    with pytest.raises(InputDataError, match="no line of H2O lies within 25 cm-1 of the grid "
                                             "900-905 cm-1"):
        AbsorptionTable.build({"H2O": h2o}, wavenumber=900.0 + 0.1 * np.arange(51),
                              temperatures=NODES)


@pytest.mark.parametrize(("cache_path", "reason"), [("a file", "File exists"),
                                                    ("a file/sub", "Not a directory")])
def test_a_cache_that_cannot_be_written_gives_the_table_uncached_with_a_warning(
        h2o, tmp_path, monkeypatch, caplog, cache_path, reason):
    (tmp_path / "a file").write_text("")
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path / cache_path))
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        table = cached(h2o)
    [warning] = [r.getMessage() for r in caplog.records if r.name == LOGGER]
    assert warning.startswith("the absorption table is used without being cached: "
                              f"{tmp_path / cache_path}/absorption-")
    assert f"cannot be written ({reason}); set INVFLAME_CACHE to a writable folder" in warning
    np.testing.assert_array_equal(table.sigma, AbsorptionTable.build(
        {"H2O": h2o}, wavenumber=GRID, temperatures=NODES, progress=False).sigma)
