"""Column faults found under a header that lies, and θ written with the other sign.

The audit found each column fault under a true header (a swap, v in volts) and each lying
header over true columns; two at once were left standing. The rig's own logs, rewritten by
a script written from the format, with the fault a lab script could make, and the blind
generator's ``sign`` and ``double`` classes (its own FEM, lab controller and writer).
Before: θ negated under a true P header gave a false "u and v swapped" and a θ fit of
−312 %; the thesis's lead under an open-loop header with u and v swapped, "no law found"
and −6348 %; the lab's session step with v in volts, "no law found" and −406 % (its v steps
by one count: the unit is decided; a P step's v steps by kp counts, and with no law named
its gain and v's unit are one).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station.analysis.law_words import thesis_ga_sign
from station.compare import thesis_case
from station.logged import LoggedRun
from station.logged.sensor_evidence import sensor_evidence
from station.logged.sensors import decide_faults
from station.plant import load_model
from tests.blind.audit import U_UNITS, V_UNITS, AuditCase, write_audit_case, write_case

P = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
LEAD = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
PULSES = "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"
P_2009 = "2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt"
SWEEP = "swept_sine_kp_1_amp_50.txt"
OPEN_LOOP = ["#SLFR RTP OL_Test"]


def _rewrite(src: Path, dst: Path, header=None, negate=False, swap=False, volts=None, negate_a=False,
             degrees=False, corrupt=None, zero=None, drop=None, theta0=None) -> Path:
    """The log with its header replaced (the column line kept), θ (or a) negated or written in
    degrees (6 decimals), u and v swapped, v written in volts of ``volts`` per count (7 digits)
    or about ``zero`` (an unsigned DAC code); ``corrupt`` (row, counts): that row's θ field, as
    written, that many higher (a digit or bit a serial line or a writer got wrong); ``drop``
    (row, rows): that many rows lost from that one on; ``theta0``: θ written from that count
    (the encoder's, where the loop took it off), before any negation; every other field as it was."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    out = []
    for ln in lines:
        if not ln.strip() or ln.startswith("#"):
            continue
        f = ln.split()
        if theta0 is not None:
            f[4] = f"{float(f[4]) + theta0:g}"
        if negate:
            f[4] = f"{-float(f[4]):g}"
        if degrees:
            f[4] = f"{float(f[4]) * 360 / 1024:.6f}"
        if corrupt is not None and len(out) == corrupt[0]:
            f[4] = f"{float(f[4]) + corrupt[1]:g}"
        if negate_a:
            f[5] = f"{-float(f[5]):.10g}"
        if volts is not None:
            f[3] = f"{float(f[3]) * volts:.7g}"
        if zero is not None:
            f[3] = f"{float(f[3]) + zero:.10g}"
        if swap:  # after volts: the command's column, in volts, moves
            f[2], f[3] = f[3], f[2]
        out.append("\t".join(f))
    if drop is not None:
        out = out[:drop[0]] + out[drop[0] + drop[1]:]
    dst.write_text("\n".join((head if header is None else header + head[-1:]) + out) + "\n")
    return dst


def _said(run: LoggedRun) -> set[str]:
    return {c.data for c in run.audit.claims if c.verdict == "contradicted" and c.claim == "columns"}


@pytest.mark.parametrize("name, header", [(P, None), (LEAD, None), (P, OPEN_LOOP), (LEAD, OPEN_LOOP),
                                          (P_2009, None), (SWEEP, None), (SWEEP, OPEN_LOOP)])
def test_theta_written_negated_is_read_back(rig_data, tmp_path, name, header):
    """Also the mirror a law cannot decide: a P law of gain 1 (the 2014 sweep, kp = 1) reads the
    same with θ negated as with u and v swapped. On the sweep the hub lags its reference, so how
    closely θ follows u could not tell them apart: before, "u and v swapped" and a θ fit of
    -367558 %; the nominal model run in closed loop by the law decides (``logged.rewrite_evidence.model_miss``)."""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "neg.txt", header, negate=True))
    assert _said(run) == {"θ written with the other sign"}
    assert run.reproduced and run.source == ("header" if header is None else "inferred (header contradicted)")
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)
    # the sensors then see the encoder as the model's: no encoder reversal claimed on top
    assert "encoder_scale" not in run.sensors.effects and "motor_polarity" not in run.sensors.effects


@pytest.mark.parametrize("name, header", [(P, None), (P, OPEN_LOOP), (LEAD, None), (LEAD_ACCEL, OPEN_LOOP),
                                          (P_2009, []), (SWEEP, None), (SWEEP, OPEN_LOOP)])
@pytest.mark.parametrize("fault", ["negate", "swap"])
def test_theta_from_its_zero_beside_a_sign_or_a_swap(rig_data, tmp_path, name, header, fault):
    """θ written from the encoder's count 59 where the loop took it off, beside θ negated or u
    and v swapped: two column faults, under the true header, an open-loop one or none. Each
    was found alone; together, the θ zero was tried only on the columns as named and the
    rewrites only from θ's written zero. The P step read as "2(s+5e-12)/(s+2e-12) ... with its
    first row of memory taken as logged" (θ fit -342 %), the lead as "no law found". Now a
    rewrite whose θ rests off 0 has its zero taken off as well; the kp = 1 sweep, whose
    law reads the same from θ0 with u and v exchanged as from −θ0 with θ negated, is told by
    the nominal model as the one-fault mirror is."""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "zero.txt", header, theta0=59.0,
                                       negate=fault == "negate", swap=fault == "swap"))
    said = {"negate": "θ written with the other sign", "swap": "u and v swapped"}[fault]
    assert _said(run) == {said, "θ logged before its zero was taken off (θ0 = 59 counts)"}
    assert run.reproduced and run.source == ("header" if header is None else
                                             "inferred (header contradicted)" if header else "inferred")
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)
    assert "encoder_scale" not in run.sensors.effects


@pytest.mark.parametrize("header", [None, OPEN_LOOP])
def test_a_session_with_a_negated_gets_one_sign(rig_data, tmp_path, header):
    """The rig's four logs with a negated (a lab script that wrote a with the other sign than
    its loop fed back), under their headers or open-loop ones. Before, the lead + accelerometer
    step under its own header read its a column back ("a written with the other sign") while the
    other three read the accelerometer reversed; the session then decided accel_gain -1.31 for all
    four, reversing that run's a twice: its loop's feedback turned positive, and `station
    diagnose` on the four saw a nominal θ fit of 37.8 % (75.9 % under open-loop headers, where Ga
    took the sign). Now a's sign is Ga's everywhere: the thesis's Ga on -a, beside the
    accelerometer read reversed, and every run of the session simulates as its clean log does."""
    model = load_model("tmm-fit")
    runs, clean = [], []
    for name in (PULSES, P, LEAD, LEAD_ACCEL):
        head = header if header is not None and name != PULSES else None
        runs.append(LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / name, head, negate_a=True)))
        clean.append(LoggedRun.from_path(rig_data / name))
    assert not any("a written with the other sign" in _said(run) for run in runs)
    ga = runs[-1]
    assert ga.reproduced and ga.source == "inferred (header contradicted)"
    assert thesis_ga_sign(ga.controller.ga, ga.log.dt) == -1
    assert "the thesis's accelerometer feedback Ga on -a" in ga.audit.of("controller").data
    assert thesis_case(ga, ga.reference.amplitude) == "lead-accel"
    session = decide_faults([sensor_evidence(run, model) for run in runs]).effects
    assert session["accel_gain"] < 0 and all(run.sensors.effects["accel_gain"] < 0 for run in runs)
    faulty = model.with_effects(session)
    for run, whole in zip(runs, clean):
        fit, was = run.simulate(faulty, sensors=False).fit_pct, whole.simulate(model, sensors=False).fit_pct
        assert fit["theta"] >= was["theta"] - 5.0, (run.log.path, fit, was)


@pytest.mark.parametrize("name", [P, LEAD, LEAD_ACCEL])
def test_a_true_log_is_never_read_negated_or_swapped(rig_data, name):
    assert not _said(LoggedRun.from_path(rig_data / name))


def test_the_thesis_lead_under_an_open_loop_header_with_u_and_v_swapped(rig_data, tmp_path):
    run = LoggedRun.from_path(_rewrite(rig_data / LEAD, tmp_path / "ol_swap.txt", OPEN_LOOP, swap=True))
    assert _said(run) == {"u and v swapped"}
    assert run.source == "inferred (header contradicted)" and run.reproduced
    assert run.controller.spec["design"]["text"] == "20(s+2π·5)/(s+2π·20)"


@pytest.mark.parametrize("header", [None, OPEN_LOOP])
def test_the_kp_1_sweep_with_u_and_v_swapped_is_not_read_theta_negated(rig_data, tmp_path, header):
    """The mirror of :func:`test_theta_written_negated_is_read_back`'s sweep: before, u and v
    swapped on the 2014 sweep (P, kp = 1) under an open-loop header were read "θ written with the
    other sign", θ fit -367558 %."""
    clean = LoggedRun.from_path(rig_data / SWEEP)
    run = LoggedRun.from_path(_rewrite(rig_data / SWEEP, tmp_path / SWEEP, header, swap=True))
    assert _said(run) == {"u and v swapped"} and run.reproduced
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)


def test_the_2014_sweep_without_accelerometer_with_theta_negated_under_an_open_loop_header(rig_data, tmp_path):
    """21 s of a kp = 1 sweep in the 2014 layout (θ third): the nominal model driven open loop by
    v drifts far over such a run (θ RMS 231 counts against 131 for the wrong rewrite, u and v
    swapped), so the rewrites are judged in closed loop, each by its law. Before: "u and v
    swapped", θ fit -357256 %."""
    name = "without_accel_01_28_14_test_2.txt"
    lines = (rig_data / name).read_text().splitlines()
    rows = [ln.split("\t") for ln in lines[1:] if ln.strip()]
    for f in rows:
        f[2] = f"{-float(f[2]):g}"
    path = tmp_path / name
    path.write_text("\n".join(OPEN_LOOP + lines[:1] + ["\t".join(f) for f in rows]) + "\n")
    clean, run = LoggedRun.from_path(rig_data / name), LoggedRun.from_path(path)
    assert lines[0].split("\t")[2] == "theta" and _said(run) - _said(clean) == {"θ written with the other sign"}
    assert "u and v swapped" not in _said(run)
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)


def test_a_p_step_with_theta_negated_is_not_a_swap(rig_data, tmp_path):
    # with u and v swapped back, v is the 0/50 step: any law of high gain at a ±50 clamp gives it
    run = LoggedRun.from_path(_rewrite(rig_data / P, tmp_path / "neg.txt", negate=True))
    assert "u and v swapped" not in _said(run)


@pytest.mark.parametrize("header", [OPEN_LOOP, ["#SLFR RTP P_control_Test", "#kp=1.5"], None])
def test_the_2009_p_step_negated_is_negated_not_swapped(rig_data, tmp_path, header):
    """The 2009 P step (kp = 1 at alignment 0: v = u − θ, one row) with θ negated reads the same
    law as v and θ exchanged and kp = −1 (θ' = −θ: v = u + θ', and θ' = −(u − v)): no law tells
    them apart, the tracking does (a closed loop's θ follows u). Before, under an open-loop
    header or one that lies about kp: "v and θ swapped", P kp = −1, overshoot 0 %, θ fit −10 867 %
    (under its own header the header's law decided: θ negated)."""
    clean = LoggedRun.from_path(rig_data / P_2009)
    run = LoggedRun.from_path(_rewrite(rig_data / P_2009, tmp_path / "neg.txt", header, negate=True))
    assert _said(run) == {"θ written with the other sign"}
    assert run.reproduced and run.alignment == 0 and run.controller.spec["kp"] == 1.0
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)


@pytest.mark.parametrize("name", [P, LEAD, P_2009])
@pytest.mark.parametrize("fault", ["negate", "degrees", "swap"])
def test_a_column_fault_beside_a_corrupted_field(rig_data, tmp_path, name, fault):
    """A column fault (θ negated, θ in degrees, u and v swapped) beside one corrupted θ field
    (row 500 written 64 higher). Each alone was found; together the rewrite was judged on every
    row, the corrupted one too, and refused: "no law found" (θ fit −197 to −15 469 %), or on the
    2009 step "v and θ swapped" with kp = −1. Now a rewrite is judged as the law is, its
    corrupted fields set aside (:func:`station.logged.columns.check_columns`), and θ's unit
    spares them (:func:`station.logged.quantum.quantum_fits`): the fault said, the field set
    aside, the clean log's numbers."""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / f"{fault}.txt", negate=fault == "negate",
                                       degrees=fault == "degrees", swap=fault == "swap", corrupt=(500, 64)))
    said = {"negate": "θ written with the other sign", "degrees": "θ in degrees", "swap": "u and v swapped"}[fault]
    assert _said(run) == {said}
    assert run.reproduced and run.identified.corrupted.theta_rows == (500,)
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.5)


@pytest.mark.parametrize("name, fault", [(P, "volts"), (P_2009, "volts"), (P, "zero"), (LEAD, "zero")])
def test_the_commands_unit_or_zero_beside_a_corrupted_field(rig_data, tmp_path, name, fault):
    """v in volts (5/2048 V a count) or about an unsigned DAC code's 2048, beside θ of row 500
    written 64 higher. The unit and the zero are read where the header's law then reproduces v;
    judged on every row, the corrupted one too, neither was: "v in another unit, its size not
    found" (the P step: overshoot 132 %, the 2009 step 65 %), or "not this law (max |dv| = 2.2e+03
    counts)". Now the header's law past its corrupted fields decides them."""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / f"{fault}.txt", corrupt=(500, 64),
                                       volts=5 / 2048 if fault == "volts" else None,
                                       zero=2048.0 if fault == "zero" else None))
    said = {"volts": "v in steps of 0.00244141", "zero": "v about 2048 counts"}[fault]
    assert _said(run) == {said}
    assert run.source == "header" and run.reproduced and run.identified.corrupted.theta_rows == (500,)
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.5)


@pytest.mark.parametrize("name, fault", [(LEAD_ACCEL, "negate"), (LEAD_ACCEL, "swap"), (LEAD_ACCEL, "volts"),
                                         (LEAD, "volts")])
def test_a_column_fault_beside_rows_lost(rig_data, tmp_path, name, fault):
    """A column fault beside 11 rows lost at row 300, under the true header. The lead + Ga
    step's law is judged on the rows before the jump (Ga's state is in no column); the header's
    law was judged across it, and every rewrite refused: θ negated read "the encoder the other
    way" with "no law found", u and v swapped "undecided" beside a false accelerometer offset,
    and a float v in volts (on the lead too: its unit's ratio judged by a replay that did not
    start again at the jump) "size not found" or a crash. Now each fault is said and the log
    reads as the same log without it."""
    plain = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "plain.txt", drop=(300, 11)))
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / f"{fault}.txt", drop=(300, 11),
                                       negate=fault == "negate", swap=fault == "swap",
                                       volts=5 / 2048 if fault == "volts" else None))
    said = {"negate": "θ written with the other sign", "swap": "u and v swapped",
            "volts": "v in units of 0.00244141"}[fault]
    assert _said(run) - {"n jumps at 1 row"} == {said}
    assert run.source == "header" and run.reproduced
    assert run.identified.judged_to == plain.identified.judged_to == (300 if name == LEAD_ACCEL else None)
    assert run.step_metrics() == plain.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(plain.simulate(model).fit_pct["theta"], abs=0.5)


@pytest.mark.parametrize("name, header, fault", [
    (P, None, "volts"), (LEAD, None, "volts"), (LEAD_ACCEL, None, "volts"), (P_2009, [], "volts"),
    (P_2009, OPEN_LOOP, "volts"), (SWEEP, OPEN_LOOP, "volts"),
    (P, None, "zero"), (P, OPEN_LOOP, "zero"), (P, [], "zero"), (P_2009, OPEN_LOOP, "zero"), (SWEEP, [], "zero")])
def test_theta_from_its_zero_beside_the_commands_unit_or_zero(rig_data, tmp_path, name, header, fault):
    """θ written from the encoder's count −59 where the loop took it off, beside v in volts of a
    ±5 V 12-bit converter or about 128 (an unsigned 8-bit DAC code): a script that wrote the
    device's raw words. Each fault alone was read; together the unit and v's zero were asked
    only from θ as written. The P step read 1(s+5e-12)/(s+2e-12) (volts) or 2(s-1e-12)/(s-8e-12)
    (about 128) "with its first row of memory taken as logged", the thesis's leads "no law found".
    A P law's v in volts is read under its own header, or where kp = 1 decides the unit (with
    no law named, gain and unit are one)."""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "zero.txt", header, theta0=-59.0,
                                       volts=5 / 2048 if fault == "volts" else None,
                                       zero=128.0 if fault == "zero" else None))
    said = _said(run) - {"θ logged before its zero was taken off (θ0 = -59 counts)"}
    assert len(said) == 1 and len(_said(run)) == 2
    if fault == "volts":
        assert next(iter(said)) in {"v in steps of 0.00244141", "v in units of 0.00244141"}
    else:
        assert said == {"v about 128 counts"}
    assert run.reproduced and run.source == ("header" if header is None else
                                             "inferred (header contradicted)" if header else "inferred")
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)


@pytest.mark.parametrize("header", [[], OPEN_LOOP])
def test_an_encoder_not_zeroed_is_not_read_as_two_zeros(rig_data, tmp_path, header):
    """The loop ran on θ as written (the encoder not zeroed): its P law reproduces v from θ's
    rest count, v reading −kp·θ0 there. That is one claim on the start, not v about −kp·θ0
    beside θ from its zero, which gives the same v
    (:func:`station.logged.column_zeros.check_command_offset` asks θ's zero only where no law
    reproduces the log as written)."""
    src = _rewrite(rig_data / P_2009, tmp_path / "raw.txt", header, theta0=-59.0)
    lines = src.read_text().splitlines()
    out = [ln if ln.startswith("#") else "\t".join(
        f[:3] + [f"{float(f[3]) + 59.0:g}"] + f[4:]) for ln in lines for f in [ln.split()]]
    src.write_text("\n".join(out) + "\n")
    run = LoggedRun.from_path(src)
    said = _said(run)  # (v rewritten without the hub's answer to it: the sensors' check is not asked here)
    assert run.reproduced and "θ starts at -59 counts (the encoder not zeroed)" in said
    assert not {c for c in said if c.startswith(("v about", "θ logged before"))}
    assert run.controller.spec.get("kind") == "p" and run.controller.spec.get("kp") == 1.0


# zero:command: the session's open-loop header over volts of a 16-bit DAC and over 32768, a lead about
# 128 under no header, a P in volts under its header, a float P about 128, a lead in volts under none
@pytest.mark.parametrize("seed", [0, 1, 4, 6, 8, 5])
def test_blind_theta_from_its_zero_beside_the_commands_unit_or_zero(tmp_path, seed):
    path, hidden = write_audit_case(tmp_path, "zero:command", seed)
    run = LoggedRun.from_path(path)
    assert run.reproduced and run.alignment == hidden.alignment
    sources = {"none": "inferred", "open-loop": "inferred (header contradicted)"}
    assert run.source == sources.get(hidden.header, "header")
    said = _said(run) - {f"θ logged before its zero was taken off (θ0 = {hidden.theta_zero:g} counts)"}
    assert len(_said(run)) == 2 and len(said) == 1
    if hidden.v_zero is not None:
        assert said == {f"v about {hidden.v_zero:g} counts"}
    else:
        (unit,) = said
        assert unit.startswith(("v in steps of", "v in units of"))
        assert float(unit.split()[-1]) == pytest.approx(V_UNITS[hidden.v_unit], rel=1e-3)


# a hub Coulomb friction holds still the whole run (a lead on a 29-count sine, friction 40 DAC
# counts), v written in volts: before, u and θ read swapped under every header (the swap moved
# the hub that "v under one count while the hub moved" asks for), with a gain −2 law and a
# reference "moving at t = 0"; with θ0 beside it too, u and v swapped and a law 1700(s+50)/(s+2π·2)
@pytest.mark.parametrize("header", ["lead", "none", "open-loop"])
@pytest.mark.parametrize("unit", sorted(V_UNITS))
@pytest.mark.parametrize("zero", [None, -59.0])
def test_blind_a_hub_held_still_with_v_in_volts_is_no_swap(tmp_path, header, unit, zero):
    case = AuditCase(name="v_unit+coulomb_friction", law="lead", kp=None, num_s=(2.0, 26.0), den_s=(1.0, 40.0),
                     design_text="2(s+13)/(s+40)", recursion="trunc", alignment=0, limit=200.0, header=header,
                     header_kp=None, reference="sine", amplitude=29.0, effects={"coulomb_friction": 40.0},
                     v_unit=unit, theta_zero=zero)
    path, _ = write_case(tmp_path, case, 0)
    run = LoggedRun.from_path(path)
    assert np.ptp(np.asarray(run.log.data["theta"], dtype=float)) == 0  # the hub never moved: the case holds
    assert run.reproduced
    sources = {"none": "inferred", "open-loop": "inferred (header contradicted)"}
    assert run.source == sources.get(header, "header")
    said = _said(run) - ({f"θ logged before its zero was taken off (θ0 = {zero:g} counts)"} if zero else set())
    assert len(_said(run)) == 1 + (zero is not None) and len(said) == 1
    (step,) = said
    assert step.startswith("v in steps of") and float(step.split()[-1]) == pytest.approx(V_UNITS[unit], rel=1e-3)


# the same under a P header on a step: v is only 0 and kp·u, which any law gives at a clamp of its
# peak, in any unit. Before, with θ0 = -116: v "in steps of 0.00915527" (30 counts: kp·u, the law at
# a clamp of 1) and not reproduced by 29 counts; with θ0 = 0, "P, kp = 1.2: not this law, no law
# found". A converter's count (±2.5, 5 or 10 V, 8 to 16 bits) read by the header's law at its own
# clamp is the size now; a header that lies about kp reads no size.
@pytest.mark.parametrize("unit", sorted(V_UNITS))
@pytest.mark.parametrize("zero", [None, -116.0])
@pytest.mark.parametrize("header_kp", [1.2, 1.5])
def test_blind_a_p_step_held_still_with_v_in_volts(tmp_path, unit, zero, header_kp):
    case = AuditCase(name="zero:command+coulomb_friction", law="p", kp=1.2, num_s=None, den_s=None,
                     design_text="P, kp = 1.2", recursion="trunc", alignment=1, limit=200.0, header="p",
                     header_kp=header_kp, reference="step", amplitude=25.0, effects={"coulomb_friction": 60.0},
                     v_unit=unit, theta_zero=zero)
    path, _ = write_case(tmp_path, case, 4)
    run = LoggedRun.from_path(path)
    assert np.ptp(np.asarray(run.log.data["theta"], dtype=float)) == 0  # the hub never moved: the case holds
    said = _said(run) - ({f"θ logged before its zero was taken off (θ0 = {zero:g} counts)"} if zero else set())
    if header_kp == 1.2:
        assert run.source == "header" and run.reproduced
        assert len(_said(run)) == 1 + (zero is not None) and said == {f"v in steps of {V_UNITS[unit]:.6g}"}
    else:  # the lie's kp·u in counts of no converter: no size read, the header contradicted
        assert not run.reproduced and not any(x.startswith("v in steps") for x in said)
        assert next(c for c in run.audit.claims if c.claim == "controller").verdict == "contradicted"


# u in degrees or radians on that step. Before, under its true header: "P, kp = 1: not this law, no
# law found" (a true header contradicted: u's unit was read only on a v that pins a law). The
# header's law at its own clamp reads it now. Guards: u and v swapped give a "P law" in steps of
# v/u (a draft read it so: a ratio of v to u is no converter's count); a header that lies about kp
# reads no unit and is contradicted.
@pytest.mark.parametrize("unit", sorted(U_UNITS))
@pytest.mark.parametrize("kp, header_kp", [(1.0, 1.0), (1.5, 1.5), (1.5, 1.2)])
def test_blind_a_p_step_held_still_with_u_in_degrees_or_radians(tmp_path, unit, kp, header_kp):
    case = AuditCase(name="u_unit+coulomb_friction", law="p", kp=kp, num_s=None, den_s=None,
                     design_text=f"P, kp = {kp:g}", recursion="none", alignment=1, limit=200.0, header="p",
                     header_kp=header_kp, reference="step", amplitude=25.0, effects={"coulomb_friction": 60.0},
                     u_unit=unit)
    path, _ = write_case(tmp_path, case, 2)
    run = LoggedRun.from_path(path)
    assert np.ptp(np.asarray(run.log.data["theta"], dtype=float)) == 0  # the hub never moved: the case holds
    said = _said(run)
    assert not any("swapped" in x or x.startswith("v in steps") for x in said)
    if header_kp == kp:
        assert said == {f"u in {unit}"} and run.source == "header" and run.reproduced
        assert run.controller.spec.get("kp") == kp
    else:
        assert not said and not run.reproduced
        assert next(c for c in run.audit.claims if c.claim == "controller").verdict == "contradicted"


# u and v swapped on a P step the hub never follows: v is then the step and u is kp·u, which the
# header's law gives at a clamp of v's peak (as any law of high gain does). Before, "P, kp = 1.5:
# not this law, no law found" (a true header contradicted), and with θ0 beside it θ0 was said on
# that peak clamp and the log not reproduced. Now the swap is read at the law's own clamp, θ0 with
# it; a header that lies about kp reads no swap. A saturated step (kp·u past the ±200 clamp) too.
@pytest.mark.parametrize("kp, header_kp, amplitude", [(1.5, 1.5, 25.0), (1.2, 1.2, 25.0), (2.5, 2.5, 120.0),
                                                      (1.5, 1.2, 25.0)])
@pytest.mark.parametrize("zero", [None, -58.0])
def test_blind_a_p_step_held_still_with_u_and_v_swapped(tmp_path, kp, header_kp, amplitude, zero):
    case = AuditCase(name="swap+coulomb_friction", law="p", kp=kp, num_s=None, den_s=None,
                     design_text=f"P, kp = {kp:g}", recursion="trunc", alignment=1, limit=200.0, header="p",
                     header_kp=header_kp, reference="step",
                     amplitude=amplitude, effects={"coulomb_friction": 60.0 if amplitude < 100 else 450.0},
                     swap=("u", "v"), theta_zero=zero)
    path, _ = write_case(tmp_path, case, 0)
    run = LoggedRun.from_path(path)
    assert np.ptp(np.asarray(run.log.data["theta"], dtype=float)) == 0  # the hub never moved: the case holds
    zeroed = {f"θ logged before its zero was taken off (θ0 = {zero:g} counts)"} if zero else set()
    if header_kp == kp:
        assert run.source == "header" and run.reproduced and _said(run) == {"u and v swapped"} | zeroed
    else:
        assert "u and v swapped" not in _said(run) and not run.reproduced
        assert next(c for c in run.audit.claims if c.claim == "controller").verdict == "contradicted"


# a guard: v and θ swapped on a P sweep of kp = 1 the hub never follows (v = u) leave v at 0 and
# the error at 0, which every law gives; a draft read the swap so, under a header lying about kp
def test_blind_a_rewrite_to_a_v_of_zero_is_no_swap(tmp_path):
    case = AuditCase(name="lie:p_kp+coulomb_friction", law="p", kp=1.0, num_s=None, den_s=None,
                     design_text="P, kp = 1", recursion="none", alignment=1, limit=150.0, header="p", header_kp=2.0,
                     reference="sweep", amplitude=25.0, effects={"coulomb_friction": 60.0})
    path, _ = write_case(tmp_path, case, 2)
    run = LoggedRun.from_path(path)
    assert np.ptp(np.asarray(run.log.data["theta"], dtype=float)) == 0  # the hub never moved: the case holds
    assert not any("swapped" in x for x in _said(run)) and run.source == "inferred (header contradicted)"


# θ and a swapped beside v in volts, the hub held still: the column named θ (a's noise) moves, the
# one named a does not. Before: "moving at t = 0" and v "in another unit, its size not found"
# (the swap's v was read only where its hub moved)
@pytest.mark.parametrize("unit", sorted(V_UNITS))
def test_blind_theta_and_a_swapped_beside_v_in_volts_the_hub_held_still(tmp_path, unit):
    case = AuditCase(name="pair+coulomb_friction", law="lead", kp=None, num_s=(1.5, 36.0), den_s=(1.0, 66.0),
                     design_text="1.5(s+24)/(s+66)", recursion="trunc", alignment=0, limit=200.0, header="lead",
                     header_kp=None, reference="step", amplitude=25.0, effects={"coulomb_friction": 60.0},
                     v_unit=unit, swap=("theta", "a"))
    path, _ = write_case(tmp_path, case, 1)
    run = LoggedRun.from_path(path)
    assert np.ptp(np.asarray(run.log.data["theta"], dtype=float)) == 0  # the hub never moved: the case holds
    assert run.source == "header" and run.reproduced
    assert _said(run) == {"θ and a swapped", f"v in steps of {V_UNITS[unit]:.6g}"}


# rows:column: the thesis's lead + Ga (named) with θ and a swapped, v in volts (a sine) and θ negated,
# a lead on the stored integer with u and v swapped over three gaps, and a P with θ and a swapped (the
# last two were read already: their laws' memory is in the rows)
@pytest.mark.parametrize("case, seed", [("rows:column", s) for s in (6, 4, 8, 1, 0)])
def test_blind_column_faults_beside_rows_lost(tmp_path, case, seed):
    path, hidden = write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    assert run.source == "header" and run.reproduced and run.alignment == hidden.alignment
    assert (run.identified.judged_to is not None) is (hidden.ga_s is not None)
    said = _said(run) - {"n jumps at 1 row", "n jumps at 2 rows", "n jumps at 3 rows"}
    shown = {"u": "u", "v": "v", "theta": "θ", "a": "a"}
    if hidden.negate:
        assert said == {"θ written with the other sign"}
    elif hidden.swap:
        assert said == {f"{shown[hidden.swap[0]]} and {shown[hidden.swap[1]]} swapped"}
    else:
        assert len(said) == 1 and next(iter(said)).startswith(("v in steps of", "v in units of"))


# zero:column: a P of gain 1 (the mirror), a P at alignment 0, a lead on the sweep, one under no
# header and one under the session's open-loop header; each read no law, or a near-integrator, before
@pytest.mark.parametrize("seed", [1, 3, 4, 5, 9])
def test_blind_theta_from_its_zero_beside_a_sign_or_a_swap(tmp_path, seed):
    path, hidden = write_audit_case(tmp_path, "zero:column", seed)
    run = LoggedRun.from_path(path)
    assert run.reproduced and run.alignment == hidden.alignment
    sources = {"none": "inferred", "open-loop": "inferred (header contradicted)"}
    assert run.source == sources.get(hidden.header, "header")
    fault = "θ written with the other sign" if hidden.negate else "u and v swapped"
    assert _said(run) == {fault, f"θ logged before its zero was taken off (θ0 = {hidden.theta_zero:g} counts)"}


@pytest.mark.parametrize("volts", [5 / 2048, 10 / 32768])
def test_the_thesis_p_step_in_volts_under_an_open_loop_header(rig_data, tmp_path, volts):
    clean = LoggedRun.from_path(rig_data / P)
    run = LoggedRun.from_path(_rewrite(rig_data / P, tmp_path / "volts.txt", OPEN_LOOP, volts=volts))
    (said,) = _said(run)
    step = float(said.split()[-1])
    claim = next(c for c in run.audit.claims if c.data == said)
    assert "the header's open loop (v = u) reproduces neither" in claim.evidence
    assert run.source == "inferred (header contradicted)" and run.reproduced
    # a P law's v scaled is another kp: with no law named only the law in volts is decided
    # (kp 2 on steps of one count, or kp 1 on steps of two: the largest step is taken)
    assert step == pytest.approx(2 * volts, rel=1e-3) and run.controller.spec["kp"] == 1.0
    assert run.controller.spec["kp"] * step == pytest.approx(2.0 * volts, rel=1e-3)
    assert run.step_metrics() == clean.step_metrics()  # θ and u as logged: the run's own step


# seeds that draw each header (sign: none, open loop, P, lead) and each fault beside the
# session's lie (double: u/v swap, v in volts, printed to 5 digits); all ten of each in
# scripts/validate_audit.py
@pytest.mark.parametrize("case, seed", [("sign", s) for s in (0, 2, 4, 9)] + [("double", s) for s in (0, 2, 7)])
def test_blind_sign_and_double_faults(tmp_path, case, seed):
    path, hidden = write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    controller = next(c for c in run.audit.claims if c.claim == "controller")
    assert (controller.verdict == "contradicted") is hidden.lies
    assert run.reproduced and run.alignment == hidden.alignment
    said = _said(run)
    if hidden.negate:
        assert said == {"θ written with the other sign"}
    elif hidden.swap:
        assert said == {"u and v swapped"}
    elif hidden.v_unit is not None:
        assert len(said) == 1 and next(iter(said)).startswith("v in steps of")
    else:  # printed to few digits: judged to its printing, no column contradicted
        assert not said


# sign: the headers none, open loop (at alignments 1 and 0), P and lead; seed 2 (an open-loop
# header over a lead on the truncated integer at alignment 0 whose law needs rows on a
# quantization boundary) is left out: with its θ field corrupted no law is found even with θ
# as the loop fed it back (a corrupted field beside boundary rows, not the sign)
@pytest.mark.parametrize("case, seed", [("sign", s) for s in (0, 3, 4, 7, 9)] + [("double", s) for s in (0, 7)])
def test_blind_column_faults_beside_a_corrupted_field(tmp_path, case, seed):
    """The generator's θ negated (under each header) and the session's lie beside a column
    fault, with one θ field 40 counts higher where the hub moves: the fault and the lie said as
    without it, the field set aside at its row, the law at the hidden alignment."""
    path, hidden = write_audit_case(tmp_path, case, seed)
    clean = LoggedRun.from_path(path)
    moves = np.flatnonzero(np.abs(np.diff(clean.data["theta"])) > 0)
    row = int(moves[moves.size // 2])  # the hub moves there
    _corrupt_theta(path, row, 40)  # as written: the column θ is named by (negated or not)
    run = LoggedRun.from_path(path)
    assert _said(run) == _said(clean)
    assert run.source == clean.source and run.reproduced and run.alignment == hidden.alignment
    assert run.identified.corrupted is not None and run.identified.corrupted.theta_rows == (row,)
    assert run.step_metrics() == clean.step_metrics()


def test_a_p_header_with_the_wrong_kp_over_swapped_columns(rig_data, tmp_path):
    """The header's law reproduces no rewrite when it lies too: the data's law is inferred on
    each rewrite as under an open-loop header. Before: 'P, kp = 1.5; data: not this law, no law
    found', the model driven by u as v."""
    run = LoggedRun.from_path(_rewrite(rig_data / P, tmp_path / "kp_swap.txt",
                                       ["#SLFR RTP P_control_Test", "#kp=1.5"], swap=True))
    assert _said(run) == {"u and v swapped"}
    assert run.source == "inferred (header contradicted)" and run.reproduced
    assert run.controller.spec["kp"] == 2.0


@pytest.mark.parametrize("seed, pair", [(32, ("u", "v")), (55, ("theta", "a")), (3, ("u", "v"))])
def test_blind_p_header_lies_and_columns_swapped(tmp_path, seed, pair):
    import dataclasses

    import tests.blind.audit as blind

    case = dataclasses.replace(blind.draw_case("lie:p_kp", seed), swap=pair)
    sim = blind.simulate_audit_case(case, seed)
    sim = dataclasses.replace(sim, **{pair[0]: getattr(sim, pair[1]), pair[1]: getattr(sim, pair[0])})
    path = tmp_path / f"p_swap_{seed}_SLFR_RTP_P_control_Test.txt"
    path.write_text(blind.format_audit_run(case, sim))
    run = LoggedRun.from_path(path)
    shown = {"theta": "θ"}
    assert _said(run) == {f"{shown.get(pair[0], pair[0])} and {shown.get(pair[1], pair[1])} swapped"}
    assert run.source == "inferred (header contradicted)" and run.reproduced
    assert run.controller.spec["kp"] == case.kp and run.alignment == case.alignment


LYING_LEAD = ["#SLFR RTP Motor_Comp_w_accel_fb", "#Gth num=[ 2.97 -2.89]", "#Gth den=[ 1. -0.957]"]


@pytest.mark.parametrize("fault", ["volts", "zero"])
@pytest.mark.parametrize("header", [["#SLFR RTP P_control_Test", "#kp=1.5"], LYING_LEAD])
def test_a_lying_closed_loop_header_over_the_commands_unit_or_zero(rig_data, tmp_path, header, fault):
    """The thesis's P step (kp = 2) under a header naming another law, its v in volts or about
    an unsigned DAC code's 2048: the data's law reads v back as under an open-loop header.
    Before: 'not this law; v in another unit, its size not found', or (about 2048, under the
    lead) 2(s-5e-12)/(s-3e-13) with "cut from a longer run"."""
    clean = LoggedRun.from_path(rig_data / P)
    run = LoggedRun.from_path(_rewrite(rig_data / P, tmp_path / f"{fault}.txt", header,
                                       volts=5 / 2048 if fault == "volts" else None,
                                       zero=2048.0 if fault == "zero" else None))
    (said,) = _said(run)
    assert run.source == "inferred (header contradicted)" and run.reproduced and run.controller.spec["kind"] == "p"
    if fault == "zero":
        assert said == "v about 2048 counts" and run.controller.spec["kp"] == 2.0
    else:  # with the header's law refused, kp and v's unit are one: the largest step is taken
        claim = next(c for c in run.audit.claims if c.data == said)
        assert "the header's law reproduces neither" in claim.evidence
        step = float(said.split()[-1])
        assert run.controller.spec["kp"] * step == pytest.approx(2.0 * 5 / 2048, rel=1e-3)
    assert run.step_metrics() == clean.step_metrics()


@pytest.mark.parametrize("seed", [0, 1, 3, 6, 7, 8])
def test_blind_a_lying_closed_loop_header_over_one_column_fault(tmp_path, seed):
    """lie:column (v in volts under a lead's other pole; v about a DAC code, θ0 or u in degrees
    or radians under a P's or a lead's lie): all ten in scripts/validate_audit.py. Before, the
    command's faults (seeds 0, 1, 7, 8) kept the header's law or named an integrator
    1.5(s+1e-09)/s; θ0 and u's unit (seeds 3, 6) were read already."""
    path, hidden = write_audit_case(tmp_path, "lie:column", seed)
    run = LoggedRun.from_path(path)
    assert run.source == "inferred (header contradicted)" and run.reproduced and run.alignment == hidden.alignment
    (said,) = _said(run)
    if hidden.v_unit is not None:
        assert said.startswith("v in steps of")
    elif hidden.v_zero is not None:
        assert said == f"v about {hidden.v_zero:g} counts"
    elif hidden.theta_zero is not None:
        assert said == f"θ logged before its zero was taken off (θ0 = {hidden.theta_zero:g} counts)"
    else:
        assert said == f"u in {hidden.u_unit}"
    if hidden.law == "p":
        assert run.controller.spec["kp"] == hidden.kp
    else:
        np.testing.assert_allclose(run.controller.spec["design"]["num_s"], hidden.num_s, rtol=1e-9)


def _corrupt_theta(path: Path, row: int, by: float) -> None:
    """The log's θ field of data row ``row`` written ``by`` counts higher (any layout)."""
    lines = path.read_text().splitlines()
    head = next(k for k, x in enumerate(lines) if x[:1].isdigit())  # '#' lines, or the 2014 layout's names
    names = lines[head - 1].lstrip("#").split("\t")
    j = names.index("theta") if "theta" in names else 4  # the 2014 layout's, or the rig's t n u v θ a
    cells = lines[head + row].split("\t")
    cells[j] = f"{float(cells[j]) + by:g}"
    lines[head + row] = "\t".join(cells)
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("header", [OPEN_LOOP, ["#SLFR RTP P_control_Test", "#kp=2.0"], None])
def test_accelerometer_feedback_beside_a_corrupted_field_under_any_header(rig_data, tmp_path, header):
    """The thesis's lead + accelerometer step with θ of row 500 written 64 higher: under its
    true header the law is judged past the field; under a lying one (or none)
    Ga's state is in no column, so no stretch after the field and no one-input least squares
    gives the law: it is inferred on the first half. Before: 'not this law; no law found'."""
    clean = LoggedRun.from_path(rig_data / LEAD_ACCEL)
    path = _rewrite(rig_data / LEAD_ACCEL, tmp_path / "corrupt.txt", header, corrupt=(500, 64))
    if header is None:  # no header: the column line alone, without its '#'
        lines = path.read_text().splitlines()
        path.write_text("\n".join([lines[5][1:]] + lines[6:]) + "\n")
    run = LoggedRun.from_path(path)
    assert run.reproduced and run.identified.corrupted.theta_rows == (500,)
    assert run.source == ("inferred" if header is None else "inferred (header contradicted)")
    np.testing.assert_allclose(run.controller.gth.num, clean.controller.gth.num, rtol=1e-6)
    np.testing.assert_allclose(run.controller.ga.num, clean.controller.ga.num, rtol=1e-6)
    assert run.step_metrics() == clean.step_metrics()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_blind_accelerometer_feedback_under_a_lying_header_beside_a_corrupted_field(tmp_path, seed):
    """lie:accel_fb (a lead and a scaled Ga of its own on the float command, under an open-loop
    header or the lead alone) with one θ field 40 counts higher where the hub moves in its
    second half: the lie said, the field set aside, the law and Ga as without it (found before
    the first-half search too: a one-input least squares there misses few enough rows)."""
    path, hidden = write_audit_case(tmp_path, "lie:accel_fb", seed)
    clean = LoggedRun.from_path(path)
    moves = np.flatnonzero(np.abs(np.diff(clean.data["theta"])) > 0)
    row = int(moves[np.searchsorted(moves, clean.data["theta"].size // 2)])
    _corrupt_theta(path, row, 40)
    run = LoggedRun.from_path(path)
    assert run.source == "inferred (header contradicted)" and run.reproduced
    assert run.identified.corrupted.theta_rows == (row,) and run.alignment == hidden.alignment
    np.testing.assert_allclose(run.controller.ga.num, clean.controller.ga.num, rtol=1e-6)
    np.testing.assert_allclose(run.controller.gth.num, clean.controller.gth.num, rtol=1e-6)


# --- two column faults at once under a true header ----------------------------------------

@pytest.mark.parametrize("name", [LEAD, LEAD_ACCEL])
def test_u_and_v_swapped_and_theta_negated_under_a_true_header(rig_data, tmp_path, name):
    """Two faults of one script: its columns in another order and the angle with the other sign.
    Before: 'not this law; no law found', the model driven by u as v. (The P step is no test of
    a u/v swap: its u is a 0/50 step, which any law of high gain at a ±50 clamp gives.)"""
    clean = LoggedRun.from_path(rig_data / name)
    run = LoggedRun.from_path(_rewrite(rig_data / name, tmp_path / "two.txt", swap=True, negate=True))
    assert _said(run) == {"u and v swapped", "θ written with the other sign"}
    assert run.source == "header" and run.reproduced and run.alignment == clean.alignment
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=0.05)


@pytest.mark.parametrize("volts", [5 / 2048, 10 / 32768])
def test_u_and_v_swapped_and_v_in_volts_under_a_true_header(rig_data, tmp_path, volts):
    # the column named u holds the P step's command in volts, the one named v the reference in counts
    run = LoggedRun.from_path(_rewrite(rig_data / P, tmp_path / "two.txt", volts=volts, swap=True))
    said = _said(run)
    (unit,) = [s for s in said if s.startswith("v in steps of")]
    assert said == {"u and v swapped", unit} and float(unit.split()[-1]) == pytest.approx(volts, rel=1e-3)
    assert run.source == "header" and run.reproduced


def test_a_p_law_of_gain_one_is_not_read_as_its_own_mirror(tmp_path):
    """v = u − θ is u = v + θ: with u and v swapped and θ negated a P law of gain 1 reproduces a
    log as well as it does as named. A log that no law reproduces as named (its v moved by 0.01
    counts: a float command printed) must not be 'read' as that mirror: the tracking says which
    column is the reference (u − θ the smaller RMS)."""
    import numpy as np

    from station.control import make_controller
    from tests.test_infer_controller import _closed_loop

    u, theta, v = _closed_loop(make_controller("p", kp=1.0), 1)
    v = v + 0.01 * np.sign(v)
    rows = "".join(f"{0.002 * i!r}\t{i}\t{float(u[i])!r}\t{float(v[i])!r}\t{float(theta[i])!r}\t0\n"
                   for i in range(u.size))
    path = tmp_path / "p.txt"
    path.write_text("#SLFR RTP PID_control_Test\n#kp = 1.0\n#ki = 0.3\n#kd = 0.0\n#t\tn\tu\tv\t$\\theta$\ta\n" + rows)
    run = LoggedRun.from_path(path)
    assert not {c for c in _said(run) if not c.startswith("a is no tip")}  # a: zeros here
    assert np.array_equal(run.data["u"], u) and run.controller is None


@pytest.mark.parametrize("seed", [0, 1, 2, 5])  # θ/a and u/v, each beside θ negated or v in volts; all ten in scripts/validate_audit.py
def test_blind_pairs_of_column_faults(tmp_path, seed):
    path, hidden = write_audit_case(tmp_path, "pair", seed)
    run = LoggedRun.from_path(path)
    assert run.reproduced and run.source == "header"
    shown = {"theta": "θ"}
    swap = f"{shown.get(hidden.swap[0], hidden.swap[0])} and {shown.get(hidden.swap[1], hidden.swap[1])} swapped"
    said = _said(run)
    assert swap in said and len(said) == 2
    assert ("θ written with the other sign" in said) is hidden.negate


def test_a_true_lead_header_a_count_off_is_completed_not_contradicted(tmp_path):
    """The header prints 3(s+30)/(s+35) to 8 digits; on the truncated integer that print replays a
    count off, and the data's own simplest law, 3(s+2π·6)/(s+2π·7), reproduces a 25-count sine as
    well. Before: the true header 'contradicted' by the other design; now the design its print
    rounds is the one judged, and it reproduces every v."""
    path, hidden = write_audit_case(tmp_path, "pair", 5)  # this seed's law, columns as named
    lines = path.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln.split("\t") for ln in lines if ln and not ln.startswith("#")]
    for f in rows:  # the faults undone: u and v back, θ its sign
        f[2], f[3] = f[3], f[2]
        f[4] = f"{-float(f[4]):g}"
    path.write_text("\n".join(head + ["\t".join(f) for f in rows]) + "\n")
    run = LoggedRun.from_path(path)
    controller = next(c for c in run.audit.claims if c.claim == "controller")
    assert controller.verdict == "confirmed" and run.source == "header" and run.reproduced
    assert run.controller.spec["design"]["text"] == hidden.design_text == "3(s+30)/(s+35)"
    assert not _said(run)
