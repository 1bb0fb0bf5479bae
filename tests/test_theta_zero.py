"""θ written as the encoder read it, where the loop took its starting count off.

The lab's client reads θ0 at START (``q``) and its loop's error is u − (θ − θ0); a script that
logs the encoder's count as read writes θ from θ0. Before, the audit took the loop's error as
u − θ (the encoder "not zeroed"): the rig's P step so written (θ0 = −59) was read as a law
2(s+5e-12)/(s+2e-12) carrying the offset as the memory of a run "cut from a longer one", its
overshoot and settling not found and its θ fit −342 %; the thesis's lead step said "no law
found" and simulated open loop (θ fit −239 %). The rig's logs are rewritten by a script written
from the format; the blind generator's "theta_zero" class (tests/blind/audit.py) simulates the
loop on θ − θ0 with its own FEM and lab controller.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station.logged import LoggedRun
from station.plant import load_model

P = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
LEAD = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
P_2009 = "2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt"
LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
CLAIM = "θ as the loop's error used it"


def _from(src: Path, dst: Path, zero: float, header: str = "true") -> Path:
    """The rig's log with θ (the fifth column: t n u v θ a ...) written from ``zero``; its
    header kept ("true"), an open-loop one ("open-loop"), or none but the column line ("none")."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = []
    for ln in lines:
        if ln.strip() and not ln.startswith("#"):
            f = ln.split()
            f[4] = f"{float(f[4]) + zero:g}"
            rows.append("\t".join(f))
    head = {"true": head, "open-loop": ["#SLFR RTP OL_Test"] + head[-1:], "none": head[-1:]}[header]
    dst.write_text("\n".join(head + rows) + "\n")
    return dst


def _zeros(run: LoggedRun) -> list[str]:
    return [c.data for c in run.audit.claims if c.claim == "columns" and c.header == CLAIM]


@pytest.mark.parametrize("name, zero, header", [
    (name, zero, header) for name, zero in [(P, -59.0), (LEAD, -59.0), (P_2009, 137.0), (P, 3.0)]
    for header in ("true", "open-loop", "none")] + [(LEAD_ACCEL, -59.0, "true")])
def test_theta_from_the_encoders_starting_count_is_read_from_it(rig_data, tmp_path, name, zero, header):
    """θ0 said exactly, the law the clean log's (the header's, or the data's under an open-loop
    header or none), and the step's numbers and the model's θ fit those of the clean log. The
    lead + accelerometer step's v moves at rest (Ga on a's noise): θ and u say the rest."""
    clean = LoggedRun.from_path(_from(rig_data / name, tmp_path / "clean.txt", 0.0, header))
    run = LoggedRun.from_path(_from(rig_data / name, tmp_path / "from.txt", zero, header))
    assert _zeros(run) == [f"θ logged before its zero was taken off (θ0 = {zero:g} counts)"]
    assert _zeros(clean) == []
    assert run.reproduced and run.source == clean.source
    assert run.controller.name == clean.controller.name
    np.testing.assert_array_equal(run.log.data["theta"], clean.log.data["theta"])
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=1e-9)
    assert not any("not zeroed" in line for line in run.audit.lines())


def test_a_p_header_that_lies_beside_theta_from_its_starting_count(rig_data, tmp_path):
    """Two claims at once: ``#kp=3.0`` over the rig's kp = 2, and θ written from −59. The lie
    said, the data's kp = 2 found on θ − θ0 (before: the integrator law of a "cut" run)."""
    path = _from(rig_data / P, tmp_path / "lie.txt", -59.0)
    path.write_text(path.read_text().replace("kp=2.0", "kp=3.0"))
    run = LoggedRun.from_path(path)
    assert _zeros(run) == ["θ logged before its zero was taken off (θ0 = -59 counts)"]
    assert run.source == "inferred (header contradicted)" and run.controller.spec["kp"] == 2.0
    assert run.step_metrics().overshoot_pct == pytest.approx(24.0)


def test_an_encoder_not_zeroed_under_a_loop_on_its_count_is_no_such_fault(tmp_path, monkeypatch):
    """The blind generator's P loop run on the encoder's count as read, 59 counts off the hub's
    zero (the encoder not zeroed, no count taken off): the law reproduces θ as written, and θ is
    not read from its first sample."""
    import tests.blind.audit as blind

    real = blind.encoder
    monkeypatch.setattr(blind, "encoder", lambda th: real(th) + 59)
    path, hidden = blind.write_audit_case(tmp_path, "honest:p", 0)
    run = LoggedRun.from_path(path)
    assert run.log.data["theta"][0] == 59.0
    assert _zeros(run) == []
    assert run.source == "header" and run.reproduced


@pytest.mark.parametrize("case, seed", [("theta_zero", 3), ("theta_zero", 5), ("theta_zero", 2), ("theta_zero", 8),
                                        ("theta_zero+coulomb_friction", 1), ("theta_zero+coulomb_friction", 6)])
def test_blind_theta_from_the_encoders_starting_count(tmp_path, case, seed):
    """The independent generator's P and leads under a true header, none (the 2014 layout) or the
    lab's session's open-loop one, the loop on θ − θ0 and θ written as read: θ0 said exactly,
    the law confirmed or inferred, and the design named where inferred (seed 8: 2(s+22)/(s+32),
    once named with a cancelled pair (s+1000)/(s+1000), Tustin's z = 0, beside it)."""
    import tests.blind.audit as blind

    path, hidden = blind.write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    assert _zeros(run) == [f"θ logged before its zero was taken off (θ0 = {hidden.theta_zero:g} counts)"]
    assert run.source == {"none": "inferred", "open-loop": "inferred (header contradicted)"}.get(hidden.header, "header")
    assert run.reproduced
    assert run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments
    if hidden.header in ("none", "open-loop"):
        np.testing.assert_allclose(run.controller.spec["design"]["num_s"], hidden.num_s, rtol=1e-9)
        np.testing.assert_allclose(run.controller.spec["design"]["den_s"], hidden.den_s, rtol=1e-9)
