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
