"""One model everywhere: the simulated rig (sim://?model=, station step --model), replay,
compare and the log header run the same Model, effects included."""

import argparse

import numpy as np
import pytest

from station.errors import StationError
from station.plant.model import load_model
from station.protocol import PROTOCOLS
from station.replay import replay
from station.runlog import read_log

EFFECTS = {"coulomb_friction": 6.0, "backlash": 4.0, "deadzone": 3.0, "saturation": 150.0, "delay": 1.0,
           "accel_gain": 0.8, "param:drive_c": 1.5}


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("models") / "effects.toml"
    load_model().with_effects(EFFECTS, name="with-effects").save(path)
    return path


@pytest.mark.parametrize("protocol", PROTOCOLS)
@pytest.mark.parametrize("kind", ["p", "lead-accel", "open-loop"])
def test_loop_and_simulated_device_equal_simulate_for_a_model_with_effects(tmp_path, model_file, kind, protocol):
    """Noise-free simulated rig with a model's effects: the logged run is the model's
    prediction exactly (the device steps the same ModelPlant that simulate() runs)."""
    from station.experiment import run_step

    log_path = tmp_path / "run.tsv"
    rep = run_step(port=f"sim://?noise=0&model={model_file}", protocol=protocol, controller=kind,
                   amplitude=60.0 if kind != "lead-accel" else 200.0, step_tick=10, duration=1.0,
                   out=log_path, lean=False)
    assert rep.result.ok, rep.result.message
    r = replay(log_path, model=model_file)
    nominal = replay(log_path, model=True)
    np.testing.assert_array_equal(r.prediction["theta"], r.log.data["theta"])
    np.testing.assert_array_equal(r.prediction["a"], r.log.data["a"])
    assert not np.array_equal(nominal.prediction["theta"], r.log.data["theta"])  # the effects matter
    header = read_log(log_path).meta["plant"]["model"]
    assert header["name"] == "with-effects" and header["effects"] == EFFECTS and header["params"] == "tmm-fit"


def test_step_command_model_options_build_the_sim_url():
    from station.runsetup import sim_port

    assert sim_port("sim://", None, None, None) == "sim://"
    assert sim_port("sim://", "rig.toml", 6, 3) == "sim://?model=rig.toml&elements=6&seed=3"
    assert sim_port("sim://?noise=0", "tmm-fit") == "sim://?noise=0&model=tmm-fit"
    with pytest.raises(StationError, match="--model: only for the simulated rig"):
        sim_port("/dev/ttyACM0", "tmm-fit")


def test_sim_url_model_sets_the_element_count_unless_given(model_file, tmp_path):
    from station.sim.protocol_sim import parse_url

    path = tmp_path / "six.toml"
    path.write_text('params = "tmm-fit"\nn_elements = 6\n')
    assert parse_url(f"sim://?model={path}")["elements"] == 6
    assert parse_url(f"sim://?model={path}&elements=2")["elements"] == 2


def _run(module, argv):
    parser = argparse.ArgumentParser()
    module.configure(parser)
    return module.run(parser.parse_args(argv))


def test_compare_and_replay_commands_take_a_model(rig_data, model_file, tmp_path, capsys):
    from station.commands import compare, replay as replay_cmd

    log = rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    assert _run(compare, [str(log), "--model", str(model_file), "--out-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "with-effects" in out and "coulomb_friction = 6" in out
    assert _run(replay_cmd, [str(log), "--model", str(model_file)]) == 0
    assert "model: with-effects" in capsys.readouterr().out
    with pytest.raises(StationError, match="model file not found"):
        _run(compare, [str(log), "--model", str(tmp_path / "none.toml"), "--out-dir", str(tmp_path), "--force"])


def test_modes_command_uses_the_model_linear_part(tmp_path, capsys):
    from station.commands import modes

    path = tmp_path / "stiff.toml"
    load_model().with_effects({"param:clamp_k": 4.0}, name="stiff").save(path)
    assert _run(modes, ["--elements", "4", "--model", str(path)]) == 0
    stiff = capsys.readouterr().out
    assert _run(modes, ["--elements", "4"]) == 0
    assert stiff != capsys.readouterr().out and "param:clamp_k = 4" in stiff
