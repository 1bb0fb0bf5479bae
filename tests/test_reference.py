"""One definition of a step reference (station.logged.reference), shared by replay and compare."""

import math

import numpy as np
import pytest

from station.logged.reference import classify_reference, step_amplitude


@pytest.mark.parametrize("u, expected", [
    ([0, 0, 100, 100, 100], {"kind": "step", "amplitude": 100.0, "tick": 2}),
    ([-40, -40, -40], {"kind": "step", "amplitude": -40.0, "tick": 0}),  # --step-time 0
    ([0, 0, 0], {"kind": "zero"}),
    ([], {"kind": "zero"}),
    ([0, 100, 100, 0], {"kind": "other"}),  # a pulse: two values, not a step
    ([100, 100, 0, 0], {"kind": "other"}),  # down to zero
    ([0, 50, 100, 100], {"kind": "other"}),  # two steps
    ([0, 100, math.nan], {"kind": "missing"}),
])
def test_classify_reference(u, expected):
    assert classify_reference(u) == expected
    assert step_amplitude(u) == expected.get("amplitude")


def _write_log(path, u):
    from station.control import make_controller
    from station.plant import DiscretePlant, simulate
    from station.runlog import RunLogWriter

    ctrl = make_controller("lead", limit=200.0)
    sim = simulate(DiscretePlant(n_elements=4), ctrl, u, alignment=1)
    with RunLogWriter(path, {"controller": ctrl.spec, "dt": 0.002}) as w:
        for k in range(u.size):
            w.append((sim["t"][k], k, u[k], sim["v"][k], sim["theta"][k], sim["a"][k], sim["theta_d_hat"][k],
                      round(sim["v"][k]), 0, math.nan))


@pytest.mark.parametrize("u, step", [
    (np.full(400, 100.0), 100.0),  # a log from --step-time 0: a step in both (compare said no)
    (np.r_[np.zeros(10), np.full(390, 100.0)], 100.0),
    (np.r_[np.zeros(10), np.full(100, 100.0), np.zeros(290)], None),  # a pulse: a step in neither (compare said yes)
])
def test_replay_and_compare_agree_on_what_a_step_is(tmp_path, u, step):
    from station.compare import compare_run
    from station.plant import DiscretePlant
    from station.replay import replay

    path = tmp_path / "run.tsv"
    _write_log(path, u)
    c = compare_run(path, DiscretePlant(n_elements=4))
    r = replay(path, model=False)
    assert c.step == step
    assert (r.reference["kind"] == "step") == (step is not None)
    assert (c.rig is not None) == (step is not None)


@pytest.mark.parametrize("u, theta0, expected", [
    ([20, 20, 70, 70], 20.0, {"kind": "step", "amplitude": 70.0, "tick": 2, "from": 20.0}),  # from a held position
    ([20, 20, 70, 70], 18.0, {"kind": "step", "amplitude": 70.0, "tick": 2, "from": 20.0}),  # held short by friction
    ([100, 100, 0, 0], 100.0, {"kind": "step", "amplitude": 0.0, "tick": 2, "from": 100.0}),  # back to 0
    ([100, 100, 0, 0], 0.0, {"kind": "other"}),  # a pulse from rest
    ([100, 100, 0, 0], None, {"kind": "other"}),  # u alone cannot say which
    ([20, 20, 70, 70, 20], 20.0, {"kind": "other"}),  # three levels
    ([0, 0, 70, 70], 5.0, {"kind": "step", "amplitude": 70.0, "tick": 2}),  # from 0, whatever θ
])
def test_a_step_from_a_held_position(u, theta0, expected):
    ref = classify_reference(u, theta0)
    assert ref == expected
    if ref.is_step:
        assert ref.height == ref.amplitude - ref.initial


def test_step_metrics_of_a_step_from_a_held_position_are_the_steps():
    # the docstring's 100-count step answered by a 2 Hz ring, shifted to start at 20, and
    # mirrored (a step down from 120 to 20): the same overshoot and settling, the same figures
    from station.analysis.metrics import step_info, step_metrics

    t = np.arange(1000) * 0.002
    theta = np.round(100 * (1 - np.exp(-8 * t) * np.cos(2 * np.pi * 2 * t)))
    base, info = step_metrics(t, theta, 100), step_info(t, theta, 100, 0.0)
    assert base.overshoot_pct == 16.0
    assert step_metrics(t, theta + 20, 120, 20) == base
    assert step_metrics(t, 120 - theta, 20, 120) == base
    assert step_info(t, theta + 20, 120, 0.0, u_initial=20) == info
    assert step_info(t, 120 - theta, 20, 0.0, u_initial=120) == info
    with pytest.raises(ValueError, match="u_final - u_initial must be a non-zero step size"):
        step_metrics(t, theta, 20, 20)
