"""The README's Python API example runs as written."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def python_api_example() -> str:
    """The first ```python block after the README's "## Python API" heading."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("## Python API"):]
    match = re.search(r"```python\n(.*?)```", section, flags=re.S)
    assert match, "README.md has no ```python block under '## Python API'"
    return match.group(1)


def test_the_python_api_example_runs_and_reconstructs(capsys):
    namespace: dict = {}
    exec(compile(python_api_example(), str(README), "exec"), namespace)  # noqa: S102
    result, rep, start, truth = (namespace[k] for k in ("result", "rep", "start", "truth"))
    fields = rep.fields(result.x)
    assert fields.shape == truth.values.shape
    loss = result.history["loss"]
    assert loss[-1] < loss[0]
    assert str(fields.shape) in capsys.readouterr().out
    assert start.shape == truth.values.shape
