"""Lab conveniences: station.toml (working folder or ~/.config/station), a missing port's
error, a wrong protocol's hint, a custom Python controller's log replayed for the model."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from station.cli import main
from station.experiment import run_step
from station.replay import replay
from station.runlog import read_log


def test_config_in_the_working_folder_sets_defaults_and_options_win(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "none"))
    (tmp_path / "station.toml").write_text('limit = 150\nsoft_limit = 900\nout_dir = "lab"\ntimeout = 0.2\n')
    assert main(["step", "--duration", "0.1", "--quiet"]) == 0
    (log,) = (tmp_path / "lab").glob("step-lead-*.tsv")
    meta = read_log(log).meta
    assert (meta["limit"], meta["soft_limit"], meta["limits"]["timeout"]) == (150.0, 900.0, 0.2)
    assert "settings from station.toml" in capsys.readouterr().err
    assert main(["step", "--duration", "0.1", "--quiet", "--limit", "120", "--out", "x.tsv"]) == 0
    assert read_log(tmp_path / "x.tsv").meta["limit"] == 120.0  # the option wins


def test_user_config_and_its_errors(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "cfg"))
    user = tmp_path / "cfg" / "station" / "station.toml"
    user.parent.mkdir(parents=True)
    user.write_text("soft_limit = -5\n")
    assert main(["step", "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert f"{user}: line 1: soft_limit = -5: -5 is out of range" in err and len(err.strip().splitlines()) == 1
    user.write_text('protocol = "v2"\n')
    assert main(["step"]) == 2 and "protocol = 'v2': expected one of v1, legacy" in capsys.readouterr().err
    user.write_text("colour = 1\n")
    assert main(["step"]) == 2 and "colour: unknown setting" in capsys.readouterr().err
    assert list(tmp_path.glob("runs")) == []  # nothing started
    assert main(["ports"]) == 0  # other commands are not held up by the step's config


def test_missing_port_names_it_once_and_suggests_station_ports(tmp_path, capsys):
    assert main(["step", "--port", "/dev/ttyNOPE7", "--out", str(tmp_path / "r.tsv")]) == 2
    err = capsys.readouterr().err
    assert err.count("/dev/ttyNOPE7") == 1 and "`station ports`" in err
    assert not (tmp_path / "r.tsv").exists()


def test_wrong_protocol_error_suggests_the_other(tmp_path, capsys):
    assert main(["step", "--port", "sim://?protocol=legacy", "--protocol", "v1", "--timeout", "0.2",
                 "--out", str(tmp_path / "r.tsv")]) == 2
    assert "(try --protocol legacy)" in capsys.readouterr().err


class BangBang:
    """A custom Python controller: ±60 counts toward the reference (not linear, not in any header)."""

    spec = {"kind": "custom", "name": "bang-bang"}

    def reset(self):
        pass

    def step(self, u, theta, a):
        return (60.0 if theta < u else -60.0), u


def test_custom_python_controller_log_is_replayed_for_the_model_only(tmp_path):
    report = run_step(controller=BangBang(), amplitude=50, duration=0.5, out=tmp_path / "c.tsv", figure=False)
    assert report.result.ok
    rep = replay(report.log_path)
    assert rep.controller is None and rep.max_abs_dv is None
    assert any("custom Python controller (bang-bang)" in n for n in rep.notes)
    assert rep.fit_pct["theta"] > 99.0  # the simulated rig is the model: the logged v reproduces θ
    j = rep.to_json()
    assert json.loads(json.dumps(j))["outcome"]["reason"] == "completed"
    assert np.isfinite(read_log(report.log_path).data["v"]).all()


def test_identify_runs_its_experiments_with_the_folders_station_toml(tmp_path, monkeypatch, capsys):
    """station identify takes station.toml's bounds as station step does (it ran with
    200 / 2048 / 40 beside a file that said 50 / 300 / 5), and its experiments' folder goes where
    every command's made-up names go: station.toml's out_dir (docs/logs.md, one rule)."""
    from station.diagnosis.identify import loop

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "none"))
    (tmp_path / "station.toml").write_text('soft_limit = 300\nlimit = 50\nmax_step = 5\nmax_lag = 40\n'
                                           'out_dir = "lab"\n')
    seen = {}

    def fake_run_step(**kw):
        seen.update(kw)
        raise SystemExit(99)  # one experiment is enough to see what it was given

    monkeypatch.setattr(loop, "run_step", fake_run_step)
    try:
        main(["identify", "--quiet"])
    except SystemExit as exc:
        assert exc.code == 99
    assert (seen["limit"], seen["soft_limit"], seen["limits"].max_step, seen["limits"].max_lag) == (50.0, 300.0, 5.0,
                                                                                                   0.04)
    assert Path(seen["out"]).parent.parent == Path("lab")  # lab/identify-<UTC time>/NN-....tsv
    assert "settings from station.toml" in capsys.readouterr().err
