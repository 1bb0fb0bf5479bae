"""The sensor and wiring faults of DESIGN.md's vocabulary in the plant: accel_gain (either
sign), accel_offset, accel_drift, encoder_scale (either sign), motor_polarity.

Checked against independent truth: hand computations on the nominal run, the mirror
symmetry of the plant (every torque and friction law is odd, so a reversed motor read
through a reversed encoder is the plant seen through a reversed accelerometer, to the
last bit), the closed loop's scaling law, and the model file's round trip.
"""

import numpy as np
import pytest

from station.control import make_controller, step_reference
from station.errors import StationError
from station.plant import simulate
from station.plant.effects import EFFECTS, SENSOR_FAULTS, check_effects
from station.plant.model import load_model

N = 800
DT = 0.002


@pytest.fixture(scope="module")
def nominal():
    return load_model()


def _pulses(n=N):
    v = np.zeros(n)
    v[20:120], v[300:400] = 100.4, -100.6
    return v


def _open(model, v, **kw):
    return simulate(model, None, np.zeros(len(v)), alignment=0, v_open=v, quantize=False, **kw)


# --- the vocabulary --------------------------------------------------------------------

def test_the_faults_are_in_the_vocabulary_with_design_units_and_neutral_values():
    assert set(SENSOR_FAULTS) == {"accel_gain", "accel_offset", "accel_drift", "encoder_scale", "motor_polarity"}
    assert EFFECTS["accel_offset"].unit == "accelerometer counts" and EFFECTS["accel_offset"].neutral == 0.0
    assert EFFECTS["accel_drift"].unit == "accelerometer counts per s" and EFFECTS["accel_drift"].neutral == 0.0
    assert EFFECTS["encoder_scale"].unit == "1" and EFFECTS["encoder_scale"].neutral == 1.0
    assert EFFECTS["motor_polarity"].unit == "1" and EFFECTS["motor_polarity"].neutral == 1.0


@pytest.mark.parametrize("name, good, bad", [
    # a model holds what the data may decide (the search spans 0.3..3, ±30 and ±20: below)
    ("accel_gain", [-3.0, -1.2, -0.3, 0.3, 1.0, 2.5, 3.0, 0.01, -6.0, 100.0], [0.0, 0.0099, -0.0099, 101.0, -101.0]),
    ("encoder_scale", [4.0, -1.0, -4.0, 0.25, 16.0, -0.25, 1.0], [0.0, 0.2, -0.2, 17.0, -17.0]),
    ("motor_polarity", [1.0, -1.0], [0.0, 0.5, -0.5, 2.0, -2.0, -0.999]),
    # the protocol's SAMPLE accel field is an i16: an unzeroed channel reads anywhere in it
    ("accel_offset", [-32768.0, -30.0, -2.5, 0.0, 7.0, 30.0, 512.0, 32767.0], [-32769.0, 32767.5]),
    ("accel_drift", [-32768.0, -20.0, -0.5, 0.0, 3.0, 20.0, 30.0, 32767.0], [-32769.0, 32768.0]),
])
def test_ranges_either_sign_and_never_through_zero(name, good, bad):
    for x in good:
        assert check_effects({name: x}) == {name: x}
    for x in bad:
        with pytest.raises(StationError, match=f"'{name}' = .* out of range") as info:
            check_effects({name: x}, "m.toml")
        assert "\n" not in str(info.value) and str(info.value).startswith("m.toml: ")
        if EFFECTS[name].signed:
            assert "±" in str(info.value)


def test_the_search_spans_less_than_a_model_may_hold_and_searches_about_a_decided_value():
    spec = EFFECTS["accel_gain"]
    assert (spec.lower, spec.upper) == (0.3, 3.0) and spec.bounds == (0.01, 100.0)
    assert spec.searched(-1.2) and not spec.searched(6.0) and not spec.searched(-0.2)
    assert spec.search_about(-1.2) == (0.3, 3.0)
    lo, hi = spec.search_about(-6.0)  # the search's factor of 10, geometrically about 6
    assert lo == pytest.approx(6.0 / 10 ** 0.5) and hi == pytest.approx(6.0 * 10 ** 0.5)
    assert spec.search_about(0.02)[0] == 0.01  # within what a model may hold
    assert EFFECTS["coulomb_friction"].bounds == (0.0, 40.0)  # no held range: the search's


def test_a_model_file_carries_the_faults_and_reads_them_back(tmp_path, nominal):
    faults = {"accel_gain": -1.2, "accel_offset": -2.5, "accel_drift": 0.75, "encoder_scale": 4.0,
              "motor_polarity": -1.0, "coulomb_friction": 6.0}
    m = nominal.with_effects(faults, name="reversed")
    m.save(tmp_path / "m.toml")
    text = (tmp_path / "m.toml").read_text()
    assert '"accel_gain" = -1.2' in text and '"motor_polarity" = -1.0' in text and '"encoder_scale" = 4.0' in text
    back = load_model(tmp_path / "m.toml")
    assert back == m and back.effect_dict() == faults
    assert m.with_effects({"motor_polarity": 1.0, "encoder_scale": 1.0}).effect_dict().keys() == \
        faults.keys() - {"motor_polarity", "encoder_scale"}  # the neutral value removes a fault


@pytest.mark.parametrize("body", ['"motor_polarity" = 0.5', '"accel_gain" = 0.0', '"encoder_scale" = -20.0'])
def test_a_model_file_with_a_fault_out_of_range_is_refused_in_one_line(tmp_path, body):
    path = tmp_path / "m.toml"
    path.write_text(f"n_elements = 4\n[effects]\n{body}\n")
    with pytest.raises(StationError) as info:
        load_model(path)
    msg = str(info.value)
    assert str(path) in msg and "line 3" in msg and "out of range" in msg and "\n" not in msg


# --- each fault against the nominal run ------------------------------------------------

@pytest.mark.parametrize("gain", [-3.0, -1.2, -0.3, 0.5, 2.0])
def test_accel_gain_scales_a_with_its_sign_and_leaves_theta(nominal, gain):
    v = _pulses()
    base, faulty = _open(nominal, v), _open(nominal.with_effects({"accel_gain": gain}), v)
    np.testing.assert_array_equal(faulty.theta, base.theta)
    np.testing.assert_allclose(faulty.a, gain * base.a, rtol=1e-12, atol=1e-12)
    assert np.corrcoef(faulty.a, base.a)[0, 1] == pytest.approx(np.sign(gain))


@pytest.mark.parametrize("offset, drift", [(3.0, 0.0), (0.0, -4.0), (-2.5, 7.5), (30.0, 20.0)])
@pytest.mark.parametrize("dt", [0.002, 0.001])
def test_accel_offset_and_drift_add_b_plus_r_t_from_the_first_sample(nominal, offset, drift, dt):
    v = _pulses()
    fx = {"accel_offset": offset, "accel_drift": drift}
    base, faulty = _open(nominal, v, dt=dt), _open(nominal.with_effects(fx), v, dt=dt)
    np.testing.assert_array_equal(faulty.theta, base.theta)
    t = np.arange(v.size) * dt
    np.testing.assert_allclose(faulty.a - base.a, offset + drift * t, rtol=0, atol=1e-9)
    # quantized: the bias acts before the rounding (a whole offset shifts every reading by itself)
    q = simulate(nominal.with_effects({"accel_offset": 4.0}), None, np.zeros(v.size), alignment=0, v_open=v)
    q0 = simulate(nominal, None, np.zeros(v.size), alignment=0, v_open=v)
    np.testing.assert_array_equal(q.a - q0.a, 4.0)


@pytest.mark.parametrize("scale", [4.0, -1.0, -4.0, 0.5])
def test_encoder_scale_multiplies_theta_before_its_rounding(nominal, scale):
    v = _pulses()
    base, faulty = _open(nominal, v), _open(nominal.with_effects({"encoder_scale": scale}), v)
    np.testing.assert_allclose(faulty.theta, scale * base.theta, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(faulty.a, base.a)
    q = simulate(nominal.with_effects({"encoder_scale": scale}), None, np.zeros(v.size), alignment=0, v_open=v)
    assert np.abs(q.theta - scale * base.theta).max() <= 0.5  # rounded once, after the scale
    assert np.array_equal(q.theta, np.round(q.theta))


def test_a_reversed_motor_mirrors_a_linear_open_loop_run(nominal):
    v = _pulses()
    base, faulty = _open(nominal, v), _open(nominal.with_effects({"motor_polarity": -1.0}), v)
    np.testing.assert_array_equal(faulty.theta, -base.theta)
    np.testing.assert_array_equal(faulty.a, -base.a)
    np.testing.assert_array_equal(faulty.v, base.v)  # the log keeps the command the station sent


AMPLIFIER = {"amp_offset": 5.0, "saturation": 90.0, "deadzone": 4.0, "delay": 2.0}


@pytest.mark.parametrize("plant", [{}, {"coulomb_friction": 6.0}, {"static_friction": 14.0, "coulomb_friction": 6.0},
                                   {"backlash": 6.0, "viscous_friction": 2.0}])
def test_the_polarity_turns_the_whole_amplifier_output_around_offset_included(nominal, plant):
    # torque −amp(v; o) = amp(−v; −o) (truncation, saturation and dead-zone are odd): the
    # reversed motor's run is the mirrored command's with the amplifier's offset mirrored
    # too (polarity at the amplifier's output, after its offset), float for float
    v = _pulses()
    reversed_ = nominal.with_effects({**plant, **AMPLIFIER, "motor_polarity": -1.0})
    mirrored = nominal.with_effects({**plant, **AMPLIFIER, "amp_offset": -AMPLIFIER["amp_offset"]})
    got = _open(reversed_, v, command="trunc")
    want = _open(mirrored, -v, command="trunc")
    np.testing.assert_array_equal(got.theta, want.theta)
    np.testing.assert_array_equal(got.a, want.a)
    assert np.abs(got.theta).max() > 20.0  # the pulses moved it
    # not the polarity at the amplifier's input: the offset would then push the same way
    before = _open(nominal.with_effects({**plant, **AMPLIFIER}), -v, command="trunc")
    assert np.abs(before.theta - got.theta).max() > 1.0


# --- closed loops ----------------------------------------------------------------------

SYMMETRIC = [{}, {"coulomb_friction": 8.0, "amp_offset": -3.0}, {"static_friction": 12.0, "coulomb_friction": 5.0},
             {"backlash": 5.0, "delay": 1.0, "param:drive_c": 1.5, "accel_offset": 2.0, "accel_drift": -3.0}]


@pytest.mark.parametrize("effects", SYMMETRIC)
@pytest.mark.parametrize("kind, amp", [("p", 60.0), ("lead", 100.0), ("lead-accel", 200.0)])
def test_a_reversed_motor_read_by_a_reversed_encoder_is_a_reversed_accelerometer(nominal, effects, kind, amp):
    # z -> -z maps the plant driven by -amp(v) onto the one driven by amp(v) (every law odd):
    # θ read by -s of -θ is s·θ, a read by g of -a is -g·a; the station sees the same samples
    # and sends the same commands, float for float
    u = step_reference(amp, N, at_tick=10)
    c = make_controller(kind)
    wired = simulate(nominal.with_effects({**effects, "motor_polarity": -1.0, "encoder_scale": -2.0,
                                           "accel_gain": 0.8}), c, u, command="round")
    accel = simulate(nominal.with_effects({**effects, "encoder_scale": 2.0, "accel_gain": -0.8}), c, u,
                     command="round")
    for key in wired.keys():
        np.testing.assert_array_equal(wired[key], accel[key], err_msg=key)


@pytest.mark.parametrize("kind", ["p", "lead"])
def test_a_reversed_motor_or_encoder_runs_a_closed_loop_away(nominal, kind):
    u = step_reference(50.0, N, at_tick=10)
    c = make_controller(kind)
    for fault in ({"motor_polarity": -1.0}, {"encoder_scale": -1.0}):
        run = simulate(nominal.with_effects(fault), c, u, command="round")
        assert run.theta[-1] < -500.0 and np.abs(run.v[-50:]).min() == c.limit  # positive feedback: clamped
    fine = simulate(nominal, c, u, command="round")
    assert abs(fine.theta[-1] - 50.0) < 15.0


@pytest.mark.parametrize("scale", [4.0, 2.0, 0.5])
@pytest.mark.parametrize("effects", [{}, {"coulomb_friction": 4.0}])
def test_a_p_loop_through_a_scaled_encoder_is_the_loop_with_kp_times_the_scale(nominal, scale, effects):
    # v = kp (u - s θ) = (kp s)(u/s - θ): the same physical run at kp·s towards u/s
    u = step_reference(60.0, N, at_tick=10)
    kp = 1.5
    got = simulate(nominal.with_effects({**effects, "encoder_scale": scale}), make_controller("p", kp=kp), u,
                   quantize=False)
    want = simulate(nominal.with_effects(effects), make_controller("p", kp=kp * scale), u / scale, quantize=False)
    np.testing.assert_allclose(got.theta, scale * want.theta, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(got.v, want.v, rtol=1e-9, atol=1e-9)


# --- every path the same float operations ------------------------------------------------

ALL_FAULTS = {"accel_gain": -1.3, "accel_offset": 2.5, "accel_drift": -6.0, "encoder_scale": -4.0,
              "motor_polarity": -1.0, "coulomb_friction": 5.0, "amp_offset": 2.0, "delay": 1.0}


class _Wrapped:
    def __init__(self, inner):
        self.inner = inner

    def step(self, u, theta, a):
        return self.inner.step(u, theta, a)

    def reset(self):
        self.inner.reset()


@pytest.mark.parametrize("effects", [ALL_FAULTS, {k: ALL_FAULTS[k] for k in SENSOR_FAULTS}])
def test_model_plant_steps_like_simulate_and_its_drift_restarts_on_reset(nominal, effects):
    model = nominal.with_effects(effects)
    v = np.round(_pulses())
    run = _open(model, v)
    plant = model.plant()
    for _ in range(2):  # reset: at rest, the drift from 0 again
        rows = []
        for x in v:
            rows.append(plant.outputs())
            plant.advance(x)
        np.testing.assert_array_equal(np.array(rows), np.column_stack([run.theta, run.a]))
        plant.reset()


@pytest.mark.parametrize("effects", [ALL_FAULTS, {"accel_gain": 1.3, "encoder_scale": 4.0, "motor_polarity": -1.0}])
def test_a_python_controller_runs_with_the_same_faults(nominal, effects):
    model = nominal.with_effects(effects)
    c, u = make_controller("lead-accel"), step_reference(200.0, N, at_tick=10)
    compiled = simulate(model, c, u, command="round")
    python = simulate(model, _Wrapped(c), u, command="round")
    for key in ("theta", "a"):
        np.testing.assert_array_equal(python[key], compiled[key], err_msg=key)


def test_the_plain_python_kernel_equals_the_compiled_one_with_the_faults(nominal):
    from station.plant import kernel
    from station.plant.simulate import _coeffs

    kernel._compile()
    assert hasattr(kernel._compiled_loop, "py_func"), "the sample loop is not numba-compiled"
    model = nominal.with_effects(ALL_FAULTS)
    form = model.linear_form()
    fx = kernel.effects_of(model)
    assert fx.accel_drift == pytest.approx(-6.0 * DT) and fx.motor_polarity == -1.0 and fx.encoder_scale == -4.0
    c = make_controller("lead-accel")
    gnum, gden = _coeffs(c.gth)
    anum, aden = _coeffs(c.ga)
    u = step_reference(200.0, 300, at_tick=10)
    args = (form.lam, form.bm, form.bp, form.cm, form.co, form.gw_v, form.gw_p, form.substeps,
            np.zeros(form.lam.size, complex), u, np.zeros(1), False, True, gnum, gden, anum, aden, True, 200.0, 1,
            True, 1, 0, *fx)
    plain = kernel._compiled_loop.py_func(*args)
    compiled = kernel.run_kernel(*args)
    for x, y in zip(plain, compiled):
        np.testing.assert_array_equal(x, y)


# --- the simulated device (sim://?model=FILE): the same plant, the station's zeroing ------

WIRING = {"motor_polarity": -1.0, "encoder_scale": -2.0, "accel_gain": 0.7, "coulomb_friction": 6.0}


def _record(tmp_path, effects, protocol, kind, name="faults"):
    from station.experiment import run_step

    path = tmp_path / f"{name}.toml"
    load_model().with_effects(effects, name=name).save(path)
    log = tmp_path / f"{name}-{protocol}-{kind}.tsv"
    rep = run_step(port=f"sim://?noise=0&model={path}", protocol=protocol, controller=kind,
                   amplitude=200.0 if kind == "lead-accel" else 60.0, step_tick=10, duration=1.0, out=log,
                   lean=False, figure=False, timeout=5.0)  # lockstep: a busy machine must not time it out
    assert rep.result.ok, rep.result.message
    return log, path


@pytest.mark.parametrize("protocol", ["v1", "legacy"])
@pytest.mark.parametrize("kind", ["p", "lead-accel", "open-loop"])
def test_station_step_on_a_miswired_simulated_rig_equals_simulate(tmp_path, protocol, kind):
    """Noise-free: the logged θ and a are the model's prediction (replay --model) exactly,
    and the nominal model's are not; the header carries the faults."""
    from station.replay import replay
    from station.runlog import read_log

    log, path = _record(tmp_path, WIRING, protocol, kind)
    r = replay(log, model=path)
    np.testing.assert_array_equal(r.prediction["theta"], r.log.data["theta"])
    np.testing.assert_array_equal(r.prediction["a"], r.log.data["a"])
    nominal = replay(log, model=True)
    assert not np.array_equal(nominal.prediction["theta"], r.log.data["theta"])
    assert read_log(log).meta["plant"]["model"]["effects"] == WIRING


@pytest.mark.parametrize("protocol", ["v1", "legacy"])
def test_the_stations_zeroing_removes_a_constant_accelerometer_offset_on_the_simulated_rig(tmp_path, protocol):
    # the sensor's bias is there when the station zeroes at rest (v1 START's 16 ticks, the
    # legacy pre-run), so a log recorded by the station shows none of it, as on the rig:
    # accel_offset is what a log holds beyond its zeroing
    from station.replay import replay

    log, _ = _record(tmp_path, {"accel_offset": 3.0}, protocol, "p")
    plain = replay(log, model=True)
    np.testing.assert_array_equal(plain.prediction["a"], plain.log.data["a"])


@pytest.mark.parametrize("protocol", ["v1", "legacy"])
def test_a_drifting_accelerometer_drifts_in_the_log_of_the_simulated_rig(tmp_path, protocol):
    # 10 counts/s: under 0.3 counts over the 16 zeroing readings, which see the device's own
    # offset only; the drift's clock starts with the run (legacy 'q'; v1 START, 16 ticks
    # before tick 0)
    from station.replay import replay

    log, path = _record(tmp_path, {"accel_drift": 10.0}, protocol, "p")
    r, plain = replay(log, model=path), replay(log, model=True)
    extra = r.log.data["a"] - r.prediction["a"]
    if protocol == "legacy":
        np.testing.assert_array_equal(extra, 0.0)
    else:
        assert set(np.unique(extra)) <= {0.0, 1.0}  # 16 ticks' drift (0.32 counts) more at each reading
    t = np.asarray(r.log.data["t"])
    slope = np.polyfit(t, r.log.data["a"] - plain.prediction["a"], 1)[0]
    assert slope == pytest.approx(10.0, rel=0.05)
