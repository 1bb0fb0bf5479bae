"""``station identify``: the experiments (references against the blind generator's), the rivals a
diagnosis leaves open, the experiment design (friction is separated by an experiment that
excites friction, beam damping by one that rings the beam, within the soft limit), the loop
(early stops reported and not used, the budget, signals) and the command (bad input refused
before any run; on the simulated rig with hidden effects it names them within 25 %).
"""

from __future__ import annotations

import itertools

import json
import re
import signal
from pathlib import Path
from types import SimpleNamespace

import numpy as np

import pytest

from station import DT, cli
from station.control import file_reference
from station.diagnosis.identify import loop as identify_mod
from station.diagnosis.identify.design import MIN_SEPARATION, choose_experiment, predict
from station.diagnosis.identify.experiments import (PRBS_HOLD_TICKS, THESIS_EXPERIMENTS, Experiment,
                                           candidate_experiments, write_reference)
from station.diagnosis.identify.loop import ExperimentRun, identify, step_runner
from station.diagnosis.identify.prefer import prefer
from station.diagnosis.honesty.rivals import JACKKNIFE_Z, Rival, Rivals, jackknife_interval, rivals
from station.plant.model import as_model
from station.rig import DEFAULT_STEP_TICK
from tests.blind.generator import RUNS, reference as blind_reference

NOMINAL = as_model(None)


# --- the experiments -----------------------------------------------------------------------

def test_thesis_experiments_are_the_blind_generators_runs():
    for exp, run in zip(THESIS_EXPERIMENTS, RUNS):
        np.testing.assert_array_equal(exp.u(), blind_reference(run), err_msg=run)
    assert [e.controller for e in THESIS_EXPERIMENTS] == ["p", "lead", "lead-accel", "open-loop"]
    assert THESIS_EXPERIMENTS[0].kp == 2.0


@pytest.mark.parametrize("exp", candidate_experiments(), ids=lambda e: e.slug)
def test_candidate_references_have_their_shape(exp):
    u, a = exp.u(), exp.amplitude
    assert u.size == 1000 and not np.any(u[:DEFAULT_STEP_TICK])
    assert np.max(np.abs(u)) == pytest.approx(a, rel=1e-9) or exp.reference in ("chirp", "triangle", "reversals")
    assert np.max(np.abs(u)) <= a * (1 + 1e-12)
    if exp.reference == "ramp":
        assert np.all(np.diff(u[DEFAULT_STEP_TICK:]) > 0) and u[-1] == pytest.approx(a)
    if exp.reference == "triangle":
        assert u.max() == pytest.approx(a, rel=0.01) and u.min() == pytest.approx(-a, rel=0.01) and abs(u[-1]) < 0.02 * a
    if exp.reference == "stairs":  # holds at A/3, 2A/3, A, 2A/3, A/3, 0, each a sixth of the run
        levels = [float(x) for x, _ in itertools.groupby(u[DEFAULT_STEP_TICK:])]
        assert levels == pytest.approx([a / 3, 2 * a / 3, a, 2 * a / 3, a / 3, 0.0])
        assert u[DEFAULT_STEP_TICK] == pytest.approx(a / 3) and u[-1] == 0.0
    if exp.reference == "reversals":  # three periods of the triangle: six turning points
        slope = np.sign(np.diff(u[DEFAULT_STEP_TICK:]))
        turns = np.count_nonzero(np.diff(slope[slope != 0]))
        assert turns == 6 and u.max() == pytest.approx(a, rel=0.01) and u.min() == pytest.approx(-a, rel=0.01)
    if exp.reference == "prbs":
        assert set(np.unique(u[DEFAULT_STEP_TICK:])) == {-a, a}
        runs = np.diff(np.flatnonzero(np.diff(u[DEFAULT_STEP_TICK:]) != 0))
        assert np.all(runs % PRBS_HOLD_TICKS == 0)
    if not exp.closed:
        assert a <= 200  # the rig's clamp


def test_reference_file_round_trips_through_station_steps_reader(tmp_path):
    exp = Experiment("open-loop", "triangle", 30.0)
    path = write_reference(exp, tmp_path / "ref.tsv")
    np.testing.assert_allclose(file_reference(path, "u"), exp.u(), atol=1e-8)


def test_experiment_refuses_a_gain_for_another_controller():
    with pytest.raises(ValueError):
        Experiment("lead", "step", 100.0, kp=2.0)
    with pytest.raises(ValueError):
        Experiment("p", "step", 100.0)
    assert Experiment("p", "step", 50.0, kp=2.0).label == "P (kp 2) step of 50 counts"


# --- the rivals ----------------------------------------------------------------------------

def _effect(name, value, accepted=True, cost_gain=50.0, interval=None):
    return SimpleNamespace(name=name, value=value, accepted=accepted, cost_gain_pct=cost_gain, interval=interval)


def _diag(effects, folds=(), **extra):
    d = SimpleNamespace(effects=list(effects), accepted=[e.name for e in effects if e.accepted], folds=list(folds))
    for k, v in extra.items():
        setattr(d, k, v)
    return d


def test_jackknife_interval_by_hand():
    lo, hi = jackknife_interval(10.0, [9.0, 10.0, 11.0, 10.0])
    sigma = np.sqrt(3 / 4 * 2.0)  # (n-1)/n * sum of squared deviations
    assert (lo, hi) == pytest.approx((10 - JACKKNIFE_Z * sigma, 10 + JACKKNIFE_Z * sigma))
    assert jackknife_interval(10.0, [9.0]) is None


def test_rivals_from_alternatives_and_wide_intervals():
    iv = SimpleNamespace(lo=6.0, hi=15.0, lo_at_bound=False, hi_at_bound=False)
    d = _diag([_effect("coulomb_friction", 10.0, interval=iv), _effect("param:drive_c", 2.0, interval=[1.95, 2.05])],
              alternatives=[{"causes": ["deadzone", "param:drive_c"], "values": {"deadzone": 9.0, "param:drive_c": 2.1},
                             "gain_pct": 40.0, "cost_ratio": 1.02}])
    rv = rivals(d)
    assert rv.chosen == {"coulomb_friction": 10.0, "param:drive_c": 2.0}
    assert [r.kind for r in rv.rivals] == ["alternative", "interval", "interval"]
    assert rv.rivals[0].effects == {"deadzone": 9.0, "param:drive_c": 2.1}
    assert [r.effects["coulomb_friction"] for r in rv.rivals[1:]] == [6.0, 15.0]
    assert all(r.effects["param:drive_c"] == 2.0 for r in rv.rivals[1:])  # the narrow one stays
    assert rv.wide == ["coulomb_friction"] and "upper end" in rv.rivals[2].label


def test_rivals_fall_back_to_the_jackknife_and_the_runner_ups():
    folds = [{"values": {"coulomb_friction": v}} for v in (9.0, 10.0, 11.0, 10.0)]
    d = _diag([_effect("coulomb_friction", 10.0, cost_gain=60.0), _effect("deadzone", 12.0, False, cost_gain=50.0),
               _effect("delay", 1.0, False, cost_gain=10.0)], folds)
    rv = rivals(d)
    assert [r.effects for r in rv.rivals if r.kind == "alternative"] == [{"deadzone": 12.0}]
    lo, hi = jackknife_interval(10.0, [9.0, 10.0, 11.0, 10.0])
    assert [r.effects["coulomb_friction"] for r in rv.rivals if r.kind == "interval"] == pytest.approx([lo, hi])
    assert any("jackknife" in s for s in rv.sources)


def test_no_rivals_for_none_or_a_settled_diagnosis():
    assert rivals(_diag([_effect("delay", 2.0, False)], alternatives=[])).rivals == []
    settled = _diag([_effect("coulomb_friction", 10.0, interval=[9.5, 10.5])], alternatives=[])
    assert rivals(settled).rivals == []


# --- the design ------------------------------------------------------------------------------

def _design(chosen, rival, **kw):
    rv = Rivals(chosen, f"{chosen}", [Rival(rival, f"{rival}", "interval")], [], [])
    return choose_experiment(NOMINAL, rv, **kw)


FRICTION_EXCITERS = ("open-loop ramp", "open-loop triangle", "open-loop stairs", "open-loop 3 reversals", "open-loop ±30",
                     "open-loop ±60", "P (kp 2) step of 10", "P (kp 2) step of 25", "P (kp 2) ramp")


def test_friction_is_separated_by_an_experiment_that_excites_friction():
    d = _design({"coulomb_friction": 8.0}, {"coulomb_friction": 15.0})
    assert d.experiment is not None and d.experiment.label.startswith(FRICTION_EXCITERS), d.experiment.label
    # the why names the difference in counts of θ, as the predictions give it
    m = re.search(r"by up to ([\d.e+]+) counts of θ \((\d+)× the encoder", d.why)
    assert m, d.why
    p0, p1 = list(d.predictions.values())
    assert float(m.group(1)) == pytest.approx(np.max(np.abs(p1.theta - p0.theta)), rel=0.01)
    assert float(m.group(1)) > 10
    # the thesis's fast lead + accelerometer step tells the two frictions apart far less
    fast = next(c for c in d.candidates if c.experiment.label == "lead + accelerometer step of 400 counts")
    assert d.candidates[0].separations[0] > 10 * fast.separations[0]


def test_beam_damping_is_separated_by_an_experiment_that_rings_the_beam():
    d = _design({"beam_damping": 0.01}, {"beam_damping": 0.03})
    assert d.experiment is not None and "counts of a" in d.why
    p0, p1 = list(d.predictions.values())
    da = p1.a - p0.a
    spectrum = np.abs(np.fft.rfft(da - da.mean()))
    f = np.fft.rfftfreq(da.size, DT)
    peak = f[np.argmax(spectrum)]
    # a beam mode (DESIGN.md: first 2.52 Hz, second ≈ 18 Hz; stiffness-proportional damping
    # changes the second mode's decay the most)
    assert 1.5 <= peak <= 5.0 or 15.0 <= peak <= 21.0, peak


def test_design_keeps_every_model_within_the_soft_limit():
    d = _design({"coulomb_friction": 8.0}, {"coulomb_friction": 15.0}, soft_limit=150.0)
    assert d.experiment is not None
    for p in d.predictions.values():
        assert np.max(np.abs(p.theta)) <= 0.8 * 150
    ramp80 = next(c for c in d.candidates if c.experiment.label == "open-loop ramp to 80 DAC counts")
    assert not ramp80.feasible and "soft limit" in ramp80.note and ramp80.score == 0


def test_design_says_when_nothing_separates():
    same = _design({"coulomb_friction": 8.0}, {"coulomb_friction": 8.0})
    assert same.experiment is None and f"{MIN_SEPARATION:g} noise variances" in same.why
    none = choose_experiment(NOMINAL, Rivals({}, "the nominal model", [], [], []))
    assert none.experiment is None and "no rivals" in none.why


def test_prediction_is_the_run_as_the_device_runs_it():
    """Open loop with alignment 1: the first command acts one tick after its reference sample."""
    exp = Experiment("open-loop", "pulses", 100.0)
    p = predict(NOMINAL, exp)
    assert np.all(p.theta[:22] == 0) and p.theta[25] > 0  # pulse from tick 20, acting from tick 21


# --- the loop --------------------------------------------------------------------------------

def _hidden_model(tmp_path, effects) -> Path:
    path = tmp_path / "hidden.toml"
    lines = ['name = "hidden"', 'params = "tmm-fit"', "n_elements = 4", "[effects]"]
    path.write_text("\n".join(lines + [f'"{k}" = {v}' for k, v in effects.items()]) + "\n")
    return path


def test_an_experiment_that_stops_early_is_reported_and_not_used(tmp_path):
    model = _hidden_model(tmp_path, {"coulomb_friction": 10.0})
    good = step_runner(f"sim://?model={model}")
    silent = step_runner(f"sim://?model={model}&silent_after=300")

    def runner(exp, log):
        return (silent if exp is THESIS_EXPERIMENTS[1] else good)(exp, log)

    ident = identify(out_dir=tmp_path / "runs", runner=runner, budget=0, candidates=["coulomb_friction", "delay"])
    lead = ident.experiments[1]
    assert lead.reason == "timeout" and not lead.used
    assert [r.used for r in ident.experiments] == [True, False, True, True]
    assert {r.file for r in ident.diagnosis.runs} == {Path(r.log).name for r in ident.experiments if r.used}
    doc = ident.to_json()
    assert doc["experiments"][1]["outcome"] == "timeout" and doc["experiments"][1]["used"] is False
    assert doc["cause"] == "coulomb_friction"


def _always_doubtful(real):
    """The real diagnosis, with a rival it never rules out (a deadzone instead of friction)."""
    def fake(runs, **kw):
        d = real(runs, **kw)
        d.alternatives = [{"causes": ["deadzone"], "values": {"deadzone": 12.0}, "gain_pct": 0.0, "cost_ratio": 1.0}]
        return d
    return fake


def test_budget_bounds_the_designed_experiments(tmp_path, monkeypatch):
    monkeypatch.setattr(identify_mod, "diagnose", _always_doubtful(identify_mod.diagnose))
    model = _hidden_model(tmp_path, {"coulomb_friction": 10.0})
    kw = {"candidates": ["coulomb_friction", "delay"], "runner": step_runner(f"sim://?model={model}")}
    zero = identify(out_dir=tmp_path / "zero", budget=0, **kw)
    assert len(zero.experiments) == 4 and "budget of 0" in zero.stopped
    two = identify(out_dir=tmp_path / "two", budget=2, **kw)
    assert len(two.experiments) == 6 and "budget of 2" in two.stopped
    designed = two.experiments[4:]
    assert all(r.design is not None and r.used for r in designed)
    assert designed[0].experiment != designed[1].experiment  # never the same twice
    for r in designed:
        assert "deadzone 12 DAC counts" in r.why and "counts of" in r.why
        assert Path(r.log).is_file() and Path(r.log).with_name(Path(r.log).stem + ".u.tsv").is_file() \
            or r.experiment.reference == "step"
    assert two.diagnoses == 3 and set(two.timings) == {"experiments", "diagnosis", "design", "total"}
    # a rival that fits every run as well after two experiments designed against it is not chased further
    four = identify(out_dir=tmp_path / "four", budget=4, **kw)
    assert len(four.experiments) == 4 + identify_mod.SURVIVALS and "cannot tell them apart" in four.stopped
    assert [a["causes"] for a in four.diagnosis.alternatives] == [["deadzone"]]  # still listed


def test_prefer_keeps_the_explanation_that_fits_every_run(tmp_path):
    """A greedy re-diagnosis that fits worse is set aside for the earlier explanation, refitted."""
    model = _hidden_model(tmp_path, {"deadzone": 8.0, "param:act_K": 0.8})
    run = step_runner(f"sim://?model={model}")
    logs = [run(exp, tmp_path / f"{k}.tsv").log for k, exp in enumerate(THESIS_EXPERIMENTS)]
    old = _diag([_effect("deadzone", 7.0), _effect("param:act_K", 0.78)])
    new = _diag([_effect("coulomb_friction", 13.0)])
    pref = prefer(old, new, logs, NOMINAL)
    assert pref.keep_old and pref.old_cost < pref.new_cost
    assert pref.values["deadzone"] == pytest.approx(8.0, rel=0.1) and pref.values["param:act_K"] == pytest.approx(0.8, rel=0.05)
    assert "fits them better" in pref.note
    assert not prefer(new, old, logs, NOMINAL).keep_old  # the worse one never wins
    assert prefer(old, old, logs, NOMINAL).note == ""  # same structure: nothing to compare


def test_recheck_candidates_keep_the_causes_the_rivals_and_the_best_others():
    d = _diag([_effect("coulomb_friction", 10.0, cost_gain=60.0), _effect("delay", 1.0, False, cost_gain=-5.0),
               _effect("param:act_K", 0.9, False, cost_gain=30.0), _effect("backlash", 2.0, False, cost_gain=40.0)])
    names = identify_mod.recheck_candidates(d, ["deadzone"], ["coulomb_friction", "delay", "deadzone", "param:act_K",
                                                                  "backlash"])
    assert names == ["coulomb_friction", "deadzone", "backlash", "param:act_K"]


def test_a_signal_ends_the_identification(tmp_path):
    calls = []

    def runner(exp, log):
        calls.append(exp)
        return ExperimentRun(log, "sigint", 130) if len(calls) == 2 else ExperimentRun(log, "timeout", 1)

    ident = identify(out_dir=tmp_path / "runs", runner=runner)
    assert len(calls) == 2 and ident.exit_code == 130 and ident.diagnosis is None
    assert "sigint" in ident.stopped


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_between_experiments_starts_no_other(tmp_path, signum, code):
    """A signal that arrives while the station diagnoses or designs (recorded by the CLI's
    guard) keeps the next experiment from starting: the device never gets its START."""
    from station.signals import StopSignals

    calls = []
    with StopSignals() as guard:
        guard.defer()  # as after a run: signals are recorded, the work polls them

        def runner(exp, log):
            calls.append(exp)
            guard.signum = signum  # came while the next experiment was being chosen
            return ExperimentRun(log, "timeout", 1)

        ident = identify(out_dir=tmp_path / "runs", runner=runner)
    assert len(calls) == 1 and ident.exit_code == code
    assert ident.stopped == f"stopped by {'sigint' if code == 130 else 'sigterm'} before experiment 2 started"


# --- the command -------------------------------------------------------------------------------

@pytest.mark.parametrize("args, words", [
    (["--budget", "-1"], "--budget"),
    (["--model", "no-such-model.toml"], "no-such-model"),
    (["--port", "/dev/no-such-port"], "no such device"),
])
def test_bad_input_is_one_line_before_any_run(tmp_path, capsys, args, words):
    out = tmp_path / "runs"
    assert cli.main(["identify", "--out-dir", str(out), "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and words in err
    assert not out.exists()


def test_budget_help_names_the_loops_default():
    import subprocess
    import sys

    from station.diagnosis.identify.loop import DEFAULT_BUDGET

    sub = next(a for a in cli.build_parser()._actions if hasattr(a, "choices") and a.choices and "identify" in a.choices)
    budget = next(a for a in sub.choices["identify"]._actions if "--budget" in a.option_strings)
    assert f"default {DEFAULT_BUDGET};" in budget.help
    # building the parser (every command's start-up) does not load the diagnosis
    code = "import sys, station.cli; station.cli.build_parser(); print('station.diagnosis' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"


def test_outputs_are_never_overwritten_without_force(tmp_path, capsys):
    existing = tmp_path / "d.json"
    existing.write_text("{}")
    assert cli.main(["identify", "--out-dir", str(tmp_path / "runs"), "--json", str(existing), "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err and existing.read_text() == "{}"
    full = tmp_path / "full"
    full.mkdir()
    (full / "old.tsv").write_text("x")
    assert cli.main(["identify", "--out-dir", str(full), "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err and [p.name for p in full.iterdir()] == ["old.tsv"]


def test_a_silent_device_leaves_nothing_to_diagnose(tmp_path, capsys):
    out = tmp_path / "d.json"
    code = cli.main(["identify", "--port", "sim://?silent_after=100", "--out-dir", str(tmp_path / "runs"),
                     "--json", str(out), "--quiet"])
    assert code == 1
    doc = json.loads(out.read_text())
    assert [e["outcome"] for e in doc["experiments"]] == ["timeout"] * 4
    assert not any(e["used"] for e in doc["experiments"]) and doc["cause"] is None
    assert "nothing to diagnose" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.parametrize("hidden", [{"coulomb_friction": 4.0, "param:J_base": 1.5},
                                    {"backlash": 6.0, "coulomb_friction": 6.0},
                                    {"static_friction": 12.0, "coulomb_friction": 5.0, "viscous_friction": 3.0}],
                         ids=lambda h: "+".join(h))
def test_identify_names_hidden_effects_on_the_simulated_rig(tmp_path, capsys, hidden):
    """DESIGN.md "Identifying a rig", done when: two or three hidden effects named within 25 % in
    at most 8 designed experiments (issue 17's breakaway case: static_friction with its sliding
    level, which the thesis's four cannot tell from viscous plus Coulomb friction). The model
    file is served by the simulated rig; the diagnosis sees only the logs."""
    model = _hidden_model(tmp_path, hidden)
    out, saved, report = tmp_path / "id.json", tmp_path / "found.toml", tmp_path / "report"
    code = cli.main(["identify", "--port", f"sim://?model={model}", "--out-dir", str(tmp_path / "runs"),
                     "--json", str(out), "--save-model", str(saved), "--report", str(report), "--quiet"])
    assert code == 0
    doc = json.loads(out.read_text())
    held = {"coulomb_friction"} if "static_friction" in hidden else set()  # breakaway's sliding level: no cause
    assert set(hidden) - held <= set(doc["causes"]), doc["causes"]
    found = doc["identify"]["model"]["effects"]  # the identified model, as --save-model writes it
    for name, value in hidden.items():
        assert found[name] == pytest.approx(value, rel=0.25), (name, found)
    assert 4 <= len(doc["experiments"]) <= 12 and doc["identify"]["budget"] == 8
    for e in doc["experiments"]:
        assert {"log", "controller", "reference", "why"} <= set(e) and Path(e["log"]).is_file() and e["why"]
    assert as_model(saved).effect_dict() == pytest.approx(found)
    assert (report / "identify.html").is_file() and (report / "report.html").is_file()
    printed = capsys.readouterr().out
    assert "ended:" in printed and "cause:" in printed
