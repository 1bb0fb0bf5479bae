"""Breakaway friction in the diagnosis's search (station.diagnosis.search.selection): static_friction
is fitted as coulomb_friction plus a breakaway excess (one step, v_s >= v_c by construction),
named over plain Coulomb friction only when the excess pays for itself.

Objectives here are synthetic (smooth, with a known optimum), runs come from the independent
generator (tests/blind), never from station.plant.
"""

from __future__ import annotations

import numpy as np
import pytest

from station import diagnosis
from station.diagnosis.search.fitting import EXCESS, MIN_EXCESS, UNSTICK_COST, effect_axes, excess_of, fit_beside, fit_set, set_axes
from station.diagnosis.search.selection import Trial, credible, excess_fraction, screen_costs


def test_static_friction_is_fitted_on_the_sliding_level_and_an_excess():
    axes = effect_axes()
    assert set_axes(("static_friction",), axes) == [axes["coulomb_friction"], EXCESS]
    assert set_axes(("amp_offset", "static_friction"), axes) == [axes["amp_offset"], axes["coulomb_friction"], EXCESS]
    assert set_axes(("param:drive_c",), axes) == [axes["param:drive_c"]]
    assert EXCESS.lower == 0.0 and EXCESS.upper == 30.0  # static_friction's 70 = coulomb_friction's 40 + 30


class _Cost:
    """An evaluator whose cost is smooth with its minimum at (v_c, v_s, o) = (6, 14, -2); it
    fails on a breakaway level below the sliding level (a model file error)."""

    def __init__(self):
        self.calls = 0

    def cost(self, values, runs):
        self.calls += 1
        v_c = values.get("coulomb_friction", 0.0)
        v_s = values.get("static_friction", v_c)
        assert v_s >= v_c, values
        return 1.0 + (v_c - 6.0) ** 2 + 0.5 * (v_s - 14.0) ** 2 + (values.get("amp_offset", 0.0) + 2.0) ** 2


def test_fit_set_finds_both_friction_levels_and_never_asks_for_v_s_below_v_c():
    ev = _Cost()
    axes = effect_axes()
    alone = fit_set(ev, set_axes(("static_friction",), axes), [0], {})
    assert set(alone) == {"coulomb_friction", "static_friction"}
    assert alone["coulomb_friction"] == pytest.approx(6.0, abs=0.2)
    assert alone["static_friction"] == pytest.approx(14.0, abs=0.3)
    # beside an accepted effect, from its value: all three refined together
    joint = fit_set(ev, set_axes(("amp_offset", "static_friction"), axes), [0], {"amp_offset": -1.0})
    assert joint["amp_offset"] == pytest.approx(-2.0, abs=0.3) and joint["static_friction"] == pytest.approx(14, abs=0.5)


def _trial(name, excess_fractions, cost):
    values = [{"coulomb_friction": 10.0 * (1 - f), "static_friction": 10.0} for f in excess_fractions]
    if name == "coulomb_friction":
        values = [{"coulomb_friction": 8.0}] * len(excess_fractions)
    return Trial((name,), values, {}, cost)


def test_breakaway_friction_is_named_only_when_its_excess_pays():
    terms = 1000
    assert excess_fraction(_trial("static_friction", [0.3, 0.5, 0.4], 1.0)) == pytest.approx(0.4)
    coulomb = _trial("coulomb_friction", [0, 0, 0], 2000.0)
    big = {"coulomb_friction": coulomb, "static_friction": _trial("static_friction", [0.4, 0.5, 0.45], 1000.0)}
    assert set(credible(big, terms)) == {"coulomb_friction", "static_friction"}
    # an excess of a few percent is what a second friction axis finds by luck on a jagged cost
    small = {"coulomb_friction": coulomb, "static_friction": _trial("static_friction", [0.05, 0.02, 0.2], 1000.0)}
    assert set(credible(small, terms)) == {"coulomb_friction"}
    assert MIN_EXCESS == 0.1
    # a real excess that does not pay for its parameter over Coulomb friction beside the same effects
    close = {"coulomb_friction": coulomb, "static_friction": _trial("static_friction", [0.4, 0.5, 0.45], 1980.0)}
    assert set(credible(close, terms)) == {"coulomb_friction"}
    # without a Coulomb trial to compare with (an upgrade in place), the excess alone decides
    assert set(credible({"static_friction": big["static_friction"]}, terms)) == {"static_friction"}
    assert credible({"static_friction": small["static_friction"]}, terms) == {}


@pytest.fixture(scope="module")
def blind_logs(tmp_path_factory):
    """Four rig-format logs of a clean case from the independent generator (tests/blind)."""
    from tests.blind.generator import write_case

    return [str(p) for p in write_case(tmp_path_factory.mktemp("logs"), {}, 0)]


def friction_simulator(v_c: float, v_s: float):
    """θ off from the log by smooth errors that vanish only at the given sliding and
    breakaway levels (v_s = v_c: plain Coulomb friction)."""
    def simulate(case, model):
        eff = model.effect_dict()
        k = np.arange(case.n)
        fc = eff.get("coulomb_friction", 0.0)
        fs = max(eff.get("static_friction", 0.0), fc)
        theta = case.theta + 0.4 * (fc - v_c) * np.sin(np.pi * k / case.n) \
            + 0.4 * (fs - v_s) * np.sin(2 * np.pi * k / case.n)
        return theta, case.a + eff.get("delay", 0.0)
    return simulate


def test_diagnose_names_breakaway_friction_as_one_cause_with_its_sliding_level(blind_logs):
    d = diagnosis.diagnose(blind_logs, candidates=["coulomb_friction", "static_friction", "delay"],
                           simulate=friction_simulator(6.0, 14.0))
    assert d.causes == ["static_friction"]
    fx = d.extended_model.effect_dict()
    assert fx["static_friction"] == pytest.approx(14.0, abs=0.3)
    assert fx["coulomb_friction"] == pytest.approx(6.0, abs=0.3)


def test_diagnose_keeps_plain_coulomb_friction_when_there_is_no_breakaway(blind_logs):
    d = diagnosis.diagnose(blind_logs, candidates=["coulomb_friction", "static_friction", "delay"],
                           simulate=friction_simulator(10.0, 10.0))
    assert d.causes == ["coulomb_friction"]
    assert d.extended_model.effect_dict() == {"coulomb_friction": pytest.approx(10.0, abs=0.3)}


def test_a_breakaway_within_luck_of_coulomb_friction_is_not_named():
    """credible judges the breakaway over plain Coulomb friction against what luck reaches
    around the Coulomb friction (the null floor), as every step of the search is judged."""
    terms = 1000
    coulomb = _trial("coulomb_friction", [0, 0, 0], 2000.0)
    static = _trial("static_friction", [0.4, 0.5, 0.45], 1800.0)  # 10 % lower: pays against the cost alone
    trials = {"coulomb_friction": coulomb, "static_friction": static}
    assert set(credible(trials, terms)) == {"coulomb_friction", "static_friction"}
    assert set(credible(trials, terms, lambda tr: 1850.0)) == {"coulomb_friction"}  # luck reaches 7.5 % below
    assert set(credible(trials, terms, lambda tr: 1990.0)) == {"coulomb_friction", "static_friction"}


class _Valley:
    """An evaluator whose cost has a narrow diagonal valley in (coulomb_friction, amp_offset): the
    offset pays only with the friction moved with it (as a sliding level and an amplifier offset
    do); alone the friction's best is 6."""

    def cost(self, values, runs):
        c, o = values.get("coulomb_friction", 0.0), values.get("amp_offset", 0.0)
        return 1.0 + 10.0 * (c - 6.0 - o) ** 2 + 0.5 * (o - 3.0) ** 2 + 0.001 * values.get("param:EI", 1.0)


def test_the_joint_screen_finds_a_partner_that_the_held_friction_hides():
    ev, axes = _Valley(), effect_axes()
    fixed = {"coulomb_friction": 6.0}
    c0 = ev.cost(fixed, [0])
    held = screen_costs(ev, axes, ["amp_offset", "param:EI"], fixed, [0])
    assert held.get("amp_offset", c0) > 0.95 * c0  # beside the friction held, the offset hardly pays
    joint = screen_costs(ev, axes, ["amp_offset", "param:EI"], fixed, [0], refit=["coulomb_friction"])
    assert list(joint)[0] == "amp_offset" and joint["amp_offset"] < 0.5 * c0
    cost, values = fit_beside(ev, axes, ["coulomb_friction"], "amp_offset", [0], fixed)
    assert cost == pytest.approx(joint["amp_offset"])
    assert values["coulomb_friction"] - values["amp_offset"] == pytest.approx(6.0, abs=0.3)


class _TwoValleys:
    """An evaluator whose breakaway cost has two valleys, as stick-slip's has: a shallow one at
    v_s 13.7 (J 4, far from the noise) and the true one at v_c 8.5, v_s 24.9 (J 1) that exists only
    near that sliding level, so a fit bracketing the excess from the Coulomb level 9.4 never
    sees it (blind static_friction + amp_offset + delay seed 7)."""

    def __init__(self, shallow=3.0):
        self.calls, self.shallow = 0, shallow

    def cost(self, values, runs):
        self.calls += 1
        v_c = values.get("coulomb_friction", 0.0)
        v_s = values.get("static_friction", v_c)
        deep = abs(v_c - 8.5) < 0.5 and abs(v_s - 24.9) < 6
        g = 0.3 * (v_s - 24.9) ** 2 if deep else self.shallow + 0.3 * (v_s - 13.7) ** 2
        return 1.0 + (v_c - 8.5) ** 2 + g  # J: a mean over the runs, 1 at the noise floor


def test_a_breakaway_fold_left_in_a_worse_valley_is_fitted_again_from_a_fold_that_found_the_better():
    from station.diagnosis.runs.folds import Fold
    from station.diagnosis.search.fitting import unstick

    ev, axes, names = _TwoValleys(), effect_axes(), ("static_friction",)
    folds = [Fold((1, 2), (0,)), Fold((0, 2), (1,)), Fold((0, 1), (2,))]
    shallow = {"coulomb_friction": 9.4, "static_friction": 13.7}
    deep = {"coulomb_friction": 8.5, "static_friction": 24.9}
    # the precondition: fitted from the Coulomb level, a fold stays in the shallow valley
    # with an excess far above MIN_EXCESS (not "stuck" by the excess alone)
    alone = fit_set(ev, set_axes(names, axes), (0, 2), shallow)
    assert alone["static_friction"] == pytest.approx(13.7, abs=0.3) and excess_of(alone) > 3 * MIN_EXCESS
    out = unstick(ev, folds, names, axes, [dict(deep), dict(shallow), dict(shallow)])
    assert out[0] == deep
    for fv in out[1:]:
        assert fv["static_friction"] == pytest.approx(24.9, abs=0.3)
        assert fv["coulomb_friction"] == pytest.approx(8.5, abs=0.2)
    # where no other fold fits a fold's runs better, nothing is fitted again: cost look-ups
    # only (the real Evaluator caches them), where a fit takes a hundred
    ev.calls = 0
    same = [dict(shallow) for _ in folds]
    assert unstick(ev, folds, names, axes, same) == same and ev.calls <= 4 * len(folds)
    assert unstick(ev, folds, ("coulomb_friction",), axes, [dict(shallow)] * 3) == [shallow] * 3  # no breakaway
    # near the noise a lower point is luck as often as the truth (UNSTICK_COST): left alone
    near = _TwoValleys(shallow=0.2)
    close = {"coulomb_friction": 8.5, "static_friction": 13.7}
    assert ev.cost(close, (0, 2)) > UNSTICK_COST > near.cost(close, (0, 2)) > near.cost(deep, (0, 2))
    assert unstick(near, folds, names, axes, [dict(deep), dict(close), dict(close)]) == [deep, close, close]
