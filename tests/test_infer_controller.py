"""Controller identification from the data: open loop, P and low-order linear laws are
found only when they reproduce every logged v to 1e-6 counts; PID headers are matched to
a standard discretization or say that none does."""

import numpy as np
import pytest

from station.analysis.controller_id import TOLERANCE, infer_controller
from station.analysis.pid_law import match_pid, pid_controllers
from station.control import make_controller
from station.control.rerun import replay_commands
from station.replay import replay


def _closed_loop(controller, d, n=1500, seed=0):
    """u, theta, v of a controller closed around a crude integrator plant with the rig's
    clamp; the reference is a random staircase (rich enough to identify a law)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.integers(-120, 120, n // 100 + 1).astype(float), 100)[:n]
    theta = np.zeros(n)
    v = np.zeros(n)
    controller.reset()
    for k in range(n):
        if k >= d:
            v[k], _ = controller.step(u[k], theta[k - d], 0.0)
        if k + 1 < n:
            theta[k + 1] = np.round(theta[k] + 0.02 * v[k] - 0.001 * theta[k])
    return u, theta, v


@pytest.mark.parametrize("kp, d", [(1.0, 1), (2.0, 0), (0.37, 1)])
def test_p_law_found_with_its_gain_and_alignment(kp, d):
    u, theta, v = _closed_loop(make_controller("p", kp=kp), d)
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.controller.spec["kp"] == pytest.approx(kp, rel=1e-12)
    assert hit.alignment == d and hit.max_abs_dv <= TOLERANCE
    assert hit.controller.name == "p"


@pytest.mark.parametrize("d", [0, 1])
def test_lead_found_as_first_order_linear_law(d):
    lead = make_controller("lead")
    u, theta, v = _closed_loop(lead, d)
    assert np.max(np.abs(v)) == 200.0  # clamped somewhere: the regression must skip those rows
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.alignment == d and hit.max_abs_dv <= TOLERANCE
    np.testing.assert_allclose(hit.controller.gth.num, lead.gth.num, rtol=1e-9)
    np.testing.assert_allclose(hit.controller.gth.den, lead.gth.den, rtol=1e-9)


def test_nonlinear_law_is_not_claimed():
    u, theta, v = _closed_loop(make_controller("p", kp=1.0), 1)
    v_bent = v + 0.01 * np.sign(v)  # a dead-band-like offset no linear law reproduces exactly
    assert infer_controller(u, theta, v_bent) is None


def test_open_loop_found():
    u = np.repeat([0.0, 100.0, 0.0, -100.0], 50)
    assert infer_controller(u, np.zeros_like(u), u).law.startswith("open loop")


def test_missing_u_or_no_commands_give_none():
    u, theta, v = _closed_loop(make_controller("p", kp=1.0), 1)
    assert infer_controller(np.full_like(u, np.nan), theta, v) is None
    assert infer_controller(u, theta, np.zeros_like(v)) is None


@pytest.mark.parametrize("rule", ["backward Euler", "forward Euler", "Tustin"])
def test_pid_header_replayed_with_the_discretization_that_reproduces_v(tmp_path, rule):
    kp, ki, kd = 0.8, 0.5, 0.002
    ctl = next(c for what, c in pid_controllers(kp, ki, kd) if rule in what)
    u, theta, v = _closed_loop(ctl, 1)
    hit, _ = match_pid(kp, ki, kd, u, theta, v)
    assert hit is not None and rule in hit.law and hit.alignment == 1
    # through replay, from a rig-format file
    path = tmp_path / "pid.txt"
    rows = "".join(f"{0.002 * k!r}\t{k}\t{float(u[k])!r}\t{float(v[k])!r}\t{float(theta[k])!r}\t0\n" for k in range(u.size))
    path.write_text(f"#SLFR_RTP PID_control_Test\n#kp = {kp}\n#ki = {ki}\n#kd = {kd}\n"
                    "#t\tn\tu\tv\t$\\theta$\ta\n" + rows)
    r = replay(path, model=False)
    assert r.controller_source == "header" and r.reproduced
    assert any(rule in n for n in r.notes)
    v_again, _ = replay_commands(hit.controller, u, theta, np.zeros_like(u), 1)
    assert np.max(np.abs(v_again - v)) <= TOLERANCE


def test_pid_header_that_nothing_reproduces_says_so_once(tmp_path):
    u, theta, v = _closed_loop(make_controller("p", kp=1.0), 1)
    v = v + 0.01 * np.sign(v)
    path = tmp_path / "pid.txt"
    rows = "".join(f"{0.002 * k!r}\t{k}\t{float(u[k])!r}\t{float(v[k])!r}\t{float(theta[k])!r}\t0\n" for k in range(u.size))
    path.write_text("#SLFR_RTP PID_control_Test\n#kp = 1.0\n#ki = 0.3\n#kd = 0.0\n#t\tn\tu\tv\t$\\theta$\ta\n" + rows)
    r = replay(path, model=False)
    assert r.controller is None and r.controller_source is None
    pid_notes = [n for n in r.notes if "no standard discretization" in n]
    assert len(pid_notes) == 1
    assert not any("names no controller" in n for n in r.notes)


def test_every_2014_sweep_in_the_rig_data_is_p_inferred(rig_data):
    # the shared folder holds without_accel_01_28_14_test_2.txt; a lab's copy of the public
    # repositories also has with_accel_01_28_14_test_1.txt: every one found is checked
    paths = sorted(rig_data.glob("*_01_28_14_*.txt"))
    assert paths, f"no 2014 sweep in {rig_data}"
    for path in paths:
        r = replay(path, model=False)
        assert r.controller_source == "inferred" and r.controller_spec["kp"] == 1.0 and r.alignment == 1, path
        assert r.max_abs_dv <= 1e-6, path


def test_rig_header_controllers_keep_their_source(rig_data):
    r = replay(rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt", model=False)
    assert r.controller_source == "header" and r.to_json()["controller_source"] == "header"
