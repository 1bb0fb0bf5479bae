"""Step metrics against the thesis's experimental table (from the rig logs) and by hand;
NRMSE fit by hand."""

import math

import numpy as np
import pytest

from station.analysis.fit import nrmse_fit
from station.analysis.metrics import step_metrics
from station.runlog import read_log

# DESIGN.md: the thesis's experimental table, reproduced exactly from the rig logs.
TABLE = [
    ("SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt", 24.00, 1.250),
    ("step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt", 10.00, None),
    ("step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt", 21.50, 0.608),
]


@pytest.mark.parametrize("name, overshoot, settling", TABLE)
def test_thesis_table_from_rig_logs(rig_data, name, overshoot, settling):
    log = read_log(rig_data / name)
    m = step_metrics(log.data["t"], log.data["theta"], log.data["u"][-1])
    assert round(m.overshoot_pct, 2) == overshoot
    if settling is None:
        assert m.settling_time_s is None
    else:
        assert m.settling_time_s == pytest.approx(settling, abs=1e-9)


def test_settling_by_hand():
    t = np.arange(8) * 0.1
    # u_final 50: band max(0.5, 1) = 1 count. Last outside (|53-50| = 3 > 1) is index 3;
    # |51 - 50| = 1 is inside (strictly greater is outside).
    theta = np.array([0, 30, 60, 53, 51, 49, 50, 50])
    m = step_metrics(t, theta, 50.0)
    assert m.overshoot_pct == pytest.approx(20.0)
    assert m.settling_time_s == pytest.approx(0.4)
    # band is 1 % when that exceeds one count: u_final 400 -> 4 counts
    m = step_metrics(t, np.array([0, 300, 420, 405, 404, 396, 400, 400]), 400.0)
    assert m.settling_time_s == pytest.approx(0.4)
    assert step_metrics(t[:4], theta[:4], 50.0).settling_time_s is None  # ends at 53: outside


def test_not_settled_when_last_sample_outside():
    assert step_metrics([0.0, 0.1, 0.2], [0, 50, 52], 50.0).settling_time_s is None


def test_negative_step_and_always_inside():
    m = step_metrics([0.0, 0.1, 0.2, 0.3], [0, -110, -100, -100], -100.0)
    assert m.overshoot_pct == pytest.approx(10.0)
    assert m.settling_time_s == pytest.approx(0.2)
    assert step_metrics([0.5, 0.6], [100, 100], 100.0).settling_time_s == 0.5


def test_step_metrics_rejects_bad_input():
    with pytest.raises(ValueError, match="non-zero"):
        step_metrics([0.0, 0.1], [0, 0], 0.0)
    with pytest.raises(ValueError, match="same"):
        step_metrics([0.0, 0.1], [0], 1.0)


def test_nrmse_fit_by_hand():
    y = np.array([1.0, 2.0, 3.0, 4.0])            # ||y - mean|| = sqrt(5)
    assert nrmse_fit(y, y) == 100.0
    assert nrmse_fit(y, np.full(4, 2.5)) == pytest.approx(0.0)
    yhat = y + np.array([1.0, 0.0, 0.0, 0.0])      # ||err|| = 1
    assert nrmse_fit(y, yhat) == pytest.approx(100 * (1 - 1 / math.sqrt(5)))
    assert nrmse_fit(y, -y) < 0
    assert math.isnan(nrmse_fit(np.ones(3), np.zeros(3)))
    with pytest.raises(ValueError, match="shape"):
        nrmse_fit(y, y[:3])


def test_a_run_still_swinging_at_its_end_has_not_settled():
    """±7 counts at 2.5 Hz around the step to the run's end: its last few samples cross the
    1-count band, which is not settling (it was "settled at 1.99 s" when only the last
    sample outside counted)."""
    from station.analysis.metrics import step_info

    t = np.arange(1000) * 0.002
    theta = np.round(100 + 7 * np.sin(2 * np.pi * 2.5 * (t - t[-1])))
    assert abs(theta[-1] - 100) <= 1 and np.max(np.abs(theta[-100:] - 100)) >= 6  # crossing, still swinging
    assert step_metrics(t, theta, 100.0).settling_time_s is None
    assert step_info(t, theta, 100.0).settling_time_2pct_s is None


def test_exactly_on_the_band_edge_is_inside_for_both_bands():
    """θ settling 1 count off a 50-count step: 1 count is the edge of both the thesis's band
    (max(1 %, 1 count)) and the 2 % band; strictly greater is outside in both, so both
    report the same settling sample (python-control alone counted the edge as outside)."""
    from station.analysis.metrics import step_info

    t = np.arange(1000) * 0.002
    theta = np.r_[np.zeros(10), [30, 45, 60, 55, 48], np.full(985, 51.0)]
    m = step_metrics(t, theta, 50.0)
    info = step_info(t, theta, 50.0, step_time=0.02)
    assert m.settling_time_s == pytest.approx(0.030)
    assert info.settling_time_2pct_s == pytest.approx(m.settling_time_s - 0.02)


def test_settled_needs_the_minimum_hold():
    from station.analysis.metrics import SETTLE_HOLD_S, settled_index

    t = np.arange(200) * 0.002
    need = round(SETTLE_HOLD_S / 0.002)  # 50 samples
    for inside, settled in ((need, True), (need - 1, False)):
        y = np.r_[np.full(200 - inside, 10.0), np.zeros(inside)]
        assert (settled_index(t, y, 0.0, 1.0) == 200 - inside) if settled else settled_index(t, y, 0.0, 1.0) is None


def test_a_response_that_never_reached_the_step_says_so():
    """A fuzzing round: a 0.1 s step printed 'overshoot -29.00 %' beside 'rise n/a'."""
    import numpy as np

    from station.analysis.metrics import step_metrics

    t = np.arange(50) * 0.002
    m = step_metrics(t, np.minimum(np.arange(50.0), 35.5), 50.0)  # peaks at 71 % of the step
    assert m.overshoot_pct == pytest.approx(-29.0)
    assert m.overshoot_words() == "overshoot -29.00 % (θ never reached the step: its peak 71 % of it)"
    assert step_metrics(t, np.full(50, 60.0), 50.0).overshoot_words() == "overshoot 20.00 %"
