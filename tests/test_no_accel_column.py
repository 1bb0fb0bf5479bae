"""A log without an accelerometer column is simulated and its θ fitted.

A lab log of a P or lead run that never recorded a (the 2014 layout's columns cut, a script
that logged the encoder only) was refused by `station replay`, `compare` and `survey`: "no 'a'
column: simulating it on a model ... needs u, theta, a", although the closed loop never reads
a and the model makes its own. The invariant: what a use needs is what it reads. Simulating a
run needs what drives it and θ; a is needed by a law that feeds it back and by the sensor audit
(a diagnosis fits θ alone). Truth: the rig's own logs with the a column cut, against the same
logs whole (the θ fit cannot depend on a column the simulation does not read; the 2014 sweep,
run with the accelerometer off the beam, is simulated without its mass as the whole log is: the
mounting is decided from θ/v, and was asked only when an a column read no tip acceleration).
"""

from __future__ import annotations

import pytest

from station.compare import compare_run, format_comparison
from station.diagnosis.runs.cases import load_case
from station.errors import StationError
from station.logged import LoggedRun
from station.plant import load_model
from station.plots import plot_comparison
from station.replay import format_report, replay
from station.survey import format_table, survey_one

P = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
LEAD = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
SWEEP_2014 = "without_accel_01_28_14_test_2.txt"


def _without_a(src, dst):
    """``src`` with its a column (the rig layout's sixth, the 2014 layout's 'accel') cut."""
    lines = src.read_text().splitlines()
    out = []
    if lines[0].startswith("#"):  # the rig layout: t n u v θ a [θ̂_d]
        for ln in lines:
            out.append("#t\tn\tu\tv\t$\\theta$" if ln.startswith("#t") else ln if ln.startswith("#")
                       else "\t".join(ln.split("\t")[:5]))
    else:  # the 2014 layout: a column line naming them
        k = lines[0].split("\t").index("accel")
        out = ["\t".join(c for i, c in enumerate(ln.split("\t")) if i != k) for ln in lines]
    dst.write_text("\n".join(out) + "\n")
    return dst


@pytest.mark.parametrize("name", [P, LEAD, SWEEP_2014])
def test_a_log_without_a_gets_the_theta_fit_of_the_whole_log(rig_data, tmp_path, name):
    path = _without_a(rig_data / name, tmp_path / name)
    assert not LoggedRun.from_path(path).has_column("a")
    whole, cut = replay(rig_data / name), replay(path)
    assert cut.fit_pct["theta"] == pytest.approx(whole.fit_pct["theta"], abs=1e-9)
    assert cut.fit_pct["accel"] is None and whole.fit_pct["accel"] is not None
    text = format_report(cut)
    assert "accel n/a" in text and "the log has no a column" in text, text
    compared = compare_run(path, load_model("tmm-fit"))
    assert compared.fit_pct["theta"] == pytest.approx(whole.fit_pct["theta"], abs=1e-9)
    assert compared.fit_pct["accel"] is None and "fit a %" in format_comparison(compared)
    plot_comparison(compared, tmp_path / "cut.png")
    assert (tmp_path / "cut.png").stat().st_size > 0
    row = survey_one(path)
    assert row.status != "unusable" and row.fit_accel_pct is None
    assert f"fit theta {row.fit_theta_pct:.1f} %, a -" in format_table([row])


def test_a_law_that_feeds_a_back_still_needs_it(rig_data, tmp_path):
    path = _without_a(rig_data / LEAD_ACCEL, tmp_path / LEAD_ACCEL)
    with pytest.raises(StationError, match=r"no 'a' column: replaying its controller \(lead-accel\) needs"):
        replay(path)
    with pytest.raises(StationError, match=r"no 'a' column: a diagnosis .* needs u, theta, v, a"):
        load_case(path)
    # a lead loop never reads a: a diagnosis fits its θ alone (tests/test_theta_only.py)
    lead = load_case(_without_a(rig_data / LEAD, tmp_path / LEAD))
    assert not lead.fits_a and lead.kind == "lead" and "the log has no a column: its θ alone is fitted" in lead.notes
