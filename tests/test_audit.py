"""The log audit (DESIGN.md "Log audit"): every claim a log makes checked against its data,
the contradictions said first, and the data's answer used by replay, compare, survey and
the model run.

Truth: the rig's real logs (nothing there may be contradicted), and logs written by the
blind generator (tests/blind/audit.py: lying headers, the lab's integer recursions) with
what they hide known."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.analysis.continuous_design import to_continuous
from station.analysis.controller_id import infer_controller
from station.compare import compare_run, format_comparison
from station.logged import LoggedRun
from station.logged.accelerometer import MOUNTED_CLAIM
from station.logged.audit import ACCEL_CLAIM, ACCEL_DRIFT_COUNTS, CLAIMS, SOURCES, VERDICTS, file_name_claims
from station.runlog.timebase import row_ticks
from station.logged.start import START_CLAIM
from station.logged.units import unsigned_words, word_claims
from station.plant import DiscretePlant, load_model
from station.replay import format_report, replay
from station.survey import format_table, survey
from tests.blind.audit import GA_S, LabController, draw_case, reference, write_audit_case
from tests.blind.rig import tustin

RIG_LOGS = [
    "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
    "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
    "log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt",
    "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt",
    "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
    "swept_sine_kp_1_amp_50.txt",
    "without_accel_01_28_14_test_2.txt",
    "2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt",
    "2009/swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
    "2009/swept_sine_no_sat_amp=50_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
    "2009/swept_sine_no_sat_amp=75_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
]


@pytest.mark.parametrize("name", RIG_LOGS)
def test_real_logs_contradict_nothing(rig_data, name):
    run = LoggedRun.from_path(rig_data / name)
    audit = run.audit
    named = name != "without_accel_01_28_14_test_2.txt"
    # the 2014 log "without accel" has an a column with no accelerometer behind it, and the
    # accelerometer's mass was off the beam (θ/v's notch): its two contradictions
    assert [c.header for c in audit.contradicted] == ([] if named else [ACCEL_CLAIM, MOUNTED_CLAIM]), audit.lines()
    assert (run.mounting.mounted, run.mounting.claim is None) == ((True, True) if named else (False, False))
    assert audit.accel_is_tip is named
    assert run.reproduced
    rows = audit.to_json()
    assert rows[0]["claim"] == "controller" and all(set(r) == {"claim", "header", "data", "verdict", "evidence"}
                                                    for r in rows)
    assert all(r["claim"] in CLAIMS and r["verdict"] in VERDICTS for r in rows)
    assert audit.controller_source in SOURCES
    assert rows[0]["verdict"] == ("confirmed" if named else "unchecked")
    stated = file_name_claims(name)
    confirmed = {r["header"] for r in rows if r["verdict"] == "confirmed"}
    for kp in stated.get("kp", []):
        assert f"file name: kp = {kp:g}" in confirmed
    for amp in stated.get("amp", []):
        assert f"file name: amplitude {amp:g}" in confirmed
    for n in stated.get("stopn", []) + stated.get("duration", []):
        assert f"file name: {n:g} samples" in confirmed


def test_file_name_claims():
    assert file_name_claims("SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt") == {"kp": [2.0]}
    assert file_name_claims("swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt") == {
        "amp": [25.0], "kp": [1.0], "stopn": [20000.0]}
    assert file_name_claims("log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt") == {"uend": [77.0]}
    assert file_name_claims("audit_lie-p-kp_0_SLFR_RTP_P_control_Test.txt") == {}
    assert file_name_claims(RIG_LOGS[4]) == {"amp": [100.0], "duration": [1000.0]}


BLIND = [("lie:open_loop", 0), ("lie:open_loop", 1), ("lie:p_kp", 0), ("lie:lead_pole", 2), ("int:trunc_d0", 1),
         ("int:round_d1", 2), ("session", 0), ("session+coulomb_friction", 1), ("honest:p", 3),
         ("honest:lead_int", 0), ("honest:lead_sent", 0), ("honest:lead_sent+coulomb_friction", 1),
         # a lead on the float logging the whole count it sent, under an open-loop header: a step
         # whose least squares on the counts puts the pole 6 % off; a truncated one
         ("lie:sent", 2), ("lie:sent+coulomb_friction", 4),
         # DESIGN.md's Ga beside a lead on whole counts (rounded integer recursion; sent as rounded)
         ("lie:accel_int", 0), ("lie:accel_int", 1),
         # honest headers on what they state: a P header with no clamp over a ±150 clamp; leads printed
         # to 8 digits whose integer recursion the printing moves by a count (were "contradicted")
         ("honest:p", 8), ("honest:lead_int", 6), ("honest:lead_int", 7),
         # of two designs the integer log cannot tell apart, the one in rad/s (were 2π·2.5, 2π·1.9/2π·9)
         ("int:trunc_d0", 7), ("int:trunc_d1", 3),
         # round designs whose rational Tustin coefficients put rows exactly on a quantization boundary,
         # from both sides: the one law, its ties decided by the lab's last bit (were order 2-3 laws with a
         # cancelled pair, or no law at all)
         ("int:round_d0", 5), ("int:trunc_d0+coulomb_friction", 6), ("session", 5), ("int:trunc_d1", 9),
         ("honest:lead_int+coulomb_friction", 8),
         # a lead with accelerometer feedback under a header without Ga (open loop at d 0 and 1, the
         # lead alone on a 5 Hz sine, which hardly pins Ga's slowest pole, and on a sweep at a ±150 clamp)
         ("lie:accel_fb", 0), ("lie:accel_fb", 5), ("lie:accel_fb", 8), ("lie:accel_fb+coulomb_friction", 9),
         # the same over rows lost (Ga's state in no column: judged on the rows before the first jump), under
         # an open-loop header, the lead alone over two gaps, and none on a sweep whose first 437 rows gave
         # the products' slowest pole a hair right of 0 (were "no law found")
         ("lie:accel_rows", 2), ("lie:accel_rows+coulomb_friction", 4), ("lie:accel_rows", 8)]


@pytest.mark.parametrize("case, seed", BLIND)
def test_blind_headers_and_recursions(tmp_path, case, seed):
    path, hidden = write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    audit = run.audit
    controller_rows = [c for c in audit.claims if c.claim == "controller"]
    assert (controller_rows[0].verdict == "contradicted") is hidden.lies
    assert audit.controller_source == ("inferred (header contradicted)" if hidden.lies else
                                       "inferred" if hidden.header == "none" else "header")
    assert run.reproduced and run.closed
    assert run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments
    if hidden.lies:
        assert audit.lines()[0].startswith("header: ") and "; data: " in audit.lines()[0]
    if run.source != "header":
        spec = run.controller.spec
        if hidden.law == "p":
            assert spec["kp"] == hidden.kp
        else:
            assert spec["design"]["method"] == "Tustin"
            np.testing.assert_allclose(spec["design"]["num_s"], hidden.num_s, rtol=1e-9)
            np.testing.assert_allclose(spec["design"]["den_s"], hidden.den_s, rtol=1e-9)
            for d in spec["design"]["alternatives"]:  # any design named beside it reproduces the log too
                assert _lab_reproduces(run, d, hidden.limit, hidden.recursion, run.alignment), d["text"]
        assert run.controller.recursion == hidden.recursion or hidden.law == "p"
    if hidden.ga_s is not None:  # the accelerometer feedback too, its continuous form (Tustin's inverse)
        back = to_continuous(run.controller.ga.num, run.controller.ga.den, 0.002, "Tustin")
        for found, truth in zip(back, hidden.ga_s):
            np.testing.assert_allclose(found[-len(truth):], truth, rtol=1e-3)
            assert np.all(np.abs(found[:-len(truth)]) <= 1e-9 * np.max(np.abs(truth)))


def test_the_rigs_accelerometer_run_under_an_open_loop_header_is_its_lead_and_ga(rig_data, tmp_path):
    # the thesis's lead + accelerometer step with its header saying open loop, or the lead
    # without Ga: the data's law is the thesis's Gth and Ga (DESIGN.md), to the log's digits
    from station.control.designs import lead_controller
    from station.logged.controller import same_law

    src = rig_data / "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
    lines = src.read_text().splitlines()
    rows = [x for x in lines if x and not x.startswith("#")]
    no_ga = [("#Ga num=[]" if x.startswith("#Ga num") else "#Ga den=[]" if x.startswith("#Ga den") else x)
             for x in lines if x.startswith("#")]
    for name, header in (("ol.txt", ["#SLFR RTP OL_Test", lines[5]]), ("no_ga.txt", no_ga)):
        path = tmp_path / name
        path.write_text("\n".join(header + rows) + "\n")
        run = LoggedRun.from_path(path)
        assert run.audit.controller_source == "inferred (header contradicted)", name
        assert same_law(lead_controller(accel=True), run.controller)
        assert run.reproduced and run.alignment == 1 and run.max_abs_dv < 1e-6
        assert "the thesis's accelerometer feedback Ga" in run.audit.lines()[0]
        assert run.controller.spec["design"]["text"] == "20(s+2π·5)/(s+2π·20)"


def test_session_said_first_everywhere(tmp_path):
    path, hidden = write_audit_case(tmp_path / "logs", "session", 0)
    report = replay(path, model=False)
    text = format_report(report).splitlines()
    assert text[0] == report.audit.lines()[0]
    assert text[0].startswith("header: open loop; data: 1.5(s+12)/(s+48) (Tustin, 0.002 s)") and "exactly" in text[0]
    j = report.to_json()
    assert j["controller_source"] == "inferred (header contradicted)"
    assert j["audit"][0]["verdict"] == "contradicted" and j["audit"][0]["header"] == "open loop"
    json.dumps(j)
    comp = compare_run(path, DiscretePlant())
    assert format_comparison(comp).splitlines()[0] == f"{path.name}: {text[0]}"
    assert comp.to_json()["controller_source"] == "inferred (header contradicted)"
    rows = survey([tmp_path / "logs"], model=False, workers=1)
    assert format_table(rows, tmp_path / "logs").splitlines()[0] == f"{path.name}: {text[0]}"


def test_integer_recursion_simulated_as_the_lab_ran_it(tmp_path):
    """The model run of a log whose recursion stored integers equals a closed loop stepped
    by hand: the plant, the generator's lab recursion, the device's truncation."""
    path, hidden = write_audit_case(tmp_path, "int:trunc_d0", 1)
    run = LoggedRun.from_path(path)
    pred = run.simulate(DiscretePlant()).prediction
    plant = DiscretePlant()
    plant.reset()
    lab = LabController(*tustin(list(hidden.num_s), list(hidden.den_s)), hidden.limit, "trunc")
    u = reference(hidden)
    theta = np.zeros(u.size)
    v = np.zeros(u.size)
    for k in range(u.size):
        theta[k] = np.round(plant.outputs()[0])
        v[k] = lab.step(u[k] - theta[k])  # alignment 0
        plant.advance(float(math.trunc(v[k])))
    np.testing.assert_array_equal(pred["v"], v)
    np.testing.assert_array_equal(pred["theta"], theta)


@pytest.mark.parametrize("stored", ["trunc", "round"])
@pytest.mark.parametrize("lying", [False, True])
@pytest.mark.parametrize("step", ["lead", "lead+accel"])
def test_the_rigs_lead_logged_as_the_whole_counts_it_sent(rig_data, tmp_path, stored, lying, step):
    """Lab software that recurses on the float and logs the whole count it sends: the thesis's
    lead step with each v truncated (or rounded) as such software would. The header's law
    reproduces every logged v exactly with that recursion, said in the audit and in the
    notes, and the model run sends what the log holds; before, replay said "does NOT
    reproduce the logged v: max |dv| = 0.999 counts" and used the float law. Under an
    open-loop header the data's law is the thesis's design, found from the counts alone
    (before: "no law found"); beside the accelerometer feedback, the thesis's Ga (whole
    counts cannot pin Ga's own coefficients)."""
    import math

    from station.control.compensator import SENT
    from station.rounding import half_away

    src = rig_data / {"lead": "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
                      "lead+accel": "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_"
                                    "Comp_Gth.txt"}[step]
    q = math.trunc if stored == "trunc" else half_away
    lines = src.read_text().splitlines()
    names = [x for x in lines if x.startswith("#")][-1][1:].split("\t")
    col = names.index("v")
    out = []
    for line in lines:
        cells = line.split("\t")
        if not line.startswith("#") and len(cells) > col:
            cells[col] = str(int(q(float(cells[col]))))
        out.append("\t".join(cells))
    said = {"trunc": "truncated", "round": "rounded"}[stored]
    if lying:
        out = ["#SLFR RTP OL_Test"] + [x for x in out if not x.startswith("#")]
        out.insert(1, "#" + "\t".join(names))
    path = tmp_path / ("ol_SLFR_RTP_OL_Test.txt" if lying else src.name)
    path.write_text("\n".join(out) + "\n")
    run = LoggedRun.from_path(path)
    assert run.controller.recursion == f"float-{stored}" and f"float-{stored}" in SENT
    assert run.reproduced and run.max_abs_dv == 0.0 and run.alignment == 1
    if lying:
        assert run.audit.controller_source == "inferred (header contradicted)"
        ga = ", with the thesis's accelerometer feedback Ga" if step == "lead+accel" else ""
        assert run.audit.lines()[0] == (f"header: open loop; data: 20(s+2π·5)/(s+2π·20) (Tustin, 0.002 s), its "
                                        f"recursion on the float, the command sent as its {said} integer{ga} at "
                                        f"alignment 1, reproduces every logged v exactly")
    else:
        assert run.audit.controller_source == "header" and run.audit.lines() == []
        assert any(f"its recursion on the float, the command sent as its {said} integer" in n for n in run.notes)
    logged = np.asarray(run.data["v"], float)
    np.testing.assert_array_equal(run.replayed.v_replayed, logged)
    sim = run.simulate(DiscretePlant(), sensors=False).prediction
    assert np.all(sim["v"] == np.round(sim["v"]))  # the model is sent whole counts as the rig was
    float_law = LoggedRun.from_path(src)
    assert float_law.controller.recursion == "none" and float_law.max_abs_dv < 1e-6  # the rig's own log: the float
    if stored == "trunc":  # the same loop the rig ran: its device truncated the float it was sent
        ours, rigs = run.simulate(DiscretePlant(), sensors=False), float_law.simulate(DiscretePlant(), sensors=False)
        np.testing.assert_array_equal(ours.prediction["theta"], rigs.prediction["theta"])
        np.testing.assert_array_equal(ours.prediction["a"], rigs.prediction["a"])


def _rewrite(src, dst, column, scale, digits=None):
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    names = head[-1][1:].split("\t")
    col = names.index(column)
    out = []
    for line in lines[len(head):]:
        cells = line.split("\t")
        x = float(cells[col]) * scale
        cells[col] = repr(x) if digits is None else f"{x:.{digits}f}"
        out.append("\t".join(cells))
    dst.write_text("\n".join(head + out) + "\n")
    return dst


def test_t_in_ms_and_theta_in_radians_are_found_and_converted(rig_data, tmp_path):
    src = rig_data / RIG_LOGS[1]
    truth = LoggedRun.from_path(src)
    ms = LoggedRun.from_path(_rewrite(src, tmp_path / "p_step_ms.txt", "t", 1000.0))
    rows = {(c.claim, c.data): c.verdict for c in ms.audit.claims}
    assert rows[("columns", "t in ms")] == "contradicted"
    assert ms.dt == 0.002 and ms.reproduced and ms.alignment == 1
    assert ms.step_metrics() == truth.step_metrics()
    rad = LoggedRun.from_path(_rewrite(src, tmp_path / "p_step_rad.txt", "$\\theta$", 2 * math.pi / 1024, 6))
    rows = {(c.claim, c.data): c.verdict for c in rad.audit.claims}
    assert rows[("columns", "θ in radians")] == "contradicted"
    np.testing.assert_array_equal(rad.data["theta"], truth.data["theta"])
    assert rad.reproduced and rad.source == "header"


def _as_words(src, dst, columns):
    """The log with each named column's values written as the legacy protocol's 16-bit words
    read unsigned (x mod 65536), as a lab client that decodes them so writes them."""
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    names = head[-1][1:].split("\t")
    cols = [names.index(c) for c in columns]
    out = []
    for line in lines[len(head):]:
        cells = line.split("\t")
        for col in cols:
            cells[col] = f"{int(float(cells[col])) % 65536}"
        out.append("\t".join(cells))
    dst.write_text("\n".join(head + out) + "\n")
    return dst


@pytest.mark.parametrize("name, columns", [(RIG_LOGS[0], ("v", "$\\theta$", "a")), (RIG_LOGS[1], ("v", "a")),
                                           (RIG_LOGS[7], ("u", "v", "$\\theta$", "a"))])
def test_columns_read_as_unsigned_words_are_found_and_read_signed(rig_data, tmp_path, name, columns):
    # The rig's logs with columns as a client writes them that reads the legacy protocol's
    # two's-complement words as unsigned (the lab's own system-ID files hold v = 65472 for -64):
    # every column that went negative is contradicted and read back exactly; the rest as the log
    src = rig_data / name
    truth = LoggedRun.from_path(src)
    run = LoggedRun.from_path(_as_words(src, tmp_path / src.name, columns))
    std = {"$\\theta$": "theta"}
    wrapped = [c for c in columns if np.any(truth.data[std.get(c, c)] < 0)]
    assert wrapped  # each of these logs goes negative somewhere
    said = [c.header for c in run.audit.contradicted]
    shown = {"$\\theta$": "θ"}
    assert said == [f"{shown.get(c, c)} in signed counts" for c in wrapped], said
    assert run.audit.lines()[0].startswith(f"header: {said[0]}; data: ")
    for col in ("u", "v", "theta", "a"):
        np.testing.assert_array_equal(run.data[col], truth.data[col])
    assert (run.reproduced, run.alignment, run.source) == (truth.reproduced, truth.alignment, truth.source)
    assert run.step_metrics() == truth.step_metrics()


@given(st.lists(st.integers(-2048, 2047), min_size=2, max_size=300))
@settings(max_examples=300, deadline=None)
def test_unsigned_words_decided_from_the_numbers(values):
    # Truth: a signed column of the rig's range written as words is found exactly when it goes
    # negative, and read back exactly; a column that never does is left as it is.
    x = np.array(values, dtype=float)
    claims, signed = word_claims({"v": np.mod(x, 65536.0)})
    assert bool(claims) is bool(np.any(x < 0))
    if claims:
        np.testing.assert_array_equal(signed["v"], x)
    assert not unsigned_words(x)  # signed counts are never words


@given(st.integers(32768 - 500, 32768 + 500), st.integers(600, 3000), st.integers(0, 2**32 - 1))
@settings(max_examples=100, deadline=None)
def test_an_unsigned_channel_around_mid_scale_is_not_words(centre, swing, seed):
    # An ADC read unsigned around 32768 (no zeroing), crossing the middle, is no word column:
    # read as two's complement it would jump by 65535 there
    x = np.round(centre + swing * np.sin(np.linspace(0.0, 20.0, 500))
                 + np.random.default_rng(seed).normal(0.0, 2.0, 500))
    assert np.min(x) < 32768 <= np.max(x)
    assert not unsigned_words(x)


@pytest.mark.parametrize("case, seed", [("words", 0), ("words", 1), ("words", 4), ("words+coulomb_friction", 8)])
def test_blind_columns_read_as_unsigned_words(tmp_path, case, seed):
    path, hidden = write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    shown = {"u": "u", "v": "v", "theta": "θ", "a": "a", "theta_d_hat": "θ̂d"}
    said = [c.header for c in run.audit.contradicted]
    assert hidden.wrapped and said == [f"{shown[c]} in signed counts" for c in hidden.wrapped]
    assert run.reproduced and run.source == "header" and all(np.max(run.data[c]) < 32768 for c in hidden.wrapped)


def _swap_columns(src, dst, first, second, header=True):
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    names = head[-1][1:].split("\t")
    i, j = names.index(first), names.index(second)
    rows = []
    for line in lines[len(head):]:
        cells = line.split("\t")
        cells[i], cells[j] = cells[j], cells[i]
        rows.append("\t".join(cells))
    dst.write_text("\n".join((head if header else ["\t".join(names)]) + rows) + "\n")
    return dst


@pytest.mark.parametrize("name, first, second, header", [
    (RIG_LOGS[1], "u", "v", True), (RIG_LOGS[1], "$\\theta$", "a", True), (RIG_LOGS[4], "u", "v", True),
    (RIG_LOGS[4], "$\\theta$", "a", True), (RIG_LOGS[7], "$\\theta$", "a", True),
    (RIG_LOGS[1], "u", "v", False), (RIG_LOGS[1], "$\\theta$", "a", False),
    # the command and the angle, the reference and the angle (a layout mapped onto another by place)
    (RIG_LOGS[1], "v", "$\\theta$", True), (RIG_LOGS[1], "u", "$\\theta$", True), (RIG_LOGS[4], "v", "$\\theta$", True),
    (RIG_LOGS[4], "u", "$\\theta$", True), (RIG_LOGS[3], "v", "$\\theta$", True),
    (RIG_LOGS[1], "v", "$\\theta$", False)])
def test_two_columns_swapped_are_found(rig_data, tmp_path, name, first, second, header):
    # The header's law (or, with no header, the law the data give) reproduces every logged v
    # only with the two columns exchanged: the column line is contradicted, said first, and the
    # log read swapped (before, the P step with u and v swapped was "inferred" a
    # 300(s-2)/(s-3000) with Ga at a ±50 clamp, θ fit -3690 %; with v and θ swapped it was "not
    # this law, no law found", overshoot 100 %, θ fit -196 %)
    src = rig_data / name
    truth = LoggedRun.from_path(src)
    run = LoggedRun.from_path(_swap_columns(src, tmp_path / src.name, first, second, header))
    shown = {"$\\theta$": "θ"}
    pair = f"{shown.get(first, first)} and {shown.get(second, second)}"
    assert run.audit.lines()[0] == f"header: {pair} as the column line names them; data: {pair} swapped"
    assert [c.claim for c in run.audit.contradicted] == ["columns"]
    for col in ("u", "v", "theta", "a"):
        np.testing.assert_array_equal(run.data[col], truth.data[col])
    assert (run.reproduced, run.alignment, run.source) == (True, truth.alignment, "header" if header else "inferred")
    if header:
        assert run.step_metrics() == truth.step_metrics()
    else:
        assert run.controller.spec["kp"] == 2.0
    plain = LoggedRun.from_path(src)  # the log as it is: nothing swapped
    assert not plain.audit.contradicted


def test_the_thesis_logs_written_hostile_simulate_as_the_logs_themselves(rig_data, tmp_path):
    # The four thesis logs a diagnosis fits, three of them rewritten: the pulses' v, θ and a as
    # unsigned words, the P step's u and v swapped, the lead step's θ and a swapped. Each says so
    # first and is simulated sample for sample as the log itself (`station diagnose` on the four
    # gives the same answer: drive damping ×3.41 + Coulomb friction 4.97, 35.8 %)
    names = (RIG_LOGS[0], RIG_LOGS[1], RIG_LOGS[4])
    hostile = (_as_words(rig_data / names[0], tmp_path / names[0], ("v", "$\\theta$", "a")),
               _swap_columns(rig_data / names[1], tmp_path / names[1], "u", "v"),
               _swap_columns(rig_data / names[2], tmp_path / names[2], "$\\theta$", "a"))
    for name, path in zip(names, hostile):
        truth, run = LoggedRun.from_path(rig_data / name), LoggedRun.from_path(path)
        assert run.audit.lines() and all(line.startswith("header: ") for line in run.audit.lines())
        ours = run.simulate(DiscretePlant(), sensors=False).prediction
        theirs = truth.simulate(DiscretePlant(), sensors=False).prediction
        for col in ("theta", "a", "v"):
            np.testing.assert_array_equal(ours[col], theirs[col])


def test_a_command_column_of_two_levels_identifies_no_law(tmp_path):
    # A log with no header over a held hub, a step of 150 and v of 0 then 200: any law of high
    # gain clamped at ±200 gives it, so none is inferred, nor a swap of its columns (before: the
    # P step with u and v swapped, so v was the step itself, was "inferred" a 300(s-2)/(s-3000)
    # with Ga at a ±50 clamp, "reproducing every logged v")
    rows = [f"{k * 0.002:g}\t{k}\t{150 if k >= 20 else 0}\t{200 if k >= 20 else 0}\t0\t0" for k in range(400)]
    path = tmp_path / "held_no_header.txt"
    path.write_text("\n".join(["t\tn\tu\tv\ttheta\ta"] + rows) + "\n")
    run = LoggedRun.from_path(path)
    assert run.source is None and run.controller is None and not run.audit.contradicted
    assert [c.data for c in run.audit.claims if c.claim == "controller"] == ["no law found"]
    step = np.where(np.arange(300) >= 20, 50.0, 0.0)
    assert infer_controller(np.zeros(300), np.zeros(300), step) is None
    bang = np.sign(np.sin(np.arange(300) / 7.0)) * 200.0
    assert infer_controller(bang / 10.0, np.zeros(300), bang) is None


def test_a_header_law_over_two_levels_of_v_is_not_confirmed(tmp_path):
    # A P header (kp = 2) over a held hub and a step of 150: v = clamp(2·150) = 200 on every row
    # after the step. kp = 2 gives it, and so does any kp >= 1.34: the data cannot confirm the
    # header's gain (before: "confirmed")
    rows = [f"{k * 0.002:g}\t{k}\t{150 if k >= 20 else 0}\t{200 if k >= 20 else 0}\t0\t0" for k in range(400)]
    path = tmp_path / "held_SLFR_RTP_P_control_Test.txt"
    path.write_text("\n".join(["#SLFR RTP P_control_Test", "#kp=2.0", "#t\tn\tu\tv\t$\\theta$\ta"] + rows) + "\n")
    run = LoggedRun.from_path(path)
    claim = next(c for c in run.audit.claims if c.claim == "controller")
    assert run.reproduced and run.source == "header"
    assert claim.verdict == "unchecked" and "cannot confirm" in claim.evidence


@pytest.mark.parametrize("name", [RIG_LOGS[1], RIG_LOGS[4], RIG_LOGS[3]])
@pytest.mark.parametrize("cut", ["drop", "repeat"])
def test_a_true_header_over_missing_or_repeated_rows_is_not_contradicted(rig_data, tmp_path, name, cut):
    # The P, lead and lead + accelerometer steps with 20 rows deleted, or 10 rows repeated, at row
    # 500: the rows say so ("n jumps"). The P and the lead are replayed again from the jump with
    # their memory as logged and reproduce every other row: confirmed. Ga's memory is a's whole
    # past, which the log lacks across the gap: judged up to it, "unchecked" (before: the P and
    # lead "unchecked", and every law "contradicted" before that, its first miss after the gap)
    src = rig_data / name
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    rows = lines[len(head):]
    rows = rows[:500] + rows[520:] if cut == "drop" else rows[:500] + rows[490:500] + rows[500:]
    path = tmp_path / src.name
    path.write_text("\n".join(head + rows) + "\n")
    run = LoggedRun.from_path(path)
    verdicts = {c.claim: c for c in run.audit.claims if c.claim in ("controller", "sample_time") and
                c.verdict != "confirmed"}
    assert verdicts["sample_time"].data == "n jumps at 1 row"
    said = {"drop": "ticks missing at 1 row", "repeat": "a tick repeated or gone back at 1 row"}[cut]
    assert verdicts["sample_time"].evidence.endswith(said), verdicts["sample_time"].evidence
    assert run.source == "header" and run.alignment == 1 and run.reproduced
    assert not any(c.claim == "controller" for c in run.audit.contradicted)
    if name == RIG_LOGS[3]:
        assert verdicts["controller"].verdict == "unchecked" and "row 500" in verdicts["controller"].data
        assert run.identified.judged_to == 500
        report = format_report(replay(path, model=False))
        assert "reproduces the logged v up to row 500, where n jumps" in report
    else:
        assert "controller" not in verdicts and run.identified.judged_to is None
        assert run.max_abs_dv <= 1e-6


@pytest.mark.parametrize("header", ["#SLFR RTP OL_Test", "#SLFR RTP P_control_Test\n#kp=2.0", None])
@pytest.mark.parametrize("cut", ["drop", "repeat"])
def test_a_lying_header_over_rows_lost_from_the_accelerometer_run(rig_data, tmp_path, header, cut):
    # The lead + Ga step with 11 rows deleted, or 10 written again, at row 200, under an open-loop
    # header, a P header or none: Ga's state is a's whole past, in no column, so its law is inferred on
    # the 200 rows before the jump and judged there (as its true header's is), the thesis's lead and Ga
    # named, the header contradicted. Before: "no law found", the model driven open loop by v
    src = rig_data / RIG_LOGS[3]
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    rows = lines[len(head):]
    rows = rows[:200] + rows[211:] if cut == "drop" else rows[:200] + rows[190:200] + rows[200:]
    path = tmp_path / src.name
    path.write_text("\n".join(([header] if header else []) + head[-1:] + rows) + "\n")
    run = LoggedRun.from_path(path)
    claim = next(c for c in run.audit.claims if c.claim == "controller")
    assert run.source == ("inferred (header contradicted)" if header else "inferred")
    assert claim.verdict == ("contradicted" if header else "unchecked")
    assert claim.data.endswith("before row 200, where n jumps (not judged across it)"), claim.data
    assert run.identified.judged_to == 200 and run.reproduced and run.alignment == 1
    assert run.controller.spec["design"]["text"] == "20(s+2π·5)/(s+2π·20)"
    found = to_continuous(run.controller.ga.num, run.controller.ga.den, 0.002, "Tustin")
    np.testing.assert_allclose(found[1], GA_S[1], rtol=1e-6)  # DESIGN.md's Ga, the lab's software's
    report = format_report(replay(path, model=False))
    assert "reproduces the logged v up to row 200, where n jumps" in report


@pytest.mark.parametrize("name", [RIG_LOGS[0], RIG_LOGS[1], RIG_LOGS[4], RIG_LOGS[3]])
@pytest.mark.parametrize("cut", ["drop", "repeat", "swap"])
def test_rows_missing_or_repeated_are_simulated_on_their_ticks(rig_data, tmp_path, name, cut):
    # Rows lost (or written twice, or two blocks written in the wrong order) while the hub
    # moves: the model runs on every tick and is compared at the rows there are, so at each kept
    # row it predicts what it predicts on the whole log (independent truth: the log before the
    # cut), and the note names what n did. Before: the rows were taken as consecutive ticks, the
    # model 15 ticks ahead of the log after the gap; rows out of order were said as "(n jumps: )".
    src = rig_data / name
    whole = LoggedRun.from_path(src)
    u, v = whole.data["u"], whole.data["v"]
    # a span in the motion where u (and, open loop, v) stay what the row before held: the held
    # values are then exact (a closed loop's v is the model's own)
    start = next(k for k in range(60, 1000) if np.all(u[k - 1:k + 15] == u[k - 1]) and np.ptp(whole.data["theta"][k:k + 15])
                 and (whole.closed or np.all(v[k - 1:k + 15] == v[k - 1])))
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    rows = lines[len(head):]
    kept = {"drop": np.r_[0:start, start + 15:len(rows)], "repeat": np.r_[0:start, start - 5:start, start:len(rows)],
            "swap": np.r_[0:start, start + 5:start + 10, start:start + 5, start + 10:len(rows)]}[cut]
    path = tmp_path / src.name
    path.write_text("\n".join(head + [rows[k] for k in kept]) + "\n")
    run = LoggedRun.from_path(path)
    assert run.source == whole.source and run.alignment == whole.alignment
    model = load_model("rig")
    sim, truth = run.simulate(model), whole.simulate(model)
    said = {"drop": "15 tick(s) missing", "repeat": "5 row(s) repeating a tick", "swap": "5 row(s) out of order"}[cut]
    assert f"on the log's ticks (n jumps: {said}" in sim.how, sim.how
    for key in ("theta", "a", "v", "t"):
        np.testing.assert_array_equal(sim.prediction[key], truth.prediction[key][kept], err_msg=key)
    np.testing.assert_array_equal(sim.theta_measured, truth.theta_measured[kept])


def test_a_law_is_inferred_across_rows_missing_from_a_log_that_names_none(rig_data, tmp_path):
    # The 2014 sweep (no header, no n: t jumps) with 15 rows deleted mid-run: P kp = 1 is
    # inferred from the rows whose lags do not cross the jump and replays every other row
    # (before: no law found, the model driven open loop by the logged v, θ fit -3062 %)
    src = rig_data / RIG_LOGS[6]
    lines = src.read_text().splitlines()
    path = tmp_path / src.name
    path.write_text("\n".join(lines[:2001] + lines[2016:]) + "\n")
    run = LoggedRun.from_path(path)
    assert run.source == "inferred" and run.controller.spec["kind"] == "p" and run.controller.spec["kp"] == 1.0
    assert run.reproduced and run.alignment == 1
    assert run.data["n"][2000] - run.data["n"][1999] == 16


def test_row_ticks_places_rows_only_where_it_can():
    assert row_ticks(np.arange(5.0)) is None                       # consecutive
    assert row_ticks([0, 1, 3, 4]).tolist() == [0, 1, 3, 4]       # a tick lost
    assert row_ticks([7, 8, 8, 9]).tolist() == [0, 1, 1, 2]       # a row written twice
    assert row_ticks([0, 1, 2, 1, 2, 3]).tolist() == [0, 1, 2, 1, 2, 3]  # rows written again
    assert row_ticks([5, 6, 0, 1]) is None                        # a counter that wraps: not placed
    assert row_ticks([0, 1.5, 3]) is None                         # not ticks
    assert row_ticks([0, 1, 1000]) is None                        # more missing than there are rows
    assert row_ticks([0, np.nan, 2]) is None


@pytest.mark.parametrize("offset, jitter", [(1764072000.0, 2e-4), (1234.5, 0.0), (0.002, 0.0)])
def test_a_clock_that_does_not_start_at_zero_or_jitters(rig_data, tmp_path, offset, jitter):
    # The P step with t as a lab script stamps it: the host's wall clock at each sample's arrival
    # (jittered by up to 0.1 ms), a clock since boot, 1-based ticks. Before: "sampled at
    # 0.00199699 s, not the rig's": no controller replayed, the model at the wrong rate; and
    # "settling (1 %) 1235.750 s"
    src = rig_data / RIG_LOGS[1]
    truth = LoggedRun.from_path(src)
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    rng = np.random.default_rng(3)
    rows = []
    for line in lines[len(head):]:
        cells = line.split("\t")
        cells[0] = f"{float(cells[0]) + offset + jitter * rng.uniform(-0.5, 0.5):.7f}"
        rows.append("\t".join(cells))
    path = tmp_path / src.name
    path.write_text("\n".join(head + rows) + "\n")
    run = LoggedRun.from_path(path)
    assert run.dt == 0.002 and run.reproduced and run.source == "header" and not run.audit.contradicted
    assert run.step_metrics() == truth.step_metrics()
    if jitter:
        rows = {c.claim: c for c in run.audit.claims}
        assert rows["sample_time"].verdict == "confirmed" and "host's time stamps" in rows["sample_time"].data
        np.testing.assert_allclose(np.diff(run.data["t"]), 0.002, rtol=1e-9)


def test_a_stated_amplitude_the_data_contradict(rig_data, tmp_path):
    src = rig_data / RIG_LOGS[1]  # a step of 50
    path = tmp_path / "step_amp_100_SLFR_RTP_P_control_kp=2.0.txt"
    path.write_text(src.read_text())
    audit = LoggedRun.from_path(path).audit
    ref = [c for c in audit.claims if c.claim == "reference" and c.header != START_CLAIM]
    assert [c.verdict for c in ref] == ["contradicted"] and "a step of 50" in ref[0].data
    assert audit.lines() == ["header: file name: amplitude 100; data: a step of 50 at tick 50"]


def test_draws_are_deterministic():
    assert draw_case("session", 4) == draw_case("session", 4)
    assert draw_case("lie:p_kp", 0).kp != 2.0


@pytest.mark.parametrize("creep", [0.0, 5.0, 15.0, 40.0])
def test_an_a_column_with_no_accelerometer_behind_it(rig_data, tmp_path, creep):
    # A rig log whose a is replaced by a noisy channel creeping `creep` counts over the run
    # (an unplugged input, as in the 2014 log): contradicted from ACCEL_DRIFT_COUNTS on by its
    # creep, below it by its silence where the sweep moved the tip (station.logged.accelerometer),
    # said first by replay beside its accel fit; the sweep's θ/v keeps the accelerometer's mass
    # on the beam (it was: the rig's swept sine).
    src = rig_data / "swept_sine_kp_1_amp_50.txt"  # 22 s, at rest for its first 0.5 s
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    col = head[-1][1:].split("\t").index("a")
    rows = lines[len(head):]
    rng = np.random.default_rng(7)
    out = []
    for k, line in enumerate(rows):
        cells = line.split("\t")
        cells[col] = f"{-66 + creep * k / len(rows) + rng.normal(0, 3):.0f}"
        out.append("\t".join(cells))
    path = tmp_path / "swept_sine_unplugged_accel.txt"
    path.write_text("\n".join(head + out) + "\n")
    run = LoggedRun.from_path(path)
    # the drift is the window mean's distance from rest: about creep × (1 - window / run)
    creeps = creep * (1 - 2.0 / (len(rows) * 0.002)) >= ACCEL_DRIFT_COUNTS
    assert not run.audit.accel_is_tip
    (claim,) = [c for c in run.audit.contradicted if c.header == ACCEL_CLAIM]
    assert ("reads noise where the tip moved" in claim.data) is not creeps
    assert run.mounting.mounted is True and run.mounting.claim.verdict == "confirmed"
    text = format_report(replay(path))
    assert "a is no tip acceleration" in text.splitlines()[0]
    assert "(a is no tip acceleration: the audit)" in text


def _lab_reproduces(run, design: dict, limit: float, recursion: str, alignment: int) -> bool:
    """The lab's recursion of a design (the blind generator's LabController, scipy's Tustin),
    fed the logged u[k] − θ[k − d] at the alignment d, gives every logged v exactly."""
    from tests.blind.audit import LabController

    from scipy.signal import cont2discrete

    method = design.get("method", "Tustin")
    if method == "Tustin":  # the generator's own, as the log was made (rows may sit on a rounding boundary)
        num, den = tustin(design["num_s"], design["den_s"])
    else:
        how = {"ZOH": "zoh", "backward Euler": "backward_diff", "forward Euler": "euler"}[method]
        num, den, _ = cont2discrete((design["num_s"], design["den_s"]), 0.002, method=how)
        num, den = np.ravel(num), np.ravel(den)
        num = num[len(num) - len(den):]  # descending powers of z, as many as den's: ascending of z^-1
    ctrl = LabController(num / den[0], den / den[0], limit, recursion)
    u, theta, v = (np.asarray(run.data[c], float) for c in ("u", "theta", "v"))
    out = [0.0 if k < alignment else ctrl.step(u[k] - theta[k - alignment]) for k in range(len(v))]
    return bool(np.array_equal(np.asarray(out), v))


def test_designs_a_log_cannot_tell_apart_are_each_named(tmp_path):
    # a settled step on the stored integer pins a lead's pole only so far: the lab's third
    # session's lead 1.5(s+12)/(s+48) run on this step reproduces every v, and so does (s+47);
    # the audit named one as if sure (it picked (s+47)). Every design it names reproduces the
    # log, and the one run is among them.
    import dataclasses

    from tests.blind.audit import format_audit_run, simulate_audit_case

    base = draw_case("session", 0)
    case = dataclasses.replace(draw_case("session", 2), num_s=base.num_s, den_s=base.den_s,
                               design_text=base.design_text, limit=base.limit)
    path = tmp_path / "step_SLFR_RTP_OL_Test.txt"
    path.write_text(format_audit_run(case, simulate_audit_case(case, 2)))
    run = LoggedRun.from_path(path)
    design = run.controller.spec["design"]
    named = [design] + design["alternatives"]
    assert len(named) >= 2, design["text"]
    assert any(np.allclose(d["num_s"], case.num_s, rtol=1e-9) and np.allclose(d["den_s"], case.den_s, rtol=1e-9)
               for d in named)
    for d in named:
        assert _lab_reproduces(run, d, case.limit, case.recursion, run.alignment), d["text"]
    line = run.audit.lines()[0]
    assert all(d["text"] in line for d in named) and "(the log reproduced by each" in line


def test_a_log_without_a_header_names_the_designs_it_cannot_tell_apart(tmp_path):
    # blind int:trunc_d0 seed 5: a step of 41 on the stored integer under no header; 1(s+18)/(s+66)
    # was run, 1(s+17)/(s+65) is named first, and the one run is among the others said beside it
    path, hidden = write_audit_case(tmp_path, "int:trunc_d0", 5)
    run = LoggedRun.from_path(path)
    design = run.controller.spec["design"]
    named = [design] + design["alternatives"]
    assert any(np.allclose(d["num_s"], hidden.num_s, rtol=1e-9) and np.allclose(d["den_s"], hidden.den_s, rtol=1e-9)
               for d in named)
    for d in named:
        assert _lab_reproduces(run, d, hidden.limit, hidden.recursion, run.alignment), d["text"]
    line = next(x for x in format_report(replay(path)).splitlines() if x.startswith("  controller: "))
    assert all(d["text"] in line for d in named) and "(the log reproduced by each; " in line, line
    assert f"{design['more_alternatives']} more as simple" in line


def test_a_law_on_the_other_stored_integer_is_named_beside_it(tmp_path):
    # blind int:round_d1+coulomb_friction seed 4: 2(s+5)/(s+41) on the rounded integer was run;
    # 2(s+9)/(s+42) on the truncated integer reproduces the step too and is named first (truncation
    # is tried first). The rounding law was said nowhere; now every law that reproduces the log on
    # either stored integer is named, each with the integer its recursion runs on
    path, hidden = write_audit_case(tmp_path, "int:round_d1+coulomb_friction", 4)
    run = LoggedRun.from_path(path)
    design = run.controller.spec["design"]
    law = run.controller.spec.get("recursion", "none")
    named = [design] + design["alternatives"]
    assert any(np.allclose(d["num_s"], hidden.num_s, rtol=1e-9) and np.allclose(d["den_s"], hidden.den_s, rtol=1e-9)
               and d.get("recursion", law) == hidden.recursion for d in named)
    assert {d.get("recursion", law) for d in named} == {"trunc", "round"}
    for d in named:
        assert _lab_reproduces(run, d, hidden.limit, d.get("recursion", law), run.alignment), d["text"]
    line = next(x for x in format_report(replay(path)).splitlines() if x.startswith("  controller: "))
    assert all(d["text"] in line for d in named) and "(on the rounded integer)" in line, line
    assert "(inferred from the data; on the truncated integer)" in line, line  # the answer's own integer too


def test_a_claim_several_runs_share_is_said_once_with_the_runs_it_holds_for():
    """A diagnosis of the lab's April 2009 session said its lying header 16 times, once per
    run, before its answer; each claim is said once now, the runs named where not all hold it."""
    from station.logged.audit import NAMED_RUNS, said_once

    lie, zero = "header: open loop; data: a lead", "header: θ: 0; data: θ starts at 1 count"
    runs = [(f"run{k}.txt", [lie] + ([zero] if k in (2, 5) else []) + ([f"only {k}"] if k == 7 else []))
            for k in range(10)]
    out = said_once(runs)
    assert out == ["audit: 10 of 10 runs: " + lie, f"audit: 2 of 10 runs (run2.txt, run5.txt): {zero}",
                   "audit: run7.txt: only 7"]
    many = said_once([(f"r{k}", [zero] if k < NAMED_RUNS + 2 else []) for k in range(9)])
    named = ", ".join(f"r{k}" for k in range(NAMED_RUNS))
    assert many == [f"audit: {NAMED_RUNS + 2} of 9 runs ({named} and 2 more): {zero}"]
    assert said_once([("a", []), ("b", [])]) == [] and said_once([("a", [lie])]) == [f"audit: a: {lie}"]


def _p_log(tmp_path, name, u, v, theta):
    rows = [f"{k * 0.002:g}\t{k}\t{u[k]:g}\t{v[k]:g}\t{theta[k]:g}\t0" for k in range(len(u))]
    path = tmp_path / f"{name}_SLFR_RTP_P_control_Test.txt"
    path.write_text("\n".join(["#SLFR RTP P_control_Test", "#kp=2.0", "#t\tn\tu\tv\t$\\theta$\ta"] + rows) + "\n")
    return path


@pytest.mark.parametrize("rows", [1, 2, 12, 400])
@pytest.mark.parametrize("kind", ["rest", "bang-bang", "few"])
def test_a_replay_the_data_cannot_judge_says_so(tmp_path, rows, kind):
    # A P log whose v is 0 throughout (a cut of the run before its step, 1-2 rows), only 0 and one
    # level, or free of both on under 10 rows: every law of high gain replays it, and both
    # alignments alike. replay and compare said "reproduces ..., alignment d = 1" and no more
    # (a 1-row log "reproduced" its header); now the audit's doubt follows the verdict in both
    k = np.arange(rows)
    u = np.where(k >= rows // 2, 150.0, 0.0) if kind != "rest" else np.zeros(rows)
    v = np.where(k >= rows // 2, 200.0, 0.0) if kind != "rest" else np.zeros(rows)
    theta = np.zeros(rows)
    if kind == "few":  # the hub creeps 1 count on 3 rows: v = 2·(150 − 1) there... still too few rows
        theta[-3:] = 1.0 if rows > 3 else 0.0
        v = np.where(k >= rows // 2, np.minimum(2 * (u - np.roll(theta, 1)), 200.0), 0.0)
    path = _p_log(tmp_path, f"{kind}{rows}", u, v, theta)
    run = LoggedRun.from_path(path)
    claim = run.audit.of("controller")
    assert run.reproduced and claim.verdict == "unchecked", claim
    text = format_report(replay(path))
    assert "replay reproduces the logged v" in text
    assert "the data cannot confirm this one" in text.split("replay reproduces the logged v", 1)[1]
    notes = compare_run(path, DiscretePlant()).notes
    assert any("the data cannot confirm this one" in n for n in notes), notes
    if kind == "rest":
        assert "v is 0 on every row" in text and "(0 and 1 alike: the data cannot tell them apart)" in text


def test_a_replay_the_data_judge_says_no_doubt(tmp_path):
    # The converse, from a separate law: v[k] = trunc(2·(u[k] − θ[k−1])) over a hub that moves every
    # row. The law is pinned and the alignment decided: one line, no "but", no "alike"
    rng = np.random.default_rng(7)
    k = np.arange(300)
    u = np.where(k >= 20, 50.0, 0.0)
    theta = np.concatenate([[0.0] * 20, np.cumsum(rng.integers(1, 3, 280)) * 0.1]).round()
    prev = np.concatenate([[0.0], theta[:-1]])
    v = np.clip(np.trunc(2 * (u - prev)), -200, 200)
    path = _p_log(tmp_path, "moving", u, v, theta)
    text = format_report(replay(path))
    line = next(x for x in text.splitlines() if "replay reproduces" in x)
    assert line.endswith("alignment d = 1"), line
    assert "cannot confirm" not in text
