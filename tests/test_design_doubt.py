"""How far a log pins a first-order design (station.analysis.design_doubt), against designs
replayed one by one through the lab's own recursion (tests.blind.audit.LabController) and the
blind generator's hidden laws."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from station.analysis.continuous_design import ContinuousDesign
from station.analysis.design_doubt import DesignSpan, alternatives_phrase, design_span, round_roots, span_phrase
from station.analysis.law_rows import BOUNDARY, LawRows
from station.logged import LoggedRun
from tests.blind.audit import LabController, write_audit_case
from tests.blind.rig import tustin

DT = 0.002


def _lab_log(num_s, den_s, e, limit=200.0, recursion="trunc"):
    num, den = tustin(num_s, den_s, DT)
    ctrl = LabController(num, den, limit, recursion)
    return np.array([ctrl.step(x) for x in e])


def _error(n=600, amplitude=26):
    """A 5 Hz sine error in whole counts with a slow offset: an open-loop e, any e will do."""
    k = np.arange(n)
    return np.trunc(amplitude * np.sin(2 * np.pi * 5 * k * DT) + 6 * np.sin(2 * np.pi * 0.7 * k * DT))


def _span(e, v, method="Tustin"):
    rows = LawRows(e, v, 0, 1, 200.0)
    lo, hi = rows.bounds("trunc")
    return design_span(rows.X, lo - BOUNDARY, hi + BOUNDARY, DT, method, 1e3 * 60)


@functools.lru_cache(maxsize=2)
def _unit_laws(zeros, poles):
    """[b0, b1, a1] of (s+z)/(s+p) by scipy's bilinear, one row per design."""
    return np.array([np.concatenate([law[0], law[1][1:]]) for law in
                     (tustin([1.0, z], [1.0, p], DT) for z, p in zip(zeros, poles))])


def _replays(zeros, poles, gain, e, v, limit=200.0):
    """Which gain·(s+z)/(s+p), Tustin (scipy's bilinear), give every logged v through the lab's
    truncating recursion, all designs at once: bool, shape (len(zeros),)."""
    laws = _unit_laws(tuple(zeros), tuple(poles))
    b0, b1, a1 = gain * laws[:, 0], gain * laws[:, 1], laws[:, 2]
    out, prev_e, prev_v = np.ones(len(laws), bool), 0.0, np.zeros(len(laws))
    for x, logged in zip(e, v):
        y = np.clip(np.trunc(b0 * x + b1 * prev_e - a1 * prev_v), -limit, limit)
        out &= y == logged
        prev_e, prev_v = x, y
    return out


def test_every_design_that_replays_the_log_lies_in_the_span():
    # a gain-1 lead on the truncated integer over a 26-count sine: a family reproduces it.
    # Replayed through the lab's recursion, every (z, p) of a grid about the hidden one that
    # gives every logged v lies in the span, at any gain, and the grid's reach its ends
    e = _error()
    v = _lab_log([1.0, 12.0], [1.0, 59.0], e)
    span = _span(e, v)
    assert span is not None and span.holds(12.0, 59.0)
    z, p = (g.ravel() for g in np.meshgrid(np.arange(10.5, 13.5, 0.05), np.arange(55.0, 62.0, 0.1)))
    hit = _replays(z, p, 1.0, e, v)
    assert np.count_nonzero(hit) > 5 and np.ptp(z[hit]) > 0.3 and np.ptp(p[hit]) > 0.3
    inside = np.array([span.holds(a, b) for a, b in zip(z, p)])
    assert np.all(inside[hit]) and not np.all(inside)
    reached = np.zeros(z.size, bool)
    for gain in np.arange(0.9, 1.1, 0.01):  # every gain: the span is over them all, and no wider
        hit = _replays(z, p, gain, e, v)
        assert np.all(inside[hit]), gain
        reached |= hit
    assert z[reached].min() - span.zero[0] < 0.25 and span.zero[1] - z[reached].max() < 0.25  # of 0.93
    assert p[reached].min() - span.pole[0] < 0.8 and span.pole[1] - p[reached].max() < 0.8  # of 3.5


def test_a_sweep_pins_the_design_and_no_span_is_said():
    k = np.arange(2000)
    e = np.trunc(50 * np.sin(2 * np.pi * 2.5 * (k * DT) ** 2))  # the lab's 0-10 Hz sweep
    v = _lab_log([3.0, 39.0], [1.0, 60.0], e)
    span = _span(e, v)
    assert span is not None and span.holds(13.0, 60.0)
    assert not span.wide(13.0, 60.0)
    design = {"num_s": [3.0, 39.0], "den_s": [1.0, 60.0], "span": span.to_json()}
    assert span_phrase(design) == ""


@pytest.mark.parametrize("span, zero, pole, wide", [
    (((15.2, 18.5), (60.6, 67.3)), 17.0, 65.0, True),     # 16 and 18 as round as 17
    (((11.8, 12.1), (47.3, 48.5)), 12.0, 48.0, False),    # nothing else of 2 digits
    (((11.8, 12.1), (44.2, 50.0)), 12.0, 48.0, True),     # the pole open
    (((0.0, 13.8), (0.0, 68.8)), 10.0, 50.0, True),
    (((9.95, 10.04), (49.6, 50.2)), 10.0, 50.0, False),
    (((9.95, 10.04), (67.5, 72.0)), 10.0, 70.0, True),    # 68 as readily typed as 70
    (((9.95, 10.04), (49.6, 50.2)), 10.01, 50.01, True),  # 4 digits: 10.02 and 50.02 inside
])
def test_a_span_is_wide_where_it_holds_another_number_as_round(span, zero, pole, wide):
    assert DesignSpan(*span).wide(zero, pole) is wide


def test_the_round_roots_of_a_span_are_each_inside_it_and_none_inside_is_missed():
    roots = round_roots((15.2, 16.9), 3)
    values = sorted({-f[0].real for f in roots if f[1] == ""})
    assert all(15.2 <= x <= 16.9 for x in values)
    for x in np.arange(15.2, 16.95, 0.1):  # every number of 3 digits there (17 of them), and 16
        assert any(abs(round(x, 1) - y) < 1e-9 for y in values), x
    # wider, 3 digits hold more than WITHIN numbers and pin none: only 2 digits' are tried
    assert sorted({-f[0].real for f in round_roots((15.2, 18.5), 3) if f[1] == ""}) == [16.0, 17.0, 18.0]
    roots = round_roots((15.2, 18.5), 3)
    hz = [f for f in roots if f[1] == "2π·"]  # 2π times Hz: 2π·2.5 = 15.7, 2π·2.9 = 18.2
    assert hz and all(15.2 <= -f[0].real <= 18.5 and abs(f[0].real - 2 * np.pi * f[2]) < 1e-9 for f in hz)
    assert any(abs(f[2] + 2.5) < 1e-12 for f in hz)


def test_the_blind_session_with_u_and_v_swapped_says_the_family_it_cannot_tell_apart(tmp_path):
    # blind `double` seed 1: the lab's session on a 26-count sine, u and v swapped; the hidden
    # 1(s+12)/(s+59) and 1(s+10)/(s+50) reproduce every stored integer, and so do many more:
    # the audit named one and said nothing of the rest. It now says how far the log pins them.
    path, hidden = write_audit_case(tmp_path, "double", 1)
    run = LoggedRun.from_path(path)
    design = run.controller.spec["design"]
    assert run.reproduced and design["method"] == "Tustin"
    span = DesignSpan.from_json(design["span"])
    assert span.holds(hidden.num_s[1] / hidden.num_s[0], hidden.den_s[1])
    line = run.audit.lines()[0]
    assert "the log pins it only to a zero in" in line and span_phrase(design)[2:] in line


def test_the_simplest_tustin_design_in_the_family_is_named_over_another_method(tmp_path):
    # blind `double` seed 4: 1(s+22)/(s+66) on a 33-count sine; the roundings near the fit held
    # no Tustin design, and 0.94(s+22)/(s+62) by ZOH was named. The round numbers the span
    # admits hold the Tustin one, preferred at as few digits.
    path, hidden = write_audit_case(tmp_path, "double", 4)
    run = LoggedRun.from_path(path)
    design = run.controller.spec["design"]
    assert design["method"] == "Tustin", design["text"]
    assert np.allclose(design["num_s"], hidden.num_s) and np.allclose(design["den_s"], hidden.den_s)


def test_one_text_on_one_integer_is_said_once_with_every_method_that_gives_it():
    alts = [("0.99(s+20)/(s+34)", "ZOH", ""), ("0.99(s+20)/(s+34)", "forward Euler", ""),
            ("1(s+12)/(s+60)", "Tustin", ""), ("1(s+12)/(s+60)", "Tustin", "round"), ("2(s+3)/(s+9)", "ZOH", "")]
    phrase = alternatives_phrase(alts, "Tustin", 2)
    assert phrase.count("0.99(s+20)/(s+34)") == 1 and "0.99(s+20)/(s+34) (ZOH or forward Euler)" in phrase
    assert phrase.count("1(s+12)/(s+60)") == 2  # on the float and on the rounded integer: two laws
    assert "2(s+3)/(s+9) (ZOH)" in phrase and phrase.endswith("(the log reproduced by each; 2 more as simple)")
    assert alternatives_phrase([], "Tustin") == ""


def _design(method, span=None):
    return ContinuousDesign((1.0, 12.0), (1.0, 60.0), method, "1(s+12)/(s+60)", 4, span=span)


def test_a_span_is_said_under_a_name_only_where_the_named_design_has_one():
    # A ZOH name has no span; the other integer's Tustin span bounds other designs, and said
    # under the ZOH name it would contradict it. Where both have one, it is both's.
    mine, theirs = DesignSpan((10.0, 14.0), (50.0, 70.0)), DesignSpan((8.0, 13.0), (55.0, 80.0))
    assert _design("ZOH").with_alternatives(_design("Tustin", theirs), "round").span is None
    both = _design("Tustin", mine).with_alternatives(_design("Tustin", theirs), "round").span
    assert both == DesignSpan((8.0, 14.0), (50.0, 80.0))
    assert _design("Tustin", mine).with_alternatives(_design("ZOH"), "round").span == mine


def test_the_blind_case_with_one_design_under_two_methods_says_it_once(tmp_path):
    # blind `zero:command` seed 9: 0.99(s+20)/(s+34) by ZOH and by forward Euler reproduce the
    # log as well as the named 1(s+11)/(s+2π·3); the line said the same text twice.
    path, _ = write_audit_case(tmp_path, "zero:command", 9)
    run = LoggedRun.from_path(path)
    design = run.controller.spec["design"]
    said = {(d["text"], d.get("recursion", "")) for d in design["alternatives"]}
    assert any(t == "0.99(s+20)/(s+34)" for t, _ in said), design["alternatives"]
    line = alternatives_phrase([(d["text"], d["method"], d.get("recursion", "")) for d in design["alternatives"]],
                               design["method"], design["more_alternatives"])  # as replay's controller line says
    for text in {t for t, _ in said} - {design["text"]}:
        assert line.count(text) == sum(t == text for t, _ in said), line


def test_the_round_roots_nearest_the_fit_come_first():
    values = [-f[0].real for f in round_roots((0.0, 70.0), 2, near=40.0)]
    dist = [abs(np.log(x / 40.0)) for x in values]
    assert values[0] == 40.0 and dist == sorted(dist)
    assert sorted(values) == sorted(-f[0].real for f in round_roots((0.0, 70.0), 2))  # the same numbers


def test_a_wide_family_is_named_by_its_members_nearest_the_fit(tmp_path):
    # blind `double` seed 1 (1(s+12)/(s+59) on a 26-count sine): every gain-1 lead of zero/pole
    # about 0.2 reproduces it; the lowest round numbers were said beside the name
    # (1(s+0.1)/(s+0.5), 1(s+0.2)/(s+1), 120 times off), now those nearest the fit
    path, hidden = write_audit_case(tmp_path, "double", 1)
    design = LoggedRun.from_path(path).controller.spec["design"]
    zero, pole = hidden.num_s[1] / hidden.num_s[0], hidden.den_s[1]
    for d in [design, *design["alternatives"]]:
        z, p = d["num_s"][1] / d["num_s"][0], d["den_s"][1]
        assert 1 / 4 < z / zero < 4 and 1 / 4 < p / pole < 4, d["text"]
