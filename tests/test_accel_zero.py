"""a written as the accelerometer read it, where the loop fed Ga the reading less its zero.

The lab's client zeroes the accelerometer before a test (the rig's logs read a about 0.04 at
rest) and feeds its accelerometer feedback the reading less that zero a0; a script that logs the
reading as read writes a from a0. Before, the header's law reproduced no logged v (the rig's
lead + accelerometer step written 37 counts over: max |dv| = 282 counts), "no law found" was
said, and the model ran open loop on the logged v: θ fit −219 % where the clean log fits 88.2 %.
The rig's log is rewritten by a script written from the format; the blind generator's "a_zero"
class (tests/blind/audit.py) simulates the loop on a − a0 with its own FEM and lab controller.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station.logged import LoggedRun
from station.plant import load_model

P = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
CLAIM = "a as the loop's accelerometer feedback used it"


def _from(src: Path, dst: Path, zero: float, theta0: float = 0.0, header: list[str] | None = None) -> Path:
    """The rig's log with a (the sixth column: t n u v θ a ...) written ``zero`` counts over,
    and θ (the fifth) from ``theta0``; its header lines (all but the column line) replaced by
    ``header`` when given."""
    lines = src.read_text().splitlines()
    if header is not None:
        heads = [ln for ln in lines if ln.startswith("#")]
        lines = header + heads[-1:] + [ln for ln in lines if not ln.startswith("#")]
    out = []
    for ln in lines:
        if ln.strip() and not ln.startswith("#"):
            f = ln.split()
            f[5] = repr(float(f[5]) + zero)
            f[4] = f"{float(f[4]) + theta0:g}"
            ln = "\t".join(f)
        out.append(ln)
    dst.write_text("\n".join(out) + "\n")
    return dst


def _zeros(run: LoggedRun) -> list[str]:
    return [c.data for c in run.audit.claims if c.claim == "columns" and c.header == CLAIM]


@pytest.mark.parametrize("zero", [37.0, -12.5, 0.75])
def test_a_from_the_accelerometers_zero_is_read_from_it(rig_data, tmp_path, zero):
    """The thesis's lead + accelerometer step: a0 said, the header's law reproducing every v
    from a − a0, and the step's numbers and the model's fits those of the clean log."""
    clean = LoggedRun.from_path(_from(rig_data / LEAD_ACCEL, tmp_path / "clean.txt", 0.0))
    run = LoggedRun.from_path(_from(rig_data / LEAD_ACCEL, tmp_path / "from.txt", zero))
    assert _zeros(run) == [f"a logged before its zero was taken off (a0 = {zero:.4g} counts)"]
    assert _zeros(clean) == []
    assert run.reproduced and run.source == clean.source == "header"
    np.testing.assert_allclose(run.log.data["a"], clean.log.data["a"], atol=1e-9)
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    fit, clean_fit = run.simulate(model).fit_pct, clean.simulate(model).fit_pct
    assert fit["theta"] == pytest.approx(clean_fit["theta"], abs=1e-6)
    assert fit["accel"] == pytest.approx(clean_fit["accel"], abs=1e-6)
    assert not any(line.startswith("header: a: zero at rest") for line in run.audit.lines())


def test_both_zeros_taken_off_by_the_loop(rig_data, tmp_path):
    """The lab's client taking θ0 = −59 and a0 = 37 off, its script writing both readings as
    read: both said, and the clean log's numbers (before: "no law found", an overshoot of −8 %
    and a θ fit of −90 %, after a law search of minutes)."""
    clean = LoggedRun.from_path(_from(rig_data / LEAD_ACCEL, tmp_path / "clean.txt", 0.0))
    run = LoggedRun.from_path(_from(rig_data / LEAD_ACCEL, tmp_path / "both.txt", 37.0, theta0=-59.0))
    assert _zeros(run) == ["a logged before its zero was taken off (a0 = 37 counts)"]
    assert [c.data for c in run.audit.claims if c.header == "θ as the loop's error used it"] == [
        "θ logged before its zero was taken off (θ0 = -59 counts)"]
    assert run.reproduced and run.source == "header"
    np.testing.assert_array_equal(run.log.data["theta"], clean.log.data["theta"])
    assert run.step_metrics() == clean.step_metrics()


@pytest.mark.parametrize("header, zero", [("#SLFR RTP OL_Test", 37.0), ("#SLFR RTP OL_Test", -0.75), (None, 12.5)])
def test_a_zero_under_a_header_that_names_no_law(rig_data, tmp_path, header, zero):
    """The thesis's lead + accelerometer step under an open-loop header, or no header, a written
    from a0: the law and Ga inferred with a0 beside them (before: "no law found" after a search
    of 186 s, and the model run open loop on the logged v, θ fit 63.5 % against the clean log's
    88.2 %), and the clean log's numbers."""
    clean = LoggedRun.from_path(_from(rig_data / LEAD_ACCEL, tmp_path / "clean.txt", 0.0))
    heads = [] if header is None else [header]
    run = LoggedRun.from_path(_from(rig_data / LEAD_ACCEL, tmp_path / "from.txt", zero, header=heads))
    assert _zeros(run) == [f"a logged before its zero was taken off (a0 = {zero:.4g} counts)"]
    assert run.reproduced and run.source == ("inferred (header contradicted)" if header else "inferred")
    assert run.controller.name == "20(s+2π·5)/(s+2π·20) with Ga"
    np.testing.assert_allclose(run.log.data["a"], clean.log.data["a"], atol=1e-6)
    assert run.step_metrics() == clean.step_metrics()
    model = load_model("tmm-fit")
    assert run.simulate(model).fit_pct["theta"] == pytest.approx(clean.simulate(model).fit_pct["theta"], abs=1e-3)


def test_a_law_with_no_accelerometer_feedback_under_an_open_loop_header(rig_data, tmp_path):
    """The thesis's lead without Ga under an open-loop header, a written 37 counts over: the
    lead inferred from θ alone, and no zero read from a."""
    lead = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
    run = LoggedRun.from_path(_from(rig_data / lead, tmp_path / "lead.txt", 37.0, header=["#SLFR RTP OL_Test"]))
    assert _zeros(run) == []
    assert run.reproduced and run.source == "inferred (header contradicted)"
    assert getattr(run.controller, "ga", None) is None


def test_a_law_that_does_not_feed_a_back_leaves_a_as_written(rig_data, tmp_path):
    """The P step written 37 counts over in a: its law reproduces v from θ alone, so a is not
    the loop's and no zero is read from it (an offset the sensor audit may say)."""
    run = LoggedRun.from_path(_from(rig_data / P, tmp_path / "p.txt", 37.0))
    assert _zeros(run) == []
    assert run.reproduced and run.source == "header"


def test_an_offset_the_loop_fed_back_is_no_such_fault(tmp_path):
    """The blind generator's accelerometer reading 23 counts over the tip's acceleration, its loop
    feeding Ga that reading (a sensor's offset, nothing taken off): the law reproduces a as
    written, and a is not read from a zero."""
    import tests.blind.audit as blind

    path = tmp_path / "bias.txt"
    hidden = blind.draw_case("a_zero", 1)  # its a0 not added: the reading is written as the loop used it
    path.write_text(blind.format_audit_run(hidden, blind.simulate_audit_case(hidden, 1, accel_bias=23.0)))
    run = LoggedRun.from_path(path)
    assert np.mean(run.log.data["a"][:10]) == pytest.approx(23.0, abs=1.0)
    assert _zeros(run) == []
    assert run.source == "header" and run.reproduced


@pytest.mark.parametrize("case, seed", [("a_zero", 0), ("a_zero", 2), ("a_zero", 3), ("a_zero", 8), ("a_zero", 9),
                                        ("a_zero+coulomb_friction", 5), ("a_zero+coulomb_friction", 7)])
def test_blind_a_from_the_accelerometers_zero(tmp_path, case, seed):
    """The independent generator's thesis lead + accelerometer feedback under its true header, at
    either alignment and clamp, on the float command (seeds 0, 2) or the whole count stored
    (truncated 3 and 5, rounded 9) or sent (8, 7: a0 bisected on the first row missed), its loop
    on a − a0 and a written as read: a0 said to 0.01 counts and the header's law reproducing
    every v at the hidden alignment."""
    import tests.blind.audit as blind

    path, hidden = blind.write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    (said,) = _zeros(run)
    assert float(said.split("a0 = ")[1].split()[0]) == pytest.approx(hidden.a_zero, abs=0.01)
    assert run.source == "header" and run.reproduced
    assert run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments


@pytest.mark.parametrize("case, seed", [("lie:a_zero", 1), ("lie:a_zero", 4)])
def test_blind_a_zero_under_a_header_that_names_no_law(tmp_path, case, seed):
    """The independent generator's lead and scaled Ga of their own on the float command, under an
    open-loop header (seed 1) or none (4), the loop on a − a0 and a written as read: a0 said to
    0.01 counts, the law and Ga inferred on a − a0 at the hidden alignment, and the lead named."""
    import tests.blind.audit as blind

    path, hidden = blind.write_audit_case(tmp_path, case, seed)
    run = LoggedRun.from_path(path)
    (said,) = _zeros(run)
    assert float(said.split("a0 = ")[1].split()[0]) == pytest.approx(hidden.a_zero, abs=0.01)
    assert run.source == ("inferred (header contradicted)" if hidden.header == "open-loop" else "inferred")
    assert run.reproduced and getattr(run.controller, "ga", None) is not None
    assert run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments
    assert run.controller.spec["design"]["text"] == hidden.design_text


def test_a0_searched_alone_where_the_joint_fit_stops_short(tmp_path):
    """The blind generator's lead + Ga of its own (slowest pole −0.064 rad/s), a from its zero
    17.31, no header: the joint fit of Gth, Ga and a0 stops short of a0 and of v; a0 searched
    alone finds both (the generator's truth: a0 and Ga's Tustin form)."""
    from station.analysis.accel_law import accel_feedback
    from station.analysis.continuous_design import discretize
    from station.logged.sensor_zeros import TOLERANCE, _a0_searched, _gth_miss
    from station.runlog import read_log
    from tests.blind.audit import write_audit_case

    path, hidden = write_audit_case(tmp_path, "lie:a_zero+coulomb_friction", 3)
    log = read_log(path)
    u, theta, a, v = (np.asarray(log.data[c], float) for c in ("u", "theta", "a", "v"))
    d, m, p, limit = hidden.alignment, 1, 3, hidden.limit
    joint = accel_feedback(u, theta, a, v, d, m, p, limit, log.dt, zero=True)
    assert TOLERANCE < _gth_miss(u, theta, v, d, m, limit, joint) < 1.0  # near, not reproduced
    ga = _a0_searched(u, theta, a, v, d, m, p, limit, log.dt, joint.a0, (joint.a0 - 1.0, joint.a0 + 1.0))
    assert ga is not None and abs(ga.a0 - hidden.a_zero) < 1e-6
    assert _gth_miss(u, theta, v, d, m, limit, ga) <= TOLERANCE
    _, den = discretize(np.array(hidden.ga_s[0]), np.array(hidden.ga_s[1]), log.dt, "Tustin")
    assert np.allclose(ga.den, den, rtol=0, atol=1e-7)


@pytest.mark.parametrize("slope", [1.0, -1.0])
def test_a0_search_stays_where_a_rests_on_a_miss_that_falls_on_and_on(monkeypatch, slope):
    """A scripted miss that falls without end one way (no minimum): the a0 search asks only
    a0 within its bounds, ends within them in a bounded number of fits and gives no Ga,
    where Brent's bracket unbounded ran to the float's overflow."""
    from station.analysis.accel_law import AccelFeedback
    from station.logged import sensor_zeros

    asked = []

    def fit(u, theta, a, v, d, m, p, limit, dt):
        asked.append(float(a[0]))
        return AccelFeedback(np.ones(1), np.ones(1), np.zeros(3), 0.0)

    monkeypatch.setattr(sensor_zeros, "accel_feedback", fit)
    monkeypatch.setattr(sensor_zeros, "_gth_miss",
                        lambda u, theta, v, d, m, limit, ga: 0.1 + 10.0 ** (slope * (ga.a0 - 17.0)))
    zeros = np.zeros(3)
    got = sensor_zeros._a0_searched(zeros, zeros, zeros, zeros, 0, 1, 1, 1.0, 0.002, 17.0, (16.0, 18.0))
    a0s = [-x for x in asked]  # a − a0 with a = 0
    assert got is None
    assert 0 < len(a0s) <= 2 * sensor_zeros.A0_ITERATIONS and all(16.0 <= x <= 18.0 for x in a0s)
