"""The shipped rig models against the rig's own logs (independent truth: measured data,
the thesis's overshoot table), including logs they were not fitted to (docs/diagnosis.md
"Which model to ship")."""

import json
import math

import numpy as np
import pytest

from station.analysis.metrics import step_metrics
from station.cli import main
from station.diagnosis.runs.cases import load_case, simulate_case
from station.plant.model import load_model

THESIS_STEPS = {  # log -> the rig's overshoot, % (DESIGN.md, the thesis's table)
    "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt": 24.0,
    "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt": 10.0,
    "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt": 21.5,
}
NOT_FITTED_2014 = ["swept_sine_kp_1_amp_50.txt", "without_accel_01_28_14_test_2.txt"]
SESSION_2009 = ["2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt",
                "2009/swept_sine_no_sat_amp=50_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
                "2009/swept_sine_no_sat_amp=75_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
                "2009/swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt"]


def _theta_sse(case, model) -> float:
    theta, _ = simulate_case(case, model)
    return float(np.sum((case.theta - theta) ** 2))


def _pooled_gain(rig_data, logs, model) -> float:
    """θ RMS gain over tmm-fit, pooled over all samples of the logs (scripts/rig_study.py's)."""
    num = den = 0.0
    for log in logs:
        case = load_case(rig_data / log)
        num += _theta_sse(case, load_model(model))
        den += _theta_sse(case, load_model("tmm-fit"))
    return 1 - math.sqrt(num / den)


@pytest.mark.parametrize("log", sorted(THESIS_STEPS))
def test_rig_model_step_overshoots_near_the_rig(rig_data, log):
    """The thesis's FEM misses the P step by 14 points; the rig model is within 3 of every step
    (issue 26's bar; 22.0 / 12.0 / 19.0 % against the rig's 24.0 / 10.0 / 21.5 %)."""
    case = load_case(rig_data / log)
    theta, _ = simulate_case(case, load_model("rig"))
    u = np.asarray(case.run.data["u"], float)
    got = step_metrics(np.arange(case.n) * case.run.dt, theta, float(u[-1])).overshoot_pct
    assert abs(got - THESIS_STEPS[log]) <= 3.0


@pytest.mark.parametrize("log", NOT_FITTED_2014 + SESSION_2009)
def test_rig_model_beats_the_nominal_on_logs_it_was_not_fitted_to(rig_data, log):
    """Fitted on the four thesis logs; better than tmm-fit on every other rig log of both eras."""
    case = load_case(rig_data / log)
    assert _theta_sse(case, load_model("rig")) < _theta_sse(case, load_model("tmm-fit"))


def test_rig_model_pooled_gain_on_the_unseen_2014_logs(rig_data):
    """The two shared 2013-14 logs no fit uses: 28.0 % pooled (8.4 and 48.4 %; both models
    simulate the 28 Jan sweep without the accelerometer's mass, as the log audit found it run,
    and tmm-fit's error there falls from 4.6 to 3.5 counts RMS, so that sweep weighs less in the
    pool: 32.3 % with the mass on it). Issue 26 asks 40 %, which no structure fitted on the
    thesis logs reaches (docs/diagnosis.md); this guards the shipped model's level."""
    assert _pooled_gain(rig_data, NOT_FITTED_2014, "rig") >= 0.26


def test_rig_model_pooled_gain_on_the_2009_session(rig_data):
    """The other era, never fitted by `rig`: 36.6 % pooled (the former rig without the
    amplifier offset: 26.7 %)."""
    assert _pooled_gain(rig_data, SESSION_2009, "rig") >= 0.33


def test_station_compare_judges_the_unseen_logs_as_the_study_does(rig_data, tmp_path, capsys):
    """`station compare`'s θ fit of rig and of tmm-fit on each unseen 2013-14 log gives the same
    θ RMS gain as the study's simulation (both simulate the log as the rig ran it)."""
    for log in NOT_FITTED_2014:
        fits = {}
        for model in ("rig", "tmm-fit"):
            out = tmp_path / f"{model}-{log}.json"
            assert main(["compare", str(rig_data / log), "--model", model, "--json", str(out),
                         "--out-dir", str(tmp_path), "--force"]) == 0
            (run,) = json.loads(out.read_text())["runs"]
            fits[model] = run["fit_pct"]["theta"]
        capsys.readouterr()
        gain_compare = 1 - (100 - fits["rig"]) / (100 - fits["tmm-fit"])  # NRMSE fits share ‖θ − mean θ‖
        assert gain_compare == pytest.approx(_pooled_gain(rig_data, [log], "rig"), abs=1e-9)


@pytest.mark.parametrize("log", SESSION_2009)
def test_rig_2009_fits_its_session_better_than_the_2014_rig(rig_data, log):
    """The rig drifted: the 2009 logs want far less friction than the 2013-14 runs."""
    case = load_case(rig_data / log)
    assert _theta_sse(case, load_model("rig-2009")) < _theta_sse(case, load_model("rig"))


def test_rig_2009_has_less_friction_than_2014():
    old, new = load_model("rig-2009").effect_dict(), load_model("rig").effect_dict()
    assert old["coulomb_friction"] < 3.0 < new["coulomb_friction"]


def test_both_eras_have_a_negative_amplifier_offset():
    """Fitted separately on each era's own logs, the amplifier offset comes out −1.5 (2009)
    and −2.0 DAC counts (2013-14): the same sign and size (station survey shares it)."""
    for name in ("rig", "rig-2009"):
        assert -3.0 < load_model(name).effect_dict()["amp_offset"] < -1.0
