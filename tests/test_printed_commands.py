"""A command column printed to few digits: a law is judged to the log's printing.

A script that writes its log with ``%g`` (6 significant digits) or MATLAB's ``csvwrite`` (5)
prints a lead's float command 183.2547182 as 183.255 or 183.25. Judged to 1e-6 counts, the
thesis's own lead was "not this law" (θ fit −485 %), and under an open-loop header no law was
found. The truth here: the rig's logs re-printed by a script written from the format (not
by the station's writer), the printing module against Python's own ``%`` formatting, and the
blind generator's lab controller for the designs.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.control.rerun import command_error, printed_commands
from station.logged import LoggedRun
from station.plant import load_model
from station.runlog.printing import printing_of
from tests.blind.audit import write_audit_case

LEAD = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
THESIS_LEAD = "20(s+2π·5)/(s+2π·20)"


@pytest.mark.parametrize("fmt, digits, decimals", [("%.6g", 6, None), ("%.5g", 5, None), ("%.4g", 4, None),
                                                   ("%.2f", None, 2), ("%.4f", None, 4)])
def test_a_printing_is_decided_from_the_values(fmt, digits, decimals):
    x = np.random.default_rng(3).uniform(-200.0, 200.0, 500)
    printed = np.array([float(fmt % v) for v in x])
    p = printing_of(printed)
    assert p is not None
    if digits is not None:
        assert p.significant and p.digits == digits and p.text() == f"{digits} significant digits"
    else:
        assert not p.significant and p.decimals == decimals and p.text() == f"{decimals} decimals"
    # the printing's resolution bounds every value's printing error, and is no looser than a digit
    res = p.resolution(x)
    assert np.all(np.abs(printed - x) <= res * (1 + 1e-9))
    assert np.max(np.abs(printed - x) / res) > 0.9


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-255, 255, allow_nan=False), min_size=20, max_size=60), st.integers(3, 9))
def test_resolution_bounds_the_printing_error(values, digits):
    x = np.array(values)
    printed = np.array([float(f"{v:.{digits}g}") for v in x])
    p = printing_of(printed)
    if p is None:  # whole numbers, or fewer than MIN_VALUES that are not
        return
    assert np.all(np.abs(printed - x) <= p.resolution(x) * (1 + 1e-9) + 1e-12)


def test_whole_counts_and_full_floats_have_no_printing():
    rng = np.random.default_rng(0)
    assert printing_of(np.round(rng.uniform(-200, 200, 300))) is None  # integer commands
    assert printing_of(rng.uniform(-200, 200, 300)) is None  # repr: 17 digits
    assert printing_of(np.array([0.5, 1.5, 2.0] * 3)) is None  # fewer than MIN_VALUES not whole
    # the lab's own %0.10g: finer than a law's 1e-6 counts, so compared as computed
    lab = np.array([float("%0.10g" % v) for v in rng.uniform(-200, 200, 300)])
    assert printing_of(lab) is not None and printed_commands(lab) is None


def test_a_printed_law_is_judged_to_half_its_last_digit_no_more():
    rng = np.random.default_rng(1)
    law = rng.uniform(-150, 150, 400)
    printed = np.round(law, 2)
    assert np.max(command_error(law, printed)) == 0.0
    # a law 0.01 off everywhere is another law at 2 decimals (a P law's dead-band-like bend)
    assert np.max(command_error(law + 0.01, printed)) > 0.004
    # whole counts: any difference counts
    assert np.max(command_error(law, np.round(law))) > 0.4


def _reprint(src, dst, digits, header=None, swap=False, drop=()):
    """The rig's log re-printed by a script: every number to ``digits`` significant digits,
    optionally another header, u and v swapped, rows dropped."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln.split() for ln in lines if ln.strip() and not ln.startswith("#")]
    if header is not None:
        head = header + head[-1:]
    out = []
    for i, r in enumerate(rows):
        if i in drop:
            continue
        vals = [float(x) for x in r]
        if swap:
            vals[2], vals[3] = vals[3], vals[2]
        out.append("\t".join(f"{x:.{digits}g}" for x in vals))
    dst.write_text("\n".join(head + out) + "\n")
    return dst


@pytest.fixture(scope="module")
def clean(rig_data):
    return LoggedRun.from_path(rig_data / LEAD)


@pytest.mark.parametrize("digits", [5, 6])
def test_the_thesis_lead_printed_to_few_digits_is_its_lead(rig_data, tmp_path, clean, digits):
    run = LoggedRun.from_path(_reprint(rig_data / LEAD, tmp_path / f"lead{digits}.txt", digits))
    claim = next(c for c in run.audit.claims if c.claim == "controller")
    assert claim.verdict == "confirmed" and f"to its printing ({digits} significant digits)" in claim.evidence
    assert run.source == "header" and run.reproduced and run.alignment == 1
    assert any(n.startswith(f"v is printed to {digits} significant digits") for n in run.notes)
    model = load_model("tmm-fit")
    fits, ref = run.simulate(model).fit_pct, clean.simulate(model).fit_pct
    assert fits["theta"] == pytest.approx(ref["theta"], abs=0.05)


@pytest.mark.parametrize("digits, swap, drop", [(6, False, ()), (5, False, ()), (6, True, ()),
                                                (6, False, tuple(range(300, 312)) + tuple(range(700, 705)))])
def test_the_thesis_lead_printed_under_an_open_loop_header_is_inferred(rig_data, tmp_path, digits, swap, drop):
    path = _reprint(rig_data / LEAD, tmp_path / "ol.txt", digits, ["#SLFR RTP OL_Test"], swap, drop)
    run = LoggedRun.from_path(path)
    assert run.source == "inferred (header contradicted)" and run.reproduced
    assert run.controller.spec["design"]["text"] == THESIS_LEAD
    assert run.controller.spec["design"]["alternatives"] == []
    swapped = [c for c in run.audit.claims if c.data == "u and v swapped"]
    assert bool(swapped) is swap
    jumps = [c for c in run.audit.claims if c.data.startswith("n jumps")]
    assert bool(jumps) is bool(drop)


@pytest.mark.parametrize("seed", range(10))
def test_blind_printed_logs(tmp_path, seed):
    # a lead on the float under its true header or an open-loop one, every number printed to 5
    # or 6 significant digits by the blind generator (its own FEM, lab controller and writer)
    path, hidden = write_audit_case(tmp_path, "printed", seed)
    run = LoggedRun.from_path(path)
    controller = next(c for c in run.audit.claims if c.claim == "controller")
    assert (controller.verdict == "contradicted") is hidden.lies
    assert run.reproduced and run.alignment == hidden.alignment
    if hidden.lies:
        design = run.controller.spec["design"]
        np.testing.assert_allclose(design["num_s"], hidden.num_s, rtol=1e-9)
        np.testing.assert_allclose(design["den_s"], hidden.den_s, rtol=1e-9)
    assert not [c for c in run.audit.claims if c.claim == "columns" and c.verdict == "contradicted"]
