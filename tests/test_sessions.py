"""station survey DIR... --diagnose: sessions and drift (DESIGN.md "Sessions and drift", issue 17).

Blind: the independent generator (tests/blind, never station.plant) writes the four thesis-like
runs of a case into one folder per session; the diagnosis sees only the files. The real rig:
its 2009 logs (a subfolder) against the 2013-14 ones.
"""

from __future__ import annotations

import json
import math
import re

import pytest

from station.cli import main
from station.plant.model import builtin_models
from station.diagnosis.sessions.diagnose import ACCEL_DRIFT_COUNTS, diagnose_sessions
from station.diagnosis.sessions.layout import PerSession, key
from station.diagnosis.sessions.logs import cut_lengths, group_sessions, model_file_names
from station.runlog.text import header_lines
from tests.blind.cases import TOLERANCE, value_error
from tests.blind.generator import write_case

DRIFT = {"s2009": 3.0, "s2014": 12.0}
"""Hidden Coulomb friction per session, DAC counts; both share param:drive_c = DRIVE_C."""
DRIVE_C = 1.6

FEW = ("coulomb_friction", "deadzone", "param:drive_c", "param:drive_k", "param:J_base")
"""Candidates of the tests that judge the drift decision, not the vocabulary (the diagnosis's
blind tests walk the whole vocabulary; the drift test below does too)."""


@pytest.fixture(scope="module")
def drift_folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("sessions") / "lab"
    for seed, (name, friction) in enumerate(DRIFT.items(), 1):
        write_case(root / name, {"coulomb_friction": friction, "param:drive_c": DRIVE_C}, seed)
    return root


def _station_log(path, meta):
    path.write_text("\n".join(header_lines(meta)) + "\n" + "\t".join(["0"] * 10) + "\n")


# --- grouping, bounds, per-session values: no diagnosis ------------------------------------


def test_sessions_are_folders_or_our_header_session(tmp_path):
    for folder in ("a/2009", "b/2009", "c"):
        (tmp_path / folder).mkdir(parents=True)
    for f in ("a/2009/x.txt", "b/2009/y.txt", "c/z.txt"):
        (tmp_path / f).write_text("t\tv\ttheta\ta\n")
    _station_log(tmp_path / "c" / "ours.tsv", {"session": "bench-3", "dt": 0.002})
    _station_log(tmp_path / "a" / "2009" / "also.tsv", {"session": "bench-3"})
    groups = {s.name: sorted(p.name for p in s.paths) for s in group_sessions(sorted(tmp_path.rglob("*.t*")))}
    assert groups == {"bench-3": ["also.tsv", "ours.tsv"], "c": ["z.txt"], "a/2009": ["x.txt"], "b/2009": ["y.txt"]}


@pytest.mark.parametrize("folder, header, name, file", [
    ("rig", None, "rig-session", "rig-session.toml"),            # the 2013-14 logs' folder: not the built-in
    ("x", "tmm-fit", "tmm-fit-session", "tmm-fit-session.toml"),
    ("x", "RIG-2009", "RIG-2009-session", "RIG-2009-session.toml"),
    ("x", "..rig", "..rig", "rig-session.toml"),                 # its file stem would be the built-in's
    ("x", "s" * 5000, "s" * 60, "s" * 60 + ".toml"),            # a header's long name: cut before any work
    ("x", "bench\x00\n 3\t", "bench 3", "bench_3.toml"),
    ("x", "rig2", "rig2", "rig2.toml"),
])
def test_session_names_are_short_and_not_a_built_in_models(tmp_path, folder, header, name, file):
    path = tmp_path / folder / "run.tsv"
    path.parent.mkdir(parents=True)
    if header is None:
        path.write_text("t\tv\ttheta\ta\n")
    else:
        _station_log(path, {"session": header, "dt": 0.002})
    sessions = group_sessions([path])
    assert [s.name for s in sessions] == [name]
    assert model_file_names(sessions) == [file]
    for n in [name, file]:
        assert n.lower().removesuffix(".toml") not in builtin_models()


def test_model_files_are_safe_unique_names(tmp_path):
    sessions = group_sessions([tmp_path / "a b" / "x.txt", tmp_path / "a_b" / "y.txt"])
    assert model_file_names(sessions) == ["a_b.toml", "a_b-2.toml"]


def test_cut_lengths_cut_the_longest_runs_to_one_length():
    # 1000 + 1000 kept, the three long runs share the rest: (20000 - 2000) / 3 = 6000 each
    assert cut_lengths([1000, 20000, 10000, 10000, 1000], 20000) == [1000, 6000, 6000, 6000, 1000]
    assert cut_lengths([1000, 5000], 20000) == [1000, 5000]
    assert sum(cut_lengths([7, 11, 13], 20)) <= 20


def test_each_run_gets_its_own_sessions_values():
    resolve = PerSession([0, 1, 1])
    effects = {"param:drive_c": 1.6, key("coulomb_friction", 0): 3.0, key("coulomb_friction", 1): 12.0}
    assert resolve(effects, 0) == {"param:drive_c": 1.6, "coulomb_friction": 3.0}
    assert resolve(effects, 2) == {"param:drive_c": 1.6, "coulomb_friction": 12.0}


def test_max_samples_default_is_the_diagnosis_one():
    import inspect

    from station.commands import survey
    from station.rig import SESSIONS_MAX_SAMPLES

    default = inspect.signature(diagnose_sessions).parameters["max_samples"].default
    assert survey.SESSIONS_MAX_SAMPLES == default == SESSIONS_MAX_SAMPLES


def test_a_drifting_accelerometer_channel_is_not_used(rig_data):
    from station.diagnosis.runs.cases import load_case
    from station.diagnosis.sessions.logs import accel_drift

    # the 2014 log's a creeps from -66 to -26 counts: no accelerometer behind it
    assert accel_drift(load_case(rig_data / "without_accel_01_28_14_test_2.txt")) > ACCEL_DRIFT_COUNTS
    assert accel_drift(load_case(rig_data / "swept_sine_kp_1_amp_50.txt")) < ACCEL_DRIFT_COUNTS / 2


# --- bad input: one line, exit 2, nothing started ---------------------------------------------


@pytest.mark.parametrize("extra, expected", [
    (["--save-models", "m"], "--save-models: only with --diagnose"),
    (["--json", "x.json"], "--json: only with --diagnose"),
    (["--diagnose", "--csv", "x.csv"], "--csv: not with --diagnose"),
    (["--diagnose", "--jobs", "2"], "--jobs: not with --diagnose"),
    (["--diagnose", "--no-model"], "--no-model: not with --diagnose"),
])
def test_options_that_do_not_go_together_are_refused(tmp_path, capsys, extra, expected):
    (tmp_path / "run.txt").write_text("t\tv\ttheta\ta\n0\t0\t0\t0\n")
    assert main(["survey", str(tmp_path), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert expected in err and "\n" not in err


def test_no_usable_run_says_why_in_one_line(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("x\n")
    assert main(["survey", str(tmp_path), "--diagnose"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("station:")]
    assert len(err) == 1 and "no usable run" in err[0] and "notes.txt" in err[0] and "no usable columns" in err[0]


def test_one_usable_run_is_refused(tmp_path, capsys):
    write_case(tmp_path / "all", {}, 1)
    one = tmp_path / "one"
    one.mkdir()
    src = sorted((tmp_path / "all").iterdir())[0]
    (one / src.name).write_bytes(src.read_bytes())
    assert main(["survey", str(one), "--diagnose"]) == 2
    assert "leave-one-run-out needs at least two" in capsys.readouterr().err
    (one / "notes.txt").write_text("x\n")  # a file set aside: the refusal says which and why
    assert main(["survey", str(one), "--diagnose"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("station:")]
    assert len(err) == 1 and "one usable run" in err[0] and "set aside" in err[0] and "notes.txt" in err[0], err


def test_an_existing_output_is_refused_before_the_diagnosis(drift_folder, tmp_path, capsys):
    out = tmp_path / "drift.json"
    out.write_text("{}")
    assert main(["survey", str(drift_folder), "--diagnose", "--json", str(out)]) == 2
    captured = capsys.readouterr()
    assert "exists; use --force" in captured.err and "step 1" not in captured.err
    assert out.read_text() == "{}"


# --- the diagnosis ----------------------------------------------------------------------------


def test_drifting_friction_is_found_per_session_and_the_damping_shared(drift_folder, tmp_path, capsys):
    from station.plant.model import load_model

    out, models, report = tmp_path / "drift.json", tmp_path / "models", tmp_path / "report"
    assert main(["survey", str(drift_folder), "--diagnose", "--json", str(out), "--save-models", str(models),
                 "--report", str(report)]) == 0
    captured = capsys.readouterr()
    doc = json.loads(out.read_text())
    assert set(doc) == {"sessions", "shared", "drifting"}
    assert all(set(s) == {"name", "runs", "effects", "model"} for s in doc["sessions"])
    assert doc["drifting"] == ["coulomb_friction"], captured.out
    assert value_error(DRIVE_C, doc["shared"]["param:drive_c"]) <= TOLERANCE, doc["shared"]
    for s in doc["sessions"]:
        found = s["effects"]["coulomb_friction"]
        assert value_error(DRIFT[s["name"]], found) <= TOLERANCE, (s["name"], found)
        assert len(s["runs"]) == 4
        model = load_model(s["model"])  # a model file any command loads
        assert model.effect("coulomb_friction") == pytest.approx(found)
        assert model.effect("param:drive_c") == pytest.approx(doc["shared"]["param:drive_c"])
    assert "coulomb_friction drifts:" in captured.out and "param:drive_c is shared" in captured.out
    assert (report / "report.html").read_text().count("coulomb_friction drifts") == 1
    assert (report / "drift.png").read_bytes().startswith(b"\x89PNG")


def test_sessions_with_the_same_effects_do_not_drift(tmp_path):
    hidden = {"coulomb_friction": 8.0, "param:drive_c": DRIVE_C}
    paths = write_case(tmp_path / "monday", hidden, 3) + write_case(tmp_path / "tuesday", hidden, 4)
    result = diagnose_sessions(group_sessions(paths), candidates=FEW)
    assert result.drifting == [], [(d.name, d.cost_gain_pct) for d in result.decisions]
    assert set(result.shared) == set(hidden), result.shared
    for name, value in hidden.items():
        assert value_error(value, result.shared[name]) <= TOLERANCE, (name, result.shared[name])
    assert all(not d.drifts for d in result.decisions) and len(result.decisions) == 2


def test_one_session_is_diagnosed_but_nothing_can_drift(drift_folder):
    result = diagnose_sessions(group_sessions(sorted((drift_folder / "s2014").iterdir())), candidates=FEW)
    doc = result.to_json()
    assert [s["name"] for s in doc["sessions"]] == ["s2014"] and doc["drifting"] == []
    assert value_error(DRIFT["s2014"], doc["shared"]["coulomb_friction"]) <= TOLERANCE
    assert any("nothing can drift" in n for n in result.notes)


@pytest.mark.slow
def test_the_rig_had_less_friction_in_2009(rig_data, tmp_path, capsys):
    """Issue 17: friction about 1-3 DAC counts in 2009 and 6-16 in 2014 (about 100 s here)."""
    out = tmp_path / "rig.json"
    assert main(["survey", str(rig_data), "--diagnose", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert "coulomb_friction" in doc["drifting"], capsys.readouterr().out
    sessions = {s["name"]: s for s in doc["sessions"]}
    assert len(sessions) == 2 and "2009" in sessions
    later = next(s for name, s in sessions.items() if name != "2009")
    assert sessions["2009"]["effects"]["coulomb_friction"] < later["effects"]["coulomb_friction"]
    assert all(math.isfinite(v) for s in doc["sessions"] for v in s["effects"].values())
    # the hold-and-release beam test is set aside, the 2009 sweeps are cut
    assert not any("hold_and_release" in r for s in doc["sessions"] for r in s["runs"])


def test_a_session_whose_accelerometer_reads_the_other_way(tmp_path, capsys):
    # the accelerometer was remounted between sessions: its sign is decided from each
    # session's own data, in that session's model only, and the friction still drifts
    from station.plant.model import load_model

    root = tmp_path / "lab"
    write_case(root / "before", {"coulomb_friction": 6.0}, 1)
    write_case(root / "after", {"coulomb_friction": 14.0, "accel_gain": -1.2}, 2)
    out, models = tmp_path / "drift.json", tmp_path / "models"
    assert main(["survey", str(root), "--diagnose", "--json", str(out), "--save-models", str(models)]) == 0
    captured = capsys.readouterr()
    assert "after: sensor fault, decided from the data: header: a: the tip's acceleration" in captured.err
    assert "before: sensor fault" not in captured.err
    # the answer leads with it, before the structure; the other session says nothing of it
    lines = captured.out.splitlines()
    assert lines[0].startswith("after: sensor fault, decided from the data: header: a: the tip's acceleration")
    assert not any(x.startswith("before: ") for x in lines)
    said = float(re.search(r"reads the other way \(accel_gain (-[\d.]+)", lines[0]).group(1))
    doc = {s["name"]: s for s in json.loads(out.read_text())["sessions"]}
    after, before = doc["after"]["effects"], doc["before"]["effects"]
    assert after["accel_gain"] < 0 and value_error(-1.2, after["accel_gain"]) <= TOLERANCE, after
    assert before.get("accel_gain", 1.0) > 0, before
    for name, friction in (("before", 6.0), ("after", 14.0)):
        assert value_error(friction, doc[name]["effects"]["coulomb_friction"]) <= TOLERANCE, doc[name]
    assert load_model(doc["after"]["model"]).effect("accel_gain") == pytest.approx(after["accel_gain"])
    assert said == pytest.approx(after["accel_gain"], abs=0.006)  # the line says the gain the model holds
    # every printed value of the gain is one a session's model holds, or said to be a size
    for line in lines:
        for m in re.finditer(r"accel_gain = (-?[\d.]+)( in size)?", line):
            v = float(m.group(1))
            assert m.group(2) or v == pytest.approx(after["accel_gain"], abs=0.006) or v > 0, line


def test_a_shared_signed_effect_is_said_as_the_sessions_models_hold_it():
    # one number, one meaning: a size searched beside a reversed sensor (PerSession) is printed
    # with the sign every session's model gives it, or said to be a size where they differ
    from station.diagnosis.sessions.diagnose import SessionResult, SessionsDiagnosis
    from station.diagnosis.sessions.report import _range, _shared

    def result(*faults):
        return SessionsDiagnosis([SessionResult(f"s{i}", [], {}, None, None, faults=f) for i, f in enumerate(faults)],
                                 {"accel_gain": 1.08, "coulomb_friction": 5.0}, [], [], [], None, 0.0, [], (0, 0), 0, 0.0)

    reversed_everywhere = result({"accel_gain": -0.85}, {"accel_gain": -1.2})
    assert reversed_everywhere.held("accel_gain", 1.08) == -1.08
    assert reversed_everywhere.to_json()["shared"]["accel_gain"] == -1.08
    assert _shared(reversed_everywhere, "accel_gain", 1.08).startswith("-1.08")
    mixed = result({"accel_gain": -0.85}, {})
    assert mixed.held("accel_gain", 1.08) == 1.08 and mixed.sign_differs("accel_gain")
    assert _shared(mixed, "accel_gain", 1.08).endswith("in size (its sign each session's sensors')")
    plain = result({}, {})
    assert plain.held("accel_gain", 1.08) == 1.08 and not plain.sign_differs("accel_gain")
    assert mixed.held("coulomb_friction", 5.0) == 5.0  # an unsigned effect as it is
    assert _range(mixed.sessions[0], "accel_gain", 1.0, 1.2).startswith("-1.2") and "..-1" in \
        _range(mixed.sessions[0], "accel_gain", 1.0, 1.2)
    assert _range(mixed.sessions[1], "accel_gain", 1.0, 1.2).startswith("1")


def test_a_sessions_answer_leads_with_what_its_logs_headers_got_wrong(tmp_path, capsys):
    # the lab's third session in miniature: open-loop headers over a lead on the truncated
    # integer command; said once for the session, with how many runs, before the structure
    import dataclasses

    from tests.blind.audit import draw_case, format_audit_run, simulate_audit_case

    base = draw_case("session", 0)
    root = tmp_path / "lab" / "april"
    root.mkdir(parents=True)
    for seed in range(3):
        c = dataclasses.replace(draw_case("session", seed), num_s=base.num_s, den_s=base.den_s,
                                design_text=base.design_text, limit=base.limit, effects={"coulomb_friction": 6.0})
        (root / f"session_{seed}_SLFR_RTP_OL_Test.txt").write_text(format_audit_run(c, simulate_audit_case(c, seed)))
    report = tmp_path / "rep"
    assert main(["survey", str(tmp_path / "lab"), "--diagnose", "--report", str(report)]) == 0
    lines = capsys.readouterr().out.splitlines()
    # grouped: one line per contradiction and the runs it holds for (a settled step on the
    # stored integer may reproduce a neighbouring pole exactly too: its own line)
    assert re.match(r"april: audit: [23] of 3 runs( \(session_\d\S+, session_\d\S+\))?: header: open loop; data: "
                    r"1.5\(s\+12\)/\(s\+4\d\)", lines[0]), lines[0]
    structure = next(i for i, x in enumerate(lines) if x.startswith("structure: "))
    assert all(x.startswith("april: ") for x in lines[:structure - 1])
    page = (report / "report.html").read_text()
    assert -1 < page.find("header: open loop; data: ") < page.find("structure: ")
