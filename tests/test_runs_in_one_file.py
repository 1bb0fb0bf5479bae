"""Runs written one after another into one file: said, and the first used.

A logger that appends writes a second run after the first: n and t go back to 0. Before,
the audit said "n jumps at 1 rows", t "not evenly spaced (steps -1.998 .. 0.002 s)", no
reference was found, and the second run was simulated as the first's continuation. The
truth here: the rig's own logs concatenated by a script (not the station's writer).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from station.logged import LoggedRun
from station.plant import load_model

P = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"


def _concatenate(src: Path, dst: Path, times: int = 2, tail: int | None = None) -> Path:
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
    body = rows * times + (rows[:tail] if tail else [])
    dst.write_text("\n".join(head + body) + "\n")
    return dst


@pytest.mark.parametrize("times", [2, 3])
def test_runs_one_after_another_are_said_and_the_first_used(rig_data, tmp_path, times):
    clean = LoggedRun.from_path(rig_data / P)
    run = LoggedRun.from_path(_concatenate(rig_data / P, tmp_path / "runs.txt", times))
    (claim,) = [c for c in run.audit.claims if c.header == "one run"]
    assert claim.verdict == "contradicted" and claim.data.startswith(f"{times} runs (n starts again at row 1000")
    assert len(run) == len(clean) == 1000
    assert run.reference == clean.reference and run.reproduced
    assert not any(n.startswith("t is not evenly spaced") for n in run.notes)
    assert not any(c.data.startswith("n jumps") for c in run.audit.claims)
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct == clean.simulate(model).fit_pct


def test_a_few_rows_after_a_run_are_no_second_run(rig_data, tmp_path):
    # five rows of a restarted logger: fewer than MIN_RUN_ROWS, left to the rows' own claims
    run = LoggedRun.from_path(_concatenate(rig_data / P, tmp_path / "tail.txt", 1, tail=5))
    assert not [c for c in run.audit.claims if c.header == "one run"]


def test_a_block_written_again_at_the_start_is_no_second_run(rig_data, tmp_path):
    # a logger that re-sent its first 30 rows: n goes back to 0 once, then on to new ticks
    lines = (rig_data / P).read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
    path = tmp_path / "resent.txt"
    path.write_text("\n".join(head + rows[:30] + rows) + "\n")
    run = LoggedRun.from_path(path)
    assert not [c for c in run.audit.claims if c.header == "one run"]
    assert [c for c in run.audit.claims if c.data.startswith("n jumps")]


def test_one_run_is_one_run(rig_data):
    for name in sorted(p.name for p in rig_data.glob("*.txt")):
        run = LoggedRun.from_path(rig_data / name)
        assert not [c for c in run.audit.claims if c.header == "one run"], name
