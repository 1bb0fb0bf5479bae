"""Unit tests of the diagnosis's own pieces: resid-style tests, signatures, grid-bracketed
fitting on piecewise-constant objectives, forward selection with a plugged-in simulator,
the CLI (errors, DESIGN.md's JSON keys, --save-model, --report) and a real-rig smoke test.

The blind hidden-effect tests (accuracy against an independent generator) are
tests/test_diagnosis_blind.py. Logs here come from that generator (tests/blind), never
from station.plant.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.optimize
import scipy.signal

from station import cli
from station import diagnosis
from station.diagnosis.search.bounded import Axis, axis_for, fit
from station.analysis.residuals import band_response, hub_sticking, noise_std, resid_test, ringing_mode

RIG_RUNS = (
    "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
    "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
    "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
    "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt",
)


# --- residual tests ---------------------------------------------------------------------

def test_white_residual_independent_of_input_stays_in_the_band():
    rng = np.random.default_rng(1)
    e, u = rng.standard_normal(5000), rng.standard_normal(5000)
    r = resid_test(e, u, max_lag=25)
    assert r.bound == pytest.approx(2.5758 / math.sqrt(5000), rel=1e-4)
    assert r.autocorr[0] == 1.0
    assert r.outside_pct <= 8.0  # 1 % expected outside
    assert np.mean(np.abs(r.crosscorr) > r.bound) <= 0.08


def test_coloured_residual_and_input_dependence_are_flagged():
    rng = np.random.default_rng(2)
    u = rng.standard_normal(5000)
    e = scipy.signal.lfilter([1.0], [1.0, -0.9], rng.standard_normal(5000))  # AR(1): r(1) = 0.9
    r = resid_test(e, u)
    assert not r.white and r.autocorr[1] == pytest.approx(0.9, abs=0.05)
    e2 = np.roll(u, 3) + 0.1 * rng.standard_normal(5000)  # residual = input 3 samples late
    r2 = resid_test(e2, u)
    assert not r2.independent
    assert r2.cross_lags[np.argmax(np.abs(r2.crosscorr))] == 3


def test_noise_std_finds_white_noise_under_a_slow_signal():
    rng = np.random.default_rng(3)
    t = np.arange(2000) * 0.002
    x = 50 * np.sin(2 * np.pi * 2.5 * t) + 0.7 * rng.standard_normal(t.size)
    assert noise_std(x) == pytest.approx(0.7, rel=0.15)
    assert noise_std(np.zeros(2000), floor=0.3) == 0.3


def test_hub_sticking_counts_constant_theta_while_the_beam_rings():
    theta = np.concatenate([np.arange(100.0), np.full(100, 100.0), np.arange(101.0, 201.0)])
    a = np.zeros(300)
    a[100:200] = 20 * np.sin(np.arange(100) / 5)
    s = hub_sticking(theta, a, dt=0.002)
    assert s.intervals == 1 and s.duration_s == pytest.approx(0.2) and s.max_abs_a > 15
    assert hub_sticking(theta, np.zeros(300)).intervals == 0  # still, but the beam is quiet


def test_band_response_sees_a_lag_and_an_amplitude_ratio():
    t = np.arange(4000) * 0.002
    model = np.sin(2 * np.pi * 3.0 * t)
    measured = 0.5 * np.sin(2 * np.pi * 3.0 * t - np.radians(30))
    b = next(x for x in band_response(measured, model) if x.band_hz == (2.0, 4.0))
    assert b.amplitude_ratio == pytest.approx(0.5, rel=0.05)
    assert b.phase_lag_deg == pytest.approx(30, abs=3)


def test_ringing_mode_frequency_and_decay():
    t = np.arange(1500) * 0.002
    x = 30 * np.exp(-1.5 * t) * np.sin(2 * np.pi * 2.5 * t)
    m = ringing_mode(x)
    assert m.frequency_hz == pytest.approx(2.5, rel=0.05)
    assert m.decay_per_s == pytest.approx(1.5, rel=0.2)


def test_ringing_mode_of_noise_falling_through_the_band_stays_in_it():
    """Noise whose spectrum falls through the band's lower edge (a motor that never broke away):
    the peak's parabolic interpolation put it at -0.16 Hz and the band-pass raised (identify's
    open-loop ramp to 20 DAC counts, issue 17)."""
    b, a = scipy.signal.butter(1, 2.0, fs=500.0)
    x = np.round(scipy.signal.lfilter(b, a, np.random.default_rng(55).normal(0.0, 3.0, 1000)))
    m = ringing_mode(x)
    assert m is not None and 1.0 <= m.frequency_hz <= 6.0


# --- fitting on piecewise-constant objectives ---------------------------------------------

def staircase(x, x0, width):
    """A bowl quantized into flat steps: zero gradient almost everywhere."""
    return math.floor(abs(x - x0) / width) + 1.0


def test_grid_bracketing_finds_the_minimum_where_least_squares_stalls():
    ax = axis_for("coulomb_friction", 0.0, 40.0, 0.0)
    res = fit(lambda v: staircase(v["coulomb_friction"], 17.3, 0.5), [ax])
    assert abs(res.values["coulomb_friction"] - 17.3) <= 0.5
    # finite-difference least squares from the nominal value does not move: flat step
    ls = scipy.optimize.least_squares(lambda x: [staircase(x[0], 17.3, 0.5)], x0=[1.0], bounds=(0, 40))
    assert abs(ls.x[0] - 1.0) < 1e-6


def test_log_axis_for_ratios_and_enumerated_delay():
    ax = axis_for("param:drive_c", 0.25, 4.0, 1.0)
    assert ax.scale == "log" and ax.grid()[0] == pytest.approx(0.25) and ax.grid()[-1] == pytest.approx(4.0)
    res = fit(lambda v: staircase(math.log(v["param:drive_c"]), math.log(2.2), 0.02), [ax])
    assert res.values["param:drive_c"] == pytest.approx(2.2, rel=0.03)
    d = axis_for("delay", 0.0, 6.0, 0.0)
    calls = []
    res = fit(lambda v: calls.append(v["delay"]) or abs(v["delay"] - 3.0), [d])
    assert res.values["delay"] == 3.0 and sorted(set(calls)) == [0, 1, 2, 3, 4, 5, 6]


def test_joint_fit_refines_both_and_never_loses_its_grid_point():
    a = Axis("x", 0.0, 40.0, "sqrt")
    b = Axis("y", 0.25, 4.0, "log")
    cost = lambda v: staircase(v["x"], 9.0, 0.2) + staircase(math.log(v["y"]), math.log(1.7), 0.01)  # noqa: E731
    res = fit(cost, [a, b], start={"x": 6.0})
    assert abs(res.values["x"] - 9.0) <= 1.0 and res.values["y"] == pytest.approx(1.7, rel=0.1)
    grid_best = min(cost({"x": 6.0, "y": g}) for g in b.grid())
    assert res.cost <= grid_best


class _TwoValleys:
    """A breakaway cost with a broad valley of plain Coulomb friction (v_s = v_c = 3.9, cost
    2) and the true stick-slip one, narrow in v_c (v_c = 5, v_s = 11.4, cost 0.5): the
    shape of blind static_friction + param:drive_c seed 2, where a fit started from the
    Coulomb friction fitted alone (3.9) stuck in the broad one."""

    def cost(self, values, runs):
        vc, vs = values.get("coulomb_friction", 0.0), values.get("static_friction", 0.0)
        broad = 2.0 + ((vc - 3.9) / 2.0) ** 2 + (vs - vc) ** 2
        true = 0.5 + ((vc - 5.0) / 0.4) ** 2 + ((vs - 11.4) / 2.0) ** 2
        return min(broad, true)


def test_breakaway_fit_leaves_the_plain_coulomb_valley():
    from station.diagnosis.search.fitting import effect_axes, fit_set, set_axes

    values = fit_set(_TwoValleys(), set_axes(("static_friction",), effect_axes()), (0,), {"coulomb_friction": 3.9})
    assert values["coulomb_friction"] == pytest.approx(5.0, rel=0.05)
    assert values["static_friction"] == pytest.approx(11.4, rel=0.05)


# --- diagnose with a plugged-in simulator -------------------------------------------------

@pytest.fixture(scope="module")
def blind_logs(tmp_path_factory):
    """Four rig-format logs of a clean case from the independent generator (tests/blind)."""
    from tests.blind.generator import write_case

    return [str(p) for p in write_case(tmp_path_factory.mktemp("logs"), {}, 0)]


def fake_simulator(true_friction: float):
    """θ off from the log by a smooth error that vanishes only at coulomb_friction = true_friction;
    a off by what the other effects do (delay makes it worse)."""
    def simulate(case, model):
        eff = model.effect_dict()
        k = np.arange(case.n)
        bump = np.sin(np.pi * k / case.n)
        theta = case.theta + 0.4 * (eff.get("coulomb_friction", 0.0) - true_friction) * bump
        a = case.a + eff.get("delay", 0.0) * bump
        return theta, a
    return simulate


def test_diagnose_names_the_effect_that_explains_the_runs(blind_logs):
    d = diagnosis.diagnose(blind_logs, candidates=["delay", "coulomb_friction"], simulate=fake_simulator(12.0))
    assert d.cause == "coulomb_friction" and d.causes == ["coulomb_friction"]
    assert d.extended_model.effect_dict()["coulomb_friction"] == pytest.approx(12.0, abs=0.3)
    assert d.gain_pct > 90 and d.validation == "leave-one-run-out"
    assert [e.name for e in d.effects] == ["coulomb_friction", "delay"]
    assert not d.effects[1].accepted and d.effects[1].gain_pct == 0.0
    assert d.simulations > 0 and all(r.role == "validation" for r in d.runs)


def test_diagnose_gives_none_when_the_model_is_right(blind_logs):
    d = diagnosis.diagnose(blind_logs, candidates=["delay", "coulomb_friction"], simulate=fake_simulator(0.0))
    assert d.cause == "none" and d.causes == [] and d.gain_pct == 0.0
    assert d.extended_model.effect_dict() == {}
    assert d.extended_fit == d.baseline_fit


def test_validate_runs_are_judged_not_fitted(blind_logs):
    d = diagnosis.diagnose(blind_logs[:2], validate=blind_logs[2:], candidates=["coulomb_friction"],
                           simulate=fake_simulator(8.0))
    assert d.validation == "validation runs"
    assert [r.role for r in d.runs] == ["fit", "fit", "validation", "validation"]
    assert d.cause == "coulomb_friction"


# --- the command --------------------------------------------------------------------------

def test_one_run_without_validate_is_a_one_line_error(blind_logs, capsys):
    assert cli.main(["diagnose", blind_logs[0]]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "at least two runs" in err and "--validate" in err


def test_unreadable_log_and_bad_model_are_one_line_errors(blind_logs, tmp_path, capsys):
    bad = tmp_path / "bad.txt"
    bad.write_text("# not a log\nhello\tworld\n1\t2\n")
    assert cli.main(["diagnose", str(bad), blind_logs[0]]) == 2
    assert capsys.readouterr().err.strip().count("\n") == 0
    assert cli.main(["diagnose", *blind_logs[:2], "--model", str(tmp_path / "missing.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("station: error:") and err.count("\n") == 0


def test_cli_json_keys_report_and_saved_model(blind_logs, tmp_path, monkeypatch, capsys):
    from station.plant.model import load_model

    real = diagnosis.diagnose
    monkeypatch.setattr(diagnosis, "diagnose", lambda runs, **kw: real(
        runs, candidates=["delay", "coulomb_friction"], simulate=fake_simulator(6.0), **kw))
    out, model_file, report = tmp_path / "d.json", tmp_path / "ext.toml", tmp_path / "rep"
    assert cli.main(["diagnose", *blind_logs, "--json", str(out), "--save-model", str(model_file),
                     "--report", str(report), "--quiet"]) == 0
    j = json.loads(out.read_text())
    assert {"cause", "causes", "baseline", "extended", "gain_pct", "effects"} <= set(j)
    assert set(j["baseline"]) == {"fit_pct"} and set(j["baseline"]["fit_pct"]) == {"theta", "accel"}
    assert set(j["extended"]["fit_pct"]) == {"theta", "accel"}
    for e in j["effects"]:
        assert {"name", "value", "unit", "gain_pct", "evidence"} <= set(e) and e["evidence"]
    assert [e["name"] for e in j["effects"]] == ["coulomb_friction", "delay"]
    assert j["effects"][0]["unit"] == "DAC counts" and j["effects"][1]["unit"] == "samples"
    assert j["cause"] == "coulomb_friction" == j["causes"][0]
    saved = load_model(model_file)
    assert saved.effect_dict() == pytest.approx({"coulomb_friction": j["effects"][0]["value"]})
    html = (report / "report.html").read_text()
    assert "coulomb_friction" in html and html.count("data:image/png;base64,") == 8
    assert len(list(report.glob("*.png"))) == 8
    assert "cause: coulomb_friction" in capsys.readouterr().out


# --- the real rig ---------------------------------------------------------------------------

def test_real_rig_smoke(rig_data):
    """The rig's runs: the nominal fits the issue quotes, and more beam-drive damping pays."""
    d = diagnosis.diagnose([str(rig_data / name) for name in RIG_RUNS], candidates=["param:drive_c", "delay"])
    fits = {r.file: r.fit_nominal["theta"] for r in d.runs}
    assert fits[RIG_RUNS[1]] == pytest.approx(69.4, abs=0.5) and fits[RIG_RUNS[0]] == pytest.approx(19.0, abs=0.5)
    assert d.cause == "param:drive_c" and d.extended_model.effect_dict()["param:drive_c"] > 1.5
    assert d.gain_pct > 5 and next(e for e in d.effects if e.name == "delay").value == 0
