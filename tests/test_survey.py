"""station survey: every file of a folder replayed into one table; bad files (binary,
empty, foreign CSV) become rows with a reason and the survey still exits 0."""

import csv
import shutil

import numpy as np

from station.cli import main
from station.survey import find_logs, survey


def _folder(tmp_path, rig_data=None):
    d = tmp_path / "logs"
    (d / "sub").mkdir(parents=True)
    (d / "binary.dat").write_bytes(bytes(range(256)) * 4)
    (d / "empty.txt").write_text("")
    (d / "foreign.csv").write_text("name,age\nann,30\n")
    (d / ".hidden").write_text("ignored")
    t = np.arange(300) * 0.002
    v = np.where((t >= 0.04) & (t < 0.14), 100.0, 0.0)
    (d / "sub" / "pulse.txt").write_text("t\tv\ttheta\ta\n" + "".join(f"{x:g}\t{y:g}\t0\t0\n" for x, y in zip(t, v)))
    if rig_data is not None:
        for name in ("SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
                     "log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt"):
            shutil.copy(rig_data / name, d / name)
    return d


def test_find_logs_recursive_skips_hidden(tmp_path):
    d = _folder(tmp_path)
    names = [p.name for p in find_logs([d])]
    assert names == ["binary.dat", "empty.txt", "foreign.csv", "pulse.txt"]


def test_bad_files_are_rows_with_reasons(tmp_path):
    rows = {r.file.split("/")[-1]: r for r in survey([_folder(tmp_path)], model=False, workers=1)}
    assert "not a text run log" in rows["binary.dat"].reason
    assert "empty" in rows["empty.txt"].reason
    assert "no usable columns" in rows["foreign.csv"].reason and "'name', 'age'" in rows["foreign.csv"].reason
    pulse = rows["pulse.txt"]
    assert pulse.usable and pulse.format == "columns" and pulse.rows == 300 and pulse.sample_time_s == 0.002
    assert all("\n" not in r.reason for r in rows.values())


def test_command_on_rig_logs_prints_table_and_writes_csv(tmp_path, rig_data, capsys):
    d = _folder(tmp_path, rig_data)
    out = tmp_path / "survey.csv"
    rep = tmp_path / "reports"
    assert main(["survey", str(d), "--csv", str(out), "--report", str(rep), "--jobs", "2"]) == 0
    captured = capsys.readouterr()
    assert "6 files: 3 replayed, 3 unusable" in captured.out
    assert "UNUSABLE" in captured.out and "survey: 6/6" in captured.err
    assert "settling (1 %) s" in captured.out and "Ts s" not in captured.out  # a settling time names its band
    rows = {r["file"].split("/")[-1]: r for r in csv.DictReader(out.open())}
    p = rows["SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"]
    assert (p["controller"], p["controller_source"], p["alignment"]) == ("p", "header", "1")
    assert float(p["overshoot_pct"]) == 24.0 and float(p["settling_thesis_s"]) == 1.25
    assert p["fit_theta_pct"] != "" and p["reason"] == ""
    beam = rows["log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt"]
    assert abs(float(beam["f1_hz"]) - 2.52) < 0.03 * 2.52 and beam["fit_theta_pct"] == ""
    assert (rep / "survey.txt").exists() and len(list(rep.glob("*.json"))) == 6


def test_missing_path_is_a_one_line_error(tmp_path, capsys):
    assert main(["survey", str(tmp_path / "nope")]) == 2
    assert "no such file or folder" in capsys.readouterr().err


def test_the_files_the_station_writes_beside_its_logs_are_not_logs(tmp_path, capsys):
    """A folder of runs as `station step` leaves it (log, figure, JSON, rerun recording), with a
    model file and a survey's own report: one log replayed, nothing unusable, the rest "not a log"."""
    runs = tmp_path / "runs"
    assert main(["step", "--duration", "0.1", "--quiet", "--out", str(runs / "r.tsv"), "--json", str(runs / "r.json"),
                 "--rrd", str(runs / "r.rrd")]) == 0
    (runs / "rig.toml").write_text('name = "rig-copy"\nparams = "tmm-fit"\n')
    assert main(["survey", str(runs), "--no-model", "--jobs", "1", "--report", str(runs / "rep"),
                 "--csv", str(runs / "s.csv")]) == 0
    capsys.readouterr()
    assert main(["survey", str(runs), "--no-model", "--jobs", "1"]) == 0
    table = capsys.readouterr().out
    assert "8 files: 1 replayed, 0 unusable, 7 not logs" in table and "UNUSABLE" not in table
    rows = {r.file.split("/")[-1]: r for r in survey([runs], model=False, workers=1)}
    assert rows["r.tsv"].status == "ok"
    assert {name: r.reason for name, r in rows.items() if r.status == "not a log"} == {
        "r.png": "a figure (PNG)", "r.json": "a JSON report", "r.rrd": "a rerun recording",
        "rig.toml": "a model or compensator file (TOML)", "s.csv": "a survey table", "survey.txt": "a survey table",
        "003_r.json": "a JSON report"}


def test_an_a_fit_of_no_tip_acceleration_says_so_in_the_table_and_the_csv(tmp_path, rig_data, capsys):
    """The 2014 sweep's a is no tip acceleration (the log audit): its fit of about -270 % is no model
    error, and the survey's table says so beside it as replay does; the CSV carries the same fact."""
    import csv
    import io

    from station.replay import NOT_TIP

    d = tmp_path / "logs"
    d.mkdir()
    for name in ("without_accel_01_28_14_test_2.txt", "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"):
        shutil.copy(rig_data / name, d / name)
    assert main(["survey", str(d), "--jobs", "1", "--csv", str(tmp_path / "s.csv")]) == 0
    out = capsys.readouterr().out
    rows = {line.split()[0]: line for line in out.splitlines() if line.startswith(("without", "SFLR"))}
    assert rows["without_accel_01_28_14_test_2.txt"].endswith(f"% ({NOT_TIP})")
    assert NOT_TIP not in rows["SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"]
    table = {r["file"].rsplit("/", 1)[-1]: r for r in csv.DictReader(io.StringIO((tmp_path / "s.csv").read_text()))}
    assert table["without_accel_01_28_14_test_2.txt"]["accel_is_tip"] == "False"
    assert table["SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"]["accel_is_tip"] == "True"
