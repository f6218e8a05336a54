"""The served page's frame: the sidebar as a drawer in a narrow window, and the page styles.

In a window of at most :data:`DRAWER_BELOW_PX` the sidebar no longer takes 320 px beside the
results (at 420 px it left them 100 px): it lies over the page as a drawer, closed when the
page opens, and the header's ☰ button opens and closes it. Above that width the sidebar sits
beside the results as before.
"""

from __future__ import annotations

from bokeh.document import Document
from bokeh.models import CustomJS

DRAWER_BELOW_PX = 900
"""Window width (px) at and below which the sidebar is a drawer."""

PAGE_CSS = f"""
@media (max-width: {DRAWER_BELOW_PX}px) {{
  #sidebar {{
    position: absolute;
    z-index: 1050;
    left: 0;
    top: 0;
    bottom: 0;
    height: auto;
    width: min(var(--sidebar-width), 88vw);
    max-width: 88vw !important;
    background-color: var(--bs-body-bg);
    box-shadow: 4px 0 16px rgba(0, 0, 0, 0.25);
  }}
  #content {{ position: relative; }}
  #main {{ padding: 8px; }}
  #header .title {{ white-space: normal; font-size: 1.05em; line-height: 1.3em; }}
}}
"""
"""Styles of the served page (the template's raw CSS)."""

# The template opens the sidebar on every page; in a narrow window it starts closed (the
# template only knows the window's width once the page is in the browser).
_CLOSE_DRAWER_JS = f"""
if (window.innerWidth <= {DRAWER_BELOW_PX}) {{
  const sidebar = document.getElementById("sidebar");
  const toggle = document.getElementById("sidebar-toggle");
  if (sidebar) sidebar.classList.remove("show");
  if (toggle) toggle.setAttribute("aria-expanded", "false");
}}
"""


def close_drawer_in_narrow_windows(document: Document) -> None:
    """Close the sidebar when ``document``'s page opens in a window of at most
    :data:`DRAWER_BELOW_PX`."""
    document.js_on_event("document_ready", CustomJS(code=_CLOSE_DRAWER_JS))
