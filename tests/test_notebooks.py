"""The notebooks under ``notebooks/`` execute without error and produce outputs.

They are stored without outputs; each is run here in a fresh kernel started with the
interpreter running the tests, so it sees the same installed packages.
"""

import json
import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

FOLDER = Path(__file__).resolve().parents[1] / "notebooks"
#: Notebook → number of figures it must draw.
FIGURES = {
    "01_composing_operators.ipynb": 2,
    "02_adjoint_and_taylor_tests.ipynb": 0,
    "03_swapping_solvers.ipynb": 2,
    "04_measurement_file.ipynb": 4,
}
NOTEBOOKS = [FOLDER / name for name in FIGURES]
CELL_TIMEOUT = 120  # s


@pytest.fixture(scope="module")
def kernel_path(tmp_path_factory) -> Path:
    """A folder for ``JUPYTER_PATH`` holding a ``python3`` kernel spec for this interpreter.

    Folders on ``JUPYTER_PATH`` come before the user's and the system's, so the kernel runs
    ``sys.executable`` whatever other ``python3`` kernels are installed.
    """
    root = tmp_path_factory.mktemp("jupyter")
    spec = root / "kernels" / "python3"
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(json.dumps(
        {"argv": argv, "display_name": "Python 3 (tests)", "language": "python"}))
    return root


def test_every_notebook_is_tested():
    assert sorted(p.name for p in FOLDER.glob("*.ipynb")) == sorted(FIGURES)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_is_stored_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code, f"{path.name} has no code cells"
    assert all(not cell.outputs and cell.execution_count is None for cell in code), (
        f"{path.name} is stored with outputs; clear them (e.g. `jupyter nbconvert "
        f"--clear-output --inplace {path.name}`)")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_executes(path, kernel_path, tmp_path, monkeypatch):
    monkeypatch.setenv("JUPYTER_PATH", str(kernel_path))
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    nb = nbformat.read(path, as_version=4)
    probe = nbformat.v4.new_code_cell("import sys; print(sys.executable)")
    nb.cells.insert(0, probe)
    NotebookClient(nb, kernel_name="python3", timeout=CELL_TIMEOUT,
                   resources={"metadata": {"path": str(tmp_path)}}).execute()

    executable = "".join(out.get("text", "") for out in nb.cells[0].outputs).strip()
    assert Path(executable) == Path(sys.executable), (
        f"the kernel ran {executable}, not the test interpreter {sys.executable}")
    code = [cell for cell in nb.cells[1:] if cell.cell_type == "code"]
    assert all(cell.execution_count is not None for cell in code)
    assert sum(len(cell.outputs) for cell in code) >= len(code) // 2, (
        f"{path.name} produced outputs in too few cells")
    images = [out for cell in code for out in cell.outputs if "image/png" in out.get("data", {})]
    assert len(images) == FIGURES[path.name], f"{path.name} drew {len(images)} figures"
