"""Options declared once (station.commands.options): every command that simulates takes
``--model`` from ``add_model_options``; ``station survey --model`` and ``run_step(model=...)``
run the model asked for."""

import argparse
import csv
import re
from pathlib import Path

import pytest

from station.cli import build_parser, main
from station.commands import options

SIMULATING = ("step", "replay", "sim-device", "bode", "compare", "modes", "survey", "diagnose", "identify", "tune")
"""The commands that simulate the model (or serve it, as the simulated rig)."""
STATION = Path(__file__).resolve().parents[1] / "station"


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_command_that_simulates_takes_the_one_model_option():
    parsers = _subparsers()
    for name, parser in parsers.items():
        model = [a for a in parser._actions if "--model" in a.option_strings]
        if name not in SIMULATING:
            assert not model, f"station {name} does not simulate, yet takes --model"
            continue
        (action,) = model
        assert action.metavar == "NAME|FILE" and action.default is None, name
        assert options.MODEL_HELP in action.help, f"station {name} --model: not add_model_options' help"


def test_model_options_are_declared_in_options_py_only():
    for path in STATION.rglob("*.py"):
        if path.name == "options.py" and path.parent.name == "commands":
            continue
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"add_argument\(\s*\"--(model|elements|params|no-model|seed)\"", text), path


def test_survey_model_option_simulates_each_log_on_that_model(tmp_path, capsys):
    from station.experiment import run_step

    logs = tmp_path / "logs"
    rep = run_step(port="sim://?noise=0", model="rig", controller="p", amplitude=50.0, duration=0.6,
                   out=logs / "p.tsv", figure=False, lean=False)
    assert rep.result.ok, rep.result.message
    fits = {}
    for label, extra in (("rig", ["--model", "rig"]), ("default", [])):
        out = tmp_path / f"{label}.csv"
        assert main(["survey", str(logs), "--jobs", "1", "--csv", str(out), *extra]) == 0
        (row,) = list(csv.DictReader(out.open()))
        fits[label] = float(row["fit_theta_pct"])
    capsys.readouterr()
    assert fits["rig"] == 100.0  # the noise-free run of the rig model, simulated on it: exact
    assert fits["default"] < 99.0  # tmm-fit lacks the rig's friction


def test_survey_refuses_a_bad_model_in_one_line(tmp_path, capsys):
    (tmp_path / "x.tsv").write_text("t\tv\ttheta\ta\n0\t0\t0\t0\n0.002\t0\t0\t0\n")
    assert main(["survey", str(tmp_path), "--model", "no-such-model"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert main(["survey", str(tmp_path), "--no-model", "--model", "rig"]) == 2
    assert "--model: not with --no-model" in capsys.readouterr().err


def test_run_step_serves_a_model_object_and_takes_the_step_time(tmp_path):
    from station.experiment import run_step
    from station.plant.model import load_model
    from station.runlog import read_log

    model = load_model().with_effects({"coulomb_friction": 5.0}, name="in-memory")
    rep = run_step(model=model, n_elements=3, seed=4, controller="p", amplitude=40.0, duration=0.2,
                   step_time=0.04, out=tmp_path / "m.tsv", figure=False, lean=False)
    assert rep.result.ok, rep.result.message
    meta = read_log(rep.log_path).meta
    assert meta["plant"]["model"]["name"] == "in-memory" and meta["plant"]["model"]["n_elements"] == 3
    assert meta["plant"]["model"]["effects"] == {"coulomb_friction": 5.0}
    assert meta["plant"]["options"]["seed"] == 4
    assert meta["reference"]["step_tick"] == 20
    with pytest.raises(Exception, match="step_time and step_tick"):
        run_step(step_time=0.04, step_tick=20, out=tmp_path / "x.tsv")


def test_run_step_says_when_a_compensator_file_limit_wins(tmp_path):
    from station.experiment import run_step
    from station.runlog import read_log

    path = tmp_path / "c.toml"
    path.write_text('limit = 150\n[gth]\nnum = [2.0]\nden = [1.0]\ndomain = "z"\n')
    with pytest.warns(UserWarning, match=r"--limit 100 is not used: .*c\.toml sets limit = 150 \(the file wins\)"):
        rep = run_step(controller=str(path), limit=100, duration=0.1, out=tmp_path / "r.tsv", figure=False,
                       lean=False)
    assert read_log(rep.log_path).meta["controller"]["limit"] == 150.0
    named = run_step(controller=str(path), duration=0.1, out_dir=tmp_path / "runs", figure=False, lean=False)
    assert named.log_path.name.startswith("step-c-")  # the file's stem names the log


def test_an_empty_value_is_refused_for_every_option_of_every_command(capsys):
    """A fuzzing round's traceback: `station step --out ''` (Path('') is the working folder, and
    its figure's name then fails). Every option and argument that takes a value, of every
    command, refuses '' in one line naming it, exit 2, before anything starts."""
    for name, parser in _subparsers().items():
        required = [a for a in parser._actions if not a.option_strings and a.nargs != 0]
        for action in parser._actions:
            if action.nargs == 0 or isinstance(action, argparse._HelpAction):
                continue
            if action.option_strings:  # the positionals given a stand-in, the option empty
                argv = [name, *(["x.txt"] * len(required)), action.option_strings[0], ""]
                shown = action.option_strings[0]
            else:
                argv = [name, ""]
                shown = action.metavar or action.dest
            with pytest.raises(SystemExit) as exc:
                build_parser().parse_args(argv)
            err = capsys.readouterr().err.strip()
            assert exc.value.code == 2 and len(err.splitlines()) == 1, (argv, err)
            assert f"argument {shown}: an empty value ''" in err, (argv, err)


def test_the_python_api_refuses_an_empty_out_too(tmp_path):
    from station.errors import StationError
    from station.experiment import run_step

    for kw, said in (({"out": ""}, "--out: an empty path"), ({"out_dir": " "}, "--out-dir: an empty path")):
        with pytest.raises(StationError, match=said):
            run_step(duration=0.1, **kw)
