"""The documentation site builds without a warning and covers the public API and the
configuration schema.

The build is the one the README gives, ``sphinx-build -W --keep-going -b html docs OUT``, into
a temporary folder; it is skipped only where Sphinx is not installed (``pip install -e
'.[docs]'``).
"""

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

from invflame.experiments.config import DEFAULTS

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: Packages whose ``__all__`` the API reference must document, one page each.
PACKAGES = ("operators", "solvers", "invflame.geometry", "invflame.spectroscopy",
            "invflame.phantoms", "invflame.openfoam", "invflame.representations")
BUILD_TIMEOUT = 600  # s


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The HTML site, built with warnings as errors."""
    pytest.importorskip("sphinx")
    out = tmp_path_factory.mktemp("html")
    build = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS),
         str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=BUILD_TIMEOUT)
    assert build.returncode == 0, (
        f"sphinx-build failed (exit {build.returncode}); its warnings:\n{build.stderr}")
    return out


def test_site_has_its_pages(site):
    for page in ("index", "theory", "notebooks", "guide/install", "guide/configuration",
                 "guide/measurement", "guide/linelists", "guide/openfoam", "honest",
                 "poolfire", "scaling", "api/index",
                 "notebooks/01_composing_operators"):
        assert (site / f"{page}.html").is_file(), f"{page}.html was not built"


@pytest.mark.parametrize("package", PACKAGES)
def test_api_reference_documents_every_public_name(site, package):
    html = (site / "api" / "generated" / f"{package}.html").read_text()
    names = importlib.import_module(package).__all__
    missing = [name for name in names if f'id="{package}.{name}"' not in html]
    assert not missing, f"{package}: public names without an API entry: {missing}"


def test_configuration_page_lists_every_key():
    """Every key of the schema, and no other, has a row in the configuration guide."""
    text = (DOCS / "guide" / "configuration.md").read_text()
    row = r"^\| `([a-z0-9_]+(?:\.[a-z0-9_]+)?)` \|"
    documented = set(re.findall(row, text, flags=re.MULTILINE))
    keys = {f"{section}.{key}" if isinstance(values, dict) else section
            for section, values in DEFAULTS.items()
            for key in (values if isinstance(values, dict) else [None])}
    assert keys - documented == set(), f"keys without a row: {sorted(keys - documented)}"
    assert documented - keys == set(), f"rows of no key: {sorted(documented - keys)}"
