"""Every numeric option of every command is range-checked before anything starts.

The cases are generated from the parsers themselves (station.cli.build_parser), so an
option added later is covered: it must use station.commands.options.number (a plain
int/float type fails the first test), its --help must state its range, and nan, inf,
-inf and the values just past each bound must give one line naming the option, exit 2,
no traceback, no file written and no port opened.
"""

from __future__ import annotations

import argparse
import math
import os

import numpy as np
import pytest

from station.cli import build_parser, main
from station.commands.options import Number, numeric_actions


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def _outside(t: Number) -> list[str]:
    """nan, ±inf, and the nearest values past each bound."""
    values = ["nan", "inf", "-inf"]
    if t.integer:
        values += [str(int(t.low) - 1), str(int(t.high) + 1)]
    else:
        values += [repr(float(np.nextafter(t.low, -np.inf))), repr(float(np.nextafter(t.high, np.inf)))]
    return values


def _positionals(parser: argparse.ArgumentParser, tmp_path) -> list[str]:
    """Stand-ins for the command's positional arguments (a file that is a valid path)."""
    args = []
    for a in parser._actions:
        if not a.option_strings and not isinstance(a, argparse._SubParsersAction):
            f = tmp_path / "in.tsv"
            args.append(str(f))
    return args


def _cases():
    for name, parser in _subparsers().items():
        for action in numeric_actions(parser):
            if isinstance(action.type, Number):
                for value in _outside(action.type):
                    yield pytest.param(name, action.option_strings[-1], value, id=f"{name} {action.option_strings[-1]} {value}")


def test_every_numeric_option_uses_a_checked_range_and_documents_it():
    seen = 0
    for name, parser in _subparsers().items():
        for action in numeric_actions(parser):
            assert isinstance(action.type, Number), f"station {name} {action.option_strings}: plain {action.type}"
            assert action.type.range_text() in action.help, f"station {name} {action.option_strings}: range not in --help"
            seen += 1
    assert seen >= 20  # step alone has 13 numeric options


@pytest.fixture
def no_port(monkeypatch):
    """Opening any port fails the test: a refused value must not get that far."""
    import serial

    def refuse(*args, **kwargs):
        raise AssertionError("a port was opened")

    monkeypatch.setattr(serial, "serial_for_url", refuse)
    monkeypatch.setattr(serial, "Serial", refuse)


@pytest.mark.parametrize("command, option, value", list(_cases()))
def test_value_outside_the_range_is_refused_in_one_line(command, option, value, tmp_path, monkeypatch, capsys, no_port):
    monkeypatch.chdir(tmp_path)
    parser = _subparsers()[command]
    argv = [command, *_positionals(parser, tmp_path), f"{option}={value}"]
    if command == "sim-device":
        argv.insert(1, "--pty")
    assert main(argv) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert f"argument {option}" in lines[0] and "Traceback" not in err
    assert os.listdir(tmp_path) == []  # no log, no figure, no folder


@pytest.mark.parametrize("argv, words", [
    (["step", "--duration", "1e9"], "--duration"),
    (["step", "--timeout", "0"], "--timeout"),
    (["step", "--timeout", "-1"], "--timeout"),
    (["step", "--soft-limit", "-5"], "--soft-limit"),
    (["step", "--step-time", "-1"], "--step-time"),
    (["step", "--amplitude", "nan"], "--amplitude"),
    (["bode", "x.tsv", "--nperseg", "10"], "--nperseg"),
    (["modes", "--count", "0"], "--count"),
    (["modes", "--count", "50"], "--count"),
    # meaningful for the controller / reference: checked after parsing, still before anything starts
    (["step", "--kp", "3"], "--kp"),
    (["step", "--controller", "p", "--kp", "3", "--step-time", "2.5"], "--step-time 2.5 s"),
    (["step", "--amplitude", "50", "--reference", "ref.tsv"], "--amplitude"),
    (["step", "--controller", "open-loop", "--amplitude", "300"], "--amplitude 300"),
    (["step", "--amplitude", "3000"], "--soft-limit"),
    (["step", "--protocol", "legacy", "--duration", "70"], "--duration 70 s"),
    (["step", "--out", "exists.tsv"], "--force"),
    (["step", "--reference", "swept-sine", "--step-time", "0.5"], "--step-time"),
    (["step", "--reference", "ref.tsv", "--step-time", "0.5"], "--step-time"),
    (["replay", "ref.tsv", "--no-model", "--elements", "10"], "--elements: not with --no-model"),
    (["step", "--json", "nodir/sub"], None),
])
def test_issue_cases_are_refused_before_anything_starts(argv, words, tmp_path, monkeypatch, capsys, no_port):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "exists.tsv").write_text("keep me\n")
    (tmp_path / "ref.tsv").write_text("t\tu\n0\t0\n0.002\t1\n")
    (tmp_path / "nodir").write_text("a file, not a folder\n")
    before = sorted(os.listdir(tmp_path))
    code = main(argv)
    err = capsys.readouterr().err
    if words is None:
        assert code == 2 and len(err.strip().splitlines()) == 1
    else:
        assert code == 2 and words in err and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err
    assert sorted(os.listdir(tmp_path)) == before
    assert (tmp_path / "exists.tsv").read_text() == "keep me\n"


def test_a_run_the_machine_cannot_hold_is_refused_before_it_starts(tmp_path, monkeypatch, capsys, no_port):
    from station import plan

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(plan, "_available_memory", lambda: 10**9)  # 1 GB
    assert main(["step", "--duration", "20000"]) == 2  # 10 million ticks: within what v1 counts
    err = capsys.readouterr().err
    assert "--duration 20000 s: 10000000 ticks need about 2.0 GB of memory; this machine has 1.0 GB" in err
    assert os.listdir(tmp_path) == []


def test_limit_overridden_by_a_compensator_file_says_which_wins(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.toml").write_text('limit = 150\n[gth]\nnum = [2.0]\nden = [1.0]\ndomain = "z"\n')
    assert main(["step", "--controller", "c.toml", "--limit", "100", "--duration", "0.1", "--quiet",
                 "--out", "r.tsv"]) == 0
    err = capsys.readouterr().err
    assert "--limit 100 is not used" in err and "limit = 150" in err
    from station.runlog import read_log

    assert read_log(tmp_path / "r.tsv").meta["controller"]["limit"] == 150.0


def test_compensator_file_not_utf8_and_unstable_pole(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.toml").write_bytes(b'name = "x"\n# caf\xe9\n')
    assert main(["step", "--controller", "bad.toml"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: line 2: not UTF-8" in err and len(err.strip().splitlines()) == 1
    assert os.listdir(tmp_path) == ["bad.toml"]
    (tmp_path / "u.toml").write_text('[gth]\nnum = [0.1]\nden = [1.0, -1.2]\ndomain = "z"\n')
    main(["step", "--controller", "u.toml", "--duration", "0.05", "--quiet", "--out", "u.tsv"])
    err = capsys.readouterr().err
    assert "u.toml: [gth]: unstable pole at z = 1.2" in err


def test_number_accepts_the_bounds_themselves():
    t = Number(0.001, 60.0)
    assert t("0.001") == 0.001 and t("60") == 60.0
    n = Number(1, 100, integer=True)
    assert n("1") == 1 and n("100") == 100 and isinstance(n("5"), int)
    with pytest.raises(argparse.ArgumentTypeError, match="whole number"):
        n("2.5")
    assert math.isfinite(t("1e-3"))
