"""Every report's page comes from one helper (station.htmlpage.html_page): one head, one style
sheet, the title escaped (issue 23 item 4)."""

from __future__ import annotations

import doctest
import pathlib

import station
from station import htmlpage
from station.htmlpage import html_page

PACKAGE = pathlib.Path(station.__file__).parent


def test_only_the_helper_writes_a_page_head():
    heads = [str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
             if "<!doctype html" in p.read_text().lower() and p.name != "htmlpage.py"]
    assert heads == [], f"pages built by hand (use station.htmlpage.html_page): {heads}"


def test_the_page_escapes_its_title_and_keeps_the_body():
    page = html_page("<script>alert(1)</script> & co", ["<h1>x</h1>", "<p>y</p>"])
    assert page.startswith("<!doctype html>") and page.endswith("</body></html>")
    assert "<title>&lt;script&gt;alert(1)&lt;/script&gt; &amp; co</title>" in page
    assert "<h1>x</h1>\n<p>y</p>" in page and page.count("<style>") == 1


def test_the_example_runs():
    result = doctest.testmod(htmlpage)
    assert result.attempted >= 1 and result.failed == 0
