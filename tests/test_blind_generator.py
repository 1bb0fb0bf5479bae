"""The blind generator (tests/blind) against the station and against physics.

(a) With no effect its logs match the station's nominal model within 1 count (the only
place the generator meets station code). (b) The station's replay reproduces the logged
commands and detects alignment 1: the logs look like the rig's. (c) Each hidden effect
changes the logs the way its physics says, measured against a clean case of the same seed;
(d) so do static friction (breakaway, Stribeck; converged in the sub-steps), viscous
friction and the amplifier's offset, and (e) the effects in no vocabulary leave their own
signature. (f) The cases draw their values deterministically, the old ones unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from station.replay import replay
from station.runlog import read_log
from tests.blind import cases, fem
from tests.blind.generator import RUNS, reference, simulate_case, write_case
from tests.blind.rig import Effects, simulate

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


def test_alignment_0_computes_each_command_from_its_own_rows_samples(tmp_path):
    """The rig's 2009 logs (DESIGN.md "Timing and log rows"): v[k] = C(u[k], θ[k], a[k]); the
    station's replay finds d = 0 and reproduces every v; the same case at alignment 1 differs."""
    effects = {"static_friction": 14.0, "coulomb_friction": 9.0, "amp_offset": 2.5}
    d0 = write_case(tmp_path / "d0", effects, seed=2, alignment=0)
    d1 = write_case(tmp_path / "d1", effects, seed=2)
    for run, p0, p1 in zip(RUNS, d0, d1):
        report = replay(p0, model=False)
        assert report.max_abs_dv is not None and report.max_abs_dv < 1e-6, run
        if run != "open_loop_pulses":
            assert report.alignment == 0, run
            assert not np.array_equal(read_log(p0).data["v"], read_log(p1).data["v"]), run
        else:  # open loop: v = u whatever the alignment
            np.testing.assert_array_equal(read_log(p0).data["v"], read_log(p1).data["v"])
    with pytest.raises(ValueError):
        simulate("p", reference("p_step"), {}, np.random.default_rng(0), alignment=2)


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


# --- (d) the later effects: static and viscous friction, amplifier offset -------------------

def _motor_still(run, k):
    """The motor did not move during tick k (true motor angle, not logged)."""
    return abs(run.motor[k + 1] - run.motor[k]) < 1e-9


def _ramp(effects):
    return simulate("open-loop", reference("open_loop_ramp"), effects, np.random.default_rng(0))


@pytest.mark.parametrize("v_c, v_s", [(10.0, 20.5), (0.0, 12.3), (10.0, None)])
def test_a_still_motor_breaks_away_at_v_s_not_v_c(v_c, v_s):
    # a slow ramp of v (one more count every 20 samples): the motor starts in the first tick
    # whose truncated command exceeds the breakaway level v_s (v_c for Coulomb friction alone)
    effects = {"coulomb_friction": v_c} if v_s is None else {"coulomb_friction": v_c, "static_friction": v_s}
    if not v_c:
        del effects["coulomb_friction"]
    run = _ramp(effects)
    level = v_c if v_s is None else v_s
    start = int(np.argmax(np.trunc(run.u) > level))
    assert all(_motor_still(run, k) for k in range(start))
    assert not _motor_still(run, start)
    assert np.all(run.theta[:start + 1] == 0)
    lag = int(np.argmax(run.theta >= 1)) - start
    if v_s is None:  # Coulomb: it creeps, pushed by the one count above v_c
        assert lag > 20
    else:  # it lurches: once sliding, the friction falls from v_s to v_c
        assert 0 < lag <= 15
        # Coulomb friction alone would have let go 100s of ticks earlier
        assert start - int(np.argmax(np.trunc(run.u) > v_c)) >= 200


def test_static_friction_stops_the_open_loop_motor_earlier_and_shorter():
    coulomb = simulate_case({"coulomb_friction": 10.0}, SEED)["open_loop_pulses"]
    static = simulate_case({"coulomb_friction": 10.0, "static_friction": 25.0}, SEED)["open_loop_pulses"]

    def last_motion(run):  # the motor's last moving tick between the two pulses
        return max(k for k in range(70, 690) if not _motor_still(run, k))

    # Coulomb alone: the creeping base drags the stuck motor on once the drive train pulls
    # harder than v_c; held up to v_s the motor stays where it first stops
    assert last_motion(static) < 100 < 150 < last_motion(coulomb)
    assert _travel({"open_loop_pulses": static}) <= _travel({"open_loop_pulses": coulomb}) - 5
    assert _first_motion({"open_loop_pulses": static}) == _first_motion({"open_loop_pulses": coulomb})


def test_static_friction_holds_a_p_step_with_more_than_v_c():
    # at rest the drive train carries no torque: the still motor holds the amplifier's k_tau v,
    # |v| <= v_s; Coulomb friction alone could hold no more than v_c
    for effects, lo, hi in (({"coulomb_friction": 10.0}, 0.0, 10.0),
                            ({"coulomb_friction": 10.0, "static_friction": 25.0}, 10.0, 25.0)):
        p = simulate_case(effects, SEED)["p_step"]
        assert np.ptp(p.theta[-250:]) == 0 and np.ptp(p.v[-250:]) == 0, effects
        assert lo < abs(p.v[-1]) <= hi or (lo == 0 and abs(p.v[-1]) <= hi), (effects, p.v[-1])
        assert abs(50 - p.theta[-1]) <= hi / 2 + 0.5  # |e| <= v_s / kp (kp = 2)


def test_static_friction_converges_with_substeps():
    # results change by at most a rounding flip of theta (the true angle by < 0.5 count) as the
    # sub-steps are doubled, also with a steep Stribeck curve (w_s = 0.02 rad/s)
    for effects in ({"coulomb_friction": 10.0, "static_friction": 25.0},
                    {"coulomb_friction": 3.0, "static_friction": 12.0, "stribeck_speed": 0.02}):
        runs = {s: simulate_case(effects, 1, substeps=s) for s in (50, 100, 200)}
        for coarse, fine in ((50, 100), (100, 200)):
            for run in RUNS:
                a, b = runs[coarse][run], runs[fine][run]
                assert np.max(np.abs(a.theta - b.theta)) <= 1.0, (effects, run, coarse)
                assert np.max(np.abs(a.theta_true - b.theta_true)) < 0.5, (effects, run, coarse)


def _damping_counts():
    """The actuator's own damping c_m / k_tau, DAC counts per rad/s: act_p / (act_K |2 pi j + act_p|)."""
    p = fem.Params()
    return p.act_p / (p.act_K * abs(complex(p.act_p, 2 * np.pi)))


def test_viscous_friction_scales_the_travel_and_the_peak_speed(clean):
    b = 3.0
    case = simulate_case({"viscous_friction": b}, SEED)
    c_m = _damping_counts()  # 14.8
    ratio = c_m / (c_m + b)
    # the travel after a pulse is its torque impulse / all damping to the ground
    ol, ol0 = case["open_loop_pulses"], clean["open_loop_pulses"]
    assert ol.theta_true[690] / ol0.theta_true[690] == pytest.approx(ratio, rel=0.002)
    assert _travel(case) == pytest.approx(ratio * _travel(clean), abs=1)
    # the 0.1 s pulse's peak speed: the whole arm as one rigid body of inertia J under
    # k_tau*100 with damping c reaches (k_tau*100/c)(1 - exp(-c T / J))
    p = fem.Params()
    j_m = fem.motor_inertia(p)[0]
    J = j_m + p.J_base + p.mu * p.L ** 3 / 3 + p.m_accel * p.L ** 2 + p.J_accel
    c0 = c_m * fem.K_TAU
    c1 = c0 / ratio
    rigid = ratio * (1 - np.exp(-c1 * 0.1 / J)) / (1 - np.exp(-c0 * 0.1 / J))
    peak = lambda run: np.max(np.diff(run.theta_true[:200]))  # noqa: E731
    assert peak(ol) / peak(ol0) == pytest.approx(rigid, abs=0.015)
    assert abs(rigid - ratio) > 0.03  # (the plain damping ratio would fail)


@pytest.mark.parametrize("offset", [6.0, -4.0])
def test_amp_offset_drifts_the_open_loop_hub(clean, offset):
    case = simulate_case({"amp_offset": offset}, SEED)
    ol, ol0 = case["open_loop_pulses"], clean["open_loop_pulses"]
    np.testing.assert_array_equal(ol.v, ol0.v)  # the log holds the computed command
    np.testing.assert_array_equal(ol.applied, np.trunc(ol0.v) + offset)
    # a constant torque k_tau*o drives every body at w = k_tau o / c_m = o num / act_p rad/s
    # once the drive train's slow transient (~1 s) is gone: 3 % faster still between the pulses
    p = fem.Params()
    num = p.act_K * abs(complex(p.act_p, 2 * np.pi))
    drift = fem.H * offset * num / p.act_p  # encoder counts per s (11 per DAC count)
    t = np.arange(3000) * 0.002
    slope = np.polyfit(t[200:690], ol.theta[200:690] - ol0.theta[200:690], 1)[0]
    assert slope == pytest.approx(1.03 * drift, rel=0.01)
    quiet = simulate("open-loop", np.zeros(3000), {"amp_offset": offset}, np.random.default_rng(0))
    assert np.polyfit(t[2000:], quiet.theta[2000:], 1)[0] == pytest.approx(drift, rel=0.002)


@pytest.mark.parametrize("offset", [6.0, -6.0])
def test_amp_offset_moves_where_a_p_loop_rests(offset):
    # no friction, no spring to ground: at rest the torque is zero, trunc(kp e) + o = 0, so the
    # hub rests o/kp past the target (an even o: a whole count, reached exactly)
    u = np.zeros(4000)
    u[50:] = 50.0
    run = simulate("p", u, {"amp_offset": offset}, np.random.default_rng(0))
    np.testing.assert_array_equal(run.theta[-1000:], 50.0 + offset / 2)
    np.testing.assert_array_equal(run.applied[-1000:], 0.0)


def test_amp_offset_acts_after_truncation_and_before_saturation_and_deadzone():
    rng = np.random.default_rng(0)
    u = reference("open_loop_pulses")
    sat = simulate("open-loop", u, {"amp_offset": 8.0, "saturation": 80.0}, rng)
    assert (sat.applied[0], sat.applied[30], sat.applied[720]) == (8.0, 80.0, -80.0)  # 108 -> 80, -92 -> -80
    dz = simulate("open-loop", u, {"amp_offset": 8.0, "deadzone": 10.0}, rng)
    assert (dz.applied[0], dz.applied[30], dz.applied[720]) == (0.0, 98.0, -82.0)
    assert np.all(dz.theta_true[:20] == 0.0)  # the offset stays inside the dead-zone: no drift
    late = simulate("open-loop", u, {"amp_offset": -3.0, "delay": 2}, rng)
    assert (late.applied[0], late.applied[21], late.applied[22]) == (-3.0, -3.0, 97.0)
    frac = simulate("open-loop", 0.7 + u, {"amp_offset": 0.5}, rng)
    assert (frac.applied[0], frac.applied[30]) == (0.5, 100.5)  # 0.7 and 100.7 truncated first


# --- (e) effects in no vocabulary -------------------------------------------------------------

def test_cyclic_encoder_error_follows_the_base_angle(clean):
    amp, period = 3.0, 96.0
    case = simulate_case({"oov:encoder_cyclic": amp, "oov:encoder_cyclic_period": period}, SEED)
    ol, ol0 = case["open_loop_pulses"], clean["open_loop_pulses"]
    np.testing.assert_array_equal(ol.theta_true, ol0.theta_true)  # open loop: the same motion
    error = ol.theta - ol0.theta

    def fit(p):  # least squares of the reading's error on sin, cos of 2 pi theta / p
        X = np.column_stack([np.sin(2 * np.pi * ol0.theta_true / p), np.cos(2 * np.pi * ol0.theta_true / p)])
        coef = np.linalg.lstsq(X, error, rcond=None)[0]
        return coef, np.sqrt(np.mean((error - X @ coef) ** 2))

    (s, c), rms = fit(period)
    assert s == pytest.approx(amp, abs=0.15) and abs(c) < 0.15
    assert rms < 0.5  # what is left is two roundings
    assert min(fit(period / 2)[1], fit(2 * period)[1]) > 1.0
    # the controller sees the error too: the closed loops move
    assert all(np.max(np.abs(case[r].theta - clean[r].theta)) >= 2 for r in ("p_step", "lead_step"))


def test_cogging_parks_the_motor_in_a_detent(clean):
    cycles = 16  # a detent every 1024 / 16 = 64 counts
    case = simulate_case({"oov:cogging": 10.0, "oov:cogging_cycles": cycles}, SEED)
    spacing = 1024 / cycles
    off = lambda m: abs(m - spacing * round(m / spacing))  # noqa: E731
    assert off(case["open_loop_pulses"].motor[690]) < 0.5
    assert off(clean["open_loop_pulses"].motor[690]) > 10  # the clean pulse stops elsewhere
    assert _travel(case) < _travel(clean) - 30


def test_position_spring_pulls_the_hub_back(clean):
    s = 0.1
    case = simulate_case({"oov:position_spring": s}, SEED)
    ol = case["open_loop_pulses"]
    assert ol.theta_true[690] < 0.25 * ol.theta_true[:690].max()  # crept back after the pulse
    assert ol.theta_true[690] < 0.35 * ol.motor[690]  # the spring stretches the drive train
    # a P loop rests where kp (u - theta) = s theta (the spring's torque): theta = kp u / (kp + s)
    u = np.zeros(4000)
    u[50:] = 50.0
    run = simulate("p", u, {"oov:position_spring": s}, np.random.default_rng(0))
    assert np.mean(run.theta[-2000:]) == pytest.approx(2 * 50 / (2 + s), abs=0.1)


def test_effects_outside_the_vocabulary_and_bad_values_are_refused():
    for bad in ({"oov:wobble": 1.0}, {"coulomb_friction": 10.0, "static_friction": 5.0},
                {"static_friction": 5.0, "stribeck_speed": 0.0}):
        with pytest.raises(ValueError):
            simulate("open-loop", np.zeros(3), bad, np.random.default_rng(0))


# --- (f) the cases ---------------------------------------------------------------------------

def test_cases_are_deterministic_and_keep_their_values():
    # the issue-8 cases' values (as first written) do not move
    assert cases.case_effects("coulomb_friction", 0) == {"coulomb_friction": pytest.approx(28.3805, abs=1e-4)}
    assert cases.case_effects("two", 1) == {"coulomb_friction": pytest.approx(9.1663, abs=1e-4),
                                            "beam_damping": pytest.approx(0.0471, abs=1e-4)}
    assert cases.case_effects("param:drive_c", 0) == {"param:drive_c": pytest.approx(0.4856, abs=1e-4)}
    offsets = []
    for seed in range(10):
        for case in cases.CASES:
            effects = cases.case_effects(case, seed)
            assert effects == cases.case_effects(case, seed)
            Effects.parse(effects)  # the generator takes every case
            for part in case.split("+"):  # a combination draws each part as it is drawn alone
                if part in cases.SETTING_MAGNITUDES:
                    assert effects[part] == cases.draw(part, seed)
                elif part not in ("clean", "two") and not part.startswith("held_offset"):  # drawn from the friction
                    single = cases.case_effects(part, seed)
                    assert {k: effects[k] for k in single} == single
        sf = cases.case_effects("static_friction", seed)
        assert 5 <= sf["static_friction"] <= 30
        assert 0.3 <= sf["coulomb_friction"] / sf["static_friction"] <= 0.7
        assert 1 <= cases.case_effects("viscous_friction", seed)["viscous_friction"] <= 5
        offsets.append(cases.case_effects("amp_offset", seed)["amp_offset"])
        cog = cases.case_effects("oov:cogging", seed)
        assert 5 <= cog["oov:cogging"] <= 15 and cog["oov:cogging_cycles"] in range(8, 25)
        enc = cases.case_effects("oov:encoder_cyclic", seed)
        assert 2 <= enc["oov:encoder_cyclic"] <= 4 and 64 <= enc["oov:encoder_cyclic_period"] <= 256
    assert all(1 <= abs(o) <= 8 for o in offsets) and min(offsets) < 0 < max(offsets)
    for seed in range(10):  # a breakaway over its sliding level, both judged: drawn apart from static_friction's
        bs = cases.case_effects("breakaway_sliding", seed)
        assert set(bs) == {"static_friction", "coulomb_friction"} and 8 <= bs["static_friction"] <= 30
        assert 0.3 <= bs["coulomb_friction"] / bs["static_friction"] <= 0.7
        assert bs != cases.case_effects("static_friction", seed)
        d0 = cases.case_effects("breakaway_sliding+amp_offset@d0", seed)
        assert d0 == {**bs, "amp_offset": cases.case_effects("amp_offset", seed)["amp_offset"]}
        held = cases.case_effects("breakaway_sliding+held_offset@d0", seed)
        assert {k: held[k] for k in bs} == bs and 0.2 <= abs(held["amp_offset"]) / bs["coulomb_friction"] <= 0.8
        offsets.append(held["amp_offset"])
    assert cases.case_alignment("breakaway_sliding+amp_offset@d0") == ("breakaway_sliding+amp_offset", 0)
    assert cases.case_alignment("breakaway_sliding") == ("breakaway_sliding", 1)
    assert min(offsets[-10:]) < 0 < max(offsets[-10:])
    with pytest.raises(ValueError):
        cases.case_effects("held_offset+breakaway_sliding", 0)
    with pytest.raises(ValueError):
        cases.case_effects("static_friction+coulomb_friction", 0)
    with pytest.raises(ValueError):
        cases.case_effects("friction", 0)


# --- (g) sensor and wiring faults ------------------------------------------------------------
# Noise-free runs of one seed with and without the fault: the reading rule (round half up)
# applied to the fault's own arithmetic on the clean run's true angle and acceleration.

NO_ACCEL_FEEDBACK = ("p_step", "lead_step", "open_loop_pulses")


@pytest.fixture(scope="module")
def quiet():
    return simulate_case({}, SEED, accel_noise=0.0)


@pytest.mark.parametrize("gain", [-1.0, -1.2, -0.5, -2.0, 1.7])
def test_a_reversed_accelerometer_reads_the_opposite_a_of_the_same_run(quiet, gain):
    case = simulate_case({"accel_gain": gain}, SEED, accel_noise=0.0)
    for run in NO_ACCEL_FEEDBACK:  # a does not feed back: the same motion
        np.testing.assert_array_equal(case[run].theta, quiet[run].theta, err_msg=run)
        a, a0 = case[run].a, quiet[run].a
        assert np.max(np.abs(a - gain * a0)) <= 0.5 + 0.5 * abs(gain), run  # both rounded once
        if gain == -1.0:  # round(-x) = -round(x) but at exact halves
            assert np.mean(a == -a0) > 0.99, run
        busy = np.abs(a0) > 3
        ls = float(np.dot(a0[busy], a[busy]) / np.dot(a0[busy], a0[busy]))
        assert ls == pytest.approx(gain, rel=0.05), run
        assert np.corrcoef(a, a0)[0, 1] * np.sign(gain) > 0.98, run
    # with the accelerometer in the loop the reversed feedback changes the motion itself
    assert not np.array_equal(case["lead_accel_step"].theta, quiet["lead_accel_step"].theta)


@pytest.mark.parametrize("offset, drift", [(4.0, 0.0), (0.0, -6.0), (-2.5, 3.0)])
def test_an_accelerometer_bias_and_drift_add_b_plus_r_t_to_a(quiet, offset, drift):
    case = simulate_case({"accel_offset": offset, "accel_drift": drift}, SEED, accel_noise=0.0)
    t = np.arange(len(quiet["p_step"].a)) * 0.002
    for run in NO_ACCEL_FEEDBACK:
        np.testing.assert_array_equal(case[run].theta, quiet[run].theta, err_msg=run)
        extra = case[run].a - quiet[run].a
        assert np.max(np.abs(extra - (offset + drift * t))) <= 1.0, run  # two roundings
        b, r = np.linalg.lstsq(np.column_stack([np.ones_like(t), t]), extra, rcond=None)[0]
        assert b == pytest.approx(offset, abs=0.1) and r == pytest.approx(drift, abs=0.1), run


def test_an_encoder_of_4096_counts_reads_four_times_the_angle(quiet):
    case = simulate_case({"encoder_scale": 4.0}, SEED, accel_noise=0.0)
    run = "open_loop_pulses"  # θ does not feed back: the same motion
    np.testing.assert_array_equal(case[run].theta_true, quiet[run].theta_true)
    assert np.max(np.abs(case[run].theta - 4 * quiet[run].theta)) <= 0.5 + 4 * 0.5
    assert np.max(np.abs(case[run].theta - 4 * case[run].theta_true)) <= 0.5
    assert np.max(np.abs(case[run].theta)) > 300
    for run in ("p_step", "lead_step", "lead_accel_step"):  # in the loop: its own motion, read x4
        assert np.max(np.abs(case[run].theta - 4 * case[run].theta_true)) <= 0.5, run
        assert not np.array_equal(case[run].theta_true, quiet[run].theta_true), run


def test_a_reversed_encoder_reads_minus_the_angle_and_runs_the_loops_away(quiet):
    case = simulate_case({"encoder_scale": -1.0}, SEED, accel_noise=0.0)
    run = "open_loop_pulses"
    assert np.mean(case[run].theta == -quiet[run].theta) > 0.99
    np.testing.assert_array_equal(case[run].a, quiet[run].a)
    for run in ("p_step", "lead_step"):  # positive feedback: the command clamps, the angle runs
        assert np.all(case[run].v[-100:] == 200.0), run
        assert case[run].theta_true[-1] > 1000 and case[run].theta[-1] == -case[run].theta_true[-1].round(), run


@pytest.mark.parametrize("effects", [{}, {"coulomb_friction": 10.0}, {"amp_offset": 4.0, "deadzone": 5.0}])
def test_a_reversed_motor_turns_the_amplifiers_output_around(effects):
    # torque -amp(v; o) = amp(-v; -o): every law of the plant is odd, so the reversed motor's
    # open-loop run is the mirrored command's with the amplifier's offset mirrored too
    u = reference("open_loop_pulses")
    rng = lambda: np.random.default_rng(0)  # noqa: E731
    mirrored = {**effects, "amp_offset": -effects.get("amp_offset", 0.0)}
    rev = simulate("open-loop", u, {**effects, "motor_polarity": -1.0}, rng(), accel_noise=0.0)
    mir = simulate("open-loop", -u, mirrored, rng(), accel_noise=0.0)
    np.testing.assert_allclose(rev.theta_true, mir.theta_true, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(rev.v, u)  # the log keeps the command sent
    straight = simulate("open-loop", u, effects, rng(), accel_noise=0.0)
    assert rev.theta[690] < -20 < 20 < straight.theta[690]


def test_a_reversed_motor_runs_the_closed_loops_away():
    case = simulate_case({"motor_polarity": -1.0}, SEED, accel_noise=0.0)
    for run in ("p_step", "lead_step", "lead_accel_step"):
        assert np.all(case[run].v[-100:] == 200.0) and case[run].theta[-1] < -1000, run


FAULTS = [{"accel_gain": -1.2, "accel_offset": 3.0, "accel_drift": -4.0},
          {"encoder_scale": 4.0, "param:drive_c": 1.5},
          {"motor_polarity": -1.0, "encoder_scale": -1.0, "amp_offset": 3.0},
          {"motor_polarity": -1.0}]


@pytest.mark.parametrize("effects", FAULTS)
def test_the_station_model_with_the_same_faults_predicts_the_generators_logs(tmp_path, effects):
    # two implementations written apart (the generator from DESIGN.md, the station's plant)
    # agree on the faults' meaning: θ exactly, a within its rounding, runs away included
    from station.plant.model import load_model

    path = tmp_path / "faults.toml"
    load_model().with_effects(effects, name="faults").save(path)
    for log in write_case(tmp_path / "logs", effects, seed=0, accel_noise=0.0):
        report = replay(log, model=path)
        theta, a = report.log.data["theta"], report.log.data["a"]
        assert np.mean(report.prediction["theta"] == theta) > 0.99, log.name
        assert np.max(np.abs(report.prediction["theta"] - theta)) <= 1.0, log.name
        assert np.max(np.abs(report.prediction["a"] - a)) <= 1.0, log.name


def test_sensor_fault_cases_draw_in_their_ranges_and_both_signs():
    gains, offsets, drifts = [], [], []
    for seed in range(20):
        gains.append(cases.case_effects("accel_reversed", seed)["accel_gain"])
        offsets.append(cases.case_effects("accel_offset", seed)["accel_offset"])
        drifts.append(cases.case_effects("accel_drift", seed)["accel_drift"])
        assert cases.case_effects("encoder_4096", seed) == {"encoder_scale": 4.0}
        assert cases.case_effects("encoder_reversed", seed) == {"encoder_scale": -1.0}
        assert cases.case_effects("motor_reversed+coulomb_friction", seed) == {
            "motor_polarity": -1.0, "coulomb_friction": cases.draw("coulomb_friction", seed)}
    assert all(-2.0 <= g <= -0.5 for g in gains) and min(gains) < -1.2 < max(gains)
    assert all(1.5 <= abs(o) <= 10 for o in offsets) and min(offsets) < 0 < max(offsets)
    assert all(1.0 <= abs(d) <= 8 for d in drifts) and min(drifts) < 0 < max(drifts)
    assert set(cases.SENSOR_PAIRS) <= set(cases.CASES) and set(cases.SENSOR_CASES) <= set(cases.CASES)
    for pair in cases.SENSOR_PAIRS:  # each fault beside a physical effect of the vocabulary
        fault, physical = pair.split("+")
        assert fault in cases.SENSOR_CASES and physical in {**cases.MAGNITUDES, **cases.NEW_MAGNITUDES}
    with pytest.raises(ValueError):
        cases.case_effects("accel_reversed+accel_gain", 0)  # the same effect twice
    for bad in ({"motor_polarity": 0.5}, {"encoder_scale": 0.0}, {"accel_gain": 0.0}):
        with pytest.raises(ValueError):
            simulate("open-loop", np.zeros(3), bad, np.random.default_rng(0))
