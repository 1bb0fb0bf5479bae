"""The reader takes every layout the rig's logs come in: columns by name with the field's
synonyms, n derived from t, the sample time reported; off-rate logs say what cannot be
replayed; a file with no usable columns is a one-line error listing found and expected."""

import numpy as np
import pytest

from station.cli import main
from station.logged import LoggedRun
from station.replay import replay
from station.runlog import RunLogError, read_log, standard_column

T = np.arange(400) * 0.002
U = np.where(T >= 0.1, 50.0, 0.0)


def _p_run(kp=1.0, d=1, u=U):
    """theta of a crude first-order plant under v = kp (u[k] - theta[k-d]), exact floats."""
    n = u.size
    theta = np.zeros(n)
    v = np.zeros(n)
    for k in range(n):
        if k >= d:
            v[k] = kp * (u[k] - theta[k - d])
        if k + 1 < n:
            theta[k + 1] = theta[k] + 0.01 * v[k]
    return theta, v


def test_synonyms():
    assert [standard_column(c) for c in ("Time (sec.)", "θ", "$\\theta$", "accel", "a", " t ", "v", "foo")] == \
        ["t", "theta", "theta", "a", "a", "t", "v", "foo"]


def test_names_in_quotes_or_with_their_units(tmp_path):
    # A spreadsheet's CSV quotes its names; exports print units after them. Before: "no usable
    # columns: found '"t (s)"', ..." and "no 'v', 'theta', 'a' column" beside 'cmd [DAC]'
    assert [standard_column(c) for c in ('"t (s)"', "'theta'", "theta (counts)", "cmd [DAC]", "Time [s]",
                                         "accel [counts]", "Time (sec.)", "foo (bar)")] == \
        ["t", "theta", "theta", "v", "t", "a", "t", "foo (bar)"]
    path = tmp_path / "export.csv"
    path.write_text('"t (s)","u (counts)","v (DAC counts)","theta (counts)","a (counts)"\n'
                    "0,0,0,0,0\n0.002,50,100,0,0\n0.004,50,98,1,2\n")
    log = read_log(path)
    assert log.sample_time == 0.002 and list(log.data["v"]) == [0, 100, 98] and list(log.data["a"]) == [0, 0, 2]


@pytest.mark.parametrize("style", ["r", "all"])
def test_quoted_fields_are_numbers(rig_data, tmp_path, style):
    """R's write.csv quotes its row names ("1",0,0.002,...); a spreadsheet may quote every field.
    Before: 'line 2: expected a number in column '', got '"1"''. Now the quotes go, and the rig's
    P step so written gives the log's own numbers."""
    src = rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    rows = [x.split("\t") for x in src.read_text().splitlines() if not x.startswith("#")]
    path = tmp_path / "exported.csv"
    if style == "r":
        path.write_text('"","t","n","u","v","theta","a"\n'
                        + "".join(f'"{k + 1}",' + ",".join(r) + "\n" for k, r in enumerate(rows)))
    else:
        path.write_text('"t","n","u","v","theta","a"\n' + "".join(",".join(f'"{x}"' for x in r) + "\n" for r in rows))
    clean, quoted = read_log(src), read_log(path)
    for name in ("t", "n", "u", "v", "theta", "a"):
        np.testing.assert_array_equal(quoted.data[name], clean.data[name])
    assert replay(path).metrics == replay(src).metrics


@pytest.mark.parametrize("comments", [["#SLFR RTP OL_Test"], ["# lab notebook p. 12", "#kp=1.0"]])
def test_comment_lines_above_a_line_of_column_names(rig_data, tmp_path, comments):
    """A 2014 log (a first line of column names, no '#' header) with comment lines put above it.
    Before: 'line 1: no usable columns: found 'SLFR', 'RTP', 'OL_Test'' (the last '#' line taken
    as the column line). Now the names line is the columns and the comments the header: the
    rows as the log's own, and the header's claim judged (an open-loop header contradicted by
    the P law the rows hold; the notebook's kp = 1 confirmed)."""
    src = rig_data / "without_accel_01_28_14_test_2.txt"
    path = tmp_path / "annotated.txt"
    path.write_text("\n".join(comments) + "\n" + src.read_text())
    clean, annotated = read_log(src), read_log(path)
    for name in ("t", "u", "v", "theta", "a"):
        np.testing.assert_array_equal(annotated.data[name], clean.data[name])
    run = LoggedRun.from_path(path)
    assert run.reproduced and run.controller.spec["kp"] == 1.0
    assert run.source == ("inferred (header contradicted)" if "OL_Test" in comments[0] else "header")


@pytest.mark.parametrize("names_end, row_end", [("", "\t"), ("\t", "\t")])
def test_a_delimiter_after_the_last_field(tmp_path, names_end, row_end):
    # A lab script that writes "%g\t" for every field, the last too: before, "expected 6
    # tab-separated numbers, got 7" or "expected a number in column '', got ''"
    rows = ["0\t0\t0\t0\t0\t0", "0.002\t1\t50\t100\t0\t0", "0.004\t2\t50\t98\t1\t2"]
    plain, ended = tmp_path / "plain_SLFR_RTP_P_control_Test.txt", tmp_path / "ended_SLFR_RTP_P_control_Test.txt"
    head = ["#SLFR RTP P_control_Test", "#kp=2.0"]
    plain.write_text("\n".join(head + ["#t\tn\tu\tv\t$\\theta$\ta"] + rows) + "\n")
    ended.write_text("\n".join(head + ["#t\tn\tu\tv\t$\\theta$\ta" + names_end] + [r + row_end for r in rows]) + "\n")
    a, b = read_log(plain), read_log(ended)
    for name in a.data:
        np.testing.assert_array_equal(a.data[name], b.data[name])
    csv = tmp_path / "ended.csv"
    csv.write_text("t,theta,v,\n0,0,0,\n0.002,1,5,\n0.004,3,5,\n")
    assert list(read_log(csv).data["theta"]) == [0, 1, 3]


P_STEP = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"


@pytest.mark.parametrize("rows_sep", [" ", "  ", ",", ";", ", "])
def test_rows_parted_otherwise_than_the_column_line(rig_data, tmp_path, rows_sep):
    # A script that printed its column line with tabs and its rows with "%g %g" or "%g,%g":
    # before, "line 4: expected 6 tab-separated numbers, got 1"
    src = rig_data / P_STEP
    lines = src.read_text().splitlines()
    path = tmp_path / P_STEP
    path.write_text("\n".join(ln if ln.startswith("#") else ln.replace("\t", rows_sep) for ln in lines) + "\n")
    clean, other = read_log(src), read_log(path)
    for name in clean.data:
        np.testing.assert_array_equal(other.data[name], clean.data[name])
    assert LoggedRun.from_path(path).reproduced


def test_a_blank_line_among_the_header_lines(rig_data, tmp_path):
    # before: the header ended at the blank line, and its first line was read as the column
    # names ("line 1: no usable columns: found 'SLFR', 'RTP', 'P_control_Test'")
    src = rig_data / P_STEP
    path = tmp_path / P_STEP
    path.write_text(src.read_text().replace("\n", "\n\n", 1))
    clean, other = read_log(src), read_log(path)
    assert other.meta == clean.meta
    for name in clean.data:
        np.testing.assert_array_equal(other.data[name], clean.data[name])


def test_a_row_of_too_few_fields_is_still_named(tmp_path):
    # the rows' own delimiter is chosen only where it gives one field per column
    path = tmp_path / "short_SLFR_RTP_P_control_Test.txt"
    path.write_text("#SLFR RTP P_control_Test\n#kp=2.0\n#t\tn\tu\tv\t$\\theta$\ta\n0 0 0 0 0\n")
    with pytest.raises(RunLogError, match="line 4: expected 6 tab-separated numbers, got 1"):
        read_log(path)


def test_a_file_holding_two_runs_is_one_line_error(rig_data, tmp_path):
    # Two runs appended to one file (the second with its own header): before, read as one run
    # of 2000 rows whose t jumps back, replayed to max |dv| = 98 counts. A '#' line among rows
    # that go on in time is no second run.
    src = rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    twice = tmp_path / "twice_SLFR_RTP_P_control_kp=2.0.txt"
    twice.write_text(src.read_text() * 2)
    with pytest.raises(RunLogError, match=r"line 1004: a second header: the file holds more than one run "
                                          r"\(after 1000 rows, t starts again at 0\); split it at line 1004"):
        read_log(twice)
    lines = src.read_text().splitlines()
    noted = tmp_path / "noted_SLFR_RTP_P_control_kp=2.0.txt"
    noted.write_text("\n".join(lines[:500] + ["# the hub touched here"] + lines[500:]) + "\n")
    np.testing.assert_array_equal(read_log(noted).data["theta"], read_log(src).data["theta"])


def test_2014_layout_maps_columns_and_derives_n(tmp_path):
    theta, v = _p_run()
    a = np.round(np.sin(T) * 5) - 39
    path = tmp_path / "without_accel.txt"
    lines = ["Time (sec.)\tu\ttheta\taccel\tv"]
    lines += [f"{t!r}\t{u!r}\t{th!r}\t{aa!r}\t{vv!r}" for t, u, th, aa, vv in zip(T.tolist(), U.tolist(), theta.tolist(), a.tolist(), v.tolist())]
    path.write_text("\n".join(lines) + "\n")
    log = read_log(path)
    assert (log.format, log.layout, log.sample_time) == ("rig", "columns", 0.002)
    np.testing.assert_array_equal(log.data["n"], np.arange(T.size))
    np.testing.assert_array_equal(log.data["a"], a)
    np.testing.assert_array_equal(log.data["theta"], theta)
    assert np.all(np.isnan(log.data["theta_d_hat"]))
    assert any("'Time (sec.)' -> t" in n for n in log.notes)


def test_2014_log_replays_with_p_inferred(tmp_path):
    theta, v = _p_run(kp=1.0, d=1)
    path = tmp_path / "sweep.txt"
    path.write_text("Time (sec.)\tu\ttheta\taccel\tv\n"
                    + "".join(f"{t!r}\t{u!r}\t{th!r}\t0.0\t{vv!r}\n" for t, u, th, vv in zip(T.tolist(), U.tolist(), theta.tolist(), v.tolist())))
    r = replay(path, model=False)
    assert r.controller_source == "inferred" and r.controller_spec["kp"] == 1.0
    assert r.alignment == 1 and r.max_abs_dv <= 1e-6


def test_rig_2014_sweeps(rig_data):
    r = replay(rig_data / "without_accel_01_28_14_test_2.txt", model=False)
    assert r.layout == "columns" and r.sample_time == 0.002 and r.samples == 10500
    assert r.controller_source == "inferred" and r.controller == "p" and r.controller_spec["kp"] == 1.0
    assert r.alignment == 1 and r.max_abs_dv <= 1e-6


def test_cut_down_copy_at_0004s_says_what_cannot_be_replayed(tmp_path):
    """`t v theta a` with every second row (0.004 s): no u, no n. The open-loop pulse is
    still simulated at its own dt; one note says the commands cannot be replayed."""
    v = np.where((T >= 0.04) & (T < 0.14), 100.0, 0.0)[::2]
    t = T[::2]
    path = tmp_path / "pulse_downsampled.txt"
    path.write_text("t\tv\ttheta\ta\n" + "".join(f"{x:g}\t{y:g}\t0\t0\n" for x, y in zip(t, v)))
    log = read_log(path)
    assert log.sample_time == 0.004 and np.array_equal(log.data["n"], np.arange(t.size))
    assert np.all(np.isnan(log.data["u"]))
    r = replay(path)
    notes = [n for n in r.notes if "cannot be replayed" in n]
    assert len(notes) == 1 and "0.004 s" in notes[0]
    assert r.controller is None and r.controller_source is None
    assert r.prediction is not None and r.prediction["theta"].size == t.size
    # the model ran at 0.004 s: the pulse moves it (the plant's theta is not all zero)
    assert np.ptp(r.prediction["theta"]) > 1
    assert not any("names no controller" in n for n in r.notes)


def test_header_with_spaces_and_2009_alignment(tmp_path):
    theta, v = _p_run(kp=1.0, d=0)
    path = tmp_path / "step_2009.txt"
    path.write_text("#SLFR RTP P_control_Test\n#kp = 1.0\n#t\tn\tu\tv\t$\\theta$\ta\n"
                    + "".join(f"{t!r}\t{k}\t{u!r}\t{vv!r}\t{th!r}\t-2\n"
                              for k, (t, u, th, vv) in enumerate(zip(T.tolist(), U.tolist(), theta.tolist(), v.tolist()))))
    r = replay(path, model=False)
    assert r.controller_source == "header" and r.alignment == 0 and r.max_abs_dv == 0


@pytest.mark.parametrize("text, found", [
    ("name,age,city\nann,30,x\n", "'name', 'age', 'city'"),
    ("#some tool output\n#alpha\tbeta\n1\t2\n", "'alpha', 'beta'"),
])
def test_no_usable_columns_is_one_line_listing_found_and_expected(tmp_path, text, found):
    path = tmp_path / "foreign.csv"
    path.write_text(text)
    with pytest.raises(RunLogError) as err:
        read_log(path)
    msg = str(err.value)
    assert "\n" not in msg and "no usable columns" in msg and found in msg
    assert "expected a time column" in msg and "theta" in msg


def test_comma_separated_with_synonyms(tmp_path):
    path = tmp_path / "export.csv"
    path.write_text("time,theta,v\n0,0,0\n0.002,1,5\n0.004,3,5\n")
    log = read_log(path)
    assert log.sample_time == 0.002 and list(log.data["theta"]) == [0, 1, 3]
    assert list(log.data["n"]) == [0, 1, 2]


@pytest.mark.parametrize("layout", ["rig", "csv"])
def test_a_byte_order_mark_is_no_part_of_the_text(tmp_path, layout):
    # Windows editors and Excel's "CSV UTF-8" write a byte-order mark first; it made the rig's
    # header line '\ufeff#SLFR' and the file "no usable columns"
    text = ("#SLFR RTP P_control_Test\n#kp=1.0\n#t\tn\tu\tv\t$\\theta$\ta\n0\t0\t0\t0\t0\t0\n"
            "0.002\t1\t50\t50\t0\t0\n0.004\t2\t50\t50\t0\t1\n" if layout == "rig" else
            "time,theta,v\n0,0,0\n0.002,1,5\n0.004,3,5\n")
    plain, marked = tmp_path / f"plain.{layout}", tmp_path / f"marked.{layout}"
    plain.write_text(text, encoding="utf-8")
    marked.write_text(text, encoding="utf-8-sig")
    assert marked.read_bytes()[:3] == b"\xef\xbb\xbf"
    a, b = read_log(plain), read_log(marked)
    assert (a.format, a.meta, a.header) == (b.format, b.meta, b.header)
    for name in a.data:
        np.testing.assert_array_equal(a.data[name], b.data[name])


def test_a_compensator_file_with_a_byte_order_mark(tmp_path):
    from station.control import load_compensator_file
    text = 'name = "p2"\nlimit = 200.0\n\n[gth]\ndomain = "z"\nnum = [2.0]\nden = [1.0]\n'
    path = tmp_path / "p2.toml"
    path.write_text(text, encoding="utf-8-sig")
    assert load_compensator_file(path).gth.num[0] == 2.0


@pytest.mark.parametrize("field", ["#Kp=1", "#KP = 1.0", "#kp=1"])
def test_a_header_field_in_another_case_is_the_same_field(tmp_path, field):
    # The rig's software writes "#kp=1.0"; a script that wrote "#Kp=1" (and a line of free text)
    # names the same P law: before, its kp was not read and the law was only inferred
    theta, v = _p_run(kp=1.0, d=1)
    rows = [f"{t:g}\t{k}\t{u:g}\t{float(vv)!r}\t{float(th)!r}\t0"
            for k, (t, u, vv, th) in enumerate(zip(T, U, v, theta))]
    path = tmp_path / "step_SLFR_RTP_P_control_Test.txt"
    path.write_text("\n".join(["#SLFR RTP P_control_Test", "# run by the lab, beam 0.41 m", field,
                               "#t\tn\tu\tv\t$\\theta$\ta"] + rows) + "\n")
    from station.logged import LoggedRun
    run = LoggedRun.from_path(path)
    assert run.source == "header" and run.controller.spec["kp"] == 1.0 and run.reproduced
    assert [c.verdict for c in run.audit.claims if c.claim == "controller"] == ["confirmed"]


def test_end_record_is_the_outcome(tmp_path):
    path = tmp_path / "ours.tsv"
    from station.runlog import RunLogWriter

    with RunLogWriter(path, {"dt": 0.002}) as w:
        w.append((0.0, 0, 0.0, 0.0, 0, 0, 0.0, 0, 0, float("nan")))
    assert read_log(path).outcome is None
    with open(path, "a") as fh:
        fh.write('# end {"reason": "completed", "ticks": 1}\n')
    assert read_log(path).outcome == {"reason": "completed", "ticks": 1}
    assert replay(path, model=False).to_json()["outcome"] == {"reason": "completed", "ticks": 1}


def test_every_rig_log_replays_with_the_new_keys(rig_data, tmp_path):
    import json

    for path in sorted(rig_data.glob("*.txt")):
        out = tmp_path / (path.stem + ".json")
        assert main(["replay", str(path), "--no-model", "--json", str(out)]) == 0, path.name
        j = json.loads(out.read_text())
        assert {"controller_source", "beam_test", "notes", "sample_time_s"} <= set(j), path.name
