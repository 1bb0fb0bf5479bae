"""A compensator file knows the model it was designed on: the [design] record's round trip and
hash, its refusals, and what `station step` does with it on the simulated rig (which model
runs, and the one line that says so)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from station.cli import main
from station.control.designs import DesignRecord, read_compensator_file
from station.design.space import DesignSpace
from station.design.tuning import design_record
from station.errors import StationError
from station.plant import load_model
from station.runsetup import design_model_note

VALUES = {"k0": 5.0, "z": 31.4159, "ratio": 4.0, "ga_gain": 1.0, "ga_freq": 1.0}


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _write(path: Path, record: DesignRecord | None) -> Path:
    path.write_text(DesignSpace("lead-accel").compensator_file(VALUES, path=path, design=record).to_toml())
    return path


def test_the_record_round_trips_with_the_models_sha256(tmp_path):
    rig = load_model("rig")
    record = DesignRecord.of("rig", rig.to_toml())
    assert record.model_sha256 == _sha(rig.to_toml()) and len(record.model_sha256) == 64
    back = read_compensator_file(_write(tmp_path / "C.toml", record))
    assert back.design == record and back.compensator().gth is not None
    assert read_compensator_file(_write(tmp_path / "old.toml", None)).design is None  # files without one still load
    assert record.matches(load_model("rig").to_toml()) and not record.matches(load_model("tmm-fit").to_toml())
    # one parameter changed is another model
    assert not record.matches(rig.with_effects({"coulomb_friction": 5.0}).to_toml())


def test_tune_records_a_name_a_relative_path_or_the_models_own_name(tmp_path):
    rig = load_model("rig")
    assert design_record("rig", rig, out=tmp_path / "C.toml") == DesignRecord("rig", _sha(rig.to_toml()))
    path = tmp_path / "models" / "m.toml"
    path.parent.mkdir()
    rig.save(path)
    rec = design_record(str(path), load_model(path), out=tmp_path / "out" / "C.toml")
    assert rec.model == "../models/m.toml" and rec.model_sha256 == _sha(load_model(path).to_toml())
    assert design_record(None, load_model("tmm-fit")).model == "tmm-fit"
    fitted = rig.with_effects({}, name="fitted")  # a Model object (the API), or a diagnosis's extended model
    assert design_record(fitted, fitted) == DesignRecord("fitted", _sha(fitted.to_toml()))


@pytest.mark.parametrize("table, words", [
    ('[design]\nmodel = "rig"\n', "[design].model_sha256: missing"),
    (f'[design]\nmodel_sha256 = "{"a" * 64}"\n', "[design].model: missing"),
    (f'[design]\nmodel = "rig"\nmodel_sha256 = "{"A" * 64}"\n', "64 lowercase hex digits"),
    (f'[design]\nmodel = "rig"\nmodel_sha256 = "{"a" * 63}"\n', "64 lowercase hex digits"),
    (f'[design]\nmodel = 3\nmodel_sha256 = "{"a" * 64}"\n', "[design].model: expected"),
    (f'[design]\nmodel = ""\nmodel_sha256 = "{"a" * 64}"\n', "[design].model: expected"),
    (f'[design]\nmodel = "rig"\nmodel_sha256 = "{"a" * 64}"\nwhen = 1\n', "[design].when: unknown field"),
    ('design = 3\n', "[design]: expected a table"),
    # a wrong model beside a missing digest: the model is said first (was "model_sha256: missing")
    ('[design]\nmodel = 5\n', "[design].model: expected a model's name"),
])
def test_a_bad_record_is_one_line_naming_the_field(tmp_path, table, words):
    path = tmp_path / "C.toml"
    text = _write(path, None).read_text()
    path.write_text(table + text if table.startswith("design") else text + "\n" + table)
    with pytest.raises(StationError) as err:
        read_compensator_file(path)
    assert words in str(err.value) and str(path) in str(err.value) and "\n" not in str(err.value)


@pytest.fixture
def designed(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return _write(tmp_path / "C.toml", DesignRecord.of("rig", load_model("rig").to_toml()))


def test_without_a_model_the_simulated_rig_runs_the_design_model(designed):
    choice = design_model_note("C.toml", None, "sim://")
    assert choice.model == "rig" and choice.note == "simulated rig: model rig, from C.toml's design record"
    other = design_model_note("C.toml", "tmm-fit", "sim://")
    assert other.model == "tmm-fit" and "designed on model 'rig'" in other.note and "another model" in other.note
    assert design_model_note("C.toml", "rig", "sim://") == ("rig", None)
    assert design_model_note("C.toml", None, "sim://?model=rig") == (None, None)  # the URL gives the model
    assert "another model" in design_model_note("C.toml", None, "sim://?model=tmm-fit").note
    assert design_model_note("C.toml", None, "/dev/ttyACM0") == (None, None)  # a real rig: nothing to say
    assert design_model_note("lead-accel", None, "sim://") == (None, None)
    assert "--elements 6" in design_model_note("C.toml", None, "sim://", 6).note


def test_a_design_model_file_runs_while_it_is_the_same(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "models").mkdir()
    model = load_model("rig").with_effects({"coulomb_friction": 9.0}, name="mine")
    model.save(tmp_path / "models" / "m.toml")
    (tmp_path / "ctl").mkdir()
    _write(tmp_path / "ctl" / "C.toml", DesignRecord.of("../models/m.toml", model.to_toml()))
    choice = design_model_note("ctl/C.toml", None, "sim://")
    assert Path(choice.model).resolve() == (tmp_path / "models" / "m.toml").resolve() and "from ctl/C.toml" in choice.note
    model.with_effects({"coulomb_friction": 10.0}).save(tmp_path / "models" / "m.toml")  # edited since
    changed = design_model_note("ctl/C.toml", None, "sim://")
    assert changed.model is None and "changed since" in changed.note
    (tmp_path / "models" / "m.toml").unlink()
    gone = design_model_note("ctl/C.toml", None, "sim://")
    assert gone.model is None and "not a built-in model or a model file here" in gone.note


def test_station_step_says_which_model_in_one_line(designed, capsys):
    assert main(["step", "--controller", "C.toml", "--amplitude", "200", "--quiet", "--out", "a.tsv",
                 "--json", "a.json"]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "design record" in line or "designed" in line]
    assert err == ["station: note: simulated rig: model rig, from C.toml's design record"]
    from station.runlog import read_log

    assert read_log("a.tsv").meta["plant"]["model"]["name"] == "rig"
    assert main(["step", "--controller", "C.toml", "--amplitude", "200", "--quiet", "--out", "b.tsv",
                 "--model", "tmm-fit"]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "designed" in line]
    assert len(err) == 1 and "'tmm-fit', another model" in err[0]
    assert read_log("b.tsv").meta["plant"]["model"]["name"] == "tmm-fit"
    json.loads(Path("a.json").read_text())  # the run's JSON as ever
