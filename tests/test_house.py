"""The layout of model/ (issue 23): small modules, no import circle, the public API at the top.

Rules checked on the source files themselves (exact, no tolerance): every module of model/ has
at most ``MAX_MODULE_LINES`` lines; the module-level imports of model/ and dashboard/ form no
circle; each sub-package's docstring names every module it holds; ``import model`` loads no
numerical package, and every name of ``model.PUBLIC_API`` is reached from ``model`` as the very
object its module defines. (The dashboard's modules get the same size rule with its own split.)
"""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

import model

ROOT = Path(__file__).resolve().parent.parent
MAX_MODULE_LINES = 600
HEAVY_PACKAGES = ("numpy", "scipy", "numba", "param", "pandas")
REQUIRED_API = (
    "Scenario",
    "ScenarioError",
    "run",
    "Results",
    "StageCache",
    "invert_receptance",
    "receptance_2p5d",
    "point_load_response",
    "fit_strain_law",
    "run_study",
    "settlement_band",
    "run_fe",
    "fra_psd",
    "synthesize_profile",
    "simulate",
)


def _modules(*packages: str) -> dict[str, Path]:
    """Dotted module name → file, for every module of the given top-level packages."""
    found = {}
    for package in packages:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


MODEL_MODULES = _modules("model")


@pytest.mark.parametrize("name", sorted(MODEL_MODULES))
def test_no_module_of_the_model_is_longer_than_600_lines(name):
    lines = MODEL_MODULES[name].read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_MODULE_LINES, f"{name}: {lines} lines"


def _top_level_imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Modules of ``known`` that the module imports when it is imported (not in functions)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    targets = set()

    def visit(statements):
        for node in statements:
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    targets.add(full if full in known else base)
            elif isinstance(node, ast.If | ast.Try | ast.With):
                for block in ("body", "orelse", "finalbody", "handlers"):
                    for child in getattr(node, block, []):
                        visit(child.body if isinstance(child, ast.ExceptHandler) else [child])

    visit(ast.parse(path.read_text(encoding="utf-8")).body)
    return (targets & known) - {name}


def test_the_model_and_dashboard_imports_form_no_circle():
    """Depth-first search over the module-level import graph; a back edge is a circle."""
    modules = _modules("model", "dashboard")
    graph = {name: _top_level_imports(name, path, set(modules)) for name, path in modules.items()}
    state: dict[str, str] = {}
    circles = []

    def search(name, trail):
        state[name] = "open"
        for target in sorted(graph[name]):
            if state.get(target) == "open":
                circles.append(" → ".join([*trail[trail.index(target) :], target]))
            elif target not in state:
                search(target, [*trail, target])
        state[name] = "done"

    for name in sorted(graph):
        if name not in state:
            search(name, [name])
    assert not circles, circles


@pytest.mark.parametrize(
    "package", sorted(name for name, path in MODEL_MODULES.items() if path.name == "__init__.py")
)
def test_every_package_docstring_names_its_modules(package):
    """A newcomer reads the package docstring to find where a formula lives."""
    folder = MODEL_MODULES[package].parent
    doc = ast.get_docstring(ast.parse(MODEL_MODULES[package].read_text(encoding="utf-8")))
    assert doc, package
    for path in sorted(folder.glob("*.py")):
        if path.stem not in ("__init__", "__main__"):
            assert f"``{path.stem}``" in doc, f"{package} does not name {path.stem}"
    for sub in sorted(folder.glob("*/__init__.py")):
        assert f"``{sub.parent.name}``" in doc, f"{package} does not name {sub.parent.name}"


def test_importing_the_package_loads_no_numerical_package():
    code = f"import sys, model; print(','.join(m for m in {HEAVY_PACKAGES!r} if m in sys.modules))"
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.strip()
    assert loaded == "", f"import model loaded {loaded}"


@pytest.mark.parametrize("name", sorted(model.PUBLIC_API))
def test_every_public_name_is_its_module_s_object(name):
    module = importlib.import_module(model.PUBLIC_API[name])
    assert getattr(model, name) is getattr(module, name)


def test_the_public_api_holds_the_documented_names_and_dir_lists_them():
    assert set(REQUIRED_API) <= set(model.PUBLIC_API)
    assert set(model.__all__) == set(model.PUBLIC_API)
    assert set(model.PUBLIC_API) <= set(dir(model))


def test_an_unknown_name_is_an_attribute_error_that_names_it():
    with pytest.raises(AttributeError, match="'nonexistent'"):
        model.nonexistent  # noqa: B018
    assert not hasattr(model, "nonexistent")
