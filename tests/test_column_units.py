"""The a and v columns' units: claims checked against their data like θ's.

The class of defect: the audit checked θ's unit (radians, degrees) and t's (ms) but took a for
the rig's accelerometer counts on trust, and judged it with thresholds in counts (half a count
of noise at least, DESIGN.md "Log audit"). The rig's own logs with a stored in m/s² or g (a
lab script scaling the converter's counts by the sensitivity) were all called "no tip
acceleration: it reads noise where the tip moved" and their a fits were -5000 to -100000 %.
The invariant tested here: a column that steps by whole multiples of another size than one
count is converted by that size, and says so; one with no common step is judged by its own
noise, not a count's; a column of counts is left as it is, whatever its offset.

Truth: the rig's own logs (``../shared/data/rig``) rewritten as such a script would have
written them, and the rig's a as logged (the thesis's lead + accelerometer log stores counts +
0.04).
"""

from __future__ import annotations

import numpy as np
import pytest

from station.logged import LoggedRun
from station.logged.audit import ACCEL_CLAIM
from station.logged.quantum import count_step, in_counts
from station.logged.sensor_evidence import sensor_evidence
from station.plant.model import load_model
from station.logged.units import ACCEL_UNIT_CLAIM, accel_unit
from station.replay import replay
from tests.test_sensor_reach import THESIS, _rewrite

A_GAIN = 1.1452654922936827
"""The rig's accelerometer sensitivity, counts per m/s² (DESIGN.md's a_gain)."""

G = 9.80665

SCALES = {"m/s²": 1.0 / A_GAIN, "g": 1.0 / (A_GAIN * G), "mV of a 3.3 V 12-bit converter": 3300.0 / 4096}


@pytest.fixture(scope="module")
def nominal():
    return load_model("tmm-fit")


def _printed(x, digits):
    return np.array([float(f"{v:.{digits}g}") for v in x])


@pytest.mark.parametrize("unit", SCALES)
@pytest.mark.parametrize("name", THESIS)
def test_a_scaled_into_another_unit_is_read_back_in_counts(rig_data, tmp_path, unit, name):
    """Rewritten with a in another unit (printed to 7 digits), the log's a is found to step by
    one count's size in that unit, converted back to the rig's very counts, and replayed as
    the rig's own log is (the same a fit, no sensor fault decided, no silence)."""
    scale = SCALES[unit]
    src = rig_data / name
    path = _rewrite(src, tmp_path / name, lambda t, a: _printed(a * scale, 7))
    clean, run = LoggedRun.from_path(src), LoggedRun.from_path(path)
    assert np.allclose(run.data["a"], clean.data["a"], rtol=0, atol=1e-9)
    (claim,) = [c for c in run.audit.claims if c.header == ACCEL_UNIT_CLAIM]
    assert claim.verdict == "contradicted" and claim.data.startswith("a in steps of")
    assert run.audit.lines()[0].startswith(f"header: {ACCEL_UNIT_CLAIM}; data: a in steps of")
    assert not any(c.header == ACCEL_CLAIM for c in run.audit.claims)
    assert run.sensors.effects == clean.sensors.effects
    assert replay(path).fit_pct == pytest.approx(replay(src).fit_pct, abs=0.05)


@pytest.mark.parametrize("name", THESIS)
def test_a_in_volts_about_a_converters_midpoint_is_read_back_in_counts(rig_data, tmp_path, name):
    """a written as a 10-bit converter's volts about its 2.5 V midpoint (5/1024 V a count, 7
    digits: 2.504883): the printing's error on the least change, times the 20 counts of a large
    change, passed the step's tolerance, and the log replayed with "accel_gain 0.01" and an a fit
    of -6912 %. Its count is found from the small changes out, its 512 counts of midpoint decided
    as an unzeroed channel's bias, and it replays as the rig's own log."""
    src = rig_data / name
    path = _rewrite(src, tmp_path / name, lambda t, a: _printed(2.5 + a * 5.0 / 1024, 7))
    clean, run = LoggedRun.from_path(src), LoggedRun.from_path(path)
    (claim,) = [c for c in run.audit.claims if c.header == ACCEL_UNIT_CLAIM]
    assert claim.data.startswith("a in steps of 0.00488"), claim
    assert run.sensors.effects == {"accel_offset": pytest.approx(512 + clean.sensors.evidence[0].accel_bias, abs=0.05)}
    assert replay(path).fit_pct == pytest.approx(replay(src).fit_pct, abs=0.5)  # its bias held, not its rest


@pytest.mark.parametrize("name", THESIS)
def test_a_float_with_no_count_is_judged_by_its_own_noise_and_its_scale_decided(rig_data, tmp_path, name, nominal):
    """a computed in floats (scaled into g with noise of its own, no common step) is not called
    a silent channel (its noise at rest, not half a count, is what it is judged against), and
    its scale is decided as the accelerometer's gain: with the sign, and against the clean
    log's own ratio over the model's a times the scale to within 25 %."""
    rng = np.random.default_rng(7)
    scale = SCALES["g"]
    path = _rewrite(rig_data / name, tmp_path / name,
                    lambda t, a: a * scale + 0.02 * scale * rng.standard_normal(a.size))
    run, clean = LoggedRun.from_path(path), LoggedRun.from_path(rig_data / name)
    (claim,) = [c for c in run.audit.claims if c.header == ACCEL_UNIT_CLAIM]
    assert claim.verdict == "unchecked"
    assert not any(c.header == ACCEL_CLAIM for c in run.audit.claims), run.audit.lines()
    clean_gain = sensor_evidence(clean, nominal).accel_ratio  # the rig's a is 1.0-1.4x the model's
    gain = run.sensors.effects["accel_gain"]
    assert 0.75 * scale * clean_gain <= gain <= 1.25 * scale * clean_gain, (gain, scale * clean_gain)


def test_a_dead_float_channel_is_still_silent(rig_data, tmp_path):
    """The other side of judging a float by its own noise: a channel that reads only its noise
    while the model's tip moves is still no tip acceleration."""
    rng = np.random.default_rng(3)
    name = THESIS[1]
    path = _rewrite(rig_data / name, tmp_path / name, lambda t, a: 0.013 + 0.001 * rng.standard_normal(a.size))
    run = LoggedRun.from_path(path)
    assert any(c.header == ACCEL_CLAIM and c.verdict == "contradicted" for c in run.audit.claims), run.audit.lines()


def test_the_rigs_own_a_is_in_counts(rig_data):
    """Every log of the rig's in ``../shared`` (the lead + accelerometer log's counts + 0.04 too)
    has its a in counts: no unit claim, nothing converted."""
    paths = sorted(rig_data.rglob("*.txt"))
    assert len(paths) >= 11
    for path in paths:
        run = LoggedRun.from_path(path)
        assert accel_unit(run.raw_log.data["a"]) is None, path.name
        assert in_counts(run.raw_log.data["a"]), path.name


@pytest.mark.parametrize("a, step", [
    (np.array([0.04, 1.04, -2.96, 0.04]), 1.0),            # counts on an offset
    (np.array([0.0, 6.0, -12.0, 0.0]), 6.0),               # whole counts of a sensor 6x the gain (in counts)
    (np.array([0.0, 0.25, 0.5, -0.75, 0.0]), 0.25),
    (np.array([3.0, 3.0, 3.0]), None),                     # never changes
    (np.array([0.0, 0.1414214, 0.3146264, 0.1732051]), None),  # no common step (√2, π, √3 tenths)
    (np.round(np.linspace(-1.0, 1.0, 50) ** 3, 6), None),  # the printing's last digit: 2e6 steps over its range
])
def test_count_step(a, step):
    got = count_step(a)
    assert (got is None) if step is None else got == pytest.approx(step, rel=1e-9)


@pytest.mark.parametrize("a, counts", [
    (np.array([0.04, 1.04, -2.96, 0.04]), True),
    (np.array([0.0, 6.0, -12.0, 0.0]), True),   # a gain of 6 read in whole counts: the gain says it
    (np.array([2.0, 2.0, 2.0]), True),
    (np.array([0.0, 0.25, 0.5, -0.75]), False),
    (np.array([0.1, 0.35, 0.2, 0.9]), False),
    # volts of a ±10 V 16-bit DAC moving by 1-3 counts a row: every change within 1e-3 of none, none a count
    (np.array([0.0, 3.0, 6.0, 5.0, 5.0]) * 10 / 32768, False),
    (np.array([0.1 + 0.2, 0.3, 1.3]), True),   # a float's rounding between equal printed values is no change
])
def test_in_counts(a, counts):
    assert in_counts(a) is counts


def test_a_diagnosis_of_logs_with_a_in_g_is_the_rigs_own(rig_data, tmp_path):
    """The diagnosis sees the rig's counts again: the same causes and values as on the logs
    themselves (before: every run's a 'no tip acceleration', the a evidence lost)."""
    from station.diagnosis import diagnose

    scale = SCALES["g"]
    paths = [_rewrite(rig_data / name, tmp_path / name, lambda t, a: _printed(a * scale, 7)) for name in THESIS]
    scaled, clean = (diagnose([str(p) for p in ps], workers=1) for ps in (paths, [rig_data / n for n in THESIS]))
    assert scaled.causes == clean.causes and not scaled.decided_faults
    assert scaled.extended_model.effect_dict() == pytest.approx(clean.extended_model.effect_dict(), rel=1e-9)
    assert scaled.gain_pct == pytest.approx(clean.gain_pct, abs=1e-9)


VOLTS = {"V of a ±5 V 12-bit converter": 5.0 / 2048, "V of a ±10 V 16-bit converter": 10.0 / 32768}

COMMAND_LOGS = ("OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
                "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt")


def _rewrite_v(src, dst, scale):
    """The rig's log with its v column (the fourth) written in another unit, 7 digits."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = np.array([[float(x) for x in ln.split()] for ln in lines if ln and not ln.startswith("#")])
    rows[:, 3] = _printed(rows[:, 3] * scale, 7)
    dst.write_text("\n".join(head + ["\t".join(f"{x:.12g}" for x in r) for r in rows]) + "\n")
    return dst


@pytest.mark.parametrize("unit", VOLTS)
@pytest.mark.parametrize("name", COMMAND_LOGS)
def test_a_command_written_in_volts_is_read_back_in_dac_counts(rig_data, tmp_path, unit, name):
    """v in volts (the P step's steps by 2 counts: kp·e; the pulses' by 100): the header's law
    reproduces it in counts, and as written it stays under one DAC count while the hub moves
    (the device would apply nothing), so it is read in counts and said (before: the P step's kp
    'contradicted' as 0.0049 and a θ fit of -252 %; the pulses 'not this law', θ fit -64 %)."""
    src = rig_data / name
    path = _rewrite_v(src, tmp_path / name, VOLTS[unit])
    run, clean = LoggedRun.from_path(path), LoggedRun.from_path(src)
    (claim,) = [c for c in run.audit.claims if c.header == "v in DAC counts"]
    assert claim.verdict == "contradicted" and float(claim.data.split()[-1]) == pytest.approx(VOLTS[unit], rel=1e-5)
    assert np.array_equal(run.data["v"], clean.data["v"])
    assert run.source == "header" and run.reproduced
    assert replay(path).fit_pct == replay(src).fit_pct


@pytest.mark.parametrize("seed", range(4))
def test_a_p_header_with_another_gain_is_not_taken_for_another_unit(tmp_path, seed):
    """The other side: v = kp'·e on the float under a header of kp = 2 also steps by a size
    other than a count, and v/(kp'/2) would fit the header's law; the hub's motion says it is
    another gain, as it is (the blind audit's generator, ``lie:p_kp``)."""
    from tests.blind.audit import write_audit_case

    path, hidden = write_audit_case(tmp_path, "lie:p_kp", seed)
    run = LoggedRun.from_path(path)
    assert not [c for c in run.audit.claims if c.header == "v in DAC counts"], hidden
    assert run.source == "inferred (header contradicted)" and run.controller.spec["kp"] == hidden.kp


@pytest.mark.parametrize("name", COMMAND_LOGS)
def test_a_command_in_millivolts_within_the_dacs_range_is_left_to_the_law(rig_data, tmp_path, name):
    """The limit, on purpose: v in mV (2.44 per count) stays within the DAC's ±255 on these runs,
    where it could as well be another gain of the law (a P law's v scaled is another kp): not
    read as another unit; the law found on v as written is said."""
    path = _rewrite_v(rig_data / name, tmp_path / name, 5000.0 / 2048)
    run = LoggedRun.from_path(path)
    assert not [c for c in run.audit.claims if c.header == "v in DAC counts"]
    assert run.audit.lines(), "the header's law is contradicted, as before"


COMMANDS = np.array([0, 1, 88, 87, 85, 86, 84, 2, -1, -3, -2, 150, 149, 60, 61, 59, 0])
"""A command in DAC counts with changes of 1-2 counts and of 60-150 (a step, a reversal)."""


@pytest.mark.parametrize("counts, size", [
    (COMMANDS, 10.0 / 32768),                       # 7 digits of a 16-bit converter's volts: refined on small steps
    (COMMANDS, 5.0 / 2048),
    (np.trunc(2.5 * np.array([0, 5, 3, 1, -1, -4, 2, 0])), 5000.0 / 2048),  # trunc(2.5 e): its least change 2 counts
    (COMMANDS + 512, 5.0 / 1024),                   # about a 10-bit converter's 2.5 V midpoint: 6 decimals
])
def test_count_step_of_printed_commands(counts, size):
    printed = np.array([float(f"{c * size:.7g}") for c in counts])
    assert count_step(printed) == pytest.approx(size, rel=1e-5)


LEAD_FLOAT = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
"""The thesis's lead step: its recursion on the float command, v logged as a float."""


@pytest.mark.parametrize("unit", VOLTS)
def test_a_float_command_in_volts_is_read_in_counts_by_the_headers_law(rig_data, tmp_path, unit):
    """The thesis's lead logged its float v; written in volts it has no whole-count steps to read
    its unit by, but the header's lead replayed on its own commands gives v in counts whatever
    unit the log wrote: the ratio is the unit (before: "v in another unit, its size not found",
    "not this law", a false "moving at t = 0" and no overshoot)."""
    src = rig_data / LEAD_FLOAT
    path = _rewrite_v(src, tmp_path / LEAD_FLOAT, VOLTS[unit])
    run, clean = LoggedRun.from_path(path), LoggedRun.from_path(src)
    (claim,) = [c for c in run.audit.claims if c.header == "v in DAC counts"]
    assert claim.verdict == "contradicted" and float(claim.data.split()[-1]) == pytest.approx(VOLTS[unit], rel=1e-5)
    assert [c.header for c in run.audit.claims if c.verdict == "contradicted"] == ["v in DAC counts"]
    np.testing.assert_allclose(run.data["v"], clean.data["v"], rtol=0, atol=1e-4 * np.max(np.abs(clean.data["v"])))
    assert run.source == "header" and run.reproduced
    assert run.step_metrics() == clean.step_metrics()
    assert replay(path).fit_pct == pytest.approx(replay(src).fit_pct, abs=0.05)


@pytest.mark.parametrize("unit", VOLTS)
def test_a_float_command_in_volts_with_no_law_named_is_said_and_no_law_is_fitted_to_it(rig_data, tmp_path, unit):
    """The same log with its header lines dropped: no law to read the unit by, and a law's gain
    and v's unit are one. Before the no-DAC-command rule: a law of order 3 in volts with a
    cancelled pole pair, 0.0009155(s^2+2000s+1e+06)(s+2π·2.069)/..., and a θ fit of -573 %: laws
    fitted to a v of 0.3 'counts' pass tolerances of 1e-6 counts a thousand times too wide. The
    unit is said to be unknown, and no law is inferred on a v that is no DAC command
    (``analysis.law_rows.no_dac_command``)."""
    path = _rewrite_v(rig_data / LEAD_FLOAT, tmp_path / LEAD_FLOAT, VOLTS[unit])
    lines = path.read_text().splitlines()
    path.write_text("\n".join([ln for ln in lines if ln.startswith("#")][-1:]
                              + [ln for ln in lines if not ln.startswith("#")]) + "\n")  # the column line only
    run = LoggedRun.from_path(path)
    (claim,) = [c for c in run.audit.claims if c.header == "v in DAC counts"]
    assert claim.verdict == "contradicted" and claim.data == "v in another unit, its size not found"
    assert "under one DAC count" in claim.evidence and "no law is inferred" in claim.evidence
    assert not run.reproduced


@pytest.mark.parametrize("seed", range(2))
def test_a_command_in_volts_with_no_header_is_read_by_the_law_the_data_give(tmp_path, seed):
    """The 2014 layout names no law; its v in volts steps by a converter's count, and the law the
    data give reproduces it in counts (before: nothing said, and no law found on the volts)."""
    import dataclasses

    import tests.blind.audit as blind

    unit = sorted(blind.V_UNITS)[seed]
    case = dataclasses.replace(blind.draw_case("int:trunc_d0", seed), v_unit=unit)
    sim = blind.simulate_audit_case(case, seed)
    sim = dataclasses.replace(sim, v=np.array([float(f"{x:.7g}") for x in sim.v * blind.V_UNITS[unit]]))
    path = tmp_path / f"volts_{seed}.txt"
    path.write_text(blind.format_audit_run(case, sim))
    run = LoggedRun.from_path(path)
    (claim,) = [c for c in run.audit.claims if c.header == "v in DAC counts"]
    assert float(claim.data.split()[-1]) == pytest.approx(blind.V_UNITS[unit], rel=1e-5)
    assert run.source == "inferred" and run.reproduced and run.alignment == case.alignment
    assert run.controller.spec["design"]["text"] == case.design_text


LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
"""The thesis's lead + accelerometer step: Ga moves v by a's noise before the step."""


def _about_zero(src, dst, zero, header=True):
    """The rig's log with v (the fourth column) written about ``zero``, every digit kept; with
    its header lines or without (the 2014 layout's bare rows)."""
    lines = src.read_text().splitlines()
    rows = [ln.split("\t") for ln in lines if ln and not ln.startswith("#")]
    for r in rows:
        r[3] = f"{float(r[3]) + zero:.17g}"
    dst.write_text("\n".join([ln for ln in lines if ln.startswith("#") and header] + ["\t".join(r) for r in rows])
                   + "\n")
    return dst


@pytest.mark.parametrize("header", [True, False], ids=["header", "bare"])
@pytest.mark.parametrize("name, zero", [(THESIS[1], 128.0), (THESIS[1], -100.0), (LEAD_FLOAT, 128.0), (THESIS[0], 128.0),
                                        (LEAD_ACCEL, 128.0), (LEAD_ACCEL, 2048.0)])
def test_a_command_written_about_another_zero_is_read_about_zero(rig_data, tmp_path, name, zero, header):
    """v written as an unsigned DAC code about its midpoint (128 of 8 bits): it reads that at
    rest, where no law commands anything (a law feeding a back: its noise's few counts about
    it), and the log's law (the header's; with no header, the data's, from rest) reproduces
    every row less it. Before, the P step so written was read as a law 2(s-9e-12)/(s-2e-13)
    that "remembered the earlier rows" (its first row's 128 carried as memory), with a header
    called a lie; the lead step, past the DAC's range as written, as "v in another unit, its size
    not found" and not reproduced (max |dv| = 128 counts); the lead + accelerometer step, with
    or without its header, so and as an encoder of 256 counts per revolution."""
    src = rig_data / name
    path = _about_zero(src, tmp_path / name, zero, header)
    clean = LoggedRun.from_path(_about_zero(src, tmp_path / f"clean_{name}", 0.0, header))
    run = LoggedRun.from_path(path)
    assert run.audit.lines()[0] == f"header: v in DAC counts about 0; data: v about {zero:g} counts"
    assert len(run.audit.lines()) == len(clean.audit.lines()) + 1
    assert run.source == clean.source == ("header" if header else "inferred")
    assert run.max_abs_dv == pytest.approx(clean.max_abs_dv, abs=1e-6)  # v + c - c: a float's last bits
    assert replay(path).fit_pct == replay(src).fit_pct


@pytest.mark.parametrize("case, seed", [("v_zero", 0), ("v_zero", 1), ("v_zero", 2), ("v_zero", 3), ("v_zero", 6),
                                        ("v_zero+coulomb_friction", 5), ("v_zero+coulomb_friction", 27)])
def test_blind_a_command_written_about_a_dac_codes_midpoint(tmp_path, case, seed):
    """The independent generator's P and leads under a true header, none (the 2014 layout) or
    the lab's session's open-loop one, whose v a script wrote as an unsigned DAC code about its
    midpoint (128, 2048, 32768). The zero said exactly and the law confirmed on v less it; with
    no header or an open-loop one, the law the data give from rest (before: a law carrying the
    zero as the memory of a "cut" run, or none); with a lead printed to 8 digits (seed 27), its
    coefficients completed from the data as they are for v about 0 (before: "not this law",
    max |dv| = 129 counts)."""
    import tests.blind.audit as blind

    path, hidden = blind.write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    zeros = [c.data for c in run.audit.claims if c.header == "v in DAC counts about 0"]
    assert zeros == [f"v about {hidden.v_zero:g} counts"]
    lied = [c for c in run.audit.claims if c.claim == "controller" and c.verdict == "contradicted"]
    assert bool(lied) is hidden.lies is (hidden.header == "open-loop")
    assert run.source == {"none": "inferred", "open-loop": "inferred (header contradicted)"}.get(hidden.header, "header")
    assert run.reproduced
    assert run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments
    if hidden.header in ("none", "open-loop"):
        np.testing.assert_allclose(run.controller.spec["design"]["num_s"], hidden.num_s, rtol=1e-9)
        np.testing.assert_allclose(run.controller.spec["design"]["den_s"], hidden.den_s, rtol=1e-9)


COUNT_IN = {"degrees": 360.0 / 1024, "radians": 2.0 * np.pi / 1024, "milliradians": 2000.0 * np.pi / 1024}
"""One encoder count of 1024/rev in each unit a script may write the reference in (an
independent table: not :data:`station.logged.units.THETA_UNITS`)."""

SWEEP_2014 = "swept_sine_kp_1_amp_50.txt"
BARE_2014 = "without_accel_01_28_14_test_2.txt"
SWEEP_2009 = "2009/swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt"


def _u_in(src, dst, unit, digits=17, columns=("u",)):
    """The rig's log with u (or each of ``columns``, "u" or "theta") written in ``unit`` to
    ``digits`` significant digits (u and θ are the third and fifth columns of the ``#`` layout,
    the second and third of the 2014 one)."""
    lines = src.read_text().splitlines()
    rig = lines[0].startswith("#")
    cols = [{"u": 2, "theta": 4}[c] if rig else {"u": 1, "theta": 2}[c] for c in columns]
    out = []
    for ln in lines:
        if ln.startswith("#") or not ln[:1].isdigit():
            out.append(ln)
            continue
        r = ln.split("\t")
        for col in cols:
            r[col] = f"{float(r[col]) * COUNT_IN[unit]:.{digits}g}"
        out.append("\t".join(r))
    dst.write_text("\n".join(out) + "\n")
    return dst


@pytest.mark.parametrize("unit", COUNT_IN)
@pytest.mark.parametrize("name, digits", [(THESIS[1], 17), (THESIS[1], 6), (LEAD_FLOAT, 17), (LEAD_ACCEL, 17),
                                          (SWEEP_2014, 17), (BARE_2014, 17), (SWEEP_2009, 17)])
def test_a_reference_written_in_degrees_or_radians_is_read_back_in_counts(rig_data, tmp_path, unit, name, digits):
    """The loop's law acts on u − θ: with u in degrees (or radians) and θ in counts it weighs one
    unit of u as 2.84 (163) counts, and reproduces every logged v with u read back in counts
    (a step's counts printed to 6 digits, 17.5781, rounded back to 50). Before: the P step so
    written gave "not this law (max |dv| = 64.8 counts); no law found", an overshoot of 252.71 %
    of a 17.6-count step and a θ fit of −125 %; the sweeps "not this law" or no law at all."""
    src = rig_data / name
    path = _u_in(src, tmp_path / name.replace("/", "_"), unit, digits)
    clean, run = LoggedRun.from_path(src), LoggedRun.from_path(path)
    assert not any(c.header == "u in encoder counts" for c in clean.audit.claims)  # the rig's own: counts
    assert run.audit.lines()[0] == f"header: u in encoder counts; data: u in {unit}"
    assert len(run.audit.lines()) == len(clean.audit.lines()) + 1
    assert run.source == clean.source and run.reproduced and run.alignment == clean.alignment
    assert run.controller.spec == clean.controller.spec
    np.testing.assert_allclose(run.data["u"], clean.data["u"], rtol=0, atol=1e-9)
    if name in (THESIS[1], LEAD_ACCEL):
        assert replay(path).fit_pct == replay(src).fit_pct


@pytest.mark.parametrize("unit", COUNT_IN)
@pytest.mark.parametrize("columns", [("theta",), ("u", "theta")])
@pytest.mark.parametrize("name", [THESIS[1], LEAD_FLOAT, SWEEP_2014])
def test_a_hub_angle_written_in_another_unit_is_read_back_in_counts(rig_data, tmp_path, unit, columns, name):
    """θ (and u with it) in degrees, radians or milliradians, 7 digits: θ read back in counts
    and the log's numbers its own. Before, θ in milliradians (6.14 a count) was taken for an
    encoder of 4096 counts a revolution: "not this law (max |dv| = 250 counts)", an overshoot
    of 660.85 %; and u written with it was left a count's millionth off its step (not settled)."""
    src = rig_data / name
    path = _u_in(src, tmp_path / name, unit, 7, columns)
    clean, run = LoggedRun.from_path(src), LoggedRun.from_path(path)
    assert run.audit.lines()[0] == f"header: θ in encoder counts; data: θ in {unit}"
    np.testing.assert_array_equal(run.data["theta"], clean.data["theta"])
    np.testing.assert_array_equal(run.data["u"], clean.data["u"])
    assert run.reproduced and run.controller.spec == clean.controller.spec
    assert run.step_metrics() == clean.step_metrics()


@pytest.mark.parametrize("case, seed", [("session", 0), ("session", 3), ("lie:p_kp", 1), ("int:trunc_d1", 2),
                                        ("lie:accel_fb", 0)])
def test_blind_a_reference_written_in_degrees(tmp_path, case, seed):
    """The independent generator's laws (the lab's session under its open-loop header, a P
    header of another gain, a lead on the stored integer with no header, a lead with Ga under
    an open-loop one), their u written in degrees: the unit said, and the law the log's own
    audit finds with u in counts found again, the header's lie too (a P header of kp = 2 over
    0.5 and u in degrees, before: "not this law (max |dv| = 42.2 counts); no law found")."""
    import dataclasses

    import tests.blind.audit as blind

    drawn = blind.draw_case(case, seed)
    sim = blind.simulate_audit_case(drawn, seed)
    counts = tmp_path / "counts.txt"
    counts.write_text(blind.format_audit_run(drawn, sim))
    path = tmp_path / "degrees.txt"
    path.write_text(blind.format_audit_run(drawn, dataclasses.replace(sim, u=sim.u * COUNT_IN["degrees"])))
    clean, run = LoggedRun.from_path(counts), LoggedRun.from_path(path)
    said = "header: u in encoder counts; data: u in degrees"
    assert sorted(run.audit.lines()) == sorted(clean.audit.lines() + [said])
    assert run.source == clean.source and run.reproduced == clean.reproduced
    if clean.controller is not None and clean.controller.spec.get("design"):
        assert run.controller.spec["design"]["text"] == clean.controller.spec["design"]["text"]


@pytest.mark.parametrize("case, seed", [("u_unit", 1), ("u_unit", 5), ("u_unit", 9), ("u_unit+coulomb_friction", 0)])
def test_blind_u_unit_class(tmp_path, case, seed):
    """The independent generator's "u_unit" class (tests/blind/audit.py): a P or a lead on the
    stored integer under its true header, none, or the session's open-loop one, u written in
    degrees or radians. A 5 Hz sine under a lead on the integer leaves the least-squares weight
    of u anywhere (6.2 on seed 5): the law decides (before that: "not this law", max |dv| = 44
    counts, on seeds 5 and 9; an open-loop header's step, seed 0 with friction, unread)."""
    import tests.blind.audit as blind

    path, hidden = blind.write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    units = [c.data for c in run.audit.claims if c.header == "u in encoder counts"]
    assert units == [f"u in {hidden.u_unit}"]
    assert run.reproduced and (run.source == "inferred (header contradicted)") is hidden.lies
    assert run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments


def test_a_law_that_leaves_u_unit_open_names_no_unit(rig_data, tmp_path):
    """The thesis's P step (kp = 2, a 50-count step from row 0) with θ written 4 times over (the
    loop's θ not): read with u in radians (163 counts a unit) an integrator whose first row the
    ±100 clamp took, v[k] = v[k-1] + 0.5 (e[k] - e[k-1]), "reproduced" every v, and so did any u
    of 4 counts or more. A unit the law does not decide is not said (was "u in radians")."""
    lines = (rig_data / THESIS[1]).read_text().splitlines()
    out = [ln if ln.startswith("#") else "\t".join(f"{4 * float(x):g}" if j == 4 else x
                                                  for j, x in enumerate(ln.split("\t"))) for ln in lines if ln]
    path = tmp_path / "theta_x4_SLFR_RTP_P_control_kp=2.0.txt"
    path.write_text("\n".join(out) + "\n")
    run = LoggedRun.from_path(path)
    assert not [c for c in run.audit.claims if c.header == "u in encoder counts"]
    assert run.controller.spec.get("kind") == "p"  # the header's law kept, said contradicted
