"""One definition of a log's sample time (RunLog.dt), one torn-line rule for both row
passes, one conversion of non-finite floats to JSON null (station.jsonio)."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import station
from station.jsonio import to_jsonable
from station.rig import DT as RIG_DT
from station.runlog import RunLogWriter, read_log

RIG_HEAD = "#SLFR RTP P_control_Test\n{extra}#t\tn\tu\tv\t$\\theta$\ta\n"


def _rig(tmp_path, rows, extra="", tail=""):
    path = tmp_path / "rig.txt"
    body = "".join(f"{k * 0.004!r}\t{k}\t0\t0\t{k}\t0\n" for k in range(rows))
    path.write_text(RIG_HEAD.format(extra=extra) + body + tail)
    return path


def test_rig_dt_is_station_dt():
    assert RIG_DT is station.DT == 0.002


def test_dt_from_t_header_and_default(tmp_path):
    log = read_log(_rig(tmp_path, 5))
    assert log.sample_time == 0.004 and log.dt == 0.004  # the median step of t
    log = read_log(_rig(tmp_path, 5, extra="#dt=0.008\n"))
    assert log.sample_time == 0.004 and log.dt == 0.008  # the header wins
    log = read_log(_rig(tmp_path, 5, extra="#dt=-1\n"))
    assert log.dt == 0.004  # a header dt that is not a positive number is ignored
    log = read_log(_rig(tmp_path, 1))
    assert log.sample_time is None and log.dt == RIG_DT  # fewer than two rows


def test_our_header_dt(tmp_path):
    path = tmp_path / "ours.tsv"
    with RunLogWriter(path, {"dt": 0.005}) as w:
        for k in range(3):
            w.append((k * 0.002, k, 0.0, 0.0, k, 0, 0.0, 0, 0, math.nan))
    log = read_log(path)
    assert (log.sample_time, log.dt) == (0.002, 0.005)


def test_torn_line_same_rule_on_the_row_by_row_pass(tmp_path):
    """'1_0' makes numpy refuse the file, so the row-by-row pass reads it: the torn last
    line is skipped there too, with one warning, and a whole unterminated rig row is kept."""
    torn = _rig(tmp_path, 4, tail="0.016\t4\t1_0\t0\t4\t0\n0.02\t5\t0")
    with pytest.warns(RuntimeWarning, match="line 8: torn last line") as record:
        log = read_log(torn)
    assert len([w for w in record if "torn" in str(w.message)]) == 1
    assert log.data["n"].tolist() == [0, 1, 2, 3, 4] and log.data["u"][4] == 10.0
    whole = _rig(tmp_path, 4, tail="0.016\t4\t1_0\t0\t4\t0\n0.02\t5\t0\t0\t5\t0")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_log(whole)) == 6


def test_to_jsonable():
    obj = {"a": [1.0, math.nan, (np.float64(math.inf), np.int64(3))], "b": np.array([1.5, np.nan]),
           "p": Path("/x/y"), "ok": np.bool_(True), "s": "t", "n": None}
    out = to_jsonable(obj)
    assert out == {"a": [1.0, None, [None, 3]], "b": [1.5, None], "p": "/x/y", "ok": True, "s": "t", "n": None}
    json.dumps(out, allow_nan=False)
    with pytest.raises(TypeError, match="object"):
        to_jsonable({"x": object()})


@pytest.mark.parametrize("t_of", [lambda i: 0.0 * i, lambda i: 2.0 - 0.002 * i, lambda i: 1000.0 * i,
                                  lambda i: 1e-9 * i],
                         ids=["all zero", "backwards", "1000 s a row", "1 ns a row"])
def test_a_t_column_that_is_no_time_base_is_not_used(rig_data, tmp_path, t_of):
    """A fuzzing round: t all 0 gave 'settling (1 %) 0.000 s', t backwards -1.250 s, t of 1000 s a
    row 625000 s and a θ fit of -15 million %. The claimed time base is used, and said."""
    from station.logged import LoggedRun

    src = rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    lines, i = [], 0
    for ln in src.read_text().splitlines():
        if ln.startswith("#") or not ln.strip():
            lines.append(ln)
            continue
        f = ln.split()
        f[0] = repr(t_of(i))
        lines.append("\t".join(f))
        i += 1
    path = tmp_path / "t.txt"
    path.write_text("\n".join(lines) + "\n")
    clean, run = LoggedRun.from_path(src), LoggedRun.from_path(path)
    assert run.step_metrics() == clean.step_metrics() and run.dt == 0.002
    (claim,) = [c for c in run.audit.claims if c.claim == "sample_time"]
    assert claim.verdict == "contradicted" and ("does not increase" in claim.data or "not a sample time" in claim.data)
    assert claim.line.startswith("header: not stated (the rig's 0.002 s assumed")  # the rig's header names no dt
    np.testing.assert_allclose(run.data["t"], clean.data["t"], rtol=0, atol=1e-12)
