"""station tune and the beam's tip: the tip position against an independent simulation, the
residual window, the hub-tip front's non-dominance, the structures past the thesis's (two-mode
shaper, notch, roll-off, damper) against their analytic forms, and a design on the rig that is
as quiet as the thesis's compensator where the former design was not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.analysis.metrics import settling_label
from station.design.evaluate import TIP_RMS_FLOOR, Requirements, judge, step_run, tip_bound, violations
from station.design.front import TradePoint, pareto, spread_along, trade_point
from station.design.search import Budget
from station.design.space import DesignSpace, add_s, convolve_shapers, damper_s, filter_s, thesis_compensator
from station.design.tip import RESIDUAL_AFTER_S, residual, tip_position
from station.control.shaper import ShaperTimes
from station.plant import load_model
from station.rounding import half_away

FORMER = {"k0": 7.176, "z": 50.24, "ratio": 1.808, "ga_gain": 0.5804, "ga_freq": 0.4487, "shaper_t2": 0.2084,
          "shaper_a2": 0.4238}
"""The former tuned lead + accelerometer on `rig` (docs/tuning.md before the tip): 0.266 s, the tip ringing."""


def _physical_tip(model, v):
    """Tip position H·w_tip/L by ZOH of M q'' + C q' + K q = b v in physical coordinates
    (scipy, not the station's scaled modal form or its kernel), v rounded as the device does."""
    import scipy.signal

    from station.plant.fem import SecondOrderModel

    p = model.linear_params()
    m = SecondOrderModel(p, model.n_elements)
    n = m.M.shape[0]
    minv = np.linalg.inv(m.M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ m.K, -minv @ m.C]])
    B = np.concatenate([np.zeros(n), minv @ m.b])[:, None]
    C = np.zeros((1, 2 * n))
    C[0, m.tip_w] = p.H / p.L
    sys = scipy.signal.cont2discrete((A, B, C, np.zeros((1, 1))), 0.002, method="zoh")
    _, y, _ = scipy.signal.dlsim(sys[:4] + (0.002,), np.array([half_away(x) for x in v]))
    return y[:, 0]


def test_the_tip_position_is_the_fems_tip_deflection_over_l():
    model = load_model("tmm-fit")  # linear: the physical ZOH simulation is the truth
    run = step_run(model, thesis_compensator("lead-accel"), 200.0)
    tip = tip_position(model, run.v)
    truth = _physical_tip(model, run.v)
    assert np.max(np.abs(tip - truth)) < 1e-6 * np.max(np.abs(truth))
    assert np.max(tip) > np.max(run.theta) + 20  # the tip swings past the hub: the beam bends


@pytest.mark.parametrize("name", ["rig", "rig-2009"])
def test_the_tips_acceleration_is_the_accelerometers_with_friction(name):
    model = load_model(name)  # friction and offsets: the tip replays the run's own commands
    run = step_run(model, thesis_compensator("lead-accel"), 200.0)
    tip = tip_position(model, run.v)
    p = model.linear_params()
    # a = a_gain·w_tip'' and tip = H·w_tip/L: the second difference, counted like a
    acc = np.diff(tip, 2) / 0.002 ** 2 * p.L / p.H * p.a_gain
    assert np.max(np.abs(acc[50:] - run.a[1:-1][50:])) < 1.0  # a is rounded to whole counts (and one sample apart)
    assert tip[-1] == pytest.approx(run.theta[-1], abs=1.0)  # at rest the beam is straight: tip = hub


def test_the_residual_window_starts_0_6_s_after_the_step():
    a = np.zeros(1000)
    k = 10 + int(round(RESIDUAL_AFTER_S / 0.002))
    a[:k] = 50.0  # the step's transient: outside the window
    a[k:] = np.where(np.arange(1000 - k) % 2, 3.0, -3.0)
    r = residual(a, 10)
    assert r.rms == pytest.approx(3.0) and r.peak == 3.0
    assert math.isnan(residual(a[:k], 10).rms)


def test_the_tips_bound_is_the_thesiss_rms_at_least_the_noise():
    assert tip_bound(1.0, 1.02) == pytest.approx(1.02) and tip_bound(1.5, 2.0) == pytest.approx(3.0)
    assert tip_bound(1.0, 0.05) == TIP_RMS_FLOOR and tip_bound(None, 1.0) is None
    from tests.test_tune import _figures

    loud = _figures(0.5)._replace(tip_residual_rms=1.2)
    assert "tip" in violations(loud, Requirements(tip_rms=1.0)) and not violations(loud, Requirements(tip_rms=1.3))


def _point(hub, tip, ok=True):
    return TradePoint(np.zeros(1), hub, tip, 1.0, hub, tip, ok, ok)


@pytest.mark.parametrize("seed", range(20))
def test_the_front_is_exactly_the_non_dominated_designs(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    hub = rng.choice([0.5, 0.7, 0.9, 1.1], n) if seed % 2 else rng.uniform(0.3, 2.0, n)  # ties on even seeds
    tip = rng.choice([0.8, 1.0, 1.5], n) if seed % 2 else rng.uniform(0.2, 3.0, n)
    ok = rng.uniform(size=n) < 0.8
    pts = [_point(h, t, o) for h, t, o in zip(hub, tip, ok)]
    front = pareto(pts)
    eligible = [i for i in range(n) if ok[i]]
    assert set(front) <= set(eligible)
    # no eligible design beats a front design on both (at least as good on both, better on one)
    for i in front:
        assert not any(hub[j] <= hub[i] and tip[j] <= tip[i] and (hub[j] < hub[i] or tip[j] < tip[i])
                       for j in eligible)
    # every other eligible design is beaten or equalled by a front design
    for j in set(eligible) - set(front):
        assert any(hub[i] <= hub[j] and tip[i] <= tip[j] for i in front)
    # one design per distinct point, ordered by the hub
    assert len({(hub[i], tip[i]) for i in front}) == len(front)
    assert [hub[i] for i in front] == sorted(hub[i] for i in front)


def test_spread_along_picks_both_ends():
    assert spread_along([3.0, 1.0, 2.0], 5) == [1, 2, 0]
    picks = spread_along(list(np.linspace(0, 1, 50)), 4)
    assert picks[0] == 0 and picks[-1] == 49 and len(picks) == 4


def test_a_two_mode_shaper_is_the_product_of_its_pairs():
    a, b = ShaperTimes((0.0, 0.2), (0.6, 0.4)), ShaperTimes((0.0, 0.027), (0.55, 0.45))
    both = convolve_shapers(a, b)
    # its z-transform is the product of the pairs' (times on the 2 ms grid)
    z = np.exp(1j * np.linspace(0.1, 3.0, 7))

    def h(s):
        return sum(amp * z ** -round(t / 0.002) for t, amp in zip(s.times, s.amplitudes))
    assert np.allclose(h(both), h(a) * h(b)) and sum(both.amplitudes) == pytest.approx(1.0)
    assert len(convolve_shapers(a, ShaperTimes((0.0, 0.2), (0.5, 0.5))).times) == 3  # 0.2 + 0.0 and 0.0 + 0.2 merged
    space = DesignSpace("lead-accel", "opt2")
    vals = dict(FORMER, shaper_t3=0.027, shaper_a3=0.45)
    assert space.shaper_times(vals) == convolve_shapers(ShaperTimes((0.0, vals["shaper_t2"]),
                                                                    (1 - vals["shaper_a2"], vals["shaper_a2"])),
                                                        ShaperTimes((0.0, 0.027), (0.55, 0.45)))


@pytest.mark.parametrize("hz, depth, width", [(18.0, 0.1, 0.2), (12.0, 0.5, 0.05), (30.0, 1.0, 0.7)])
def test_the_notch_and_the_rolloff_are_what_they_say(hz, depth, width):
    w = 2 * math.pi * hz
    num, den = filter_s("notch", {"notch_hz": hz, "notch_depth": depth, "notch_width": width})
    assert abs(np.polyval(num, 1j * w) / np.polyval(den, 1j * w)) == pytest.approx(depth)
    assert np.polyval(num, 0) / np.polyval(den, 0) == pytest.approx(1.0)
    num, den = filter_s("rolloff", {"rolloff_hz": hz, "rolloff_zeta": width})
    assert np.polyval(num, 0) / np.polyval(den, 0) == pytest.approx(1.0)
    assert abs(np.polyval(num, 1j * w) / np.polyval(den, 1j * w)) == pytest.approx(1 / (2 * width))
    space = DesignSpace("lead", "none", filter="notch")
    vals = {"k0": 5.0, "z": 2 * math.pi * 5, "ratio": 4.0, "notch_hz": hz, "notch_depth": depth, "notch_width": width}
    gnum, gden, _ = space.compensator_file(vals).gth
    lead = DesignSpace("lead").compensator_file(vals).gth
    s = 1j * w * 0.5
    assert np.polyval(gnum, s) / np.polyval(gden, s) == pytest.approx(
        np.polyval(lead[0], s) / np.polyval(lead[1], s) * np.polyval([1, 2 * depth * width * w, w * w], s)
        / np.polyval([1, 2 * width * w, w * w], s))


@pytest.mark.parametrize("phase", [-120.0, 0.0, 45.0, 180.0])
def test_the_damper_has_its_gain_and_phase_at_its_centre(phase):
    vals = {"damper_hz": 18.0, "damper_gain": 0.05, "damper_phase": phase, "damper_zeta": 0.25}
    num, den = damper_s(vals)
    w = 2 * math.pi * 18.0
    g = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    assert abs(g) == pytest.approx(0.05 / (2 * 0.25)) and math.remainder(np.angle(g, deg=True) + phase, 360) == \
        pytest.approx(0.0, abs=1e-9)
    a, b = ([1.0, 2.0], [1.0, 3.0, 5.0]), ([4.0], [1.0, 7.0])
    n, d = add_s(a, b)
    s = 0.3 + 2j
    assert np.polyval(n, s) / np.polyval(d, s) == pytest.approx(np.polyval(a[0], s) / np.polyval(a[1], s)
                                                                + np.polyval(b[0], s) / np.polyval(b[1], s))
    with pytest.raises(ValueError, match="lead-accel only"):
        DesignSpace("lead", filter="damper")


@pytest.fixture(scope="module")
def rig():
    return load_model("rig")


def test_the_former_design_rings_the_tip_on_rig(rig):
    # what the issue found: hub 0.266 s, the tip four times louder than the thesis's from 0.6 s
    former = DesignSpace("lead-accel", "opt").compensator_file(FORMER).compensator()
    f, b = judge(rig, former, 200.0), judge(rig, thesis_compensator("lead-accel"), 200.0)
    assert f.settling_2pct_s == pytest.approx(0.266) and f.tip_residual_rms > 3 * b.tip_residual_rms


@pytest.fixture(scope="module")
def quiet(rig):
    from station.design.tuning import tune

    return tune("rig", structure="lead-accel", samples=0, jobs=1, shaper="opt2",
                budget=Budget(global_log2=8, keep=4, starts=2, maxfev=80, rounds=2, screen=0), front=4)


def test_a_design_on_rig_is_as_quiet_as_the_thesiss_and_faster(quiet):
    f, b = quiet.figures[0], quiet.baseline[0]
    assert quiet.met() == [True]
    assert f.tip_residual_rms <= b.tip_residual_rms  # the tip at least as quiet from 0.6 s after the step
    assert f.settling_2pct_s < b.settling_2pct_s and f.overshoot_pct <= 5.0
    doc = quiet.to_json()
    for key in ("tip_settling_2pct_s", "tip_residual_rms", "tip_residual_peak"):
        assert doc["model"][key] == pytest.approx(getattr(f, key))
        assert doc["baseline"][key] == pytest.approx(getattr(b, key))
        assert doc["robust"]["per_model"][0]["baseline"][key] == pytest.approx(getattr(b, key))
    assert doc["robust"]["per_model"][0]["tip_rms_bound"] == pytest.approx(b.tip_residual_rms)
    assert doc["design"]["requirements"]["tip_rms"] == 1.0


def test_the_chosen_design_is_marked_in_the_tradeoff(quiet):
    tr = quiet.tradeoff
    chosen = tr.points[tr.chosen]
    again = trade_point(chosen.x, quiet.figures, quiet.baseline, quiet.model_requirements())
    assert again.hub_ratio == pytest.approx(chosen.hub_ratio) and again.tip_ratio == pytest.approx(chosen.tip_ratio)
    assert chosen.met and tr.to_json()["chosen"]["chosen"]
    for i in tr.front:  # nothing judged beats a front design on both
        p = tr.points[i]
        assert not any(q.others_met and q.hub_ratio <= p.hub_ratio and q.tip_ratio <= p.tip_ratio
                       and (q.hub_ratio, q.tip_ratio) != (p.hub_ratio, p.tip_ratio) for q in tr.points)


def test_tune_prints_each_settling_time_with_its_band(quiet):
    from station.commands.tune import format_result

    text = format_result(quiet)
    assert settling_label(2) in text and "tip residual RMS" in text
    assert "2 % settling" not in text and "settling time" not in text


@pytest.mark.parametrize("script, option, value", [
    ("heldout_tune.py", "--seeds", "0"), ("heldout_tune.py", "--seeds", "nan"), ("heldout_tune.py", "--jobs", "inf"),
    ("tuning_table.py", "--seeds", "nan"), ("tuning_table.py", "--unseen", "0"), ("tuning_table.py", "--jobs", "1.5"),
])
def test_the_tip_scripts_refuse_a_bad_number_in_one_line(script, option, value, capsys):
    import runpy
    from pathlib import Path

    main = runpy.run_path(str(Path(__file__).resolve().parents[1] / "scripts" / script), run_name="options")["main"]
    with pytest.raises(SystemExit) as exc:
        main([option, value])
    assert exc.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"argument {option}: {value} is" in last and "expected range" in last
