"""Every run recorded to its end: names that never collide, no silent overwrite, the
outcome in the log, in replay and in step --json, and null for a killed run."""

from __future__ import annotations

import datetime as dt
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from station.cli import main
from station.experiment import default_log_path, run_step
from station.runlog import read_log
from tests.stalls import timed


def test_default_log_names_never_collide(tmp_path):
    when = dt.datetime(2026, 1, 2, 3, 4, 5, 678000, tzinfo=dt.UTC)
    first = default_log_path("lead", when, folder=tmp_path)
    assert first.name == "step-lead-20260102-030405-678.tsv"
    first.write_text("x")
    second = default_log_path("lead", when, folder=tmp_path)
    assert second != first and second.name == "step-lead-20260102-030405-678-2.tsv"
    second.write_text("x")
    assert default_log_path("lead", when, folder=tmp_path).name.endswith("-3.tsv")


def test_two_quick_default_runs_keep_both_logs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    a = run_step(duration=0.05, figure=False)
    b = run_step(duration=0.05, figure=False)
    assert a.log_path != b.log_path and a.log_path.exists() and b.log_path.exists()


def test_out_is_overwritten_only_with_force(tmp_path, capsys):
    out = tmp_path / "r.tsv"
    out.write_text("precious\n")
    assert main(["step", "--duration", "0.05", "--out", str(out), "--quiet"]) == 2
    assert out.read_text() == "precious\n" and "--force" in capsys.readouterr().err
    assert main(["step", "--duration", "0.05", "--out", str(out), "--quiet", "--force"]) == 0
    assert read_log(out).outcome["reason"] == "completed"


def test_completed_and_interrupted_runs_end_with_their_outcome_and_replay_reports_it(tmp_path, capsys):
    done, cut = tmp_path / "done.tsv", tmp_path / "cut.tsv"
    sj = tmp_path / "step.json"
    assert main(["step", "--duration", "0.2", "--out", str(done), "--json", str(sj), "--quiet"]) == 0
    assert json.loads(sj.read_text())["outcome"]["reason"] == "completed"
    assert "overshoot" in capsys.readouterr().out
    # the device goes silent after tick 30: the run stops on the sample timeout
    code = main(["step", "--duration", "0.5", "--port", "sim://?silent_after=30", "--timeout", "0.05",
                 "--out", str(cut), "--quiet"])
    assert code == 1
    out = capsys.readouterr().out
    assert "no step metrics" in out and "overshoot" not in out
    for path, reason in ((done, "completed"), (cut, "timeout")):
        assert read_log(path).outcome["reason"] == reason
        rj = tmp_path / f"{path.stem}.json"
        main(["replay", str(path), "--no-model", "--json", str(rj)])
        assert json.loads(rj.read_text())["outcome"]["reason"] == reason


@timed
def test_a_sigkilled_run_has_a_null_outcome(tmp_path):
    log = tmp_path / "killed.tsv"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "station", "step", "--port", "sim://?pacing=realtime",
                             "--duration", "60", "--max-lag", "1000", "--out", str(log), "--quiet"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    try:
        deadline = time.monotonic() + 60  # waits for progress, not a timing assertion
        while time.monotonic() < deadline:
            if log.exists() and log.read_text().count("\n") > 100:
                break
            time.sleep(0.05)
        else:
            pytest.fail("the run did not start logging")
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    with pytest.warns(RuntimeWarning) if not log.read_text().endswith("\n") else _nothing():
        run = read_log(log)
    assert run.outcome is None and len(run) > 50
    rj = tmp_path / "r.json"
    main(["replay", str(log), "--no-model", "--json", str(rj)])
    assert json.loads(rj.read_text())["outcome"] is None


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
