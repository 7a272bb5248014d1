"""The sweeps' generated source in the disk cache: a damaged file is written again, whole."""

import numba
import pytest

from operators.rte.numba_targets import _source_file, compiled_sweeps


@pytest.mark.parametrize("damage", [lambda text: text.replace(b"x", b"\0"),
                                    lambda text: text[: len(text) // 2], lambda text: b""])
def test_a_damaged_source_file_is_written_again(tmp_path, monkeypatch, damage):
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path))
    source = "x = 1\nxs = [x, x]\n"
    path = _source_file(source, "probe")
    path.write_bytes(damage(path.read_bytes()))
    assert _source_file(source, "probe") == path
    assert path.read_text() == source
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]  # no temporary left


def test_sweeps_whose_cached_source_holds_null_bytes_are_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("INVFLAME_CACHE", str(tmp_path))
    build = compiled_sweeps.__wrapped__  # past the per-process cache: as a later run would
    build(1, 1, "float64")
    (path,) = (tmp_path / "sweeps").glob("*.py")
    whole = path.read_bytes()
    path.write_bytes(whole[:100] + b"\0" * 64 + whole[164:])
    with pytest.raises((SyntaxError, ValueError), match="null bytes"):
        compile(path.read_bytes(), str(path), "exec")
    module = build(1, 1, "float64")
    assert path.read_bytes() == whole
    assert all(isinstance(getattr(module, kind), numba.core.dispatcher.Dispatcher)
               for kind in ("forward", "forward_mode", "reverse"))
