"""House rules of dashboard/ (issue 23): small modules, no import circle, app.py only wiring.

Read from the source with ``ast``, nothing imported: the rules hold for the files as written.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

DASHBOARD = Path(__file__).resolve().parent.parent / "dashboard"
MAX_LINES = 600  # issue 23: a newcomer reads a module whole
MODULES = sorted(DASHBOARD.glob("*.py"))


def _module_name(path: Path) -> str:
    """``dashboard.x`` of ``dashboard/x.py`` (``dashboard`` for the package's __init__)."""
    return "dashboard" if path.stem == "__init__" else f"dashboard.{path.stem}"


def _dashboard_imports(path: Path, known: set[str]) -> set[str]:
    """The dashboard modules that ``path`` imports at its top level (when it is imported).

    ``from dashboard import plots`` imports the module ``dashboard.plots``; an import inside a
    function counts too (it is a circle deferred, not removed).
    """
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found |= {f"{node.module}.{alias.name}" for alias in node.names}
    return {name for name in found if name in known} - {_module_name(path)}


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle of ``graph`` (module → modules it imports) as a path, or None."""
    state: dict[str, str] = {}  # "open" while on the current path, "done" once explored

    def visit(module: str, path: list[str]) -> list[str] | None:
        state[module] = "open"
        for imported in sorted(graph[module]):
            if state.get(imported) == "open":
                return [*path[path.index(imported) :], imported]
            if imported not in state:
                found = visit(imported, [*path, imported])
                if found:
                    return found
        state[module] = "done"
        return None

    for module in sorted(graph):
        if module not in state:
            found = visit(module, [module])
            if found:
                return found
    return None


@pytest.mark.parametrize("path", MODULES, ids=lambda path: path.name)
def test_no_dashboard_module_is_over_600_lines(path):
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.name}: {lines} lines"


def test_dashboard_modules_import_no_circle():
    known = {_module_name(path) for path in MODULES}
    graph = {_module_name(path): _dashboard_imports(path, known) for path in MODULES}
    assert _cycle(graph) is None, " → ".join(_cycle(graph))


def test_the_cycle_finder_finds_a_circle():
    """The check above would see the old export ↔ study_view circle (and a longer one)."""
    assert _cycle({"a": {"b"}, "b": {"a"}}) == ["a", "b", "a"]
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


# What app.py may use of Panel: layouts, the page template, the server's state, and the
# component base class (pn.viewable). Widgets, panes, indicators, cards and plots belong to the
# views; app.py only places and connects them.
WIRING_CALLS = {"Column", "Row", "Tabs", "template", "state", "io", "extension", "viewable"}


def _dotted(node: ast.AST) -> str:
    """``pn.widgets.Select`` of an attribute chain (empty for anything else)."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    return ".".join([node.id, *reversed(parts)]) if isinstance(node, ast.Name) else ""


def test_app_is_a_wiring_layer():
    """app.py builds no plot, widget or pane and formats no HTML: it imports no plotting
    library, and of Panel uses only layouts, the template and the server's state."""
    tree = ast.parse((DASHBOARD / "app.py").read_text(encoding="utf-8"))
    imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {alias.name for alias in node.names}
    plotting = {name for name in imported if name.split(".")[0] in {"holoviews", "bokeh"}}
    assert not plotting, plotting
    assert not {"html", "dashboard.plots"} & imported
    panel_uses = {
        _dotted(node).split(".")[1]
        for node in ast.walk(tree)
        if isinstance(node, ast.Attribute) and _dotted(node).startswith("pn.")
    }
    assert panel_uses <= WIRING_CALLS, panel_uses - WIRING_CALLS
