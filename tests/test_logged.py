"""station.logged.LoggedRun: what a logged run was, answered in one place (controller,
alignment, closed loop, sample time, reference, hub held), and compare treating a hub-held
beam test as replay does."""

import math

import numpy as np
import pytest

from station.compare import compare_run, format_comparison
from station.control import make_controller
from station.control.rerun import is_closed_loop
from station.logged import LoggedRun
from station.plant import DiscretePlant
from station.replay import replay

P_LOG = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
ACCEL_LOG = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
OL_PULSE = "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"
HOLD = "log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt"
OLD_P = "2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt"


@pytest.mark.parametrize("name, kind, closed, alignment, step", [
    (P_LOG, "p", True, 1, 50.0), (ACCEL_LOG, "lead-accel", True, 1, 200.0), (OLD_P, "p", True, 0, 100.0),
    (OL_PULSE, "open-loop", False, None, None), (HOLD, "open-loop", False, None, 77.0)])
def test_rig_logs_understood(rig_data, name, kind, closed, alignment, step):
    run = LoggedRun.from_path(rig_data / name)
    assert run.controller.name == kind and run.source == "header"
    assert run.closed is closed and run.alignment == alignment
    assert run.reproduced and run.dt == 0.002
    assert run.reference.amplitude == step
    assert (run.held is not None) is (name == HOLD)
    assert (run.step_metrics() is not None) is (closed and step is not None)


def test_theta_relative_in_open_loop_and_rest_offset(rig_data):
    run = LoggedRun.from_path(rig_data / HOLD)
    assert run.data["theta"][0] != 0 and run.theta[0] == 0
    assert np.array_equal(run.theta, run.data["theta"] - run.data["theta"][0])
    assert run.accel_rest_offset == pytest.approx(-2.0, abs=0.5)  # DESIGN.md: ≈ −2 counts at rest
    closed = LoggedRun.from_path(rig_data / P_LOG)
    assert closed.theta is closed.data["theta"]


def test_simulate_is_what_replay_reports(rig_data):
    run = LoggedRun.from_path(rig_data / P_LOG)
    sim = run.simulate(DiscretePlant(n_elements=4))
    r = replay(rig_data / P_LOG)
    assert sim.fit_pct == pytest.approx(r.fit_pct)
    assert r.run is not None and r.run.alignment == 1


def test_one_definition_of_closed_loop():
    assert is_closed_loop(make_controller("lead")) and is_closed_loop(make_controller("p"))
    assert not is_closed_loop(make_controller("open-loop")) and not is_closed_loop(None)


def test_compare_treats_a_hub_held_beam_test_as_replay_does(rig_data, tmp_path):
    """No motor-model fit for the hold-and-release log (it printed fit θ % −991935.7 and
    drew the model ramping to 8000 counts): its v was never applied."""
    from station.plots import plot_comparison

    c = compare_run(rig_data / HOLD, DiscretePlant(n_elements=4))
    assert c.fit_pct == {"theta": None, "accel": None} and c.prediction is None and c.model is None
    assert any("hub-held beam test" in n and "cannot represent" in n for n in c.notes)
    text = format_comparison(c)
    assert "991935" not in text and "hub-held beam test" in text
    plot_comparison(c, tmp_path / "hold.png")
    assert (tmp_path / "hold.png").stat().st_size > 0
    assert replay(rig_data / HOLD, model=False).fit_pct is None  # as replay


def test_step_metrics_use_the_classified_amplitude(tmp_path):
    """A step log: the metrics use the reference's classified amplitude (a log of ours)."""
    from station.plant import simulate
    from station.runlog import RunLogWriter

    ctrl = make_controller("lead")
    u = np.r_[np.zeros(10), np.full(590, 100.0)]
    sim = simulate(DiscretePlant(n_elements=4), ctrl, u, alignment=1)
    path = tmp_path / "run.tsv"
    with RunLogWriter(path, {"controller": ctrl.spec, "dt": 0.002}) as w:
        for k in range(u.size):
            w.append((sim["t"][k], k, u[k], sim["v"][k], sim["theta"][k], sim["a"][k], sim["theta_d_hat"][k],
                      round(sim["v"][k]), 0, math.nan))
    run = LoggedRun.from_path(path)
    assert run.reference.is_step and run.reference.step_tick == 10
    assert run.step_metrics().overshoot_pct == pytest.approx(100 * (sim["theta"].max() - 100) / 100)


LEAD_LOG = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"


@pytest.mark.parametrize("b0, b1, a1, source", [
    (18.32547182, -17.20911971, -0.77672958, "header"),  # the thesis's Gth, as the lab printed it
    (2.9702970297, -2.8925742574, -0.9603960396, "inferred (header contradicted)"),  # another lead
])
def test_the_labs_b_and_a_header_lines_are_a_claim_checked_against_the_data(rig_data, tmp_path, b0, b1, a1, source):
    """ryanGT's Motor_Comp scripts printed Gth as '#b0=', '#b1=', '#a1=' lines (v[i] = b0 e[i] +
    b1 e[i-1] - a1 v[i-1]); read as Gth, they are checked like any header: the thesis's lead is
    confirmed, another lead on the same data is contradicted and the data's law used. Before,
    the lines were ignored and the controller inferred with nothing said of the header."""
    rows = (rig_data / LEAD_LOG).read_text().splitlines()
    body = [r for r in rows if not r.startswith("#Gth") and not r.startswith("#Ga")][1:]
    path = tmp_path / "lab_motor_comp.txt"
    path.write_text("\n".join(["#SLFR RTP Motor_Comp", f"#b0={b0}", f"#b1={b1}", f"#a1={a1}", *body]) + "\n")
    run = LoggedRun.from_path(path)
    assert run.source == source and run.reproduced and run.alignment == 1
    if source == "header":
        assert run.controller.name == "lead"
    else:
        assert "Gth num [2.970297" in " ".join(run.audit.lines())


@pytest.mark.parametrize("seed", [0, 3, 4])
def test_a_headers_lead_is_named_by_the_design_the_lab_discretized(tmp_path, seed):
    """A lab header printing another lead than the thesis's (ryanGT's Motor_Comp '#b0=' lines,
    Python 2's 12 digits) and confirmed on its data is named by its continuous design, as an
    inferred law is; its printed coefficients are still the ones replayed. Before, such a
    header's law was "rig-printed" in replay and survey, and only a law the data had to
    complete (another path) got its design's name."""
    from tests.blind.audit import draw_case, simulate_audit_case
    from tests.blind.rig import tustin

    case = draw_case("honest:lead_int", seed)
    num, den = tustin(list(case.num_s), list(case.den_s))
    sim = simulate_audit_case(case, seed)
    body = [f"{k * 0.002:.10g}\t{k}\t{sim.u[k]:.10g}\t{sim.v[k]:.10g}\t{sim.theta[k]:.10g}\t{sim.a[k]:.10g}"
            for k in range(len(sim.u))]
    path = tmp_path / "lab_motor_comp.txt"
    path.write_text("\n".join(["#SLFR RTP Motor_Comp", f"#b0={num[0]:.12g}", f"#b1={num[1]:.12g}",
                               f"#a1={den[1]:.12g}", "#t\tn\tu\tv\t$\\theta$\ta", *body]) + "\n")
    run = LoggedRun.from_path(path)
    assert run.source == "header" and run.reproduced and run.alignment == case.alignment
    assert run.controller.name == case.design_text
    assert run.controller.spec["design"]["text"] == case.design_text
    assert run.controller.gth.num.tolist() == [float(f"{x:.12g}") for x in num]  # as printed, not the design's
    report = replay(path)
    assert report.controller == case.design_text and report.controller_source == "header"


def test_a_station_logs_lead_keeps_the_name_its_compensator_file_gave_it(tmp_path):
    """Only a rig header's printed law is renamed by its design: our own log's controller is
    the compensator file's, and replay says the name the user gave it."""
    from station.cli import main

    toml = tmp_path / "mylead.toml"
    toml.write_text('name = "my lead"\nlimit = 200\n[gth]\ndomain = "s"\nnum = [3.0, 39.0]\nden = [1.0, 20.0]\n')
    log = tmp_path / "mylead.tsv"
    assert main(["step", "--controller", str(toml), "--duration", "0.5", "--out", str(log)]) == 0
    run = LoggedRun.from_path(log)
    assert run.source == "header" and run.reproduced and run.controller.name == "my lead"
    assert "design" not in run.controller.spec
