"""The lab's 16-bit tick counter wrapping past 32767 (65.5 s at 500 Hz).

The rig's PSoC sends n as one 16-bit word and the lab's software stored it as read and
computed t = n·dt from it: after 32767 comes −32768 (or, read unsigned, 65535 then 0). Before,
such a log read as two runs and its rows after the wrap were set aside. The rig's own 2009
sweep, its n and t rewritten as the lab's counter would have given them for a run that had
counted past the wrap (a script written from the format, not from the station).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station.logged import LoggedRun
from station.runlog import read_log
from station.runlog.timebase import unwrap_counter

SWEEP = "2009/swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt"


def _recounted(src: Path, dst: Path, first: int, unsigned: bool) -> Path:
    """The log with n counted from ``first`` by a 16-bit counter (two's complement or unsigned)
    and t = n·0.002 s, as the lab's software wrote them; every other field as it was."""
    out = []
    for ln in src.read_text().splitlines():
        if ln.startswith("#") or not ln.strip():
            out.append(ln)
            continue
        f = ln.split("\t")
        n = (int(f[1]) + first) % 65536
        n = n if unsigned or n < 32768 else n - 65536
        f[0], f[1] = f"{n * 0.002:.10g}", str(n)
        out.append("\t".join(f))
    dst.write_text("\n".join(out) + "\n")
    return dst


@pytest.mark.parametrize("first,unsigned,row", [(20000, False, 12768), (50000, True, 15536)])
def test_the_rigs_sweep_counted_past_the_wrap_reads_as_one_run(rig_data, tmp_path, first, unsigned, row):
    src = rig_data / SWEEP
    path = _recounted(src, tmp_path / "sweep_SLFR_RTP_P_control_kp=1.0.txt", first, unsigned)
    log = read_log(path)
    assert len(log) == 20000 and np.all(np.diff(log.data["n"]) == 1) and log.sample_time == 0.002
    assert np.allclose(np.diff(log.data["t"]), 0.002)
    (note,) = [x for x in log.notes if "wraps at 16 bits" in x]
    assert f"at row {row} " in note and "t with it" in note, note
    run, whole = LoggedRun.from_path(path), LoggedRun.from_path(src)
    assert len(run.log) == 20000 and run.reproduced and run.max_abs_dv == 0.0
    assert not [c for c in run.audit.claims if c.verdict == "contradicted"], run.audit.claims
    assert run.controller.spec == whole.controller.spec and run.alignment == whole.alignment


def test_two_runs_one_after_the_other_stay_two_runs(rig_data, tmp_path):
    """A second run starts again at n = 0: no 16-bit step, the audit's two runs as before."""
    lines = (rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt").read_text().splitlines()
    rows = [ln for ln in lines if ln and not ln.startswith("#")]
    path = tmp_path / "twice_SLFR_RTP_P_control_kp=2.0.txt"
    path.write_text("\n".join([ln for ln in lines if ln.startswith("#")] + rows + rows) + "\n")
    log = read_log(path)
    assert not [x for x in log.notes if "wraps" in x]
    run = LoggedRun.from_path(path)
    assert len(run.log) == len(rows) and any("2 runs" in c.data for c in run.audit.claims)


def test_unwrap_counter_takes_t_along_only_where_t_was_computed_from_n():
    n = np.array([32765.0, 32766, 32767, -32768, -32767])
    host = np.array([0.0, 0.002, 0.004, 0.006, 0.008])  # a host's stamps go on
    data, notes = {"n": n.copy(), "t": host.copy()}, []
    unwrap_counter(data, True, notes)
    assert np.array_equal(data["n"], [32765, 32766, 32767, 32768, 32769]) and np.array_equal(data["t"], host)
    assert notes == ["n wraps at 16 bits at row 3 (32767 to -32768): the device's tick counter, unwrapped"]
    data, notes = {"n": n.copy(), "t": n * 0.002}, []
    unwrap_counter(data, True, notes)
    assert np.allclose(data["t"], np.arange(32765, 32770) * 0.002) and notes[0].endswith("t with it (t = n·0.002 s)")
    for jump in (np.array([5.0, 6, 0, 1]), np.array([32767.0, -32767, -32766])):  # not one tick on
        data, notes = {"n": jump.copy(), "t": jump * 0.002}, []
        unwrap_counter(data, True, notes)
        assert np.array_equal(data["n"], jump) and not notes
