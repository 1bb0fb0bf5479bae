"""Notes and messages are whole sentences (issue 24: `note: rig: ...: its accelerometer is not
used (...); its θ is` was a template cut mid-sentence): every message template in the package
ends where a sentence can end, and the one place that shortens prose for a line keeps whole
sentences only."""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import numpy as np

from station.commands.diagnose import SENTENCE_END, whole_sentences

PACKAGE = Path(__file__).resolve().parents[1] / "station"

DANGLING = {"is", "are", "was", "were", "be", "been", "the", "an", "its", "their", "his", "her", "our", "and",
            "or", "nor", "than", "but", "of", "from", "by", "with", "into", "whose", "which", "because", "while",
            "when", "if", "so", "very", "more", "less", "not"}
"""Words no sentence ends on: a template whose text ends on one was cut short."""

MESSAGE_CALLS = {"append", "say", "warn", "progress", "StationError", "note", "notes", "print", "extend"}
"""Calls whose string arguments are notes or messages someone reads."""


def _tail(node: ast.AST) -> str | None:
    """The literal text a template ends with (None when it ends with a value)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr) and node.values:
        last = node.values[-1]
        return last.value if isinstance(last, ast.Constant) else None
    return None


def _call_name(call: ast.Call) -> str:
    f = call.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


def message_templates():
    """Every string template passed (whole, or as the last operand of a ``+``) to a message call."""
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for call in ast.walk(tree):
            if not isinstance(call, ast.Call) or _call_name(call) not in MESSAGE_CALLS:
                continue
            for arg in call.args:
                while isinstance(arg, ast.BinOp) and isinstance(arg.op, ast.Add):
                    arg = arg.right
                if isinstance(arg, ast.IfExp):
                    arg = arg.orelse
                text = _tail(arg)
                if text is not None:
                    yield f"{path.relative_to(PACKAGE.parent)}:{arg.lineno}", text


def test_the_scan_reaches_the_notes():
    found = dict(message_templates())
    assert len(found) > 200
    assert any(where.startswith("station/diagnosis/sessions/diagnose.py") and "θ is" in t for where, t in found.items())


def test_no_message_template_ends_mid_sentence():
    cut = []
    for where, text in message_templates():
        if not text or text[-1].isspace():
            continue  # a fragment joined to what follows at run time
        last = re.search(r"([^\W\d_]+)$", text)
        if last and last.group(1).lower() in DANGLING and " " in text:
            cut.append(f"{where}: ...{text[-50:]!r}")
    assert not cut, "templates that end mid-sentence:\n" + "\n".join(cut)


def test_the_scan_catches_a_cut_template(tmp_path, monkeypatch):
    """The check fails on the issue's own note (a test that cannot fail is a defect)."""
    pkg = tmp_path / "station"
    pkg.mkdir()
    (pkg / "m.py").write_text('notes = []\nnotes.append(f"{s}: its accelerometer is not used (drift); its θ is")\n')
    monkeypatch.setattr(sys.modules[__name__], "PACKAGE", pkg)
    texts = [t for _, t in message_templates()]
    assert texts and re.search(r"(\w+)$", texts[0]).group(1) in DANGLING


def test_shortened_prose_keeps_whole_sentences_only():
    rng = np.random.default_rng(24)
    words = ["θ", "off", "by", "2+", "counts", "in", "12", "%", "of", "the", "samples", "(RMS", "1.5", "counts)",
             "run", "P_step.txt", "a's", "residual", "0.3", "follows", "position"]
    for _ in range(500):
        sentences = [" ".join(rng.choice(words, rng.integers(1, 40))) + rng.choice([".", "!", "?"])
                     for _ in range(rng.integers(1, 6))]
        text = " ".join(sentences)
        width = int(rng.integers(10, 400))
        out = whole_sentences(text, width)
        if out == text:
            continue
        assert out.endswith(" (…)")
        kept = out[:-len(" (…)")]
        assert text.startswith(kept) and kept[-1] in ".!?"
        # a whole number of the text's sentences, and as many as fit in width (at least one)
        n = len(SENTENCE_END.split(kept))
        assert kept == " ".join(sentences[:n])
        assert len(kept) <= width or n == 1
        assert n == 1 or len(" ".join(sentences[:n + 1])) > width
