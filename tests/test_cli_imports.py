"""The command line's front door imports no array library; the representations' package no torch.

Nor do the modules that list the choices of ``invflame reproduce`` and ``invflame phantom``: the
solvers, and JAX with them, are imported when a solver is first used.

Each check runs in a fresh interpreter, which reports the modules loaded after each step.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from invflame.cli import arguments

REPO = Path(__file__).resolve().parents[1]
HEAVY = ("jax", "torch", "numba")


def loaded_after(steps: dict[str, str]) -> dict[str, list[str]]:
    """The heavy modules in ``sys.modules`` after each step, run in order in one fresh
    interpreter (step name → Python statements)."""
    code = "import json, sys\nreport = {}\n" + "".join(
        f"{statements}\nreport[{name!r}] = [m for m in {HEAVY!r} if m in sys.modules]\n"
        for name, statements in steps.items()) + "print(json.dumps(report))\n"
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                         timeout=300, check=False)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_importing_the_cli_and_building_its_parser_imports_no_array_library():
    report = loaded_after({
        "import invflame.cli": "import invflame.cli",
        "build_parser()": "parser = invflame.cli.build_parser()",
        "import the errors main catches": "from invflame.errors import InvflameError",
        "a command's help": "from contextlib import redirect_stdout; import io\n"
                            "with redirect_stdout(io.StringIO()):\n"
                            "    try:\n        parser.parse_args(['run', '--help'])\n"
                            "    except SystemExit:\n        pass",
    })
    assert report == {step: [] for step in report}


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["config", "--help"]])
def test_the_invflame_script_answers_and_exits_0(argv):
    out = subprocess.run([sys.executable, "-c", "import sys; from invflame.cli import main; "
                          "sys.exit(main())", *argv], cwd=REPO, capture_output=True, text=True,
                         timeout=300, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("invflame 0.") if argv == ["--version"] else "usage:" in out.stdout


@pytest.mark.parametrize(("argv", "choices"), [
    (["reproduce", "--help"], "VG/NR, VG/Tikh., VG/TV, NN/NR"),
    (["study", "--help"], "VG/NR, VG/Tikh., VG/TV, NN/NR"),
    (["phantom", "write", "--help"], "poolfire, synthetic"),
])
def test_a_help_that_lists_choices_imports_no_array_library(argv, choices):
    report = loaded_after({
        "the help": "from contextlib import redirect_stdout; import io\n"
                    "from invflame.cli import main\n"
                    "text = io.StringIO()\n"
                    "with redirect_stdout(text):\n"
                    f"    try:\n        main({argv!r})\n"
                    "    except SystemExit:\n        pass\n"
                    f"assert {choices!r} in ' '.join(text.getvalue().split()), text.getvalue()",
    })
    assert report == {"the help": []}


def test_the_atomic_files_of_the_solvers_import_no_array_library():
    report = loaded_after({"import solvers.atomic": "import solvers.atomic",
                           "from solvers.atomic import": "from solvers.atomic import write_atomic"})
    assert report == {step: [] for step in report}


def test_the_modules_behind_the_choices_of_reproduce_and_phantom_import_no_array_library():
    report = loaded_after({
        "import invflame.experiments.reproduce": "import invflame.experiments.reproduce",
        "import invflame.phantoms": "import invflame.phantoms",
    })
    assert report == {step: [] for step in report}


def test_the_solvers_package_imports_its_solvers_when_first_used():
    report = loaded_after({
        "import solvers": "import solvers",
        "available()": "names = set(solvers.available())\n"
                       "assert names >= {'adam', 'gauss-newton', 'gd', 'jaxopt-lbfgs', 'lbfgs', "
                       "'pdhg'}, names",
    })
    assert report["import solvers"] == [] and "jax" in report["available()"]


def test_the_voxel_representation_imports_no_torch():
    report = loaded_after({
        "import invflame.representations": "import invflame.representations",
        "VoxelRepresentation": "from invflame.representations import VoxelRepresentation",
        "REPRESENTATIONS['voxel']":
            "from invflame.representations import REPRESENTATIONS\nREPRESENTATIONS['voxel']",
    })
    assert all("torch" not in heavy for heavy in report.values()), report


def test_a_neural_representation_is_imported_when_used():
    report = loaded_after({
        "kinds": "from invflame.representations import REPRESENTATIONS\nkinds = sorted("
                 "REPRESENTATIONS)",
        "neural": "from invflame.representations import NeuralFieldRepresentation",
    })
    assert "torch" not in report["kinds"] and "torch" in report["neural"]


def test_choices_are_loaded_when_first_checked():
    calls = []

    def load():
        calls.append(1)
        return ["b", "a"]

    choices = arguments.Choices(load)
    assert not calls
    assert "a" in choices and "c" not in choices
    assert list(choices) == ["b", "a"] and len(choices) == 2 and choices[0] == "b"
    assert calls == [1]
