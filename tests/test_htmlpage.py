"""Every report's page comes from one helper (station.htmlpage.html_page: one head, one style
sheet, the title escaped) and every --json from one writer that turns NaN into null itself
(station.outputs.Transaction.write_json; issue 23 item 4)."""

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


def test_every_json_written_is_valid_json_with_null_for_nan(tmp_path):
    # one writer for every --json: NaN and infinities become null there, numpy values plain
    import json
    import math

    import numpy as np

    from station.outputs import write_json

    doc = {"nan": math.nan, "inf": [math.inf, -np.inf, 1.5], "np": np.float64(2.5), "arr": np.array([1.0, np.nan]),
           "nested": {"i": np.int64(3), "t": (math.nan,)}}
    path = write_json(tmp_path / "x.json", doc)
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    back = json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
    assert back == {"nan": None, "inf": [None, None, 1.5], "np": 2.5, "arr": [1.0, None],
                    "nested": {"i": 3, "t": [None]}}
