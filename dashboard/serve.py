"""Serve configuration of the dashboard: a light first page.

``python -m dashboard.serve [panel serve options]`` is ``panel serve dashboard/app.py --warm``
with two changes to what the browser downloads:

- **compression on**: Tornado gzips every HTTP response (the page and the Bokeh/Panel bundles,
  ~3 MB of JavaScript and CSS that compress about 4:1); Panel's CLI has no such option, so it is
  passed to the server here;
- **MathJax only for a formula**: Panel loads Bokeh's 1.8 MB MathJax bundle on any page that
  holds an HTML or Markdown pane, formula or not. :func:`use_light_resources` makes it load the
  bundle only when such a pane's text contains TeX delimiters (Bokeh's own test,
  ``contains_tex_string``), as Bokeh already does for its own models. The app calls it when
  served, so plain ``panel serve dashboard/app.py`` drops the bundle too.

Both act on private hooks of Panel 1.x (``panel.io.resources._panel_use_mathjax`` and
``Serve.customize_kwargs``); ``benchmarks/bench_page_weight.py`` measures the result.
"""

from __future__ import annotations

import sys
from pathlib import Path

APP = Path(__file__).resolve().parent / "app.py"


def _html_with_formula(roots) -> bool:
    """True if a Panel HTML model in ``roots`` or below shows TeX (the only reason for MathJax)."""
    from bokeh.embed.util import contains_tex_string
    from panel.models.markup import HTML

    return any(
        isinstance(model, HTML) and isinstance(model.text, str) and contains_tex_string(model.text)
        for root in roots
        for model in root.references()
    )


def use_light_resources() -> None:
    """Make Panel load the MathJax bundle only for a page that shows a formula (idempotent)."""
    from panel.io import resources

    resources._panel_use_mathjax = _html_with_formula


def main(argv: list[str] | None = None) -> None:
    """``panel serve dashboard/app.py --warm`` plus ``argv``, gzip on, MathJax only if used."""
    from panel.command import main as panel_main
    from panel.command.serve import Serve

    use_light_resources()
    customize = Serve.customize_kwargs

    def compressed(self, args, server_kwargs):
        """Panel's server options with Tornado's response compression on."""
        return {**customize(self, args, server_kwargs), "compress_response": True}

    Serve.customize_kwargs = compressed
    extra = sys.argv[1:] if argv is None else argv
    sys.argv = ["panel", "serve", str(APP), "--warm", *extra]
    panel_main()


if __name__ == "__main__":
    main()
