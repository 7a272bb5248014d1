"""Sphinx configuration of the invflame documentation.

Build (warnings are errors, as the test suite does)::

    sphinx-build -W --keep-going -b html docs docs/_build/html
"""

import importlib
import inspect
import re
import sys
from pathlib import Path

from sphinx import addnodes
from sphinx.ext.napoleon.docstring import NumpyDocstring
from sphinx.pycode import ModuleAnalyzer

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

project = "invflame"
author = "invflame developers"
copyright = "invflame developers"

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_nb",
]

# Markdown pages (MyST) and the notebooks, rendered with their stored (empty) outputs:
# building the documentation never executes them and needs no network.
nb_execution_mode = "off"
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

exclude_patterns = ["_build", "**.ipynb_checkpoints"]

# API reference: the public names of each package's __init__, numpy-style docstrings.
autosummary_generate = True
autosummary_ignore_module_all = False  # a package's __all__ lists its public names
templates_path = ["_templates"]
autosummary_context = {}  # filled by api_context
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_param = False  # parameter types as text: "array_like, shape (n,)" is no class

# Every cross-reference must resolve, except to the libraries invflame builds on (the build
# runs offline, without their inventories). The words of numpy-style type texts are text
# (see type_words_as_text).
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(np|numpy|jax|jnp|torch|scipy|pylops|pyproximal|dask|distributed|"
               r"matplotlib|tqdm|pathlib|collections|typing|argparse|dataclasses)(\..*)?"),
    (r"py:.*", r"(int|float|str|bool|dict|list|tuple|set|object|callable|type|bytes|"
               r"None|Any|Callable|Sequence|Iterable|Mapping|Path|ndarray|array_like|"
               r"optional|default)"),
]

PACKAGES = ("operators", "solvers", "invflame")


def _public_data(module_name: str) -> list[tuple[str, list[str]]]:
    """Names of a module's ``__all__`` that are data defined elsewhere, with the docstrings
    they have where they are defined.

    autodoc finds attribute docstrings in the source of the module it documents, so data that
    a package's ``__init__`` imports would be left out of the package's page; the page
    template (``_templates/autosummary/module.rst``) adds them from this list.
    """
    module = importlib.import_module(module_name)
    own = ModuleAnalyzer.for_module(module_name).find_attr_docs()
    data = []
    for name in getattr(module, "__all__", ()):
        obj = getattr(module, name)
        if (inspect.ismodule(obj) or inspect.isclass(obj) or callable(obj)
                or ("", name) in own):
            continue
        doc = []
        package = module_name.split(".")[0]
        for other in [m for n, m in sorted(sys.modules.items())
                      if n == module_name or n.startswith(f"{package}.")]:
            found = getattr(other, name, None) is obj and ModuleAnalyzer.for_module(
                other.__name__).find_attr_docs().get(("", name))
            if found:
                doc = list(found)
                break
        data.append((name, doc))
    return data


def api_context(app, config):
    """The data of every package page of the API reference, for its template."""
    index = (Path(app.srcdir) / "api" / "index.rst").read_text()
    names = re.findall(r"^   ((?:operators|solvers|invflame)[\w.]*)$", index, flags=re.MULTILINE)
    config.autosummary_context["public_data"] = {name: _public_data(name) for name in names}


def _attribute_docstring_as_written(self) -> list[str]:
    """An attribute's or property's docstring is its description.

    napoleon reads a first line ``words: more words`` of such a docstring as ``type:
    description``; this project's docstrings state the type in the annotation and write
    sentences with colons.
    """
    return type(self)(self._dedent(self._consume_to_end()), self._config).lines()


NumpyDocstring._parse_attribute_docstring = _attribute_docstring_as_written


def _import(path: str):
    """The object a dotted path names (module, then attributes), or None."""
    parts = path.split(".")
    if not all(parts):
        return None
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for name in parts[i:]:
                obj = getattr(obj, name)
        except AttributeError:
            return None
        return obj
    return None


def _candidates(node) -> list[str]:
    """Full dotted names a Python reference may mean, from its text and its context.

    The context is the package where the docstring is shown, and the modules of the project
    (a docstring may name objects of the module that defines it).
    """
    target = node["reftarget"].lstrip(".~")
    module, cls = node.get("py:module"), node.get("py:class")
    names = [target]
    if module:
        names.insert(0, f"{module}.{target}")
        if cls:
            names.insert(0, f"{module}.{cls}.{target}")
    names += [f"{name}.{target}" for name in sorted(sys.modules)
              if name.split(".")[0] in PACKAGES]
    return [n for n in names if n.split(".")[0] in PACKAGES]


TYPE_WORD = re.compile(r"(?![A-Z])[^.]*")
"""Targets that are words of a type text ("shape", "n_T", "int", "3"), not class names."""


def type_words_as_text(app, doctree):
    """Turn the references Sphinx makes of the words of parameter and attribute types into
    text, so that ``ndarray, shape (n_rays, n_out)`` neither links nor warns; names with a
    leading capital letter or a dot stay references and must resolve."""
    for node in list(doctree.findall(addnodes.pending_xref)):
        if (node.get("refdomain") == "py" and node.get("reftype") == "class"
                and TYPE_WORD.fullmatch(node["reftarget"])):
            node.replace_self(node.children)


def resolve_internal(app, env, node, contnode):
    """Resolve a reference to a project object that the reference does not document.

    A name reached through its module (``operators.checks.TaylorResult``,
    ``invflame.spectroscopy.linelist``) links to the public name that exports the same object
    when there is one, and is otherwise shown as code. A reference that names nothing
    importable stays unresolved, so Sphinx reports it.
    """
    if node.get("refdomain") != "py":
        return None
    domain = env.get_domain("py")
    for name in _candidates(node):
        obj = _import(name)
        if obj is None:
            owner = _import(name.rpartition(".")[0])
            if node["reftype"] == "attr" and isinstance(owner, type):
                return contnode  # an instance attribute, set in __init__
            continue
        parts = name.split(".")
        for i in range(1, len(parts) - 1):
            public = ".".join(parts[:i] + parts[-1:])
            if public in domain.objects and _import(public) is obj:
                return domain.resolve_xref(env, node["refdoc"], app.builder, "obj", public,
                                           node, contnode)
        return contnode
    return None


def study_table_page(app, docname, source):
    """Give a study's table copied into ``figures/`` (a run's ``table.md``, which has no
    title) a title, and mark it as linked from the pages rather than listed in a contents
    tree."""
    if docname.startswith("figures/"):
        title = docname.rpartition("/")[2].replace("_", " ").capitalize()
        source[0] = f"---\norphan: true\n---\n# {title}\n\n{source[0]}"


def setup(app):
    app.connect("config-inited", api_context)
    app.connect("source-read", study_table_page)
    app.connect("doctree-read", type_words_as_text)
    app.connect("missing-reference", resolve_internal)


html_theme = "alabaster"
html_title = "invflame"
