"""Files that break the reader: the cases the issue found each give one line naming the
file, line and field; random mutations of the rig's logs and of ours either read and
replay or raise StationError - never another exception."""

from __future__ import annotations

import json
import os
import random
import warnings

import numpy as np
import pytest

from station.cli import main
from station.errors import StationError
from station.experiment import run_step
from station.replay import replay
from station.runlog import RunLogError, read_log

RIG_FILES = ("SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
             "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
             "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt",
             "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
             "without_accel_01_28_14_test_2.txt")


@pytest.fixture(scope="module")
def our_log(tmp_path_factory):
    out = tmp_path_factory.mktemp("ours") / "ours.tsv"
    run_step(controller="lead-accel", amplitude=200, duration=0.6, out=out, figure=False)
    return out


def _one_line_error(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err


def test_one_nan_in_a_rig_log_names_file_line_and_field(rig_data, tmp_path, capsys):
    lines = (rig_data / RIG_FILES[0]).read_text().split("\n")
    fields = lines[59].split("\t")
    fields[4] = "nan"  # theta of the row on line 60
    lines[59] = "\t".join(fields)
    bad = tmp_path / "nan.txt"
    bad.write_text("\n".join(lines))
    for argv in (["replay", str(bad)], ["replay", "--no-model", str(bad)], ["compare", str(bad)]):
        err = _one_line_error(capsys, argv)
        assert "nan.txt: line 60: theta is nan" in err


@pytest.mark.parametrize("line, said", [(500, "not a text run log (byte 0xb0: not UTF-8"),
                                        (2, "kp: expected a number, got '2.0 \ufffd' (a byte that is not UTF-8")])
def test_a_byte_that_is_not_utf8_names_its_line(rig_data, tmp_path, capsys, line, said):
    # a Windows script's "°" (latin-1 0xb0) in a row, or in a header line that holds a field:
    # before, "not a text run log (invalid start byte at byte 64 of a block)", no line to look at
    lines = (rig_data / RIG_FILES[0]).read_bytes().split(b"\n")
    lines[line - 1] = lines[line - 1] + (b" \xb0" if line == 2 else b"\xb0")
    bad = tmp_path / "latin1.txt"
    bad.write_bytes(b"\n".join(lines))
    for argv in (["replay", str(bad)], ["compare", str(bad)]):
        err = _one_line_error(capsys, argv)
        assert f"latin1.txt: line {line}: {said}" in err, err


@pytest.mark.parametrize("name", RIG_FILES[:4])
def test_a_header_comment_in_another_code_page_is_read(rig_data, tmp_path, capsys, name):
    """A title or comment line written on a Windows machine ("20°C" in cp1252): no number is in
    it, so the log is read, with one warning naming the line. Before, the whole log was refused
    ("not a text run log")."""
    lines = (rig_data / name).read_bytes().split(b"\n")
    lines[0] += b" 20\xb0C"  # the title line
    lines.insert(1, b"#operator: J\xfcrgen")
    path = tmp_path / name
    path.write_bytes(b"\n".join(lines))
    with pytest.warns(RuntimeWarning, match=r"line 1: 2 '#' line\(s\) not UTF-8 text"):
        log = read_log(path)
    clean = read_log(rig_data / name)
    assert log.meta["title"].endswith("20\ufffdC") and log.meta.get("kp") == clean.meta.get("kp")
    for key in clean.data:
        np.testing.assert_array_equal(log.data[key], clean.data[key])
    assert main(["replay", "--no-model", str(path)]) == 0
    err = capsys.readouterr().err
    assert "warning:" in err and "not UTF-8" in err and "error" not in err, err


def test_gth_with_den0_is_a_header_error(rig_data, tmp_path, capsys):
    text = (rig_data / RIG_FILES[1]).read_text()
    bad = tmp_path / "den0.txt"
    bad.write_text(text.replace("#Gth den=[ 1. ", "#Gth den=[ 0. ", 1))
    assert "den=[ 0." in bad.read_text()
    err = _one_line_error(capsys, ["replay", str(bad)])
    assert "den0.txt: line 3: Gth den=" in err and "den[0] not 0" in err


def _with_meta(our_log, tmp_path, name, edit) -> str:
    lines = our_log.read_text().split("\n")
    i = next(k for k, ln in enumerate(lines[:3]) if ln.startswith("# {"))
    lines[i] = edit(lines[i])
    path = tmp_path / name
    path.write_text("\n".join(lines))
    return str(path)


def test_deeply_nested_header_json(our_log, tmp_path, capsys):
    path = _with_meta(our_log, tmp_path, "deep.tsv", lambda ln: ln[:-1] + ', "x": ' + "[" * 100000 + "]" * 100000 + "}")
    assert "line 3: metadata JSON is nested too deeply" in _one_line_error(capsys, ["replay", path])


@pytest.mark.parametrize("dt", [-1, 0, "fast", None])
def test_bad_dt_in_our_header(our_log, tmp_path, capsys, dt):
    def edit(line):
        meta = json.loads(line[2:])
        meta["dt"] = dt
        return "# " + json.dumps(meta)

    path = _with_meta(our_log, tmp_path, "dt.tsv", edit)
    err = _one_line_error(capsys, ["replay", path])
    assert "line 3: header field dt is" in err and "(0, 1]" in err


def test_compare_on_a_log_with_a_nan_row(our_log, tmp_path, capsys):
    lines = our_log.read_text().split("\n")
    fields = lines[50].split("\t")
    fields[0] = "nan"  # t
    lines[50] = "\t".join(fields)
    bad = tmp_path / "nanrow.tsv"
    bad.write_text("\n".join(lines))
    assert "nanrow.tsv: line 51: t is nan" in _one_line_error(capsys, ["compare", str(bad), "--out-dir", str(tmp_path)])


# --- random mutations ---------------------------------------------------------------------

SEEDS = int(os.environ.get("STATION_FUZZ_SEEDS", "6"))
"""Mutation rounds (each 12 mutations of every source file); raise it for a longer hunt."""

TOKENS = ["nan", "inf", "-inf", "", "x", "1e999", "-0", "0x10", "1_0", "9" * 400, "#", "\t", "é", "\x00",
          "[", "{", "# end {", "# end {}", '# {"dt": 0}', "#Gth den=[0 1]", "#Gth num=[nan]", "#kp=nan"]


def _mutate(text: str, rng: random.Random) -> str:
    lines = text.split("\n")
    for _ in range(rng.randint(1, 3)):
        op = rng.randrange(8)
        i = rng.randrange(len(lines))
        if op == 0:  # a field replaced
            parts = lines[i].split("\t")
            parts[rng.randrange(len(parts))] = rng.choice(TOKENS)
            lines[i] = "\t".join(parts)
        elif op == 1:
            del lines[i]
        elif op == 2:
            lines.insert(i, lines[rng.randrange(len(lines))])
        elif op == 3:  # a line cut short
            lines[i] = lines[i][:rng.randrange(len(lines[i]) + 1)]
        elif op == 4:  # a header line changed
            j = rng.randrange(min(6, len(lines)))
            lines[j] = lines[j][:rng.randrange(len(lines[j]) + 1)] + rng.choice(TOKENS)
        elif op == 5:
            lines.insert(i, rng.choice(TOKENS))
        elif op == 6:  # two lines swapped
            j = rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
        else:  # the file cut anywhere
            return "\n".join(lines)[:rng.randrange(len(text))]
    return "\n".join(lines)


def _sources(rig_data, our_log):
    return [rig_data / name for name in RIG_FILES if (rig_data / name).exists()] + [our_log]


@pytest.mark.parametrize("seed", range(SEEDS))
def test_mutated_logs_read_and_replay_or_raise_station_error(rig_data, our_log, tmp_path, seed):
    rng = random.Random(seed)
    outcomes = {"ok": 0, "refused": 0}
    for src in _sources(rig_data, our_log):
        text = src.read_text()
        for k in range(12):
            path = tmp_path / f"m{k}{src.suffix}"
            path.write_text(_mutate(text, rng))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # torn lines and reader notes are warnings, not failures
                try:
                    read_log(path)
                    replay(path, model=(k % 6 == 0))
                    outcomes["ok"] += 1
                except StationError:
                    outcomes["refused"] += 1
    assert outcomes["ok"] > 0 and outcomes["refused"] > 0  # the mutations hit both sides


def test_reader_error_is_a_station_error():
    assert issubclass(RunLogError, StationError)
