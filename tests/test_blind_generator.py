"""The blind generator (tests/blind) against the station and against physics.

(a) With no effect its logs match the station's nominal model within 1 count (the only
place the generator meets station code). (b) The station's replay reproduces the logged
commands and detects alignment 1: the logs look like the rig's. (c) Each hidden effect
changes the logs the way its physics says, measured against a clean case of the same seed.
"""

from __future__ import annotations

import numpy as np
import pytest

from station.replay import replay
from station.runlog import read_log
from tests.blind import fem
from tests.blind.generator import RUNS, simulate_case, write_case

SEED = 3
CONTROLLERS = {"p_step": "p", "lead_step": "lead", "lead_accel_step": "lead-accel", "open_loop_pulses": "open-loop"}


@pytest.fixture(scope="module")
def clean_logs(tmp_path_factory):
    return write_case(tmp_path_factory.mktemp("clean"), {}, seed=SEED)


@pytest.fixture(scope="module")
def clean():
    return simulate_case({}, SEED)


def test_generator_imports_nothing_of_the_station_model():
    import ast
    from pathlib import Path

    for path in (Path(__file__).parent / "blind").glob("*.py"):
        tree = ast.parse(path.read_text())
        names = [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
        names += [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
        assert not [n for n in names if n.startswith("station")], path


def test_headers_copy_the_rig(clean_logs, rig_data):
    ours = dict(zip(RUNS, clean_logs))
    rig = {"p_step": "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
           "lead_step": "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
           "lead_accel_step": "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt",
           "open_loop_pulses": "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"}
    for run, name in rig.items():
        head = lambda p: [line for line in p.read_text().splitlines() if line.startswith("#")]  # noqa: E731
        assert head(ours[run]) == head(rig_data / name), run
        ref, gen = read_log(rig_data / name), read_log(ours[run])
        assert len(gen) == len(ref) == 1000
        np.testing.assert_array_equal(gen.data["u"], ref.data["u"], err_msg=run)


@pytest.mark.parametrize("run", RUNS)
def test_nominal_matches_station_model_within_one_count(clean_logs, run):
    report = replay(clean_logs[RUNS.index(run)])
    theta = report.log.data["theta"]
    assert report.prediction is not None
    assert np.max(np.abs(report.prediction["theta"] - theta)) <= 1.0
    assert report.fit_pct["theta"] > 98.0


def test_noise_free_nominal_equals_station_model(tmp_path):
    for path in write_case(tmp_path, {}, seed=0, accel_noise=0.0):
        report = replay(path)
        np.testing.assert_array_equal(report.prediction["theta"], report.log.data["theta"], err_msg=path.name)
        assert np.max(np.abs(report.prediction["a"] - report.log.data["a"])) <= 0.5 + 1e-9


@pytest.mark.parametrize("effects", [{}, {"coulomb_friction": 12.0, "delay": 2}, {"saturation": 90.0}])
def test_replay_reproduces_logged_v_with_alignment_1(tmp_path, effects):
    for run, path in zip(RUNS, write_case(tmp_path, effects, seed=5)):
        report = replay(path, model=False)
        assert report.controller == CONTROLLERS[run]
        assert report.max_abs_dv is not None and report.max_abs_dv < 1e-6, run
        if run != "open_loop_pulses":
            assert report.alignment == 1, run


def test_first_held_mode_is_the_sets_own():
    freq, zeta = fem.held_first_mode(fem.Params())
    assert freq == pytest.approx(2.55, abs=0.05)  # DESIGN.md: rig 2.52 Hz
    assert zeta == pytest.approx(0.0054, abs=0.0001)  # DESIGN.md: tmm-fit nominal 0.0054
    beta = fem.beta_for_damping(fem.Params(), 0.05)
    assert fem.held_first_mode(fem.Params(), beta=beta)[1] == pytest.approx(0.05, rel=1e-6)


def test_friction_and_backlash_converge_with_substeps():
    for effects in ({"coulomb_friction": 15.0}, {"backlash": 12.0}):
        coarse, fine = simulate_case(effects, 1, substeps=25), simulate_case(effects, 1, substeps=400)
        for run in RUNS:
            assert np.max(np.abs(coarse[run].theta - fine[run].theta)) <= 1.0, (effects, run)


def test_substepped_plant_without_effects_equals_exact_zoh():
    # a backlash of 1e-9 counts is never inside its gap: the sub-stepped path with nothing to do
    exact, stepped = simulate_case({}, 2), simulate_case({"backlash": 1e-9}, 2, substeps=20)
    for run in RUNS:  # round-off may flip one rounding at a half count in closed loop
        assert np.max(np.abs(exact[run].theta - stepped[run].theta)) <= 1.0, run
        assert np.mean(exact[run].theta != stepped[run].theta) < 0.05, run


# --- (c) each effect moves the logs the way its physics says ------------------------------

def _travel(case):
    """Encoder counts the open-loop +100 pulse moved the hub (theta before the -100 pulse)."""
    return case["open_loop_pulses"].theta[690]


def _first_motion(case):
    """First tick at which the open-loop pulse has moved the hub 2 counts."""
    return int(np.argmax(np.abs(case["open_loop_pulses"].theta) >= 2))


def test_coulomb_friction_shortens_the_pulse_and_leaves_a_p_step_short(clean):
    case = simulate_case({"coulomb_friction": 15.0}, SEED)
    assert _travel(case) < _travel(clean) - 10
    # stuck with |e| <= v_c/kp short of the target of 50
    assert 50 - 15.0 / 2 - 1 <= case["p_step"].theta[-1] < clean["p_step"].theta[-1]


def test_deadzone_scales_the_pulse_travel():
    clean, case = simulate_case({}, SEED), simulate_case({"deadzone": 20.0}, SEED)
    # torque k_tau (100 - 20): the travel (impulse / motor damping) scales by 0.8
    assert _travel(case) == pytest.approx(0.8 * _travel(clean), abs=2)


def test_saturation_caps_the_torque_not_the_logged_v(clean):
    case = simulate_case({"saturation": 80.0}, SEED)
    assert _travel(case) == pytest.approx(0.8 * _travel(clean), abs=2)
    np.testing.assert_array_equal(case["open_loop_pulses"].v, clean["open_loop_pulses"].v)
    assert case["lead_step"].v.max() == 200.0  # the controller still asks for its clamp
    assert case["lead_step"].theta[60] < clean["lead_step"].theta[60] - 10


def test_delay_postpones_the_first_motion(clean):
    case = simulate_case({"delay": 3}, SEED)
    assert _first_motion(case) == _first_motion(clean) + 3
    assert _travel(case) == _travel(clean)


def test_backlash_postpones_the_hub_and_frees_it_to_ring(clean):
    case = simulate_case({"backlash": 15.0}, SEED)
    assert _first_motion(case) > _first_motion(clean) + 2
    assert np.std(case["open_loop_pulses"].a[200:600]) > 1.5 * np.std(clean["open_loop_pulses"].a[200:600])


def test_beam_damping_shortens_the_ringing(clean):
    case = simulate_case({"beam_damping": 0.08}, SEED)
    ring = lambda c: np.std(c["open_loop_pulses"].a[200:690])  # noqa: E731
    assert ring(case) < 0.5 * ring(clean)


def test_accel_gain_scales_a_only(clean):
    case = simulate_case({"accel_gain": 2.0}, SEED)
    ratio = np.std(case["open_loop_pulses"].a[30:400]) / np.std(clean["open_loop_pulses"].a[30:400])
    assert ratio == pytest.approx(2.0, rel=0.1)
    np.testing.assert_array_equal(case["open_loop_pulses"].theta, clean["open_loop_pulses"].theta)


def test_param_act_k_scales_the_travel(clean):
    # travel = torque impulse / motor damping c_m, and c_m = act_p k_tau / (act_K |2 pi j + act_p|)
    case = simulate_case({"param:act_K": 2.0}, SEED)
    assert _travel(case) == pytest.approx(2 * _travel(clean), abs=3)


def test_param_j_base_slows_the_hub(clean):
    case = simulate_case({"param:J_base": 2.5}, SEED)
    assert _first_motion(case) > _first_motion(clean)
    assert abs(_travel(case) - _travel(clean)) <= 2  # inertia does not change the travel


def test_param_drive_c_damps_the_p_step(clean):
    more, less = simulate_case({"param:drive_c": 2.5}, SEED), simulate_case({"param:drive_c": 0.4}, SEED)
    assert more["p_step"].theta.max() < clean["p_step"].theta.max() < less["p_step"].theta.max()


def test_param_drive_k_changes_the_runs(clean):
    case = simulate_case({"param:drive_k": 2.5}, SEED)
    assert max(np.max(np.abs(case[r].theta - clean[r].theta)) for r in RUNS) >= 2
    assert abs(_travel(case) - _travel(clean)) <= 3  # a spring does not change the travel


def test_two_effects_at_once(clean):
    both = simulate_case({"deadzone": 20.0, "delay": 3}, SEED)
    assert _first_motion(both) >= _first_motion(clean) + 3
    assert _travel(both) == pytest.approx(0.8 * _travel(clean), abs=2)


def test_unknown_effect_is_refused(tmp_path):
    with pytest.raises(ValueError, match="friction"):
        write_case(tmp_path, {"friction": 3.0}, seed=0)
