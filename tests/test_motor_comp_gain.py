"""A lead run with a gain its header does not print: the data's law, said as the header's times it.

ryanGT's Motor_Comp scripts ran v[i] = (b0·e[i] + b1·e[i−1])·gain − a1·v[i−1], v stored as a
truncated integer, and printed ``#b0=``, ``#b1=``, ``#a1=`` but not the gain. Before, such a
run's header was contradicted by the data's law with no word of how the two relate; now the
audit says the header's law times the gain (and, for the ``#b0=`` lines, that it is the gain
Motor_Comp does not print). Logs from the independent generator, their header rewritten as the
lab's script printed it (a script written from the format, not from the station).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from station.logged import LoggedRun
from tests.blind.audit import AuditCase, write_audit_case, write_case
from tests.blind.rig import DT, tustin

LEAD = ((3.0, 39.0), (1.0, 20.0))  # 3(s+13)/(s+20), the lab's April 2009 lead


def _lead_case(reference: str, alignment: int, seed: int) -> AuditCase:
    return AuditCase(name="honest:lead", law="lead", kp=None, num_s=LEAD[0], den_s=LEAD[1],
                     design_text="3(s+13)/(s+20)", recursion="trunc", alignment=alignment, limit=200.0,
                     header="lead", header_kp=None, reference=reference,
                     amplitude=100.0 if reference == "step" else 40.0, effects={"coulomb_friction": 4.0 + seed})


def _with_header(path: Path, head: list[str]) -> Path:
    """The log with its header lines replaced (the columns t n u v θ a kept)."""
    rows = ["\t".join(ln.split("\t")[:6]) for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    path.write_text("\n".join(head + ["#t\tn\tu\tv\t$\\theta$\ta"] + rows) + "\n")
    return path


def _controller(run: LoggedRun):
    return next(c for c in run.audit.claims if c.claim == "controller")


@pytest.mark.parametrize("gain,reference,alignment,seed", [
    (1.5, "step", 1, 0), (0.8, "sine", 0, 1), (2.0, "sweep", 1, 2), (0.5, "step", 0, 3)])
def test_blind_motor_comps_unprinted_gain_is_said_as_the_headers_law_times_it(tmp_path, gain, reference, alignment,
                                                                              seed):
    path, _ = write_case(tmp_path, _lead_case(reference, alignment, seed), seed)
    num, den = tustin(list(LEAD[0]), list(LEAD[1]), DT)
    _with_header(path, ["#SLFR RTP Motor_Comp", f"#b0={num[0] / gain:.10g}", f"#b1={num[1] / gain:.10g}",
                        f"#a1={den[1]:.10g}"])
    run = LoggedRun.from_path(path)
    claim = _controller(run)
    assert claim.verdict == "contradicted" and run.reproduced and run.max_abs_dv == 0.0, claim
    assert f"the header's law times {gain:g} (Motor_Comp's gain, which its #b0= lines do not print)" in claim.data
    assert claim.data.startswith("3(s+13)/(s+20)") and run.alignment == alignment


def test_blind_the_same_print_at_gain_1_is_confirmed_with_no_gain_said(tmp_path):
    path, _ = write_case(tmp_path, _lead_case("step", 1, 4), 4)
    num, den = tustin(list(LEAD[0]), list(LEAD[1]), DT)
    _with_header(path, ["#SLFR RTP Motor_Comp", f"#b0={num[0]:.10g}", f"#b1={num[1]:.10g}", f"#a1={den[1]:.10g}"])
    claim = _controller(LoggedRun.from_path(path))
    assert claim.verdict == "confirmed" and "times" not in claim.data, claim


def test_blind_a_gth_header_off_by_a_gain_says_it_without_motor_comps_words(tmp_path):
    path, _ = write_case(tmp_path, _lead_case("sine", 1, 5), 5)
    num, den = tustin(list(LEAD[0]), list(LEAD[1]), DT)
    _with_header(path, ["#SLFR RTP Motor_Comp_w_accel_fb", f"#Gth num=[{num[0] / 1.25:.8f} {num[1] / 1.25:.8f}]",
                        f"#Gth den=[1. {den[1]:.8f}]", "#Ga num=[]", "#Ga den=[]"])
    claim = _controller(LoggedRun.from_path(path))
    assert claim.verdict == "contradicted" and "; the header's law times 1.25" in claim.data, claim
    assert "Motor_Comp's gain" not in claim.data


@pytest.mark.parametrize("name", ["lie:lead_pole", "lie:p_kp"])
@pytest.mark.parametrize("seed", [0, 1])
def test_blind_another_pole_or_a_p_gain_is_not_said_as_a_times(tmp_path, name, seed):
    """Another pole is no gain apart; a P header's other gain is said as its kp already."""
    path, _ = write_audit_case(tmp_path, name, seed)
    claim = _controller(LoggedRun.from_path(path))
    assert claim.verdict == "contradicted" and "the header's law times" not in claim.data, claim
