"""What ``station diagnose`` and ``station identify`` print does not contradict itself: every
column of the candidates table says which fit it belongs to, and the final verdict, the table and
the JSON read one record (issue 24)."""

from __future__ import annotations

import math

import pytest

from station.commands.diagnose import CANDIDATE_COLUMNS, candidate_rows, format_diagnosis
from station.diagnosis.answer.result import Diagnosis, EffectResult
from station.diagnosis.honesty.doubt import Interval
from station.diagnosis.honesty.unexplained import Unexplained
from station.plant.model import as_model


def _effect(name, value, unit, gain, cost_gain, accepted, alone, interval=None):
    return EffectResult(name, value, unit, gain, cost_gain, accepted, f"{name} evidence", [alone, alone], alone,
                        interval, False)


def built_diagnosis(unexplained_flag: bool = False) -> Diagnosis:
    """A diagnosis whose accepted effects sit far from where they were fitted alone, one of them
    with a negative gain alone (the issue's `amp_offset -3.008 ... -144.2% -484.2% yes`)."""
    nominal = as_model(None)
    effects = [
        _effect("coulomb_friction", 4.97, "DAC counts", 30.0, 40.0, True, 8.973, Interval(4.5, 5.4, False, False)),
        _effect("amp_offset", -3.008, "DAC counts", -144.2, -484.2, True, 0.731, Interval(-3.1, -2.9, False, False)),
        _effect("deadzone", 2.5, "DAC counts", 12.0, 9.0, False, 2.5),
    ]
    ext = nominal.with_effects({"coulomb_friction": 4.97, "amp_offset": -3.008}, name="tmm-fit + 2")
    u = Unexplained(unexplained_flag, "4 of 5 runs keep structure" if unexplained_flag else "", [], [], 0)
    return Diagnosis(["coulomb_friction", "amp_offset"], {"theta": 80.0, "accel": 50.0},
                     {"theta": 90.0, "accel": 60.0}, 35.0, effects, ext, nominal, [], "leave-one-run-out",
                     simulations=100, elapsed_s=1.0, unexplained=u)


def test_the_table_labels_the_alone_and_the_extended_columns_and_fills_each_from_its_own_fit():
    diag = built_diagnosis()
    header, *rows = candidate_rows(diag)
    for col in ("value (alone)", "θ gain (alone)", "cost gain (alone)", "value (extended)", "95 % interval (extended)"):
        assert col in header
    by_name = {r.split()[0]: r for r in rows}
    for e in diag.effects:
        r = by_name[e.name]
        words = r.split()
        # value alone is the second cell, the extended value follows the two gains
        assert float(words[1]) == pytest.approx(e.value_alone, rel=1e-3)
        if e.accepted:
            ext = float(words[words.index("%", words.index("%") + 1) + 1])
            assert ext == pytest.approx(e.value, rel=1e-3)
            assert f"{e.interval.lo:.4g} .. {e.interval.hi:.4g}" in r and r.endswith("yes")
        else:
            assert r.endswith("no")
    assert "-3.008" in by_name["amp_offset"] and "0.731" in by_name["amp_offset"]
    # the printed diagnosis uses these rows (diagnose and identify both print format_diagnosis)
    printed = format_diagnosis(diag)
    for line in candidate_rows(diag):
        assert line in printed


@pytest.mark.parametrize("accepted", [True, False])
def test_every_effects_row_keeps_each_cell_in_its_column(accepted):
    """Every unit of the vocabulary (``DAC counts per rad/s``, ``accelerometer counts per s``, ...)
    and every value fits its column: a cell never pushes the ones after it out of line."""
    from station.plant.effects import EFFECTS as VOCABULARY

    effects = [_effect(name, -123456.7 if i % 2 else 0.5, spec.unit, -484.2 if i % 3 else 5.0, 99.9, accepted,
                       -98765.4 if i % 2 else 1.0, Interval(-1234.5, 67890.1, False, False) if accepted else None)
               for i, (name, spec) in enumerate(VOCABULARY.items())]
    diag = Diagnosis([e.name for e in effects if e.accepted], {"theta": 1.0}, {"theta": 1.0}, 0.0,
                     effects, as_model(None), as_model(None), [], "leave-one-run-out")
    header, *rows = candidate_rows(diag)
    unit_at = header.index(" unit ") + 1
    gain_end = header.index("θ gain (alone)") + len("θ gain (alone)")
    cost_end = header.index("cost gain (alone)") + len("cost gain (alone)")
    ext_end = header.index("value (extended)") + len("value (extended)")
    for e, row in zip(effects, rows):
        assert row[unit_at:].startswith(e.unit + " "), (row, e.unit)
        assert row[:gain_end].endswith(f"{e.gain_pct:.1f} %") and row[:cost_end].endswith(f"{e.cost_gain_pct:.1f} %")
        assert row[ext_end - 1] != " " and row[ext_end] == " ", row


# --- identify: the verdict, the table, the identified model and the JSON read one record -----

import re  # noqa: E402

from station.commands.identify import format_identification  # noqa: E402
from station.diagnosis.identify import loop  # noqa: E402
from station.diagnosis.identify.design import Design  # noqa: E402
from station.diagnosis.identify.experiments import candidate_experiments  # noqa: E402
from station.diagnosis.identify.loop import ExperimentRun, identify  # noqa: E402
from station.diagnosis.identify.prefer import Contest, Preference  # noqa: E402
from station.diagnosis.honesty.rivals import WIDE_INTERVAL  # noqa: E402
from station.plant.effects import EFFECTS  # noqa: E402


def parse_table(printed: str) -> dict:
    """The printed candidates table: name -> (value alone, value extended, (lo, hi) or None, accepted)."""
    lines = printed.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("effect ") and "value (alone)" in line)
    out = {}
    for line in lines[start + 1:]:
        name = line.split()[0]
        if name not in EFFECTS:
            break
        left, _, right = line.partition(" % ")
        _, _, right = right.partition(" % ")
        words = right.split()
        ext = None if words[0] == "-" else float(words[0])
        iv = None if words[1] == "-" else (float(words[1]), float(words[3]))
        out[name] = (float(left.split()[1]), ext, iv, words[-1] if iv is None else words[4])
    return out


def parse_model(printed: str) -> dict:
    """The printed 'identified model: a 1.2 unit + b 3 unit' -> {name: value}."""
    line = next(x for x in printed.splitlines() if x.startswith("identified model: "))
    return {m.group(1): float(m.group(2))
            for m in re.finditer(r"([\w:]+) (-?[\d.]+(?:e[-+]?\d+)?)", line.removeprefix("identified model: "))}


def _record(values: dict, causes: list, intervals: dict, alone: dict, flag: bool = False) -> Diagnosis:
    nominal = as_model(None)
    effects = [EffectResult(n, values[n], EFFECTS[n].unit, 20.0, 30.0, True, "", [values[n]] * 2, alone[n],
                            intervals.get(n)) for n in causes]
    effects += [EffectResult(n, v, EFFECTS[n].unit, 5.0, 4.0, False, "", [v, v], v) for n, v in alone.items()
                if n not in causes]
    u = Unexplained(flag, "4 of 5 runs keep structure that encoder rounding cannot produce." if flag else "",
                    [], [], 0)
    return Diagnosis(causes, {"theta": 80.0}, {"theta": 90.0}, 30.0, effects,
                     nominal.with_effects(values), nominal, [], "leave-one-run-out", unexplained=u)


def _identify(monkeypatch, tmp_path, diagnoses, preference=None, budget=1):
    """identify() with the device, the diagnoses, the design and the comparison stubbed."""
    queue = list(diagnoses)
    monkeypatch.setattr(loop, "diagnose", lambda runs, **kw: queue.pop(0))
    monkeypatch.setattr(loop, "read_log", lambda path: None)
    monkeypatch.setattr(loop, "command_quantization", lambda log: "round")
    monkeypatch.setattr(loop, "choose_experiment",
                        lambda base, rv, cands, *a: Design(cands[0], "it separates them", [], {}))
    monkeypatch.setattr(loop, "contest", lambda diag, met, runs, base: Contest([], [], []))  # no logs to refit on
    if preference is not None:
        monkeypatch.setattr(loop, "prefer", lambda old, new, runs, base: preference)
    return identify(out_dir=tmp_path, budget=budget, candidates=["static_friction", "coulomb_friction"],
                    runner=lambda exp, log: ExperimentRun(log, "completed", 0))


def _agrees(ident) -> str:
    """Check that what identify prints and writes reads one record; returns the printed text."""
    printed = format_identification(ident)
    doc = ident.to_json()
    table = parse_table(printed)
    model = parse_model(printed)
    # the identified model is the table's extended column (accepted and held effects), and the JSON's
    assert model == pytest.approx({n: ext for n, (_, ext, _, acc) in table.items() if acc in ("yes", "held")},
                                  rel=1e-3)
    assert model == pytest.approx(doc["identify"]["model"]["effects"], rel=1e-3)
    for e in doc["effects"]:
        if e["accepted"]:
            assert table[e["name"]][1] == pytest.approx(e["value"], rel=1e-3)
            assert table[e["name"]][2] == pytest.approx(e["interval"], rel=1e-3)
        # a held effect is "held" at its extended value in the JSON as in the table (the alone
        # value stays "value", DESIGN.md's meaning for an effect not accepted)
        assert e["held"] == (table[e["name"]][3] == "held"), e
        if e["accepted"] or e["held"]:
            assert table[e["name"]][1] == pytest.approx(e["value_extended"], rel=1e-3)
        else:
            assert e["value_extended"] is None
    # the verdict says "narrow" only of intervals the table shows narrow
    if "every interval narrow" in printed:
        for name, (_, ext, iv, acc) in table.items():
            if iv is not None:
                assert (iv[1] - iv[0]) / 2 <= WIDE_INTERVAL * abs(ext) * 1.01, (name, iv, ext)
    # the unexplained line is the JSON's
    line = next(x for x in printed.splitlines() if x.startswith("unexplained: "))
    assert line.startswith("unexplained: yes") == doc["unexplained"]
    return printed


def test_a_kept_explanation_is_the_record_identify_prints_and_writes(monkeypatch, tmp_path):
    """The issue's contradiction: the earlier explanation kept over a re-diagnosis, refitted on
    every run; the table showed the earlier diagnosis (a wide interval, 'unexplained: no', the
    sliding level at its alone value) while the verdict and the model read the refit."""
    old = _record({"static_friction": 9.0, "coulomb_friction": 6.0}, ["static_friction"],
                  {"static_friction": Interval(5.999, 12.29, False, False)}, {"static_friction": 9.5,
                                                                             "coulomb_friction": 8.973})
    new = _record({"coulomb_friction": 7.0}, ["coulomb_friction"], {}, {"static_friction": 9.5,
                                                                       "coulomb_friction": 7.0}, flag=True)
    refit = {"static_friction": 12.0, "coulomb_friction": 4.97}
    unexplained = Unexplained(True, "4 of 5 runs keep structure that encoder rounding cannot produce.", [], [], 0)
    pref = Preference(True, refit, 1.0, 50.0, "the earlier explanation fits them better",
                      {"static_friction": Interval(11.5, 12.6, False, False)}, unexplained)
    ident = _identify(monkeypatch, tmp_path, [old, new], pref)
    assert ident.stopped.startswith("settled") and ident.kept
    printed = _agrees(ident)
    assert parse_model(printed) == pytest.approx(refit, rel=1e-3)
    assert "unexplained: yes" in printed and "5.999" not in printed


def test_an_interval_wide_without_rivals_is_not_called_narrow(monkeypatch, tmp_path):
    """A delay of 1 sample with 95 % interval 0.6 .. 1.4: both ends round to the value, so no
    experiment can separate them; the verdict must not call the interval narrow."""
    diag = _record({"delay": 1.0}, ["delay"], {"delay": Interval(0.6, 1.4, False, False)}, {"delay": 1.0})
    ident = _identify(monkeypatch, tmp_path, [diag], budget=0)
    assert ident.stopped.startswith("settled") and "narrow" not in ident.stopped, ident.stopped
    _agrees(ident)


def test_an_ending_with_rivals_left_names_them(monkeypatch, tmp_path):
    """A new user's contradiction: "4 rival(s) remain" and then "alternatives: none", the rivals
    (a wide interval's ends) never named. The ending names each."""
    diag = _record({"coulomb_friction": 6.0}, ["coulomb_friction"],
                   {"coulomb_friction": Interval(3.0, 9.0, False, False)}, {"coulomb_friction": 6.0})
    ident = _identify(monkeypatch, tmp_path, [diag], budget=0)
    assert "2 rival(s) remain: coulomb_friction 3 DAC counts (the 95 % interval's lower end); coulomb_friction 9 " \
           "DAC counts (the 95 % interval's upper end)" in ident.stopped, ident.stopped
    _agrees(ident)


def test_a_settled_diagnosis_reads_the_same_everywhere(monkeypatch, tmp_path):
    diag = _record({"static_friction": 12.0, "coulomb_friction": 5.0}, ["static_friction"],
                   {"static_friction": Interval(11.5, 12.5, False, False)},
                   {"static_friction": 11.0, "coulomb_friction": 8.973}, flag=True)
    ident = _identify(monkeypatch, tmp_path, [diag], budget=0)
    assert "every interval narrow" in ident.stopped
    printed = _agrees(ident)
    assert parse_table(printed)["coulomb_friction"][1:] == (5.0, None, "held")


# --- diagnose: the cost said up front is the cost it runs -----------------------------------

def test_the_estimate_counts_the_simulations_the_diagnosis_runs(rig_data, tmp_path, capsys):
    """Issue 24: 'about 12000 simulations' up front, '22886 simulations' at the end. On two of
    the rig's logs (leave-one-run-out, the whole vocabulary; about 20 s) the estimate is within
    0.67-1.5× of the count."""
    import json

    from station.cli import main

    runs = [str(rig_data / "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"),
            str(rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt")]
    out = tmp_path / "d.json"
    assert main(["diagnose", *runs, "--json", str(out)]) == 0
    err = capsys.readouterr().err
    estimate = int(re.search(r"about (\d+) simulations", err).group(1))
    actual = json.loads(out.read_text())["simulations"]
    assert 0.67 <= estimate / actual <= 1.5, (estimate, actual)


# --- unexplained: does the extended model predict held-out runs better? (issue 26 item 4) ----

@pytest.mark.parametrize("gain, word", [(35.0, "35.0 % better"), (-14.0, "14.0 % worse"), (0.0, "no better")])
def test_unexplained_says_whether_the_extended_model_predicts_better_and_the_save_warns(tmp_path, gain, word):
    import argparse
    import contextlib
    import io

    from station.commands import diagnose as cmd

    diag = built_diagnosis(unexplained_flag=True)
    diag.gain_pct = gain
    line = next(x for x in format_diagnosis(diag).splitlines() if x.startswith("unexplained: yes"))
    assert word in line and "than the nominal model" in line
    # --save-model warns exactly when the saved model predicts no better than nominal
    args = argparse.Namespace(runs=["a.txt"], validate=[], max_samples=10**6, quiet=True, model=None,
                              report=None, json=None, save_model=str(tmp_path / "m.toml"), force=False, jobs=1)
    err = io.StringIO()
    real = (cmd.check_outputs, cmd.plan)
    cmd.check_outputs, cmd.plan = (lambda *a, **k: None), (lambda *a, **k: "")
    try:
        import station.diagnosis as pkg
        saved, pkg.diagnose = pkg.diagnose, (lambda *a, **k: diag)
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            assert cmd.run(args) == 0
    finally:
        cmd.check_outputs, cmd.plan = real
        pkg.diagnose = saved
    warned = "warning: --save-model" in err.getvalue()
    assert warned == (gain <= 0), err.getvalue()
    assert (tmp_path / "m.toml").exists()


def test_a_decided_sensor_fault_is_said_once_and_its_undecided_wiring_is_no_decided_fault():
    """A reversed accelerometer decided from the data and refined by the fit, beside a physical
    effect: the answer named it twice ("the sensor faults decided from the data, accel_gain
    -0.962; then drive_c ..., together with accel_gain -0.962"), said the wiring that reads the
    same signs under "sensor fault, decided from the data", and then "alternatives: none: no
    other explanation comes as close" although that wiring predicts the same θ and a."""
    from station.diagnosis.answer.prose import answer_points
    from station.diagnosis.answer.report import _alternatives_table
    from station.logged.sensors import SensorEvidence, decide_faults

    faults = decide_faults([SensorEvidence("x.txt", 0.95, 0.95, -0.9, -1.2)] * 3)
    assert set(faults.effects) == {"accel_gain"} and faults.alternative
    nominal = as_model(None)
    effects = [_effect("coulomb_friction", 4.97, "DAC counts", 30.0, 40.0, True, 8.9, Interval(4.5, 5.4, False, False)),
               _effect("accel_gain", -0.962, "1", 11.0, 20.0, True, -0.94, Interval(-1.03, -0.89, False, False))]
    ext = nominal.with_effects({"coulomb_friction": 4.97, "accel_gain": -0.962})
    diag = Diagnosis(["coulomb_friction", "accel_gain"], {"theta": 80.0}, {"theta": 90.0}, 35.0, effects, ext, nominal,
                     [], "leave-one-run-out", sensor_faults=faults.refined({"accel_gain": -0.962}))
    points = dict((label, text) for label, text in answer_points(diag) if label != "Audit")
    assert points["Cause"].count("(accel_gain)") == 1 and points["Cause"].count("(coulomb_friction)") == 1
    assert points["Cause"].startswith("the sensor faults decided from the data, the accelerometer")
    assert "-1.03" in points["Cause"]  # the fit's interval, said with the fault
    audit = diag.audit_lines()
    assert not any(faults.alternative in line for line in audit if line.startswith("sensor fault, decided"))
    assert any(line.startswith("sensor wiring, not decided by the data: " + faults.alternative) for line in audit)
    assert faults.alternative in points["Alternatives"]
    printed = format_diagnosis(diag)
    assert "alternatives: none (beside the sensor wiring the data cannot decide, above)" in printed
    assert "sensor wiring the data cannot decide" in "".join(_alternatives_table(diag))
    # the refined fault alone accepted: no physical effect is claimed
    alone = Diagnosis(["accel_gain"], {"theta": 80.0}, {"theta": 90.0}, 5.0, effects[1:], ext, nominal, [],
                      "leave-one-run-out", sensor_faults=faults.refined({"accel_gain": -0.962}))
    cause = dict(answer_points(alone))["Cause"]
    assert cause.count("(accel_gain)") == 1 and cause.endswith("; no physical effect beside them.")
