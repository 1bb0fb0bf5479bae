"""station.analysis.memo: a result kept by its arguments' content, never a stale one."""

from __future__ import annotations

import threading

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from station.analysis.controller_id import infer_controller
from station.analysis.memo import by_content
from station.control import lead_controller
from station.control.rerun import replay_commands


def counted():
    calls = []

    @by_content(maxsize=3)
    def f(x, scale=1.0):
        calls.append(1)
        return np.asarray(x, float).sum() * scale

    return f, calls


def test_same_content_is_computed_once_and_other_content_again():
    f, calls = counted()
    x = np.arange(5.0)
    assert f(x) == 10.0 and f(x.copy()) == 10.0 and len(calls) == 1
    assert f(x, scale=2.0) == 20.0 and len(calls) == 2  # a keyword is part of the input
    assert f(list(x)) == 10.0 and len(calls) == 3  # a list is another input: computed, not guessed
    assert f.cache_info() == {"hits": 1, "misses": 3, "size": 3}


def test_an_array_changed_in_place_is_a_new_input():
    f, calls = counted()
    x = np.arange(5.0)
    assert f(x) == 10.0
    x[0] = 100.0
    assert f(x) == 110.0 and len(calls) == 2


def test_the_least_recently_used_goes_first():
    f, calls = counted()
    for k in range(4):
        f(np.full(2, float(k)))
    f(np.full(2, 3.0))
    assert len(calls) == 4  # kept
    f(np.full(2, 0.0))
    assert len(calls) == 5  # the first went when the fourth came
    f.cache_clear()
    assert f.cache_info() == {"hits": 0, "misses": 0, "size": 0}


def test_arguments_that_cannot_be_pickled_are_computed_every_time():
    f, calls = counted()
    lock = threading.Lock()

    @by_content()
    def g(x, guard):
        calls.append(1)
        return x

    assert g(1, lock) == 1 and g(1, lock) == 1 and len(calls) == 2


@settings(max_examples=60, deadline=None)
@given(hnp.arrays(np.float64, st.integers(0, 12), elements=st.floats(allow_nan=True, allow_infinity=True)),
       hnp.arrays(np.float64, st.integers(0, 12), elements=st.floats(allow_nan=True, allow_infinity=True)))
def test_a_kept_result_is_the_one_its_input_gives(x, y):
    # independent truth: the same function undecorated
    def plain(a):
        return a.size, a.tobytes()[::-1]

    kept = by_content(maxsize=2)(plain)
    for a in (x, y, x, y, y, x):
        assert kept(a) == plain(a)


def test_identification_asked_again_is_the_same_law_and_not_recomputed():
    """A lead's commands, identified twice from equal arrays: one identification, one law."""
    rng = np.random.default_rng(3)
    n = 300
    u = np.where(np.arange(n) >= 20, 100.0, 0.0)
    theta = np.round(np.cumsum(rng.normal(0.0, 2.0, n)))
    lead = lead_controller()
    v, _ = replay_commands(lead, u, theta, np.zeros(n), alignment=1)
    infer_controller.cache_clear()
    first = infer_controller(u, theta, v, None)
    again = infer_controller(u.copy(), theta.copy(), v.copy(), None)
    assert first is not None and again is first
    assert infer_controller.cache_info()["misses"] == 1
    assert np.max(np.abs(first.v_replayed - v)) <= 1e-6


def test_a_log_audited_again_is_not_identified_again(tmp_path, monkeypatch):
    """A lead + Ga step whose header's Gth is garbage, audited twice in one process (a survey,
    then a diagnosis): the accelerometer law, the costly fit, is fitted once per distinct data
    (within one audit too: a column check's rewrite of a rewrite is the log again)."""
    import hashlib
    import json

    import station.analysis.controller_id as cid
    from station.experiment import run_step
    from station.logged import LoggedRun
    from station.runlog import read_log

    out = tmp_path / "ours.tsv"
    run_step(controller="lead-accel", amplitude=100, duration=0.2, out=out, figure=False)
    lines = out.read_text().split("\n")
    meta = json.loads(lines[2][2:])
    meta["controller"].update(kind=[], gth={"num_z": [97, 97, 29], "den_z": [-59782, 202, 0.0]})
    out.write_text("\n".join([lines[0], lines[1], "# " + json.dumps(meta), *lines[3:]]))

    seen = []
    fit = cid._with_accel_feedback

    def counted(u, theta, a, v, *args):
        seen.append(hashlib.sha1(b"".join(np.asarray(x, float).tobytes() for x in (u, theta, a, v))).hexdigest())
        return fit(u, theta, a, v, *args)

    monkeypatch.setattr(cid, "_with_accel_feedback", counted)
    infer_controller.cache_clear()
    for _ in range(2):
        run = LoggedRun(read_log(out))
        assert run.identified.claim.verdict == "contradicted"
        assert "with the thesis's accelerometer feedback Ga" in run.identified.claim.data
    assert len(seen) >= 1 and len(seen) == len(set(seen)), seen
