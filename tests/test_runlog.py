"""station.runlog: our format round-trips, stays readable by pandas/numpy, survives SIGKILL;
the rig's logs read with their header variants."""

import json
import math
import re
import os
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
import warnings

import numpy as np
import pytest

from station.errors import StationError
from station.runlog import COLUMNS, MAGIC, RunLogError, RunLogWriter, read_log
from tests.stalls import timed

RIG_FILES = {
    "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt": ("OL_Test", 1000, False),
    "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt": ("P_control_Test", 1000, False),
    "log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt": ("OL_Test", 5000, False),
    "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt":
        ("Motor_Comp_w_accel_fb", 1000, True),
    "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt":
        ("Motor_Comp_w_accel_fb", 1000, True),
    "swept_sine_kp_1_amp_50.txt": ("PID_control_Test", 11000, False),
}

# Values chosen to stress round-tripping: shortest-repr floats, tiny/huge, NaN, ints.
ROWS = [
    (0.0, 0, 0.0, 0.0, 0, 0, 0.0, 0, 0, float("nan")),
    (0.002, 1, 100.0, -0.0003305725339, 1, -2, 199.9972881, 0, 16, 57.25),
    (0.004, 2, 100.0, 0.1 + 0.2, -3, 7, 1e-300, 200, 1, 1.7976931348623157e308),
    (np.float64(0.006), np.int64(3), np.float32(0.5), 200.0, 2048, -5, float("inf"), None, 0, 12.0),
]
META = {"controller": {"kind": "lead", "gth": {"num_z": [18.325471824430103, -17.209119707383508]}},
        "alignment": 1, "reference": {"kind": "step", "amplitude": 100.0}, "note": "tab\there, ünïcode"}


def _write(path, rows=ROWS, meta=META, sinks=()):
    with RunLogWriter(path, meta, sinks=sinks) as w:
        for r in rows:
            w.append(r)
    return path


def _expected(col):
    out = []
    for r in ROWS:
        x = r[COLUMNS.index(col)]
        out.append(math.nan if x is None else float(x))
    return np.array(out)


def test_roundtrip_exact(tmp_path):
    log = read_log(_write(tmp_path / "run.tsv"))
    assert log.format == "station"
    assert log.meta == META
    assert set(COLUMNS) <= set(log.data)
    for col in COLUMNS:
        np.testing.assert_array_equal(log.data[col], _expected(col), err_msg=col)
    assert log.data["v"][2] == 0.1 + 0.2  # not 0.3: repr round-trips


def test_file_text_ints_as_ints_nan_as_nan(tmp_path):
    lines = _write(tmp_path / "run.tsv").read_text().splitlines()
    assert lines[0] == "\t".join(COLUMNS)
    assert lines[1] == MAGIC
    assert json.loads(lines[2][2:]) == META and lines[2].startswith("# ")
    assert lines[3].split("\t") == ["0.0", "0", "0.0", "0.0", "0", "0", "0.0", "0", "0", "nan"]
    assert lines[6].split("\t")[1] == "3" and lines[6].split("\t")[7] == "nan"


def test_pandas_reads_it(tmp_path):
    pd = pytest.importorskip("pandas")
    df = pd.read_csv(_write(tmp_path / "run.tsv"), sep="\t", comment="#")
    assert list(df.columns) == list(COLUMNS)
    assert len(df) == len(ROWS)
    np.testing.assert_array_equal(df["v"].to_numpy(), _expected("v"))
    np.testing.assert_array_equal(df["latency_us"].to_numpy(), _expected("latency_us"))


def test_numpy_reads_it(tmp_path):
    arr = np.genfromtxt(_write(tmp_path / "run.tsv"), names=True, delimiter="\t", comments="#")
    assert arr.dtype.names == COLUMNS
    assert arr.shape == (len(ROWS),)
    np.testing.assert_array_equal(arr["theta_d_hat"], _expected("theta_d_hat"))


def test_reads_magic_first_order_too(tmp_path):
    lines = _write(tmp_path / "run.tsv").read_text().splitlines()
    alt = tmp_path / "alt.tsv"
    alt.write_text("\n".join([lines[1], lines[2], lines[0]] + lines[3:]) + "\n")
    log = read_log(alt)
    assert log.format == "station" and log.meta == META
    np.testing.assert_array_equal(log.data["v"], _expected("v"))


def test_torn_last_line_skipped_with_warning(tmp_path):
    path = _write(tmp_path / "run.tsv")
    text = path.read_text()
    # The process died while writing the next row: "0.008\t4\t10" without a newline.
    path.write_text(text + "0.008\t4\t10")
    with pytest.warns(RuntimeWarning, match=str(path)):
        log = read_log(path)
    assert len(log) == len(ROWS)
    # A complete-looking but unterminated last row may have a cut-off number: also torn.
    path.write_text(text + "0.008\t4\t1.0\t2.0\t3\t4\t5.0\t6\t0\t1")
    with pytest.warns(RuntimeWarning, match="torn"):
        assert len(read_log(path)) == len(ROWS)


def test_malformed_row_mid_file_is_an_error(tmp_path):
    path = _write(tmp_path / "run.tsv")
    lines = path.read_text().splitlines()
    lines[4] = "\t".join(lines[4].split("\t")[:7])
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunLogError) as err:
        read_log(path)
    assert isinstance(err.value, StationError)
    assert str(path) in str(err.value) and "line 5" in str(err.value)
    assert "expected 10 tab-separated numbers, got 7" in str(err.value)


def test_non_number_names_the_column(tmp_path):
    path = _write(tmp_path / "run.tsv")
    lines = path.read_text().splitlines()
    parts = lines[3].split("\t")
    parts[4] = "abc"
    lines[3] = "\t".join(parts)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunLogError, match=r"line 4: expected a number in column 'theta', got 'abc'"):
        read_log(path)


@pytest.mark.parametrize("name, sep", [("SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt", "\t"),
                                       ("without_accel_01_28_14_test_2.txt", "\t"),
                                       ("without_accel_01_28_14_test_2.txt", ";"),
                                       ("without_accel_01_28_14_test_2.txt", " ")])
def test_a_log_written_with_decimal_commas_is_read_and_said(rig_data, tmp_path, name, sep):
    """A lab whose locale writes decimal commas (LabVIEW, Excel in much of Europe) parts its
    fields by tabs, ';' or spaces, where a comma can be nothing but the decimal mark: read,
    the same numbers as the rig's own log, and said in a note; a gain so written too (before:
    refused, "got '0,002' (a decimal comma ...)")."""
    src = rig_data / name
    path = tmp_path / "comma.txt"
    lines = src.read_text().splitlines()
    first = 0 if lines[0].startswith("#") else 1  # the 2014 layout's line of names keeps its "Time (sec.)"
    out = [ln.replace("kp=2.0", "kp=2,0") if ln.startswith("#") or k < first else ln.replace(".", ",")
           for k, ln in enumerate(lines)]
    out = [ln.replace("\t", sep) if not ln.startswith("#") and sep != "\t" and k >= first else ln
           for k, ln in enumerate(out)]
    if first and sep != "\t":
        out[0] = out[0].replace("\t", sep) if sep != " " else "t u theta a v"
    path.write_text("\n".join(out) + "\n")
    clean, log = read_log(src), read_log(path)
    for column in ("t", "n", "u", "v", "theta", "a"):
        np.testing.assert_array_equal(log.data[column], clean.data[column])
    assert any("decimal commas" in n for n in log.notes)
    if first == 0:
        assert log.meta["kp"] == 2.0 and any("kp=2,0 read as 2" in n for n in log.notes)


def test_a_decimal_comma_beside_decimal_points_is_named(rig_data, tmp_path):
    """One row with a comma where the others have points (a hand edit): not a locale's
    export; the field named, and why, in one line."""
    src = rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    lines = src.read_text().splitlines()
    lines[104] = lines[104].replace("0.2", "0,2", 1)
    fields = lines[104].split("\t")
    fields[5] = "1.5"
    lines[104] = "\t".join(fields)
    path = tmp_path / "comma.txt"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunLogError, match=r"line 105: expected a number in column 't', got '0,202' "
                                          r"\(a decimal comma: the log must be written with '\.' decimals\)$"):
        read_log(path)


def test_not_a_log(tmp_path):
    path = tmp_path / "x.txt"
    path.write_text("hello\n1 2 3\n")
    with pytest.raises(RunLogError, match="line 1"):
        read_log(path)
    with pytest.raises(RunLogError, match="run log not found"):
        read_log(tmp_path / "missing.tsv")


class _Collect:
    def __init__(self):
        self.batches = []

    def write_rows(self, columns):
        self.batches.append(columns)


class _Broken:
    def __init__(self):
        self.calls = 0

    def write_rows(self, columns):
        self.calls += 1
        raise RuntimeError("viewer went away")


def test_sinks_get_every_row_and_a_broken_sink_costs_nothing(tmp_path):
    good, bad = _Collect(), _Broken()
    rows = [(k * 0.002, k, 1.0, 2.0, k, -k, 3.0, 2, 0, 10.0) for k in range(500)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        w = RunLogWriter(tmp_path / "run.tsv", META, sinks=[good, bad])
        for r in rows:
            w.append(r)
        w.close()
    assert bad.calls == 1
    assert len(w.sink_errors) == 1 and "viewer went away" in w.sink_errors[0]
    assert sum("viewer went away" in str(c.message) for c in caught) == 1
    got = np.concatenate([b["n"] for b in good.batches])
    np.testing.assert_array_equal(got, np.arange(500))
    assert set(good.batches[0]) == set(COLUMNS)
    np.testing.assert_array_equal(read_log(tmp_path / "run.tsv").data["n"], np.arange(500))


def test_append_validates_and_close_is_idempotent(tmp_path):
    w = RunLogWriter(tmp_path / "run.tsv", META)
    with pytest.raises(ValueError, match="10 values"):
        w.append((1.0, 2))
    w.close()
    w.close()
    with pytest.raises(RunLogError, match="after close"):
        w.append(ROWS[0])


def test_bad_meta_and_bad_path(tmp_path):
    with pytest.raises(RunLogError, match="JSON"):
        RunLogWriter(tmp_path / "run.tsv", {"x": object()})
    with pytest.raises(RunLogError, match="cannot create"):
        RunLogWriter(tmp_path / "no" / "such" / "run.tsv", META)


_CHILD = textwrap.dedent("""
    import sys, time
    from station.runlog import RunLogWriter
    w = RunLogWriter(sys.argv[1], {"test": "sigkill"})
    t0 = time.monotonic()
    k = 0
    while True:
        # t column: the monotonic time of the append (CLOCK_MONOTONIC is system-wide)
        w.append((time.monotonic(), k, 1.0, 2.5, k, -k, 0.1, 2, 0, 33.0))
        k += 1
        delay = t0 + k * 0.002 - time.monotonic()
        if delay > 0:
            time.sleep(delay)
""")


@timed
def test_sigkill_loses_nothing_older_than_100ms(tmp_path):
    path = tmp_path / "killed.tsv"
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(path)])
    try:
        # Wait (bounded) until the child has logged a second of rows, then kill it.
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if path.exists() and path.read_text().count("\n") > 503:
                break
            time.sleep(0.05)
        time.sleep(0.2)
        t_kill = time.monotonic()
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a torn last line is allowed
        log = read_log(path)
    n = log.data["n"]
    assert n.size > 500
    np.testing.assert_array_equal(n, np.arange(n.size))  # no gaps, no garbage
    # Row n.size (the first missing one) was appended after every logged row; every row
    # appended before t_kill - 0.1 s is in the file, so the first missing one is younger.
    # The last logged row's successor was appended at most ~one period after it.
    assert log.data["t"][-1] >= t_kill - 0.1 - 0.002 * 2


@pytest.mark.parametrize("name", sorted(RIG_FILES))
def test_every_rig_log_reads(rig_data, name):
    test, rows, has_dhat = RIG_FILES[name]
    log = read_log(rig_data / name)
    assert log.format == "rig"
    assert log.meta["test"] == test
    assert len(log) == rows
    np.testing.assert_array_equal(log.data["n"], np.arange(rows))
    np.testing.assert_allclose(log.data["t"], np.arange(rows) * 0.002, atol=1e-9)
    for col in ("u", "v", "theta", "a"):
        assert not np.any(np.isnan(log.data[col])), col
    assert np.all(np.isnan(log.data["theta_d_hat"])) != has_dhat
    for col in ("v_applied", "status", "latency_us"):
        assert np.all(np.isnan(log.data[col]))
    # Independent check of the column mapping against numpy's own parse of the file.
    raw = np.loadtxt(rig_data / name, comments="#", delimiter="\t")
    for j, col in enumerate(("t", "n", "u", "v", "theta", "a", "theta_d_hat")[:raw.shape[1]]):
        np.testing.assert_array_equal(log.data[col], raw[:, j])


def test_rig_header_variants(rig_data):
    p = read_log(rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt")
    assert p.meta["kp"] == 2.0
    pid = read_log(rig_data / "swept_sine_kp_1_amp_50.txt")
    assert (pid.meta["kp"], pid.meta["ki"], pid.meta["kd"]) == (1.0, 0.0, 0.0)
    acc = read_log(rig_data / "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt")
    assert acc.meta["Gth"] == {"num": [18.32547182, -17.20911971], "den": [1.0, -0.77672958]}
    assert acc.meta["Ga"]["den"] == [1.0, -2.9289362, 2.85853684, -0.92960052]
    lead = read_log(rig_data / "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt")
    assert lead.meta["Ga"] == {"num": [], "den": []}
    assert lead.meta["columns"][-1] == "$\\hat{\\theta}_d$"


def test_bad_metadata_line_names_the_line(tmp_path):
    lines = _write(tmp_path / "run.tsv").read_text().splitlines()
    lines[2] = "# {not json"
    bad = tmp_path / "bad.tsv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunLogError, match=r"bad.tsv: line 3: metadata is not valid JSON"):
        read_log(bad)


class _Slow:
    """A sink that blocks until released: the file must keep being written meanwhile."""

    def __init__(self):
        import threading

        self.release = threading.Event()
        self.rows = 0

    def write_rows(self, columns):
        self.release.wait()
        self.rows += columns["n"].size


def test_a_blocked_sink_does_not_hold_up_the_file(tmp_path):
    slow = _Slow()
    path = tmp_path / "run.tsv"
    w = RunLogWriter(path, META, sinks=[slow])
    for k in range(50):
        w.append((k * 0.002, k, 0.0, 0.0, k, 0, 0.0, 0, 0, 1.0))
    deadline = time.monotonic() + 30
    while w.rows_written < 50 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert w.rows_written == 50  # on disk while the sink is still blocked
    np.testing.assert_array_equal(read_log(path).data["n"], np.arange(50))
    slow.release.set()
    w.close()
    assert slow.rows == 50


_FULL_DISK_CHILD = textwrap.dedent("""
    import json, math, resource, signal, sys, time
    from station.runlog import RunLogError, RunLogWriter
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes past the limit fail with EFBIG
    path, room = sys.argv[1], int(sys.argv[2])
    w = RunLogWriter(path, {"test": "full disk"})
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (room, hard))
    rows = [(k * 0.002, k, 0.0, 0.0, 0, 0, 0.0, 0, 0, math.nan) for k in range(300)]
    for r in rows[:200]:
        w.append(r)
    time.sleep(0.2)
    resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))  # space freed before close
    for r in rows[200:]:
        w.append(r)
    try:
        w.close()
        error = None
    except RunLogError as exc:
        error = str(exc)
    print(json.dumps({"written": w.rows_written, "unwritten": [r[1] for r in w.unwritten_rows], "error": error}))
""")


def test_write_error_counts_exactly_the_rows_in_the_file(tmp_path):
    """Disk full mid-row, then space freed before close: the rows reported written are the
    rows in the file, and unwritten_rows are exactly the others (no row in both)."""
    from station.runlog import format_value

    path = tmp_path / "full.tsv"
    RunLogWriter(path, {"test": "full disk"}).close()
    header = path.stat().st_size
    rows = [(k * 0.002, k, 0.0, 0.0, 0, 0, 0.0, 0, 0, math.nan) for k in range(300)]
    room = header + sum(len(("\t".join(format_value(x) for x in r) + "\n").encode()) for r in rows[:150]) + 7
    env = {**os.environ, "TMPDIR": str(tmp_path)}  # where the rescue file goes
    proc = subprocess.run([sys.executable, "-c", _FULL_DISK_CHILD, str(path), str(room)],
                          capture_output=True, text=True, timeout=60, env=env)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # row 150 is torn
        in_file = read_log(path).data["n"].astype(int).tolist()
    assert out["error"] is not None and f"{300 - len(in_file)} rows are not in the file" in out["error"]
    assert out["written"] == len(in_file)
    assert sorted(in_file + out["unwritten"]) == list(range(300))  # each row in exactly one place
    # the rows that did not fit are not lost: a rescue file with the same header holds them
    rescued = sorted(tmp_path.glob("full.rescued-*.tsv"))
    assert len(rescued) == 1 and str(rescued[0]) in out["error"]
    saved = read_log(rescued[0])
    assert saved.data["n"].astype(int).tolist() == out["unwritten"]
    assert saved.meta["rescued_from"] == str(path) and saved.meta["test"] == "full disk"


def test_a_writer_bug_keeps_the_rows_for_the_rescue_file(tmp_path, monkeypatch):
    import station.runlog.writer as runlog

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))

    def broken(rows):
        raise RuntimeError("formatter bug")

    w = RunLogWriter(tmp_path / "bug.tsv", {"test": "bug"})
    monkeypatch.setattr(runlog, "format_lines", broken)
    rows = [(k * 0.002, k, 0.0, 1.5, k, 0, 0.0, 2, 0, math.nan) for k in range(20)]
    for r in rows:
        w.append(r)
    deadline = time.monotonic() + 5
    while w._pump.write_error is None and time.monotonic() < deadline:  # the thread drains every 20 ms
        time.sleep(0.01)
    monkeypatch.undo()  # the rescue can format again
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    with pytest.raises(RunLogError, match=r"formatter bug.*20 rows are not in the file; they were saved to"):
        w.close()
    saved = read_log(next(tmp_path.glob("bug.rescued-*.tsv")))
    assert saved.data["n"].astype(int).tolist() == list(range(20))


def test_read_errors_carry_their_place_as_attributes(tmp_path):
    """Other code reads exc.file / exc.line / exc.key, never the message (issue: one truth)."""
    from station.runlog import RunLogError

    bad = tmp_path / "nan.txt"
    bad.write_text("#SLFR RTP P_control_Test\n#kp=2.0\n#t\tn\tu\tv\t$\\theta$\ta\n"
                   "0\t0\t0\t0\t0\t0\n0.002\t1\t0\t0\tnan\t0\n")
    with pytest.raises(RunLogError) as info:
        read_log(bad)
    exc = info.value
    assert (exc.file, exc.line, exc.key) == (str(bad), 5, "theta")
    assert str(exc).startswith(f"{bad}: line 5: theta")
    empty = tmp_path / "empty.tsv"
    empty.write_text("")
    with pytest.raises(RunLogError) as info:
        read_log(empty)
    assert (info.value.file, info.value.line) == (str(empty), None)


LEAD_ACCEL_LOG = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"


@pytest.mark.parametrize("line, edit, said", [
    (2, lambda s: s.rstrip("]"), "line 2: expected Gth num=[c0 c1 ...]"),       # no closing bracket
    (2, lambda s: "#Gth num", "line 2: expected Gth num=[c0 c1 ...]"),           # no coefficients at all
    (4, lambda s: s.rstrip("]"), "line 4: expected Ga num=[c0 c1 ...]"),        # Ga's, which was dropped
    (5, lambda s: s.rstrip("]"), "line 5: expected Ga num=[c0 c1 ...] or Ga den=[...]"),  # (was blamed on line 4)
    (3, lambda s: "#Gth num=[ 1. 2.]", "line 3: Gth num given twice"),
], ids=["Gth unclosed", "Gth bare", "Ga num unclosed", "Ga den unclosed", "Gth num twice"])
def test_a_malformed_filter_line_is_named_not_dropped(rig_data, tmp_path, line, edit, said):
    """A fuzzing round: '#Gth num=[1,2' was read as an empty Gth ('controller unknown'), an
    unclosed Ga as no Ga at all (the lead + accelerometer run taken for a lead)."""
    lines = (rig_data / LEAD_ACCEL_LOG).read_text().splitlines()
    lines[line - 1] = edit(lines[line - 1])
    path = tmp_path / "bad.txt"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunLogError, match=re.escape(said)):
        read_log(path)


def test_a_gain_printed_twice_is_named(tmp_path):
    path = tmp_path / "kp.txt"
    path.write_text("#SLFR RTP P_control_Test\n#kp=2.0\n#kp=3.0\n#t\tn\tu\tv\t$\\theta$\ta\n0\t0\t0\t0\t0\t0\n"
                    "0.002\t1\t50\t100\t0\t0\n")
    with pytest.raises(RunLogError, match=r"line 3: kp given twice \(lines 2 and 3\)"):
        read_log(path)


@pytest.mark.parametrize("digits", ["١٢", "１２", "٣.٥", "12\u00a0"])
@pytest.mark.parametrize("column", [0, 4, 5])
def test_digits_of_other_scripts_are_named_not_read(rig_data, tmp_path, digits, column):
    """A fuzzing round: float() reads Arabic-Indic "١٢" (and fullwidth "１２") as 12, so such a
    field in t, θ or a was taken for a number; no log writes them."""
    lines = (rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#")) + 100
    f = lines[k].split("\t")
    f[column] = digits
    lines[k] = "\t".join(f)
    path = tmp_path / "digits.txt"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(RunLogError, match=f"line {k + 1}: expected a number in column .*characters outside ASCII"):
        read_log(path)


def test_an_unstable_header_law_is_said_to_diverge_not_nan(rig_data, tmp_path):
    """A fuzzing round: a header Ga with a pole outside the unit circle printed '(max |dv| = nan
    counts)'. Its replay leaves the finite numbers: no match, said so; the data's law is used."""
    from station.logged import LoggedRun

    lines = (rig_data / LEAD_ACCEL_LOG).read_text().splitlines()
    lines[4] = "#Ga den=[ 1.         -3.5         2.85853684 -0.92960052]"
    path = tmp_path / "unstable.txt"
    path.write_text("\n".join(lines) + "\n")
    run = LoggedRun.from_path(path)
    claim = next(c for c in run.audit.claims if c.claim == "controller")
    assert "nan" not in claim.evidence and "its replay diverges: an unstable law" in claim.evidence
    assert claim.verdict == "contradicted" and run.reproduced


P_LOG = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
LEAD_LOG = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"


def _with_line(rig_data, tmp_path, name, line, text):
    lines = (rig_data / name).read_text().splitlines()
    lines[line - 1] = text
    path = tmp_path / "h.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("text", ["#kp=2.0 ki=0 kd=0", "#kp=2.0, ki=0.0, kd=0.0", "#Kp = 2.0; ki = 0; kd = 0"])
def test_several_gains_on_one_header_line_are_each_read(rig_data, tmp_path, text):
    """A PID script's one line of gains (before: "kp: expected a number, got '2.0 ki=0 kd=0'")."""
    log = read_log(_with_line(rig_data, tmp_path, P_LOG, 2, text))
    assert (log.meta["kp"], log.meta["ki"], log.meta["kd"]) == (2.0, 0.0, 0.0)


@pytest.mark.parametrize("text, title", [("#kp=2.0; title=foo bar", "foo bar"),
                                         ("#title = P step, 50 counts; kp = 2.0", "P step, 50 counts")])
def test_fields_parted_by_semicolons_may_hold_spaces(rig_data, tmp_path, text, title):
    """';' parts a header's fields whatever their values hold (before: "kp: expected a number,
    got '2.0; title=foo bar'")."""
    log = read_log(_with_line(rig_data, tmp_path, P_LOG, 2, text))
    assert log.meta["kp"] == 2.0 and log.meta["title"] == title


@pytest.mark.parametrize("num, den", [("[18.32547182, -17.20911971]", "[1.0, -0.77672958]"),
                                      ("[ 18.32547182,-17.20911971 ]", "[1.,-0.77672958]")])
def test_a_filter_printed_as_a_python_list_is_read(rig_data, tmp_path, num, den):
    """numpy prints [ 18.3 -17.2]; a Python list (or numpy with separator=', ') prints
    [18.3, -17.2]: the same coefficients (before: "expected numbers in Gth num=[...]")."""
    path = _with_line(rig_data, tmp_path, LEAD_LOG, 2, f"#Gth num={num}")
    lines = path.read_text().splitlines()
    lines[2] = f"#Gth den={den}"
    path.write_text("\n".join(lines) + "\n")
    assert read_log(path).meta["Gth"] == read_log(rig_data / LEAD_LOG).meta["Gth"]


@pytest.mark.parametrize("name, line, text, said", [
    (LEAD_LOG, 2, "#Gth num=[18,32547182 -17,20911971]", "line 2: expected numbers in Gth num=[...]"),
    (LEAD_LOG, 2, "#Gth num=[18,17]", "(a comma between digits"),
], ids=["Gth decimal comma", "Gth unspaced"])
def test_a_decimal_comma_in_the_header_is_named_not_misread(rig_data, tmp_path, name, line, text, said):
    """"[18,3 -17,2]" read with commas as separators would be a four-coefficient Gth: refused,
    naming the comma (a gain's one number, #kp=2,0, is read: its comma can be nothing else)."""
    with pytest.raises(RunLogError, match=re.escape(said)):
        read_log(_with_line(rig_data, tmp_path, name, line, text))
