"""A header that names Ga over a loop whose Ga, stored as a whole count, never acted.

The lab's 2009 software (ryanGT's SLFR_RTP, ``Motor_Comp_w_accel_fb``) kept v, θ̂_d and
Ga's output in int32 arrays: Ga's recursion stored its output truncated and remembered it.
The thesis's Ga adds less than a count per tick, so the stored output is 0 on every row and
the loop ran the lead alone. Before, such a log's true header was "contradicted" (the header's
law on the float replays v 236 counts off) with no word of why; now the header is confirmed,
completed from the data, and the audit says that the feedback it names did nothing. Logs from
the independent generator (its own FEM, lab controller and writer), never from the station.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from station.analysis.header_law import idle_ga
from station.control import Compensator, DiscreteTF, lead_controller
from station.logged import LoggedRun
from tests.blind.audit import GA_S, AuditCase, write_case

THESIS_LEAD = ((20.0, 20.0 * 2 * math.pi * 5), (1.0, 2 * math.pi * 20))
IDLE = "the accelerometer feedback it names did nothing"


def _case(reference: str, alignment: int, ga_recursion: str = "trunc", recursion: str = "trunc",
          effects=None) -> AuditCase:
    return AuditCase(name="idle_ga", law="lead", kp=None, num_s=THESIS_LEAD[0], den_s=THESIS_LEAD[1],
                     design_text="20(s+2π·5)/(s+2π·20)", recursion=recursion, alignment=alignment, limit=200.0,
                     header="lead", header_kp=None, reference=reference,
                     amplitude=100.0 if reference == "step" else 40.0, effects=dict(effects or {}), ga_s=GA_S,
                     ga_recursion=ga_recursion)


def _controller_claim(run: LoggedRun):
    return next(c for c in run.audit.claims if c.claim == "controller")


@pytest.mark.parametrize("reference,alignment,effects,seed", [
    ("step", 1, {}, 0), ("step", 0, {"coulomb_friction": 8.0}, 1), ("sine", 1, {"coulomb_friction": 5.0}, 2),
    ("sweep", 0, {}, 3), ("sweep", 1, {"coulomb_friction": 12.0}, 4)])
def test_blind_a_header_ga_stored_as_truncated_zero_is_confirmed_and_said_idle(tmp_path, reference, alignment,
                                                                               effects, seed):
    path, case = write_case(tmp_path, _case(reference, alignment, effects=effects), seed)
    rows = np.loadtxt(path, comments="#")
    assert np.array_equal(rows[:, 6], rows[:, 2]), "the generator's Ga acted: not the case under test"
    run = LoggedRun.from_path(path)
    claim = _controller_claim(run)
    assert claim.verdict == "confirmed" and run.source == "header", claim
    assert IDLE in claim.data and "truncated whole count (as the lab's int32 arrays" in claim.data, claim.data
    assert "the data's law has the header's Gth coefficients" in claim.evidence, claim.evidence
    assert run.reproduced and run.max_abs_dv == 0.0 and run.alignment == alignment
    assert run.controller.ga is None and run.controller.recursion == "trunc"
    assert not [c for c in run.audit.claims if c.verdict == "contradicted"]


def test_blind_a_rounded_command_says_its_ga_rounded_not_the_int32_arrays(tmp_path):
    path, _ = write_case(tmp_path, _case("step", 1, ga_recursion="round", recursion="round"), 5)
    run = LoggedRun.from_path(path)
    claim = _controller_claim(run)
    assert claim.verdict == "confirmed" and IDLE in claim.data and "rounded whole count" in claim.data, claim.data
    assert "int32" not in claim.data


def test_blind_a_ga_header_over_a_float_lead_alone_stays_contradicted(tmp_path):
    """Software that kept the float command kept Ga's output a float too: a Ga header over a
    loop without it is a lie there, whatever Ga's output would have been stored as."""
    case = dataclasses.replace(_case("step", 1, ga_recursion="none", recursion="none"), ga_s=None,
                               name="rows:column")
    path, _ = write_case(tmp_path, case, 6)
    text = path.read_text().replace("#Ga num=[]", "#Ga num=[ 0.00045097  0.00045152 -0.00044989 -0.00045043]")
    path.write_text(text.replace("#Ga den=[]", "#Ga den=[ 1.         -2.9289362   2.85853684 -0.92960052]"))
    run = LoggedRun.from_path(path)
    claim = _controller_claim(run)
    assert claim.verdict == "contradicted" and IDLE not in claim.data, claim
    assert run.reproduced and run.controller.ga is None


def test_idle_ga_needs_every_stored_output_zero_and_the_headers_gth():
    """The rule itself on hand-made a: one tick whose sum reaches a whole count makes Ga act;
    another Gth than the header's is another law, not an idle Ga; a float recursion kept no
    int32 arrays."""
    stated = lead_controller(accel=True)

    def alone(recursion: str, gain: float = 1.0) -> Compensator:
        return Compensator(DiscreteTF(stated.gth.num * gain, stated.gth.den), None, recursion=recursion)

    b0 = float(stated.ga.num[0] / stated.ga.den[0])
    quiet = np.zeros(50)
    quiet[10] = 0.99 / b0  # the sum at tick 10 is 0.99 counts: truncated to 0
    assert idle_ga(stated, alone("trunc"), quiet, 0) is not None
    assert idle_ga(stated, alone("trunc"), quiet, 1) is not None
    loud = quiet.copy()
    loud[10] = 1.01 / b0
    assert idle_ga(stated, alone("trunc"), loud, 0) is None
    assert idle_ga(stated, alone("trunc"), loud, 1) is None  # the alignment shifts it; the tick still counts
    assert idle_ga(stated, alone("trunc"), loud, 40) is not None  # ... unless it falls past the run's end
    half = np.zeros(50)
    half[10] = 0.5 / b0
    assert idle_ga(stated, alone("round"), half, 0) is None and idle_ga(stated, alone("trunc"), half, 0) is not None
    assert idle_ga(stated, alone("trunc", gain=1.1), quiet, 0) is None
    assert idle_ga(stated, alone("none"), quiet, 0) is None
    assert idle_ga(lead_controller(), alone("trunc"), quiet, 0) is None  # the header names no Ga
