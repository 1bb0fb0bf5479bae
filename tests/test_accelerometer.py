"""The accelerometer: a channel that reads nothing, and its mass on the beam or off it
(station.logged.accelerometer, the ``accel_mounted`` configuration of the model).

Independent truth: the rig's own logs (the 28 Jan 2014 sweep run without the accelerometer,
the sweeps run with it), the blind generator's own FEM (tests/blind/fem: the hub-held first
mode without the tip mass) and its runs with the accelerometer taken off the beam, or left on
it unplugged (tests/blind/generator.write_sweep; never station.plant).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from station.errors import StationError
from station.logged import LoggedRun
from station.logged.accelerometer import MOUNTED_CLAIM, decide_mounting, nominal_antiresonances
from station.logged.audit import ACCEL_CLAIM
from station.plant.model import load_model
from station.plant.modes import modal_summary
from tests.blind import cases
from tests.blind.fem import Params, held_first_mode
from tests.blind.generator import SWEEP_N, reference, write_case, write_sweep
from tests.blind.rig import simulate

WITHOUT = "without_accel_01_28_14_test_2.txt"
SWEEPS_WITH = ["swept_sine_kp_1_amp_50.txt",
               "2009/swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
               "2009/swept_sine_no_sat_amp=50_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
               "2009/swept_sine_no_sat_amp=75_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt"]
STEPS = ["SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
         "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"]


# --- the model without the accelerometer ------------------------------------------------------

def test_accel_mounted_0_is_the_beam_without_its_tip_mass_as_the_blind_fem_has_it():
    on, off = load_model("tmm-fit"), load_model("tmm-fit").with_effects({"accel_mounted": 0.0})
    for model, fem in ((on, Params()), (off, Params(m_accel=0.0, J_accel=0.0))):
        f_station = modal_summary(model.linear_params(), 4, 40.0).antiresonances_hz[0]
        assert f_station == pytest.approx(held_first_mode(fem, 4)[0], rel=1e-3)
    assert nominal_antiresonances() == pytest.approx((2.550, 3.004), abs=1e-3)
    # a param:m_accel ratio cannot bring the mass back on a beam that has none
    both = off.with_effects({"param:m_accel": 3.0})
    assert both.linear_params().m_accel == 0.0 and both.linear_params().J_accel == 0.0


def test_a_model_file_holds_the_configuration_and_refuses_anything_but_0_or_1(tmp_path):
    model = load_model().with_effects({"accel_mounted": 0.0, "coulomb_friction": 5.0}, name="no-accel")
    model.save(tmp_path / "m.toml")
    assert load_model(tmp_path / "m.toml") == model
    for bad in ("0.5", "-1", "2"):
        (tmp_path / "bad.toml").write_text(f'[effects]\naccel_mounted = {bad}\n')
        with pytest.raises(StationError, match=r"accel_mounted.*out of range 0 or 1"):
            load_model(tmp_path / "bad.toml")
    # the neutral value is the model as before: files without the key read as they did
    assert load_model().with_effects({"accel_mounted": 1.0}) == load_model()


# --- the rig's logs ---------------------------------------------------------------------------

def test_the_28_jan_sweep_ran_without_the_accelerometer_and_is_simulated_so(rig_data):
    run = LoggedRun.from_path(rig_data / WITHOUT)
    m = run.mounting
    assert m.mounted is False and 3.1 <= m.measured_hz <= 3.35
    assert m.claim.verdict == "contradicted" and m.claim.claim == "columns"
    assert m.claim.data.startswith("no accelerometer on the beam: θ/v's first antiresonance 3.")
    assert m.claim.data.endswith("the model's 2.55 Hz with its mass, 3.00 Hz without")
    assert m.claim.line in run.audit_lines and m.claim.to_json() in run.audit.to_json()
    model = load_model("rig")
    assert run.model_for(model) == model.with_effects({"accel_mounted": 0.0})
    sim = run.simulate(model)
    assert "without the accelerometer's mass" in sim.how
    # the same as simulating the beam without it by hand; and better than with it
    by_hand = run.log
    from station.logged.simulate import simulate_log
    alone = simulate_log(by_hand, run.controller, run.alignment, model.with_effects({"accel_mounted": 0.0}))
    with_mass = simulate_log(by_hand, run.controller, run.alignment, model)
    assert sim.fit_pct["theta"] == alone.fit_pct["theta"] > with_mass.fit_pct["theta"] + 5.0


@pytest.mark.parametrize("name", SWEEPS_WITH)
def test_every_sweep_with_the_accelerometer_puts_its_mass_on_the_beam(rig_data, name):
    run = LoggedRun.from_path(rig_data / name)
    assert run.audit.accel_is_tip and run.mounting.mounted is True and run.mounting.claim is None
    d = run.data  # asked anyway, the data say "on"
    forced = decide_mounting(d["v"], d["theta"], run.dt)
    assert forced.mounted is True and 2.4 <= forced.measured_hz <= 2.7 and forced.claim.verdict == "confirmed"


@pytest.mark.parametrize("name", STEPS)
def test_a_short_run_leaves_the_question_unchecked(rig_data, name):
    run = LoggedRun.from_path(rig_data / name)
    d = run.data
    m = decide_mounting(d["v"], d["theta"], run.dt)
    assert m.mounted is None and m.claim.verdict == "unchecked" and "too short" in m.claim.evidence
    assert run.model_for(load_model()) == load_model()


# --- blind: off the beam, unplugged on it, read -----------------------------------------------

def _sweep(tmp_path, effects, seed):
    return LoggedRun.from_path(write_sweep(tmp_path / f"s{seed}_{len(effects)}", effects, seed))


@pytest.mark.parametrize("physical", [{}, {"coulomb_friction": 12.0}, {"param:drive_c": 2.2},
                                      {"viscous_friction": 3.0, "beam_damping": 0.02}])
@pytest.mark.parametrize("seed", [0, 1])
def test_blind_sweeps_off_unplugged_and_read_are_told_apart(tmp_path, physical, seed):
    setup = cases.sweep_setup("accel_off", seed)
    off = _sweep(tmp_path, {**physical, **setup}, seed)
    assert not off.audit.accel_is_tip and off.mounting.mounted is False
    assert [c.header for c in off.audit.contradicted] == [ACCEL_CLAIM, MOUNTED_CLAIM], off.audit_lines
    unplugged = _sweep(tmp_path, {**physical, "accel_connected": 0.0, "accel_offset": setup["accel_offset"]}, seed)
    assert not unplugged.audit.accel_is_tip and unplugged.mounting.mounted is True  # never "off"
    read = _sweep(tmp_path, physical, seed)
    assert read.audit.accel_is_tip and read.mounting.mounted is True and read.mounting.claim is None


def test_a_channel_is_silent_only_where_the_tip_moved(tmp_path):
    # the four 2 s runs, read: none silent; the same runs unplugged: every closed loop's a is
    paths = write_case(tmp_path / "read", {"coulomb_friction": 25.0}, 3)
    assert all(LoggedRun.from_path(p).audit.accel_is_tip for p in paths)
    paths = write_case(tmp_path / "dead", {"accel_connected": 0.0, "accel_offset": 12.0}, 3)
    assert [LoggedRun.from_path(p).audit.accel_is_tip for p in paths] == [False] * 4
    for p in paths:  # too short to tell its mass: unchecked, simulated with it
        m = LoggedRun.from_path(p).mounting
        assert m.mounted is None and m.claim.verdict == "unchecked"


def test_a_slow_ramp_with_a_still_accelerometer_says_nothing(tmp_path):
    # the tip hardly accelerates: a's silence is no evidence (the model's a is as small)
    from tests.blind.generator import format_run

    u = reference("open_loop_ramp", 2000)
    sim = simulate("open-loop", u, {"coulomb_friction": 6.0}, np.random.default_rng(1))
    path = tmp_path / "ramp_SLFR_RTP_OL_Test.txt"
    path.write_text(format_run("open_loop_pulses", sim))
    run = LoggedRun.from_path(path)
    assert run.audit.accel_is_tip and run.mounting.claim is None


def test_the_sweep_is_the_rigs_2014_sweep(rig_data):
    rig = LoggedRun.from_path(rig_data / WITHOUT).data["u"]
    ours = reference("p_sweep", SWEEP_N)
    assert ours.size == rig.size and np.max(np.abs(ours - rig)) < 1e-6 * 50


@pytest.mark.slow
def test_diagnose_does_not_take_a_missing_mass_for_beam_damping(tmp_path):
    seed = 2
    hidden = cases.case_effects("accel_off+coulomb_friction", seed)
    paths = write_case(tmp_path, hidden, seed)
    paths.append(write_sweep(tmp_path, {**hidden, **cases.sweep_setup("accel_off", seed)}, seed))
    out = subprocess.run([sys.executable, "-m", "station", "diagnose", *map(str, paths), "--json",
                          str(tmp_path / "d.json")], capture_output=True, text=True, timeout=1800)
    assert out.returncode == 0, out.stderr[-2000:]
    assert any(MOUNTED_CLAIM in x and "no accelerometer on the beam" in x for x in out.stdout.splitlines()[:3])
    d = json.loads((tmp_path / "d.json").read_text())
    assert not {"beam_damping", "param:m_accel", "param:J_accel"} & set(d["causes"]), d["causes"]
    assert d["causes"][0] == "coulomb_friction"
    found = dict(d["extended_model"]["effects"])["coulomb_friction"]
    assert math.isclose(found, hidden["coulomb_friction"], rel_tol=0.25)
