"""The shipped rig models against the rig's own logs (independent truth: measured data,
the thesis's overshoot table), including logs they were not fitted to (docs/diagnosis.md)."""

import math

import numpy as np
import pytest

from station.analysis.metrics import step_metrics
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


def _theta_rms(case, model) -> float:
    theta, _ = simulate_case(case, model)
    return math.sqrt(float(np.mean((case.theta - theta) ** 2)))


@pytest.mark.parametrize("log", sorted(THESIS_STEPS))
def test_rig_model_step_overshoots_near_the_rig(rig_data, log):
    """The thesis's FEM misses the P step by 14 points; the rig model is within 3 of every step
    (issue 17's target: 24.0 / 12.0 / 19.5 % against 24.0 / 10.0 / 21.5 %)."""
    case = load_case(rig_data / log)
    theta, _ = simulate_case(case, load_model("rig"))
    u = np.asarray(case.run.data["u"], float)
    got = step_metrics(np.arange(case.n) * case.run.dt, theta, float(u[-1])).overshoot_pct
    assert abs(got - THESIS_STEPS[log]) <= 3.0


@pytest.mark.parametrize("log", NOT_FITTED_2014 + SESSION_2009)
def test_rig_model_beats_the_nominal_on_logs_it_was_not_fitted_to(rig_data, log):
    """Fitted on the four thesis logs; better than tmm-fit on every other rig log of both eras."""
    case = load_case(rig_data / log)
    assert _theta_rms(case, load_model("rig")) < _theta_rms(case, load_model("tmm-fit"))


def test_rig_model_pooled_gain_on_logs_it_was_not_fitted_to(rig_data):
    """Pooled over the six unseen logs of both eras, θ RMS 29.5 % below tmm-fit's (the
    noise-weighted fit's drive_c 2.0 + Coulomb 15.9 was 5.4 % worse than tmm-fit there)."""
    num = den = 0.0
    for log in NOT_FITTED_2014 + SESSION_2009:
        case = load_case(rig_data / log)
        num += _theta_rms(case, load_model("rig")) ** 2 * case.n
        den += _theta_rms(case, load_model("tmm-fit")) ** 2 * case.n
    assert 1 - math.sqrt(num / den) >= 0.25


@pytest.mark.parametrize("log", SESSION_2009)
def test_rig_2009_fits_its_session_better_than_the_2014_rig(rig_data, log):
    """The rig drifted: the 2009 logs want far less friction than the 2013-14 runs."""
    case = load_case(rig_data / log)
    assert _theta_rms(case, load_model("rig-2009")) < _theta_rms(case, load_model("rig"))


def test_rig_2009_has_less_friction_than_2014():
    old, new = load_model("rig-2009").effect_dict(), load_model("rig").effect_dict()
    assert old["coulomb_friction"] < 3.0 < new["coulomb_friction"]
