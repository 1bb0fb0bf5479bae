"""A worker process that dies on its own (killed from outside, out of memory, crashed) breaks its
whole pool: every task not yet finished fails with ``BrokenProcessPool`` (issue 24's hostile
round: killing one of tune's workers printed a traceback; a survey then called every log
"UNUSABLE: worker failed: BrokenProcessPool").

- ``station.pools.results`` (tune's evaluations): one line, exit code 1, nothing written;
- ``station survey``: the logs the dead worker took with it are replayed again; only a log
  whose replay kills its worker every time is a row saying so.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import station.survey as survey_mod
from station.cli import main
from station.pools import LOST, WorkerLost, process_pool, results
from tests.output_cases import write_p_log

REAL_SURVEY_ONE = survey_mod.survey_one


def _task(x: int, die: bool):
    if die:
        os.kill(os.getpid(), signal.SIGKILL)
    return x * x


@settings(max_examples=6, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(n=st.integers(2, 8), workers=st.integers(1, 3), data=st.data())
def test_a_dead_worker_is_one_line_exit_1_wherever_it_dies(n, workers, data):
    dies = data.draw(st.sets(st.integers(0, n - 1), min_size=1, max_size=n))
    with pytest.raises(WorkerLost) as info:
        with process_pool(workers) as pool:
            results([pool.submit(_task, i, i in dies) for i in range(n)])
    assert info.value.exit_code == 1 and str(info.value) == LOST and "\n" not in LOST


def _fake_survey_one(path, model=True):
    """Kills its worker for a log named crash-*, and for once-* the first time only (a marker
    file beside it: as if killed from outside); replays the others as survey does."""
    p = Path(path)
    if p.name.startswith("crash-"):
        os.kill(os.getpid(), signal.SIGKILL)
    marker = p.with_name("." + p.name + ".seen")
    if p.name.startswith("once-") and not marker.exists():
        marker.write_text("")
        os.kill(os.getpid(), signal.SIGKILL)
    return REAL_SURVEY_ONE(path, model)


@pytest.mark.parametrize("crash, once, jobs", [
    (0, 1, 2),   # killed from outside once: every log replayed
    (1, 0, 2),   # one log kills its worker every time: that row alone
    (2, 2, 3),
])
def test_a_survey_replays_what_a_dead_worker_lost_and_names_a_log_that_kills_it(tmp_path, monkeypatch, capsys, crash,
                                                                                 once, jobs):
    monkeypatch.setattr(survey_mod, "survey_one", _fake_survey_one)  # the workers are forked: they see it
    d = tmp_path / "logs"
    d.mkdir()
    u = np.where(np.arange(120) >= 10, 50.0, 0.0)
    names = ([f"crash-{i}.txt" for i in range(crash)] + [f"once-{i}.txt" for i in range(once)]
             + [f"ok-{i}.txt" for i in range(4)])
    for i, name in enumerate(names):
        write_p_log(d / name, u, seed=i)
    assert main(["survey", str(d), "--no-model", "--jobs", str(jobs), "--csv", str(tmp_path / "s.csv")]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line.endswith(".txt") or
            ".txt " in line}
    for name in names:
        row = rows[name]
        if name.startswith("crash-"):
            assert survey_mod.WORKER_DIED in row, row
        else:
            assert "UNUSABLE" not in row and " rig " in row, row
