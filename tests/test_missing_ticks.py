"""A copy that keeps every other tick of a 500 Hz loop, n and t as the loop counted them (a
logger at 250 Hz; :mod:`station.logged.missing_ticks`): the header's law judged on what its
rows can say, and the model run at every tick.

Truth: the rig's own logs (the copy's fit against the whole log's), and the independent blind
generator (``tests/blind/archive.py``: its own FEM and its own P and lead laws at every tick,
a header that may lie about kp). Before, such a copy was "closed-loop commands cannot be
replayed" and its model driven open loop by the held v: θ fit −34.9 % on the P step (69.4 %
on the whole log), 42.9 % on the lead.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from station.logged import LoggedRun
from station.logged.missing_ticks import TURN_COUNTS, _bracket
from station.plant.model import load_model
from station.replay import format_report, replay
from tests.blind.archive import write_kept_ticks
from tests.rig_logs import ACCEL_LOG, LEAD_LOG, P_LOG, SWEEP_LOG



@pytest.fixture(scope="module")
def nominal():
    return load_model("tmm-fit")


def _keep(src, dst, rows, header=None):
    """The log at ``src`` with only ``rows`` of its data kept (every digit as written), its
    header lines passed through ``header``."""
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    data = [x for x in lines if not x.startswith("#")]
    dst.write_text("\n".join([header(x) for x in head] if header else head) + "\n"
                   + "\n".join(data[k] for k in rows) + "\n")
    return dst


def _claim(run):
    return run.audit.of("controller")


def _theta_fit(run, model):
    return run.simulate(model).fit_pct["theta"]


@pytest.mark.parametrize("name, law, judged", [(P_LOG, "P, kp = 2", True), (SWEEP_LOG, "P, kp = 1", True),
                                                (LEAD_LOG, "lead", False), (ACCEL_LOG, "lead", False)])
@pytest.mark.parametrize("start, every", [(0, 2), (1, 2), (0, 5), (3, 10)])
def test_a_copy_of_every_kth_tick_keeps_the_headers_law_and_fits_as_the_whole_log(
        rig_data, tmp_path, nominal, name, law, judged, start, every):
    src = rig_data / name
    whole = LoggedRun.from_path(src)
    copy = LoggedRun.from_path(_keep(src, tmp_path / name, range(start, len(whole), every)))
    claim = _claim(copy)
    assert copy.closed and copy.source == "header" and law in claim.header
    if judged:  # P: every logged v within the law's range over θ at the tick it used
        assert claim.verdict == "confirmed" and copy.max_abs_dv == 0 and copy.identified.judged_to is None
        assert copy.alignment == whole.alignment
    else:  # a law with memory: not judged on rows without the ticks between them, and said so
        assert claim.verdict == "unchecked" and copy.identified.judged_to == 0
        assert "not judged" in claim.data and "interpolated" in claim.evidence
    # the model runs the law at every tick: the copy's θ fit is the whole log's, to 2 points
    # every other tick (a step at a tick the copy lacks is held a tick late: 1.5 points on the
    # lead from row 1), to 7 every 10th (the sweep's 20 Hz end seen at 50 Hz: 49.5 against 55.7)
    assert abs(_theta_fit(copy, nominal) - _theta_fit(whole, nominal)) < (2.0 if every == 2 else 7.0)
    assert "on the log's ticks" in copy.simulate(nominal).how and "u held" in copy.simulate(nominal).how


def test_replay_of_a_law_with_memory_on_kept_rows_says_not_judged_not_a_miss(rig_data, tmp_path):
    src = rig_data / LEAD_LOG
    path = _keep(src, tmp_path / "lead.txt", range(0, 1000, 2))
    report = replay(path, model=False)
    text = format_report(report)
    assert "replay not judged: the law's memory ran on ticks the log lacks" in text
    assert "does NOT reproduce" not in text
    assert report.reproduced is None and report.to_json()["reproduced"] is None
    assert report.to_json()["audit"][0]["verdict"] == "unchecked"


@pytest.mark.parametrize("kp", ["3.0", "1.5", "2.1"])
def test_a_p_header_with_the_wrong_kp_is_contradicted_on_kept_rows(rig_data, tmp_path, kp):
    src = rig_data / P_LOG
    path = _keep(src, tmp_path / "p.txt", range(0, 1000, 2), lambda x: re.sub(r"kp=2\.0", f"kp={kp}", x))
    claim = _claim(LoggedRun.from_path(path))
    assert claim.verdict == "contradicted" and claim.data.startswith("not this law")


@pytest.mark.parametrize("seed", range(6))
def test_rows_missing_at_random_still_confirm_the_rigs_p_law_and_refute_another_kp(rig_data, tmp_path, seed):
    # property: whichever ticks a logger lost (at most one in a row, as row_ticks places them)
    rng = np.random.default_rng(seed)
    keep, k = [], 0
    while k < 1000:
        keep.append(k)
        k += 1 + int(rng.random() < 0.6)
    src = rig_data / P_LOG
    run = LoggedRun.from_path(_keep(src, tmp_path / "p.txt", keep))
    assert _claim(run).verdict == "confirmed" and run.alignment == 1
    lie = LoggedRun.from_path(_keep(src, tmp_path / "lie.txt", keep, lambda x: x.replace("kp=2.0", "kp=2.5")))
    assert _claim(lie).verdict == "contradicted"


@pytest.mark.parametrize("kp, alignment, start, every", [(2.0, 1, 0, 2), (1.5, 0, 1, 2), (3.0, 1, 1, 2),
                                                         (1.0, 0, 0, 2), (2.0, 1, 2, 5), (1.5, 0, 0, 10)])
def test_blind_p_steps_logged_every_kth_tick(tmp_path, nominal, kp, alignment, start, every):
    path, hidden, _ = write_kept_ticks(tmp_path, 7, "p_step", every, start, kp=kp, alignment=alignment)
    run = LoggedRun.from_path(path)
    assert _claim(run).verdict == "confirmed" and run.controller.spec.get("kp") == kp
    assert alignment in run.identified.alignments
    lie_path, _, _ = write_kept_ticks(tmp_path / "lie", 7, "p_step", every, start, kp=kp, header_kp=kp * 1.3,
                                      alignment=alignment)
    assert _claim(LoggedRun.from_path(lie_path)).verdict == "contradicted"


@pytest.mark.parametrize("start", [0, 1])
def test_blind_lead_step_logged_every_other_tick_is_run_at_every_tick(tmp_path, nominal, start):
    path, _, sim = write_kept_ticks(tmp_path, 3, "lead_step", 2, start)
    run = LoggedRun.from_path(path)
    assert _claim(run).verdict == "unchecked" and run.identified.judged_to == 0
    model = run.simulate(nominal)
    # the closed loop at every tick follows the blind rig's hub; open loop on the held v drifts
    assert model.fit_pct["theta"] > 80.0
    assert np.array_equal(model.theta_measured, sim.theta[start::2])


def test_the_bracket_is_exact_where_the_tick_is_logged_and_spans_the_rows_around_a_missing_one():
    ticks = np.array([0, 2, 3, 5])
    theta = np.array([0.0, 4.0, 5.0, 9.0])
    lo, hi, judged = _bracket(ticks, theta, 1)
    # rows' ticks 0, 2, 3, 5 used θ at -1 (before the log), 1 (missing), 2 (logged), 4 (missing)
    assert judged.tolist() == [False, True, True, True]
    assert lo[1:].tolist() == [0 - TURN_COUNTS, 4.0, 5 - TURN_COUNTS]
    assert hi[1:].tolist() == [4 + TURN_COUNTS, 4.0, 9 + TURN_COUNTS]
    lo0, hi0, judged0 = _bracket(ticks, theta, 0)
    assert judged0.all() and np.array_equal(lo0, theta) and np.array_equal(hi0, theta)


@pytest.mark.parametrize("start, every", [(0, 2), (1, 2), (0, 5), (4, 5), (3, 10)])
def test_a_copy_of_every_kth_tick_keeps_the_file_names_run_length(rig_data, tmp_path, start, every):
    # duration_1000: the copy's first and last rows may be up to k - 1 ticks inside the run
    # (before: "header: file name: 1000 samples; data: 999 samples" on every other tick)
    src = rig_data / LEAD_LOG
    run = LoggedRun.from_path(_keep(src, tmp_path / LEAD_LOG, range(start, 1000, every)))
    rows = [c for c in run.audit.claims if c.header == "file name: 1000 samples"]
    assert [c.verdict for c in rows] == ["confirmed"], rows
    (tmp_path / "short").mkdir()
    short = LoggedRun.from_path(_keep(src, tmp_path / "short" / LEAD_LOG, range(start, 1000 - 3 * every, every)))
    assert [c.verdict for c in short.audit.claims if c.header == "file name: 1000 samples"] == ["contradicted"]


def test_an_open_loop_header_on_kept_rows_of_a_closed_loop_is_contradicted(rig_data, tmp_path):
    # The P step every other tick under `#SLFR RTP OL_Test`: v = 2(u - θ), not u. Before,
    # every row followed a jump of n, the replay took each row's v as logged at d = 1 and
    # "reproduced" the open loop to 0 counts; then "not judged across" a jump its d reached.
    # Now the data's P law is found on the kept rows.
    path = _keep(rig_data / P_LOG, tmp_path / "ol.txt", range(0, 1000, 2),
                 lambda x: "#SLFR RTP OL_Test" if x.startswith("#SLFR") else x)
    path.write_text("\n".join(x for x in path.read_text().splitlines() if not x.startswith("#kp")) + "\n")
    run = LoggedRun.from_path(path)
    claim = _claim(run)
    assert claim.verdict == "contradicted" and claim.header == "open loop" and claim.data == "P, kp = 2 at alignment 1"
    assert run.source == "inferred (header contradicted)" and run.alignment == 1


@pytest.mark.parametrize("law", ["open-loop", "p", "lead"])
def test_a_replay_that_judges_no_row_never_reproduces(rig_data, law):
    # Every row after a jump within d: at d = 1 the replay's every v is the logged one. Such an
    # alignment cannot be told (max |dv| inf), and an open loop at d = 0 is judged on every row.
    from station.control import make_controller
    from station.control.rerun import detect_alignment, judged_rows

    run = LoggedRun.from_path(rig_data / P_LOG)
    d = run.data
    rows = np.arange(0, 1000, 2)
    restarts = tuple(range(1, rows.size))
    fit = detect_alignment(make_controller(law), d["u"][rows], d["theta"][rows], d["a"][rows], d["v"][rows],
                           (1,), restarts=restarts)
    assert fit.max_abs_dv == np.inf
    assert not judged_rows(rows.size, 1, 0, restarts, 0).any()
    assert judged_rows(1, 1).tolist() == [True]  # a one-row log: its last row, as before


@pytest.mark.parametrize("header", ["none", "open_loop"])
@pytest.mark.parametrize("kp, alignment, every", [(2.0, 1, 2), (1.5, 0, 2), (2.5, 1, 5), (0.8, 1, 10), (3.0, 0, 5)])
def test_blind_p_law_found_on_kept_rows_where_the_header_names_none_or_an_open_loop(tmp_path, header, kp, alignment,
                                                                                   every):
    path, _, _ = write_kept_ticks(tmp_path, 11, "p_step", every, 1, kp=kp, alignment=alignment, header=header)
    run = LoggedRun.from_path(path)
    claim = _claim(run)
    assert run.controller.spec["kind"] == "p" and run.controller.spec["kp"] == kp
    assert alignment in run.identified.alignments
    assert run.source == ("inferred" if header == "none" else "inferred (header contradicted)")
    assert claim.verdict == ("unchecked" if header == "none" else "contradicted")


@pytest.mark.parametrize("every", [2, 5, 10])
def test_no_p_law_is_found_on_kept_rows_of_a_lead(tmp_path, every):
    # the blind lead's v has the lead's high-frequency gain: no P reproduces it, however wide
    # the brackets at the missing ticks (10 ticks of a step's rise)
    path, _, _ = write_kept_ticks(tmp_path, 5, "lead_step", every, 0, header="open_loop")
    run = LoggedRun.from_path(path)
    assert run.controller is None or run.controller.spec.get("kind") != "p"
    assert _claim(run).verdict == "contradicted"


def test_a_pid_header_on_kept_rows_of_a_p_run_is_contradicted_by_the_p_found(rig_data, tmp_path):
    path = _keep(rig_data / P_LOG, tmp_path / "pid.txt", range(0, 1000, 2),
                 lambda x: "#kp=2.0 ki=0.1 kd=0" if x.startswith("#kp") else x)
    run = LoggedRun.from_path(path)
    claim = _claim(run)
    assert claim.header == "PID kp = 2, ki = 0.1, kd = 0" and claim.verdict == "contradicted"
    assert claim.evidence.startswith("the header's PID kp = 2, ki = 0.1, kd = 0 does not give the logged v")
    assert run.source == "inferred (header contradicted)" and run.controller.spec["kp"] == 2.0
