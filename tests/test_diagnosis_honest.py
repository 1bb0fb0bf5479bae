"""The diagnosis's honesty (issue 17, items 2, 3, 8, 9): what stays unexplained, the
alternatives and intervals, the two defects found with hostile inputs, the report.

Fast tests plug a simulator into :func:`station.diagnosis.diagnose` whose truth is known
(a residual that follows position, a drift, two effects that act identically); the blind
ones (marked ``slow``) diagnose logs written by the independent generator tests/blind,
with effects in the vocabulary and outside every vocabulary (``oov:``).
"""

from __future__ import annotations

import json
import math
import shutil
import zlib

import numpy as np
import pytest

from station import cli, diagnosis
from station.diagnosis.honesty.doubt import integrated_time
from station.diagnosis.search.selection import NULL_PERTURBATIONS, perturbed
from station.diagnosis.honesty.unexplained import follows
from station.plant.effects import EFFECTS

P_STEP = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
HOLD_AND_RELEASE = "log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt"


@pytest.fixture(scope="module")
def blind_logs(tmp_path_factory):
    """Four rig-format logs of a clean case from the independent generator (tests/blind)."""
    from tests.blind.generator import write_case

    return [str(p) for p in write_case(tmp_path_factory.mktemp("logs"), {}, 0)]


def _noise(case, scale: float) -> np.ndarray:
    rng = np.random.default_rng(zlib.crc32(case.name.encode()))
    return scale * rng.standard_normal(case.n)


def fake(theta_error, a_error=lambda case, eff: 0.0):
    """A simulator: the run's own θ and a plus known errors (functions of the case and the
    effects), θ rounded like an encoder, a with a little noise (the fit's J_min > 0)."""
    def simulate(case, model):
        eff = model.effect_dict()
        theta = np.floor(case.theta + theta_error(case, eff) + _noise(case, 0.2) + 0.5)
        a = case.a + a_error(case, eff) + _noise(case, 0.3)
        return theta, a
    return simulate


def bump(case) -> np.ndarray:
    return np.sin(np.pi * np.arange(case.n) / case.n)


# --- the two defects --------------------------------------------------------------------

def test_null_perturbation_of_a_value_on_its_bound_goes_inward():
    lo, hi = EFFECTS["param:act_K"].lower, EFFECTS["param:act_K"].upper
    assert perturbed("param:act_K", {"param:act_K": lo}, 0.998) == pytest.approx(lo / 0.998)
    assert perturbed("param:act_K", {"param:act_K": hi}, 1.002) == pytest.approx(hi / 1.002)
    assert perturbed("param:act_K", {"param:act_K": 2.0}, 0.998) == pytest.approx(2.0 * 0.998)
    for name, factor in NULL_PERTURBATIONS:
        spec = EFFECTS[name]
        for v in (spec.lower, spec.upper):
            assert spec.lower <= perturbed(name, {name: v}, factor) <= spec.upper


def test_an_effect_fitted_on_its_range_end_runs_to_the_end_and_is_flagged(blind_logs):
    """Defect 9a: a value fitted on its bound (act_K 0.1) used to be perturbed out of range."""
    sim = fake(lambda c, e: 10.0 * math.log(e.get("param:act_K", 1.0) / 0.1) * bump(c))
    d = diagnosis.diagnose(blind_logs, candidates=["param:act_K", "delay"], simulate=sim)
    assert d.causes == ["param:act_K"]
    act = next(e for e in d.effects if e.name == "param:act_K")
    assert act.value == pytest.approx(0.1, rel=0.01) and act.at_range_end
    assert act.interval.lo == pytest.approx(0.1) and act.interval.lo_at_bound and not act.interval.hi_at_bound
    assert "at the end of its search range" in diagnosis.summary_paragraph(d)


def test_hub_held_beam_test_is_refused_before_work_with_one_line(rig_data, capsys, monkeypatch):
    """Defect 9a: the P step and the hold-and-release log died after 14 s; the held hub is a
    beam test the model cannot simulate: set aside, and one run cannot be cross-validated."""
    monkeypatch.setattr("station.diagnosis.runs.cases.simulate_case",
                        lambda *a: pytest.fail("simulated before refusing"))
    assert cli.main(["diagnose", str(rig_data / P_STEP), str(rig_data / HOLD_AND_RELEASE)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "hub-held beam test" in err and HOLD_AND_RELEASE in err
    assert "at least two runs" in err


def test_hub_held_beam_test_among_others_is_left_out_with_a_note(blind_logs, rig_data):
    d = diagnosis.diagnose(blind_logs[:2] + [str(rig_data / HOLD_AND_RELEASE)], candidates=["coulomb_friction"],
                           simulate=fake(lambda c, e: 0.4 * (e.get("coulomb_friction", 0.0) - 12.0) * bump(c)))
    assert [r.file for r in d.runs] == [blind_logs[0].split("/")[-1], blind_logs[1].split("/")[-1]]
    assert len(d.notes) == 1 and HOLD_AND_RELEASE in d.notes[0] and "left out" in d.notes[0]
    assert d.to_json()["notes"] == d.notes


@pytest.mark.parametrize("how", ["same path twice", "byte-identical copy", "same rows, other header",
                                 "RUN and --validate"])
def test_a_run_judged_on_itself_is_refused_before_work(blind_logs, tmp_path, capsys, monkeypatch, how):
    """Defect 9b: the same run twice was "judged by leave-one-run-out" on itself (82 % gain)."""
    monkeypatch.setattr("station.diagnosis.runs.cases.simulate_case",
                        lambda *a: pytest.fail("simulated before refusing"))
    first = blind_logs[0]
    if how == "same path twice":
        args = [first, first, blind_logs[1]]
    elif how == "byte-identical copy":
        copy = tmp_path / "copy.txt"
        shutil.copyfile(first, copy)
        args = [first, blind_logs[1], str(copy)]
    elif how == "same rows, other header":
        lines = open(first).read().splitlines()
        other = tmp_path / "renamed.txt"
        other.write_text("\n".join(["#SLFR RTP P_control_Test, copied", *lines[1:]]) + "\n")
        args = [first, str(other)]
    else:
        args = [first, blind_logs[1], "--validate", first]
    assert cli.main(["diagnose", *args, "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "cannot be judged on itself" in err
    if how == "RUN and --validate":
        assert "--validate run" in err


def test_distinct_runs_with_equal_headers_are_not_refused(blind_logs):
    sim = fake(lambda c, e: 0.4 * (e.get("coulomb_friction", 0.0) - 12.0) * bump(c))
    d = diagnosis.diagnose(blind_logs, candidates=["coulomb_friction"], simulate=sim)
    assert d.cause == "coulomb_friction"


# --- doubt: alternatives and intervals -----------------------------------------------------

def test_two_indistinguishable_explanations_are_both_given(blind_logs):
    """Coulomb friction and the dead-zone act identically in this simulator: the data cannot
    tell them apart, so the other one is an alternative with a cost ratio near 1."""
    sim = fake(lambda c, e: 0.4 * (e.get("coulomb_friction", 0.0) + e.get("deadzone", 0.0) - 12.0) * bump(c))
    d = diagnosis.diagnose(blind_logs, candidates=["coulomb_friction", "deadzone", "delay"], simulate=sim)
    assert len(d.causes) == 1 and d.causes[0] in ("coulomb_friction", "deadzone")
    other = ({"coulomb_friction", "deadzone"} - set(d.causes)).pop()
    assert [a.causes for a in d.alternatives] == [[other]]
    alt = d.alternatives[0]
    assert alt.instead_of == d.cause and alt.cost_ratio == pytest.approx(1.0, abs=0.02)
    assert alt.values[other] == pytest.approx(12.0, abs=0.5) and alt.gain_pct > 50
    j = d.to_json()["alternatives"][0]
    assert set(j) >= {"causes", "values", "gain_pct", "cost_ratio"}


def test_a_clear_single_effect_has_no_alternative_and_an_interval_holding_it(blind_logs):
    sim = fake(lambda c, e: 0.4 * (e.get("coulomb_friction", 0.0) - 12.0) * bump(c),
               lambda c, e: 2.0 * e.get("delay", 0.0) * bump(c))
    d = diagnosis.diagnose(blind_logs, candidates=["coulomb_friction", "deadzone", "delay"], simulate=sim)
    assert d.causes == ["coulomb_friction"] and d.alternatives == []
    cf = next(e for e in d.effects if e.name == "coulomb_friction")
    assert cf.interval.lo < 12.0 < cf.interval.hi and cf.interval.hi - cf.interval.lo < 6.0
    assert not (cf.interval.lo_at_bound or cf.interval.hi_at_bound)
    assert all(e.interval is None for e in d.effects if not e.accepted)
    j = d.to_json()
    assert j["effects"][0]["interval"] == [cf.interval.lo, cf.interval.hi]
    assert j["interval_method"].startswith("profile likelihood")


def test_integrated_autocorrelation_time():
    rng = np.random.default_rng(4)
    assert integrated_time(rng.standard_normal(20000)) == pytest.approx(1.0, abs=0.15)
    x = np.zeros(20000)  # AR(1) with phi = 0.8: tau = (1 + phi)/(1 - phi) = 9
    e = rng.standard_normal(20000)
    for k in range(1, x.size):
        x[k] = 0.8 * x[k - 1] + e[k]
    assert integrated_time(x) == pytest.approx(9.0, rel=0.2)


# --- unexplained: residuals against the sensor model's null --------------------------------

def test_a_model_right_up_to_noise_leaves_nothing_unexplained(blind_logs):
    sim = fake(lambda c, e: 0.4 * (e.get("coulomb_friction", 0.0) - 12.0) * bump(c))
    d = diagnosis.diagnose(blind_logs, candidates=["coulomb_friction"], simulate=sim)
    j = d.to_json()
    assert j["unexplained"] is False and j["unexplained_evidence"] == ""


def test_a_cyclic_error_in_position_is_unexplained_and_follows_position(blind_logs):
    """The model misses an error periodic in θ (period 100 counts, 3 counts): flagged, and
    the evidence names position and the period."""
    sim = fake(lambda c, e: -3.0 * np.sin(2 * np.pi * c.theta / 100.0) + 0.4 * (e.get("delay", 0.0)) * bump(c))
    d = diagnosis.diagnose(blind_logs, candidates=["delay"], simulate=sim)
    assert d.cause == "none"
    u = d.unexplained
    assert u.flag and u.follows[0].what == "position θ" and u.follows[0].share > 0.5
    period = float(u.follows[0].detail.split("≈ ")[1].split()[0])
    assert period == pytest.approx(100.0, rel=0.15)
    assert "position" in d.to_json()["unexplained_evidence"]


def test_a_drift_is_unexplained_and_follows_time():
    rng = np.random.default_rng(5)
    t = np.arange(1000) * 0.002
    parts = []
    for k in range(3):  # runs that rest at different places, each drifting at its own rate
        theta = np.floor(np.minimum(t * 400, 50 * (k + 1)) + 0.5)
        e = (1 + k) * 3.0 * t + 0.3 * rng.standard_normal(t.size)
        parts.append((e, theta, np.where(t < 0.1, 100.0, 0.0), t))
    found = follows(parts)
    assert found[0].what == "time (a drift)" and found[0].share > 0.8


def test_follows_names_the_command_sign_and_speed():
    rng = np.random.default_rng(6)
    t = np.arange(2000) * 0.002
    theta = np.floor(60 * np.sin(2 * np.pi * 0.7 * t) + 0.5)
    v = 80 * np.sign(np.cos(2 * np.pi * 0.7 * t))
    sign_part = [(2.0 * np.sign(v) + 0.2 * rng.standard_normal(t.size), theta, v, t)]
    assert follows(sign_part)[0].what == "the command's sign"
    speed = np.gradient(60 * np.sin(2 * np.pi * 0.7 * t), t)
    speed_part = [(0.02 * speed + 0.2 * rng.standard_normal(t.size), theta, np.zeros_like(t), t)]
    assert follows(speed_part)[0].what == "hub speed"


# --- the command and the report -------------------------------------------------------------

def test_cli_prints_and_writes_the_new_keys_and_the_report_leads_with_words(blind_logs, tmp_path, monkeypatch,
                                                                             capsys):
    real = diagnosis.diagnose
    sim = fake(lambda c, e: 0.4 * (e.get("coulomb_friction", 0.0) + e.get("deadzone", 0.0) - 12.0) * bump(c))
    monkeypatch.setattr(diagnosis, "diagnose", lambda runs, **kw: real(
        runs, candidates=["coulomb_friction", "deadzone"], simulate=sim, **kw))
    out, report = tmp_path / "d.json", tmp_path / "rep"
    assert cli.main(["diagnose", *blind_logs, "--json", str(out), "--report", str(report), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "unexplained: no" in printed and "alternatives: " in printed and "95 % interval" in printed
    j = json.loads(out.read_text())
    assert {"unexplained", "unexplained_evidence", "alternatives", "interval_method"} <= set(j)
    assert j["effects"][0]["interval"] is not None and j["effects"][1]["interval"] is None
    page = (report / "report.html").read_text()
    answer = page[page.index("<h2>Answer</h2>"):page.index("<h2>Evidence</h2>")]
    assert "dry (Coulomb) friction on the motor (coulomb_friction)" in answer or "dead-zone" in answer
    assert "95 % interval" in answer and "Still unexplained" in answer and "Alternatives" in answer
    assert "alone" in page and "in the extended model" in page
    assert len(list(report.glob("*.png"))) == 8


def test_plain_words_of_the_headline(rig_data):
    from station.diagnosis.honesty.doubt import Interval
    from station.diagnosis.answer.prose import cause_words
    from station.diagnosis.answer.result import EffectResult

    e = EffectResult("param:drive_c", 1.98, "1", 10.0, 19.0, True, "", interval=Interval(1.54, 3.16, False, False))
    assert cause_words(e) == "drive-train damping (param:drive_c) 1.98× nominal (95 % interval 1.54–3.16)"
    e = EffectResult("param:drive_k", 0.1, "1", 6.0, 11.0, True, "", interval=Interval(0.1, 0.2, True, False),
                     at_range_end=True)
    words = cause_words(e)
    assert "reaching the lower end of its search range" in words and "at the end of its search range" in words


# --- blind: the independent generator ------------------------------------------------------

def _blind(tmp_path, case: str, seed: int) -> dict:
    from tests.blind.cases import case_effects
    from tests.blind.generator import write_case

    hidden = case_effects(case, seed)
    paths = write_case(tmp_path / "logs", hidden, seed)
    result = diagnosis.diagnose([str(p) for p in paths]).to_json()
    result["hidden"] = hidden
    return result


@pytest.mark.slow
@pytest.mark.parametrize("case", ["clean", "param:drive_c"])
def test_blind_clean_and_in_vocabulary_rigs_are_not_flagged(tmp_path, case):
    r = _blind(tmp_path, case, 0)
    assert r["unexplained"] is False, r["unexplained_evidence"]
    assert r["alternatives"] == []
    if case != "clean":
        e = r["effects"][0]
        lo, hi = e["interval"]
        assert e["name"] == case and lo <= r["hidden"][case] <= hi, (r["hidden"], e["value"], e["interval"])


@pytest.mark.slow
@pytest.mark.parametrize("seed", (0, 1))
@pytest.mark.parametrize("case", ["oov:encoder_cyclic", "oov:cogging", "oov:position_spring"])
def test_blind_out_of_vocabulary_effect_is_unexplained_and_follows_position(tmp_path, case, seed):
    r = _blind(tmp_path, case, seed)
    assert r["unexplained"] is True, f"{case} seed {seed}: causes {r['causes']}, not flagged"
    assert "position θ" in [f["what"] for f in r["residual_check"]["follows"]], r["unexplained_evidence"]
    assert "position θ" in r["unexplained_evidence"]


@pytest.mark.slow
def test_blind_cogging_that_no_single_effect_pays_for_is_still_unexplained(tmp_path):
    """oov:cogging seed 8: no single effect pays and the nominal model is far from the noise
    (J 1740), so pairs are screened from nothing (station.diagnosis.search.stepwise); the pair
    found (breakaway friction + drive stiffness) is no explanation, and the diagnosis says so.
    The pair's first effect, a breakaway that did not pay alone, once made the doubt's reading
    of the steps fail (KeyError)."""
    r = _blind(tmp_path, "oov:cogging", 8)
    assert r["unexplained"] is True, f"causes {r['causes']}, not flagged"
    assert "position θ" in r["unexplained_evidence"]
