"""Serve configuration (dashboard/serve.py): MathJax only for a page that shows a formula.

The page weight itself is measured in a browser by ``benchmarks/bench_page_weight.py``.
"""

from __future__ import annotations

import panel as pn
from bokeh.document import Document
from panel.io import resources

from dashboard import serve


def _roots(pane) -> list:
    """Bokeh roots of a Panel object rendered into a fresh document."""
    document = Document()
    return [pane.get_root(document)]


def test_mathjax_only_for_a_formula(monkeypatch):
    monkeypatch.setattr(resources, "_panel_use_mathjax", resources._panel_use_mathjax)
    plain = pn.pane.Markdown("Peak invert load 19.9 kN, 80 km/h")
    formula = pn.Column(pn.pane.Markdown(r"Stress $$\sigma = E\varepsilon$$"))  # nested
    assert resources._panel_use_mathjax(_roots(plain))  # Panel's own rule: any HTML root
    serve.use_light_resources()
    assert not resources._panel_use_mathjax(_roots(plain))
    assert resources._panel_use_mathjax(_roots(formula))
