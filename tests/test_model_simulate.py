"""simulate() with a Model: effects of DESIGN.md's vocabulary, checked against hand
computations on the nominal linear plant and against refined sub-step grids."""

import dataclasses

import numpy as np
import pytest

from station.control import make_controller, pulse_reference, step_reference
from station.plant import DiscretePlant, load_params, simulate
from station.plant.model import Model, load_model
from station.plant.modes import with_beam_damping

N = 1000
CASES = {"p": 50.0, "lead": 100.0, "lead-accel": 200.0}


@pytest.fixture(scope="module")
def nominal():
    return load_model()


@pytest.mark.parametrize("kind", ["p", "lead", "lead-accel", "open-loop"])
@pytest.mark.parametrize("command", ["none", "round", "trunc"])
def test_model_without_effects_is_todays_simulation_exactly(nominal, kind, command):
    c = make_controller(kind)
    u = step_reference(CASES.get(kind, 40.0), N, at_tick=10)
    old = simulate(DiscretePlant(), c, u, alignment=1, command=command)
    new = simulate(nominal, c, u, alignment=1, command=command)
    for key in old.keys():
        np.testing.assert_array_equal(new[key], old[key], err_msg=key)


def _open(model, v, **kw):
    return simulate(model, None, np.zeros(len(v)), alignment=0, v_open=v, quantize=False, **kw)


def _pulses():
    v = np.zeros(600)
    v[20:120], v[300:400] = 100.4, -100.6
    v[450:500] = 7.0
    return v


def test_amplifier_effects_match_a_hand_computation(nominal):
    v = _pulses()
    # truncation (the device), then saturation at 90, dead-zone of 10, delay of 3 samples
    hand = np.trunc(v)
    hand = np.clip(hand, -90.0, 90.0)
    hand = np.where(np.abs(hand) > 10.0, hand - 10.0 * np.sign(hand), 0.0)
    hand = np.concatenate([np.zeros(3), hand[:-3]])
    want = _open(nominal, hand)
    model = nominal.with_effects({"saturation": 90.0, "deadzone": 10.0, "delay": 3})
    got = simulate(model, None, np.zeros(v.size), alignment=0, v_open=v, quantize=False, command="trunc")
    np.testing.assert_allclose(got["theta"], want["theta"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got["a"], want["a"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got["v"], v)  # v is the command as given, before the amplifier


@pytest.mark.parametrize("name, value, amp", [("saturation", 60.0, lambda v: np.clip(v, -60, 60)),
                                              ("deadzone", 25.0, lambda v: np.sign(v) * np.maximum(np.abs(v) - 25, 0)),
                                              ("delay", 5.0, lambda v: np.concatenate([np.zeros(5), v[:-5]]))])
def test_each_amplifier_effect_alone(nominal, name, value, amp):
    v = _pulses()
    got = _open(nominal.with_effects({name: value}), v)
    want = _open(nominal, amp(v))
    np.testing.assert_allclose(got["theta"], want["theta"], rtol=0, atol=1e-9)


def test_accel_gain_scales_a_only(nominal):
    v = _pulses()
    base, scaled = _open(nominal, v), _open(nominal.with_effects({"accel_gain": 1.7}), v)
    np.testing.assert_array_equal(scaled["theta"], base["theta"])
    np.testing.assert_allclose(scaled["a"], 1.7 * base["a"], rtol=1e-12, atol=1e-12)
    assert np.abs(base["a"]).max() > 5.0


def test_param_ratio_is_the_parameter_set_with_that_parameter_scaled(nominal):
    c, u = make_controller("lead-accel"), step_reference(200.0, N, at_tick=10)
    base = simulate(nominal, c, u)
    same = simulate(nominal.with_effects({"param:drive_c": 1.0}), c, u)
    doubled = simulate(nominal.with_effects({"param:drive_c": 2.0}), c, u)
    p2 = dataclasses.replace(load_params(), drive_c=2.0 * load_params().drive_c)
    direct = simulate(Model("drive_c x2", p2), c, u)
    for key in base.keys():
        np.testing.assert_array_equal(same[key], base[key])
        np.testing.assert_array_equal(doubled[key], direct[key])
    assert not np.array_equal(doubled["theta"], base["theta"])


def test_beam_damping_is_the_rayleigh_damped_set(nominal):
    c, u = make_controller("p"), step_reference(50.0, N, at_tick=10)
    got = simulate(nominal.with_effects({"beam_damping": 0.05}), c, u)
    want = simulate(DiscretePlant(with_beam_damping(load_params(), 0.05, 4)), c, u)
    np.testing.assert_array_equal(got["theta"], want["theta"])
    assert not np.array_equal(got["a"], simulate(nominal, c, u)["a"])


@pytest.mark.parametrize("effects", [{"coulomb_friction": 3.0}, {"coulomb_friction": 30.0}, {"backlash": 2.0},
                                     {"backlash": 20.0}, {"coulomb_friction": 10.0, "backlash": 10.0}])
@pytest.mark.parametrize("kind", ["p", "lead-accel", "open-loop"])
def test_friction_and_backlash_converge_as_the_sub_step_grid_is_refined(nominal, effects, kind):
    c = make_controller(kind)
    u = pulse_reference(100.0, N, 20, 50, return_tick=700) if kind == "open-loop" \
        else step_reference(CASES[kind], N, at_tick=10)
    model = nominal.with_effects(effects)
    runs = {m: simulate(model, c, u, command="trunc", quantize=False, substeps=m) for m in (10, 40, 160)}
    for m in (10, 40):
        assert np.abs(runs[m]["theta"] - runs[160]["theta"]).max() < 1.0, m
    # and the effect does something (a 2-count gap under lead + accel: about half a count)
    assert np.abs(runs[160]["theta"] - simulate(nominal, c, u, command="trunc", quantize=False)["theta"]).max() > 0.3


def test_friction_holds_a_motor_whose_command_is_below_the_static_level(nominal):
    v = np.full(500, 9.0)
    stuck = _open(nominal.with_effects({"coulomb_friction": 10.0}), v)
    assert np.abs(stuck["theta"]).max() < 1e-9 and np.abs(stuck["a"]).max() < 1e-9
    moving = _open(nominal.with_effects({"coulomb_friction": 8.0}), v)
    free = _open(nominal, v - 8.0)  # sliding one way: the friction is a constant -8 counts
    np.testing.assert_allclose(moving["theta"], free["theta"], atol=1e-6)


def test_friction_sticks_the_motor_after_a_pulse(nominal):
    v = np.zeros(1000)
    v[20:70] = 100.0

    def motor_speed(model):  # ω_motor (rad/s) after each sample, from the plant's own rows
        plant = model.plant()
        out = []
        for x in v:
            plant.advance(x)
            out.append((plant._form.co[2] @ plant.z).real)
        return np.abs(np.array(out))

    stuck = motor_speed(nominal.with_effects({"coulomb_friction": 15.0}))
    coasting = motor_speed(nominal.with_effects({"backlash": 1e-6}))  # no friction, same rows
    assert stuck[-300:].max() < 1e-12  # stick: the motor stands exactly still
    assert coasting[-300:].min() > 1e-5  # viscous damping alone only slows it


def test_backlash_delays_the_base_until_the_gap_is_closed(nominal):
    v = np.full(300, 60.0)
    free = _open(nominal, v)
    gap = _open(nominal.with_effects({"backlash": 20.0}), v)
    k_free = np.argmax(free["theta"] > 0.5)
    k_gap = np.argmax(gap["theta"] > 0.5)
    assert k_gap > k_free + 3
    # once in contact the base follows the motor 10 counts (half the gap) behind
    assert gap["theta"][-1] == pytest.approx(free["theta"][-1] - 10.0, abs=1.5)


class _Wrapped:
    """A controller object that is not a Compensator: step/reset only."""

    def __init__(self, inner):
        self.inner = inner

    def step(self, u, theta, a):
        return self.inner.step(u, theta, a)

    def reset(self):
        self.inner.reset()


@pytest.mark.parametrize("effects", [{}, {"coulomb_friction": 8.0, "delay": 2.0, "accel_gain": 1.3}])
def test_custom_controller_runs_in_python_with_the_same_timing(nominal, effects):
    model = nominal.with_effects(effects)
    c, u = make_controller("lead-accel"), step_reference(200.0, N, at_tick=10)
    compiled = simulate(model, c, u, command="round")
    python = simulate(model, _Wrapped(c), u, command="round")
    for key in ("theta", "a"):
        np.testing.assert_array_equal(python[key], compiled[key], err_msg=key)
    np.testing.assert_allclose(python["v"], compiled["v"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(python["theta_d_hat"], compiled["theta_d_hat"], rtol=0, atol=1e-9)


def test_object_without_step_and_reset_is_a_type_error(nominal):
    with pytest.raises(TypeError, match="step"):
        simulate(nominal, object(), np.zeros(10))
    with pytest.raises(TypeError):
        simulate(DiscretePlant(), lambda u, th, a: (u, u), np.zeros(10))


def _assert_plant_steps_like_simulate(model):
    """ModelPlant stepped tick by tick gives simulate()'s open-loop θ and a exactly."""
    v = np.round(_pulses())
    run = _open(model, v)
    plant = model.plant()
    rows = []
    for x in v:
        rows.append(plant.outputs())
        plant.advance(x)
    np.testing.assert_array_equal(np.array(rows), np.column_stack([run["theta"], run["a"]]))


def test_model_plant_steps_like_simulate(nominal):
    _assert_plant_steps_like_simulate(nominal.with_effects({"coulomb_friction": 6.0, "backlash": 4.0,
                                                            "saturation": 150.0, "deadzone": 3.0, "delay": 1.0,
                                                            "accel_gain": 0.8}))


# --- breakaway friction, viscous friction, amplifier offset (issue 17) -------------------

BREAKAWAY = [{"static_friction": 30.0, "coulomb_friction": 9.0, "stribeck_speed": 0.02},
             {"static_friction": 60.0, "stribeck_speed": 0.01},
             {"static_friction": 12.0, "coulomb_friction": 4.0, "stribeck_speed": 0.2}]


@pytest.mark.parametrize("effects", BREAKAWAY)
@pytest.mark.parametrize("kind", ["p", "lead-accel", "open-loop"])
def test_breakaway_friction_converges_as_the_sub_step_grid_is_refined(nominal, effects, kind):
    c = make_controller(kind)
    u = pulse_reference(100.0, N, 20, 50, return_tick=700) if kind == "open-loop" \
        else step_reference(CASES[kind], N, at_tick=10)
    model = nominal.with_effects(effects)
    grids = (10, 20, 40, 320)
    runs = {m: simulate(model, c, u, command="trunc", quantize=False, substeps=m)["theta"] for m in grids}
    for m, m2 in zip(grids[:2], grids[1:3]):  # doubling the sub-steps moves θ by under a count
        assert np.abs(runs[m] - runs[m2]).max() < 1.0, (m, m2)
    assert np.abs(runs[10] - runs[320]).max() < 1.0
    # and the breakaway level matters: plain Coulomb friction at the sliding level differs
    sliding = nominal.with_effects({"coulomb_friction": effects.get("coulomb_friction", 0.0)})
    plain = simulate(sliding, c, u, command="trunc", quantize=False, substeps=320)["theta"]
    assert np.abs(runs[320] - plain).max() > 0.5


@pytest.mark.parametrize("effects, start", [({"static_friction": 12.0, "coulomb_friction": 5.0}, 12.0),
                                            ({"static_friction": 12.0}, 12.0),
                                            ({"coulomb_friction": 5.0}, 5.0)])
def test_a_slow_ramp_starts_the_motor_when_the_command_crosses_the_breakaway_level(nominal, effects, start):
    v = 0.02 * np.arange(1000)  # 0 to 20 DAC counts in 2 s
    theta = _open(nominal.with_effects(effects), v)["theta"]
    k = int(np.argmax(np.abs(theta) > 1e-9))  # θ[k] is the first sample after a command moved it
    assert v[k - 1] > start >= v[k - 2]
    assert np.abs(theta[:k]).max() < 1e-12 and theta[k + 50] > 0.2


@pytest.mark.parametrize("kind", ["p", "lead-accel", "open-loop"])
def test_static_friction_at_the_coulomb_level_is_exactly_coulomb_friction(nominal, kind):
    c = make_controller(kind)
    u = pulse_reference(100.0, N, 20, 50, return_tick=700) if kind == "open-loop" \
        else step_reference(CASES[kind], N, at_tick=10)
    coulomb = simulate(nominal.with_effects({"coulomb_friction": 10.0}), c, u, command="trunc")
    equal = simulate(nominal.with_effects({"coulomb_friction": 10.0, "static_friction": 10.0,
                                           "stribeck_speed": 0.02}), c, u, command="trunc")
    for key in coulomb.keys():
        np.testing.assert_array_equal(equal[key], coulomb[key], err_msg=key)


@pytest.mark.parametrize("b", [1.0, 5.0, 20.0])
def test_viscous_friction_shortens_the_travel_after_a_pulse_by_c_m_over_c_m_plus_k_tau_b(nominal, b):
    # a torque pulse's impulse is all taken by the damping to ground, the motor's: the hub
    # comes to rest at H·k_tau·Σv·dt / (c_m + k_tau·b)
    p = nominal.params
    v = np.zeros(10000)
    v[20:70] = 100.0
    free = _open(nominal, v)["theta"][-1]
    damped = _open(nominal.with_effects({"viscous_friction": b}), v)["theta"][-1]
    assert damped / free == pytest.approx(p.c_m / (p.c_m + p.k_tau * b), rel=1e-5)
    assert damped == pytest.approx(p.H * p.k_tau * 100.0 * 50 * 0.002 / (p.c_m + p.k_tau * b), rel=1e-5)


@pytest.mark.parametrize("o", [3.0, -1.5])
def test_amp_offset_drives_the_free_motor_at_h_o_num_over_act_p(nominal, o):
    p = nominal.params
    theta = _open(nominal.with_effects({"amp_offset": o}), np.zeros(10000))["theta"]
    rate = (theta[9999] - theta[5000]) / (4999 * 0.002)  # after the start's slow transient
    assert rate == pytest.approx(p.H * o * p.act_num / p.act_p, rel=1e-6)


@pytest.mark.parametrize("kp, o", [(2.0, 4.0), (1.0, -3.0)])
def test_a_p_loop_rests_past_its_target_by_the_offset_over_kp(nominal, kp, o):
    u = step_reference(50.0, 10000, at_tick=10)
    run = simulate(nominal.with_effects({"amp_offset": o}), make_controller("p", kp=kp), u, quantize=False)
    assert run["theta"][-1] == pytest.approx(50.0 + o / kp, abs=1e-6)


def test_amp_offset_with_friction_may_stick_the_p_loop_short(nominal):
    # at rest the P loop's torque kp·e + o only has to stay below the breakaway level
    u = step_reference(50.0, 2000, at_tick=10)
    run = simulate(nominal.with_effects({"amp_offset": 4.0, "static_friction": 12.0, "coulomb_friction": 6.0}),
                   make_controller("p"), u, quantize=False)
    e = 50.0 - run["theta"][-1]
    assert abs(run["theta"][-1] - 52.0) > 1.0  # not where the loop without friction rests
    assert abs(2.0 * e + 4.0) <= 12.0  # the stuck motor's torque is within the breakaway level


def test_amplifier_order_offset_saturation_deadzone_delay(nominal):
    v = _pulses()
    o, sat, w, d = 7.0, 90.0, 10.0, 3

    def shape(x):  # DESIGN.md: quantization, offset, saturation, dead-zone
        x = np.clip(np.trunc(x) + o, -sat, sat)
        return np.where(np.abs(x) > w, x - w * np.sign(x), 0.0)

    hand = shape(v)
    hand = np.concatenate([np.full(d, shape(np.zeros(1))[0]), hand[:-d]])  # before the run the device sent 0
    want = _open(nominal, hand)
    model = nominal.with_effects({"amp_offset": o, "saturation": sat, "deadzone": w, "delay": d})
    got = simulate(model, None, np.zeros(v.size), alignment=0, v_open=v, quantize=False, command="trunc")
    np.testing.assert_allclose(got["theta"], want["theta"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got["a"], want["a"], rtol=0, atol=1e-9)
    assert hand[25] == 80.0 and hand[0] == 0.0  # 100 + 7 clamped at 90 less the dead-zone; 7 - 10 -> 0


NEW_EFFECTS = {"static_friction": 12.0, "coulomb_friction": 5.0, "stribeck_speed": 0.1, "viscous_friction": 3.0,
               "amp_offset": -3.0, "delay": 2.0}


def test_model_plant_steps_like_simulate_with_the_new_effects(nominal):
    _assert_plant_steps_like_simulate(nominal.with_effects(NEW_EFFECTS))
    # the delay line holds what the amplifier made of the device's 0 before the run: the offset
    plant = nominal.with_effects({"amp_offset": -3.0, "delay": 2.0}).plant()
    plant.advance(100.0)
    plant.reset()
    assert plant.outputs() == (0.0, 0.0)
    for _ in range(3):
        plant.advance(0.0)
    assert plant.outputs()[0] < 0.0


def test_custom_controller_runs_in_python_with_the_new_effects(nominal):
    model = nominal.with_effects(NEW_EFFECTS)
    c, u = make_controller("lead-accel"), step_reference(200.0, N, at_tick=10)
    compiled = simulate(model, c, u, command="round")
    python = simulate(model, _Wrapped(c), u, command="round")
    for key in ("theta", "a"):
        np.testing.assert_array_equal(python[key], compiled[key], err_msg=key)


@pytest.mark.parametrize("protocol", ["v1", "legacy"])
@pytest.mark.parametrize("kind", ["p", "lead-accel", "open-loop"])
def test_station_step_on_the_simulated_rig_equals_simulate_with_the_new_effects(tmp_path, nominal, kind, protocol):
    """sim://?model=FILE, noise-free: the logged θ and a are simulate()'s, sample for sample."""
    from station.experiment import run_step
    from station.runlog import read_log

    model = nominal.with_effects(NEW_EFFECTS, name="new-effects")
    path = tmp_path / "new.toml"
    model.save(path)
    log_path = tmp_path / "run.tsv"
    rep = run_step(port=f"sim://?noise=0&model={path}", protocol=protocol, controller=kind,
                   amplitude=60.0 if kind != "lead-accel" else 200.0, step_tick=10, duration=1.0,
                   out=log_path, lean=False, timeout=5.0)  # lockstep: a busy machine must not time it out
    assert rep.result.ok, rep.result.message
    log = read_log(log_path)
    d = log.data
    command = "round" if protocol == "v1" else "trunc"
    if kind == "open-loop":
        run = simulate(model, None, d["u"], alignment=1, v_open=d["v"], command=command)
    else:
        run = simulate(model, make_controller(kind), d["u"], alignment=1, command=command)
        np.testing.assert_allclose(run["v"], d["v"], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(run["theta"], d["theta"])
    np.testing.assert_array_equal(run["a"], d["a"])
    assert log.meta["plant"]["model"]["effects"] == NEW_EFFECTS
