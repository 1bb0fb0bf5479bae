"""station.control against DESIGN.md's numbers, hand-computed sequences and the rig logs."""

import math

import numpy as np
import pytest

from station.control import (
    ACCEL_DEN_S,
    ACCEL_NUM_S,
    LEAD_DEN_S,
    LEAD_NUM_S,
    Compensator,
    DiscreteTF,
    OpenLoop,
    make_controller,
    pulse_reference,
    step_reference,
    swept_sine_reference,
    tustin,
)
from station.errors import StationError

# Printed in DESIGN.md and in the accel run's header (8 decimals).
LEAD_Z = ([18.32547182, -17.20911971], [1.0, -0.77672958])
ACCEL_Z = ([0.00045097, 0.00045152, -0.00044989, -0.00045043], [1.0, -2.9289362, 2.85853684, -0.92960052])
OL_PULSE = "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"
SWEEP = "swept_sine_kp_1_amp_50.txt"
LEAD_LOG = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
ACCEL_LOG = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"


def _rig_columns(path):
    return np.loadtxt(path, comments="#", delimiter="\t")


# --- DiscreteTF -------------------------------------------------------------------------

def test_discrete_tf_normalizes_den0():
    tf = DiscreteTF([2.0, 4.0], [2.0, 1.0])
    np.testing.assert_array_equal(tf.num, [1.0, 2.0])
    np.testing.assert_array_equal(tf.den, [1.0, 0.5])


def test_discrete_tf_rejects_bad_coefficients():
    with pytest.raises(ValueError, match="den\\[0\\]"):
        DiscreteTF([1.0], [0.0, 1.0])
    with pytest.raises(ValueError):
        DiscreteTF([], [1.0])
    with pytest.raises(ValueError):
        DiscreteTF([math.nan], [1.0])


def test_discrete_tf_recursion_by_hand():
    # y[k] = x[k] + 2 x[k-1] + 0.5 y[k-1]; impulse response 1, 2.5, 1.25, 0.625
    tf = DiscreteTF([1.0, 2.0], [1.0, -0.5])
    assert [tf.step(x) for x in (1.0, 0.0, 0.0, 0.0)] == [1.0, 2.5, 1.25, 0.625]
    tf.reset()
    assert tf.step(1.0) == 1.0


def test_output_does_not_change_state():
    tf = DiscreteTF([1.0, 2.0], [1.0, -0.5])
    tf.step(1.0)
    assert tf.output(3.0) == tf.output(3.0) == 3.0 + 2.0 + 0.5
    assert tf.step(0.0) == 2.5


# --- Tustin and the rig's designs -------------------------------------------------------

def test_tustin_of_lead_equals_printed_coefficients():
    num, den = tustin(LEAD_NUM_S, LEAD_DEN_S, 0.002)
    np.testing.assert_array_equal(np.round(num, 8), LEAD_Z[0])
    np.testing.assert_array_equal(np.round(den, 8), LEAD_Z[1])


def test_tustin_of_accel_equals_header_coefficients():
    num, den = tustin(ACCEL_NUM_S, ACCEL_DEN_S, 0.002)
    np.testing.assert_array_equal(np.round(num, 8), ACCEL_Z[0])
    np.testing.assert_array_equal(np.round(den, 8), ACCEL_Z[1])


def test_dc_gains_survive_tustin():
    lead = make_controller("lead")
    assert lead.gth.dc_gain() == pytest.approx(5.0, rel=1e-12)  # 5 (p/z)(z/p)
    accel = make_controller("lead-accel")
    assert accel.ga.dc_gain() == pytest.approx(281.56096177 / 15.39673089, rel=1e-8)  # den sums to ~1e-4: cancellation
    assert make_controller("p", kp=2.0).gth.dc_gain() == 2.0


def test_tustin_rejects_improper_design():
    with pytest.raises(ValueError, match="improper"):
        tustin([1.0, 0.0, 0.0], [1.0, 1.0])


# --- Compensator structure --------------------------------------------------------------

def test_saturation_and_anti_windup_by_hand():
    # Gth: y = 2 e[k] - e[k-1] + 0.5 v[k-1], clamp 1.5; e = 1, 1, 1, 0, 0.
    # k0: 2 -> 1.5; k1, k2: 2 - 1 + 0.75 = 1.75 -> 1.5; k3: -1 + 0.75 = -0.25;
    # k4: 0.5 * -0.25 = -0.125. (Remembering the unclamped 2 would give 0 at k3.)
    comp = Compensator(DiscreteTF([2.0, -1.0], [1.0, -0.5]), None, limit=1.5)
    vs = [comp.step(e, 0.0, 0.0)[0] for e in (1.0, 1.0, 1.0, 0.0, 0.0)]
    assert vs == [1.5, 1.5, 1.5, -0.25, -0.125]
    comp.reset()
    assert comp.step(-1.0, 0.0, 0.0)[0] == -1.5


def test_accel_feedback_structure_by_hand():
    # Ga: y = 0.5 a + 0.5 y[k-1]; Gth = 2; u = 10, theta = 4, a = 2, 2; clamp 5.
    # theta_d_hat = 10 - 1 = 9, then 10 - 1.5 = 8.5; Ga keeps its own output while v clips.
    comp = Compensator(DiscreteTF([2.0], [1.0]), DiscreteTF([0.5], [1.0, -0.5]), limit=5.0)
    assert comp.step(10.0, 4.0, 2.0) == (5.0, 9.0)
    assert comp.step(10.0, 4.0, 2.0) == (5.0, 8.5)
    unclamped = Compensator(DiscreteTF([2.0], [1.0]), DiscreteTF([0.5], [1.0, -0.5]), limit=None)
    assert unclamped.step(10.0, 4.0, 2.0) == (10.0, 9.0)


def test_p_controller():
    p = make_controller("p", kp=2.0)
    assert p.step(50.0, 10.0, 3.0) == (80.0, 50.0)
    assert p.step(500.0, 0.0, 0.0) == (200.0, 500.0)
    assert p.spec["kind"] == "p" and p.spec["limit"] == 200.0 and p.spec["kp"] == 2.0


def test_open_loop():
    ol = make_controller("open-loop", limit=None)
    assert isinstance(ol, OpenLoop) and ol.gth is None and ol.ga is None
    assert ol.step(123.0, 5.0, 7.0) == (123.0, 123.0)
    assert OpenLoop(limit=100.0).step(-150.0, 0.0, 0.0) == (-100.0, -150.0)


def test_spec_is_json_and_has_designs():
    import json

    spec = json.loads(json.dumps(make_controller("lead-accel").spec))
    assert spec["kind"] == "lead-accel" and spec["limit"] == 200.0
    assert spec["gth"]["num_s"] == pytest.approx([20.0, 20.0 * 2 * math.pi * 5])
    assert spec["ga"]["den_s"] == list(ACCEL_DEN_S)
    np.testing.assert_array_equal(np.round(spec["ga"]["num_z"], 8), ACCEL_Z[0])


@pytest.mark.parametrize("log, kind", [(LEAD_LOG, "lead"), (ACCEL_LOG, "lead-accel")])
def test_designs_reproduce_rig_commands(rig_data, log, kind):
    """DESIGN.md: Tustin of the designs reproduces the logged v to 5e-8 counts (alignment 1)."""
    d = _rig_columns(rig_data / log)
    u, v, theta, a = d[:, 2], d[:, 3], d[:, 4], d[:, 5]
    comp = make_controller(kind)
    th_prev = np.concatenate([[0.0], theta[:-1]])
    a_prev = np.concatenate([[0.0], a[:-1]])
    out = np.array([comp.step(u[k], th_prev[k], a_prev[k]) for k in range(len(u))])
    assert np.max(np.abs(out[:, 0] - v)) < 1e-7
    np.testing.assert_allclose(out[:, 1], d[:, 6], atol=1e-7)


# --- compensator files ------------------------------------------------------------------

LEAD_TOML = f"""
name = "my-lead"
[gth]
num = [20.0, {20.0 * 2 * math.pi * 5!r}]
den = [1.0, {2 * math.pi * 20!r}]
domain = "s"
"""


def test_toml_s_domain_equals_builtin_lead(tmp_path):
    f = tmp_path / "lead.toml"
    f.write_text(LEAD_TOML)
    comp = make_controller(str(f))
    ref = make_controller("lead")
    np.testing.assert_array_equal(comp.gth.num, ref.gth.num)
    np.testing.assert_array_equal(comp.gth.den, ref.gth.den)
    assert comp.ga is None and comp.limit == 200.0 and comp.name == "my-lead"
    assert comp.spec["kind"] == "file" and comp.spec["file"] == str(f)


def test_toml_z_domain_with_ga_and_limit(tmp_path):
    f = tmp_path / "acc.toml"
    f.write_text(
        "limit = 150\n[gth]\nnum = [2.0]\nden = [1.0]\ndomain = 'z'\n"
        "[ga]\nnum = [0.5]\nden = [2.0, -1.0]\ndomain = 'z'\n")
    comp = make_controller(str(f))
    assert comp.limit == 150.0 and comp.name == "acc"
    np.testing.assert_array_equal(comp.ga.num, [0.25])
    np.testing.assert_array_equal(comp.ga.den, [1.0, -0.5])
    assert comp.step(100.0, 0.0, 4.0) == (150.0, 99.0)


@pytest.mark.parametrize("text, field", [
    ("[ga]\nnum=[1.0]\nden=[1.0]\ndomain='z'\n", "[gth]"),
    ("[gth]\nnum=[1.0]\nden=[1.0]\ndomain='w'\n", "[gth].domain"),
    ("[gth]\nnum=[1.0, 'x']\nden=[1.0]\ndomain='z'\n", "[gth].num[1]"),
    ("[gth]\nnum=[]\nden=[1.0]\ndomain='z'\n", "[gth].num"),
    ("[gth]\nnum=[1.0]\nden=[0.0, 1.0]\ndomain='z'\n", "[gth].den[0]"),
    ("[gth]\nnum=[1.0]\nden=[1.0]\n", "[gth].domain"),
    ("[gth]\nnum=[1.0, 2.0, 3.0]\nden=[1.0, 1.0]\ndomain='s'\n", "[gth].num"),
    ("[gth]\nnum=[1.0]\nden=[1.0]\ndomain='z'\ngain=3\n", "[gth].gain"),
    ("limit = -3\n[gth]\nnum=[1.0]\nden=[1.0]\ndomain='z'\n", "limit"),
    ("kp = 3\n[gth]\nnum=[1.0]\nden=[1.0]\ndomain='z'\n", "kp"),
    ("[gth\nnum=[1.0]\n", "not valid TOML"),
])
def test_toml_errors_name_file_and_field(tmp_path, text, field):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(StationError) as err:
        make_controller(str(f))
    msg = str(err.value)
    assert str(f) in msg and field in msg


def test_unknown_kind_is_a_station_error(tmp_path):
    with pytest.raises(StationError, match="leed"):
        make_controller("leed")


# --- references -------------------------------------------------------------------------

def test_step_reference():
    u = step_reference(100.0, 1000)
    assert u.shape == (1000,) and np.all(u[:10] == 0) and np.all(u[10:] == 100.0)


def test_swept_sine_equals_rig_log(rig_data):
    d = _rig_columns(rig_data / SWEEP)
    np.testing.assert_array_equal(swept_sine_reference(len(d), amplitude=50, dt=0.002), d[:, 2])


def test_pulse_equals_rig_ol_log(rig_data):
    d = _rig_columns(rig_data / OL_PULSE)
    np.testing.assert_array_equal(pulse_reference(100.0, len(d), 20, 50, return_tick=700), d[:, 2])


def test_pulse_rejects_overlap():
    with pytest.raises(ValueError, match="overlaps"):
        pulse_reference(100.0, 1000, 20, 50, return_tick=40)


def test_file_reference_reads_a_log_column(rig_data):
    from station.control import file_reference

    u = file_reference(rig_data / SWEEP, "u")
    np.testing.assert_array_equal(u, swept_sine_reference(11000))
    # the columns said are the log's own (a new user was shown ours: theta_d_hat, status, ...)
    for missing in ("w", "theta_d_hat", "latency_us"):
        with pytest.raises(StationError, match=f"no column '{missing}' with values \\(the log's columns: t, n, u, "
                                               f"v, theta, a\\)$"):
            file_reference(rig_data / SWEEP, missing)


def test_tustin_equals_scipy_bilinear_on_random_designs():
    # independent truth: scipy.signal.cont2discrete (tf -> ss -> bilinear -> tf)
    from scipy.signal import cont2discrete

    rng = np.random.default_rng(7)
    for order in range(1, 6):
        for _ in range(40):
            den = np.concatenate([[rng.uniform(0.5, 2.0)], rng.uniform(0.1, 500.0, order)])
            num = rng.uniform(-500.0, 500.0, int(rng.integers(1, order + 2)))
            got_num, got_den = tustin(num, den, 0.002)
            num_z, den_z, _ = cont2discrete((num, den), 0.002, method="bilinear")
            num_z = np.atleast_1d(np.squeeze(num_z))
            num_z = np.concatenate([np.zeros(den_z.size - num_z.size), num_z]) / den_z[0]
            assert np.allclose(got_den, den_z / den_z[0], rtol=0, atol=1e-12)
            assert np.allclose(got_num, num_z, rtol=0, atol=1e-12 * max(1.0, np.abs(num_z).max()))
