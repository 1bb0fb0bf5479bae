"""Three column faults at once under a true header: θ from the encoder's count, v in volts or
about an unsigned DAC code's zero, and θ negated or u and v swapped.

The audit read each fault alone and each pair; three at once were left standing. The rig's P
step with θ negated, from its count 517, and v in volts of a ±5 V 12-bit DAC read "P: not this
law (max |dv| = 200 counts); no law found" and an overshoot of 934 %; with v about 2048 in place
of volts, an integrator carrying 2048 in its memory ("2(s-4e-11)/(s-7e-13) ... clamp ±2148")
and the header contradicted. Now, where the header's law reproduces neither the log nor what
the check made of it, each rewrite is checked as a log of its own
(:func:`station.logged.columns.check_columns`), when the law lies on a line through v there
(:func:`station.logged.command_scale.law_line`). The rig's logs are rewritten by a script
written from the format (:func:`tests.test_double_faults._rewrite`); the blind generator's
``three:columns`` class writes its own.
"""

from __future__ import annotations

import pytest

from station.logged import LoggedRun
from station.logged.command_scale import law_line
from station.plant import load_model
from station.runlog import read_log
from tests.blind.audit import V_UNITS, write_audit_case
from tests.test_double_faults import LEAD, P, P_2009, _rewrite, _said

VOLTS = 5.0 / 2048
THETA0 = "θ logged before its zero was taken off (θ0 = 59 counts)"
SAID = {"negate": "θ written with the other sign", "swap": "u and v swapped", "zero": "v about 2048 counts"}


def _unit(name: str) -> str:
    """The unit's claim: a whole-count command steps by the unit, a float one is read in it."""
    return f"v in {'units' if name == LEAD else 'steps'} of {VOLTS:.6g}"


@pytest.mark.parametrize("name", [P, P_2009, LEAD])
@pytest.mark.parametrize("command", ["volts", "zero"])
@pytest.mark.parametrize("column", ["negate", "swap", "negate+swap"])
def test_three_column_faults_under_a_true_header(rig_data, tmp_path, name, command, column):
    """Three faults, and four: u and v swapped beside θ negated (:data:`station.logged.columns.PAIRS`,
    each pair checked as a log of its own too; before, nothing said, or v and θ swapped)."""
    clean = LoggedRun.from_path(rig_data / name)
    columns = column.split("+")
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "three.txt", theta0=59.0,
                                       volts=VOLTS if command == "volts" else None,
                                       zero=2048.0 if command == "zero" else None,
                                       negate="negate" in columns, swap="swap" in columns))
    said = SAID[command] if command == "zero" else _unit(name)
    assert _said(run) == {*(SAID[c] for c in columns), said, THETA0}
    assert run.reproduced and run.source == "header"
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)


# P kp 1.5 about 128 with u and v swapped (a clamp at ±150 the header does not print), P kp 0.5
# about 32768 with θ negated (before, an integrator carrying 32768), leads in volts and about 2048
@pytest.mark.parametrize("seed", [3, 8, 0, 1, 2])
def test_blind_three_column_faults(tmp_path, seed):
    path, hidden = write_audit_case(tmp_path, "three:columns", seed)
    run = LoggedRun.from_path(path)
    assert run.reproduced and run.source == "header" and run.alignment == hidden.alignment
    said = _said(run)
    assert f"θ logged before its zero was taken off (θ0 = {hidden.theta_zero:g} counts)" in said
    assert ("θ written with the other sign" in said) == hidden.negate
    assert ("u and v swapped" in said) == bool(hidden.swap)
    (command,) = {c for c in said if c.startswith("v ")}
    if hidden.v_zero is not None:
        assert command == f"v about {hidden.v_zero:g} counts"
    else:
        assert float(command.split()[-1]) == pytest.approx(V_UNITS[hidden.v_unit], rel=1e-3)
    assert len(said) == 3


def test_law_line_is_the_law_through_v_in_any_unit_and_zero(rig_data, tmp_path):
    """True where v is the header's law in another unit and about another zero, θ from its
    count; False where θ is negated (no line: the law's error has the other sign) and where
    the header names no closed-loop law."""
    both = _rewrite(rig_data / P, tmp_path / "both.txt", theta0=59.0, volts=VOLTS, zero=3.0)
    assert law_line(read_log(both))
    negated = _rewrite(rig_data / P, tmp_path / "neg.txt", theta0=59.0, volts=VOLTS, negate=True)
    assert not law_line(read_log(negated))
    open_loop = _rewrite(rig_data / P, tmp_path / "ol.txt", header=["#SLFR RTP OL_Test"], volts=VOLTS)
    assert not law_line(read_log(open_loop))


def test_law_line_is_no_line_through_a_law_that_commands_nothing(rig_data, tmp_path):
    """A header whose law moves its command by less than a count (a fuzzed Gth of gain 1e-9)
    puts any v on a line at some absurd unit: no line (before, True, and every rewrite of the
    log was identified again: 21.5 s for a 0.2 s log of the input fuzz, 1.2 s now)."""
    text = (rig_data / P).read_text().replace("#kp=2.0", "#kp=1e-9")
    path = tmp_path / "tiny.txt"
    path.write_text(text)
    assert "#kp=1e-9" in text
    assert not law_line(read_log(path))
    assert not law_line(read_log(_rewrite(path, tmp_path / "tiny_volts.txt", volts=VOLTS)))


@pytest.mark.parametrize("name, command, column", [(P, "zero", "negate"), (P_2009, "zero", "swap"),
                                                   (LEAD, "zero", "swap"), (P, "volts", "swap")])
def test_three_column_faults_under_an_open_loop_header(rig_data, tmp_path, name, command, column):
    """The lab's session's header over the three: the law inferred, each fault said. Before, θ negated
    beside v about 2048 read as an integrator carrying 2166 in its memory ("2(s-4e-11)/(s-8e-13) ...
    clamp ±2148", the log "cut from a longer run"), v's zero and θ0 unsaid; the lead's swap, nothing."""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "three.txt", header=["#SLFR RTP OL_Test"],
                                       theta0=59.0, volts=VOLTS if command == "volts" else None,
                                       zero=2048.0 if command == "zero" else None,
                                       negate=column == "negate", swap=column == "swap"))
    said = _said(run)
    assert {SAID[column], THETA0} < said and len(said) == 3
    assert (SAID["zero"] in said) == (command == "zero")
    assert run.reproduced and run.source == "inferred (header contradicted)"
    spec = run.controller.spec
    if name == LEAD:
        assert spec["design"]["text"] == "20(s+2π·5)/(s+2π·20)"
    else:  # (a P's v in volts is another kp as much: kp 2 in steps of 2 volts-counts reads as kp 1)
        assert spec["kind"] == "p" and (command != "zero" or spec["kp"] == (2.0 if name == P else 1.0))
    assert run.step_metrics() == clean.step_metrics()
