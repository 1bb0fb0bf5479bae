"""A closed loop run at another rate than the rig's 500 Hz, replayed at its own rate.

The class of defect: a rig log sampled at another rate was refused its controller ("the rig's
controllers ran at 0.002 s, on rows this log lacks") whatever its rows were, so a loop that ran
at 250 Hz or 1 kHz, every tick logged (n counting 0, 1, 2, ...), was simulated open loop from the
logged v and its P or lead law was never checked. Rows kept from a 500 Hz loop (n jumping) are
still refused: a law with memory ran on rows the log lacks.

Truth: the blind generator (``tests.blind``: its own FEM, friction and lab controllers) run at
0.004 and 0.001 s, and the rig's own logs with every other row dropped.
"""

from __future__ import annotations

import numpy as np
import pytest

from station.logged import LoggedRun
from station.logged.units import replayable_rate
from station.replay import replay
from tests.blind.generator import COLUMNS, COLUMNS_ACCEL, _coeffs
from tests.blind.rig import gth_design, simulate


def _write(path, head, run, dt, accel_column=False):
    n = len(run.u)
    rows = [[k * dt, k, run.u[k], run.v[k], run.theta[k], run.a[k]] + ([run.theta_d_hat[k]] if accel_column else [])
            for k in range(n)]
    path.write_text("\n".join(head + ["\t".join(f"{x:.10g}" for x in r) for r in rows]) + "\n")
    return path


@pytest.mark.parametrize("dt", [0.004, 0.001])
@pytest.mark.parametrize("kind", ["p", "lead"])
def test_a_loop_run_at_another_rate_is_replayed_there(tmp_path, dt, kind):
    """The header's law (P kp = 2, or the thesis's lead printed as Tustin at the log's dt)
    reproduces every logged v at the log's own rate, and the model's loop there fits θ better
    than the logged v driven open loop did (before: 28-82 %, now 75-94 %)."""
    n = int(2.0 / dt)
    u = np.where(np.arange(n) * dt >= 0.1, 50.0 if kind == "p" else 100.0, 0.0)
    run = simulate(kind, u, {"coulomb_friction": 5.0}, np.random.default_rng(1), dt=dt)
    if kind == "p":
        head = ["#SLFR RTP P_control_Test", "#kp=2.0", COLUMNS]
    else:
        num, den = gth_design(dt)
        head = ["#SLFR RTP Motor_Comp_w_accel_fb", f"#Gth num={_coeffs(num)}", f"#Gth den={_coeffs(den)}",
                "#Ga num=[]", "#Ga den=[]", COLUMNS_ACCEL]
    path = _write(tmp_path / f"{kind}_SLFR_RTP_run.txt", head, run, dt, accel_column=kind == "lead")
    logged = LoggedRun.from_path(path)
    assert replayable_rate(logged.log) and logged.source == "header" and logged.reproduced
    assert logged.dt == pytest.approx(dt)
    rep = replay(path)
    assert rep.fit_pct["theta"] > 70.0, rep.fit_pct


def test_rows_kept_from_a_500_hz_loop_without_n_are_still_refused(rig_data, tmp_path):
    """Every other row of the rig's lead step with its n column dropped (t by 0.004 s): nothing
    tells a loop at 250 Hz from rows kept from one at 500 Hz, whose law ran on rows the log
    lacks, so no controller is replayed. (With n as counted, jumping by 2, the header's law is
    kept and run at every tick: tests/test_missing_ticks.py.)"""
    name = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
    lines = (rig_data / name).read_text().splitlines()
    head = [ln.replace("#t\tn\t", "#t\t") for ln in lines if ln.startswith("#")]
    rows = [ln.split("\t", 2)[0] + "\t" + ln.split("\t", 2)[2]
            for ln in lines if ln and not ln.startswith("#")][::2]
    assert head[-1].startswith("#t\tu\t")
    path = tmp_path / name
    path.write_text("\n".join(head + rows) + "\n")
    run = LoggedRun.from_path(path)
    assert not replayable_rate(run.log) and run.controller is None
    assert any("rows are not every tick" in note for note in run.notes)
    assert any("the model is driven by the logged v" in note for note in run.notes if "rows are not every tick" in note)


@pytest.mark.parametrize("columns", ["t\tu", "t\tu\ttheta"])
def test_a_log_with_no_v_is_not_said_to_drive_a_model(tmp_path, columns):
    """A file of t and u at 0.01 s (the lab's system-ID example, ryanGT/systemid
    ``fixed_sine.txt``): no controller can be replayed, and no model can be driven by a v the
    log does not have; before, its note said "the model is driven by the logged v"."""
    t = np.arange(100) * 0.01
    rows = [[x, 50.0 * np.sin(2 * np.pi * x)] + ([3.0 * x] if "theta" in columns else []) for x in t]
    path = tmp_path / "fixed_sine.txt"
    path.write_text(columns + "\n" + "\n".join("\t".join(f"{x:.10g}" for x in r) for r in rows) + "\n")
    run = LoggedRun.from_path(path)
    assert run.controller is None
    said = [note for note in run.notes if "replayed" in note]
    assert said and not any("driven by the logged v" in note for note in said)
    assert any("no model can run on it (no usable v)" in note for note in said)
