"""One HTML page for every report the station writes (diagnosis, sessions, identify, design):
the same head, style sheet and body wrapper, so a report's page differs only in its content."""

from __future__ import annotations

import html
from collections.abc import Sequence

STYLE = ("body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:collapse}"
         "td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%;overflow-wrap:anywhere}td.ev{font-size:80%}"
         "img{max-width:100%}.note{color:#666;font-size:85%}.answer li{margin:4px 0}.warn{color:#a40}"
         "h3{overflow-wrap:anywhere}")
"""The reports' one style sheet (CSS)."""


def html_page(title: str, body: Sequence[str]) -> str:
    """A whole HTML page: UTF-8, ``title`` (escaped here) and the body's parts, one per line.

    Parameters
    ----------
    title : str
        The page's title, plain text.
    body : sequence of str
        HTML fragments, already escaped where they hold text.

    Returns
    -------
    str
        ``<!doctype html>`` ... ``</html>``.

    Examples
    --------
    >>> page = html_page("A & B", ["<p>x</p>"])
    >>> page[page.index("<title>"):page.index("</title>") + 8]
    '<title>A &amp; B</title>'
    >>> page.endswith("<body><p>x</p></body></html>")
    True
    """
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style></head><body>" + "\n".join(body) + "</body></html>")
