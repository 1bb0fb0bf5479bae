"""The rig's rows saved without their header (a script's ``numpy.savetxt`` of the data, a copy
cut from a log): the rig's column order is assumed, said in a note, and checked against the
data by the log audit like any header's claim.

Before, such a file was refused ("expected ... the rig's '#' header or a line of column names,
got numbers"), though the controller, the alignment and the column order are all in the data.
Truth: the rig's own logs (``../shared/data/rig``) with their header lines removed; what the
headered log gives is what the bare copy must give.
"""

from __future__ import annotations

import pytest

from station.errors import StationError
from station.logged import LoggedRun
from station.replay import replay
from station.runlog import read_log

LOGS = ("SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
        "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
        "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt",
        "2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt")


def _bare(src, dst, sep="\t", order=None):
    rows = [ln.split("\t") for ln in src.read_text().splitlines() if ln and not ln.startswith("#")]
    if order is not None:
        rows = [[r[j] for j in order] for r in rows]
    dst.write_text("\n".join(sep.join(r) for r in rows) + "\n")
    return dst


@pytest.mark.parametrize("name", LOGS)
@pytest.mark.parametrize("sep", ["\t", ",", " "])
def test_the_rigs_rows_without_a_header_replay_as_the_log(rig_data, tmp_path, name, sep):
    path = _bare(rig_data / name, tmp_path / "bare.txt", sep)
    log = read_log(path)
    assert log.layout == "bare" and log.header == []
    assert any(n.startswith("no header: the rig's column order t n u v theta a") for n in log.notes), log.notes
    rep, own = replay(path, model=True), replay(rig_data / name, model=True)
    assert len(rep.log.data["t"]) == len(own.log.data["t"])  # line 1 is a row, not names
    assert rep.controller_source == "inferred"  # no header to name it: the data's law
    assert rep.reproduced and rep.alignment == own.alignment
    assert rep.fit_pct == own.fit_pct
    assert (rep.metrics is None) == (own.metrics is None)
    if own.metrics is not None:
        assert rep.metrics.overshoot_pct == own.metrics.overshoot_pct


def test_a_bare_copy_with_theta_and_a_exchanged_is_read_back(rig_data, tmp_path):
    # the order assumed is a claim the audit checks: θ and a exchanged are found as they are
    # under a column line, and said without pointing at a column line the file does not have
    path = _bare(rig_data / LOGS[0], tmp_path / "bare.txt", order=[0, 1, 2, 3, 5, 4])
    run = LoggedRun.from_path(path)
    (line,) = [x for x in run.audit.lines() if "swapped" in x]
    assert line == "header: θ and a in the rig's column order (no header names them); data: θ and a swapped"
    assert replay(path, model=True).fit_pct == replay(rig_data / LOGS[0], model=True).fit_pct


@pytest.mark.parametrize("name", ["without_accel_01_28_14_test_2.txt", "swept_sine_kp_1_amp_50.txt"])
def test_the_2014_rows_without_their_column_line_replay_as_the_log(rig_data, tmp_path, name):
    # The 28 Jan 2014 sweep (5 columns, t u theta accel v) without its line of names: read in that
    # order, said, and replayed as the log (before: "got 5 numbers ... hold 6 or 7"); the swept sine
    # (6 columns of the rig's order, its '#' lines dropped) still reads in the rig's order
    lines = (rig_data / name).read_text().splitlines()
    path = tmp_path / "bare.txt"
    path.write_text("\n".join(ln for ln in lines[1:] if ln and not ln.startswith("#")) + "\n")
    log = read_log(path)
    order = "t u theta a v" if name.startswith("without") else "t n u v theta a"
    assert log.layout == "bare" and any(n.startswith("no header: the") and order in n for n in log.notes)
    rep, own = replay(path, model=True), replay(rig_data / name, model=True)
    assert len(rep.log.data["t"]) == len(own.log.data["t"])
    assert rep.reproduced and rep.alignment == own.alignment and rep.controller_source == "inferred"
    assert rep.fit_pct["theta"] == own.fit_pct["theta"]


@pytest.mark.parametrize("width", [3, 4, 8])
def test_a_line_of_other_numbers_is_still_refused_in_one_line(tmp_path, width):
    path = tmp_path / "numbers.txt"
    path.write_text("\n".join("\t".join(str(i + k) for k in range(width)) for i in range(20)) + "\n")
    with pytest.raises(StationError) as err:
        read_log(path)
    said = str(err.value)
    assert "line 1: expected '# station-runlog 1'" in said and f"got {width} numbers" in said, said
    assert "hold 5 or 6 or 7" in said and "\n" not in said
