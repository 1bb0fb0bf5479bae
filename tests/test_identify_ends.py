"""How ``station identify`` ends when it cannot go on (issue 24's hostile round): a device that
dies between experiments, a stop during a diagnosis, an output named like an experiment's
log. Whatever ended it, the message says what ran and which logs exist, the exit code is not
2 ("bad input, nothing run") once an experiment ran, and nothing the experiments wrote is
overwritten or left orphaned.

The experiments run on a stand-in runner (the identification's own ``runner`` parameter)
that writes rig-format logs of a toy plant (tests/output_cases.py) and fails where the table
says: the subject is the loop's bookkeeping, not the device.
"""

from __future__ import annotations

import signal
from pathlib import Path

import numpy as np
import pytest

import station.diagnosis.identify.loop as loop_module
from station.cli import main
from station.diagnosis.identify.experiments import THESIS_EXPERIMENTS, candidate_experiments
from station.diagnosis.identify.loop import ExperimentRun, identify, step_runner
from station.errors import StationError
from station.signals import StopSignal
from tests.output_cases import write_p_log

GONE = "cannot open port /dev/ttyUSB0: No such file or directory"


def dying_runner(fail_at: int, ran: list):
    """A runner whose experiments 1 .. fail_at-1 complete and whose device is gone after."""
    def run(experiment, log: Path) -> ExperimentRun:
        k = int(log.name[:2])
        if k >= fail_at:
            raise StationError(GONE)
        write_p_log(log, np.where(np.arange(300) >= 10, 50.0, 0.0), seed=k)
        ran.append(log)
        return ExperimentRun(log, "completed", 0)
    return run


def no_diagnosis(*args, **kwargs):
    raise AssertionError("diagnosed after the device was gone")


def test_a_device_gone_before_the_first_experiment_is_bad_input(tmp_path):
    with pytest.raises(StationError, match=GONE):
        identify(out_dir=tmp_path / "exp", runner=dying_runner(1, []), budget=0)


@pytest.mark.parametrize("fail_at", [2, 3, 4])
def test_a_device_gone_between_experiments_ends_saying_what_ran(tmp_path, monkeypatch, fail_at):
    monkeypatch.setattr(loop_module, "diagnose", no_diagnosis)
    ran: list[Path] = []
    ident = identify(out_dir=tmp_path / "exp", runner=dying_runner(fail_at, ran), budget=0)
    assert ident.exit_code == 1 and ident.diagnosis is None
    assert len(ident.experiments) == fail_at - 1 == len(ran)
    said = ident.stopped
    assert f"experiment {fail_at}" in said and "could not start" in said and GONE in said, said
    assert f"{fail_at - 1} experiment(s) ran before" in said and all(p.name in said for p in ran), said
    assert str(tmp_path / "exp") in said


def test_the_command_says_it_and_exits_1_not_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(loop_module, "diagnose", no_diagnosis)
    ran: list[Path] = []
    monkeypatch.setattr(loop_module, "step_runner", lambda *a, **k: dying_runner(3, ran))
    monkeypatch.chdir(tmp_path)
    code = main(["identify", "--out-dir", "exp", "--budget", "0", "--quiet", "--json", "i.json"])
    out, err = capsys.readouterr()
    assert code == 1, (out, err)
    assert "ended: stopped by the device: experiment 3" in out and "01-p2-step-50.tsv" in out, out
    assert "Traceback" not in err
    assert sorted(p.name for p in (tmp_path / "exp").iterdir()) == sorted(p.name for p in ran)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_during_the_diagnosis_says_which_logs_exist(tmp_path, monkeypatch, sig):
    def stopped(*args, **kwargs):
        raise StopSignal(sig)

    monkeypatch.setattr(loop_module, "diagnose", stopped)
    ran: list[Path] = []
    with pytest.raises(StopSignal) as info:
        identify(out_dir=tmp_path / "exp", runner=dying_runner(99, ran), budget=0)
    note = info.value.note
    assert len(ran) == len(THESIS_EXPERIMENTS) and f"{len(ran)} experiment(s) ran" in note, note
    assert str(tmp_path / "exp") in note and all(p.name in note for p in ran), note
    assert "no JSON, report or model written" in note and "nothing written" not in note


def test_a_designed_experiment_that_cannot_start_leaves_no_reference_file(tmp_path):
    designed = next(e for e in candidate_experiments() if e.reference != "step")
    run = step_runner("/dev/station-no-such-port")
    log = tmp_path / "05-designed.tsv"
    with pytest.raises(StationError, match="no such device"):
        run(designed, log)
    assert list(tmp_path.iterdir()) == [], "the reference written for a run that never started is gone"


def _never(*args, **kwargs):
    raise AssertionError("an experiment ran")


@pytest.mark.parametrize("option", ["--json", "--save-model"])
@pytest.mark.parametrize("name", ["01-p2-step-50.tsv", "04-open-loop-pulses-100.u.tsv", "07-chirp.png", "12-x"])
def test_an_output_named_like_an_experiments_file_is_refused_before_any_run(tmp_path, monkeypatch, capsys, option,
                                                                            name):
    monkeypatch.setattr(loop_module, "step_runner", lambda *a, **k: _never)
    monkeypatch.chdir(tmp_path)
    code = main(["identify", "--out-dir", "exp", "--quiet", option, f"exp/{name}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert f"{option} exp/{name}: in exp, the names NN-... are the experiments'" in err[0], err
    assert not (tmp_path / "exp").exists()


def test_a_report_folder_that_holds_files_needs_force(tmp_path, monkeypatch, capsys):
    # the report's figures are named as the experiments come (experiment-NN.png, <log>_run.png):
    # what is there already could be one of them
    monkeypatch.setattr(loop_module, "step_runner", lambda *a, **k: _never)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / "experiment-01.png").write_bytes(b"keep")
    code = main(["identify", "--out-dir", "exp", "--quiet", "--report", "rep"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--report rep: holds files already; use --force" in err[0], err
    assert (tmp_path / "rep" / "experiment-01.png").read_bytes() == b"keep"
