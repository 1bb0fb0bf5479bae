"""The diagnosis's fits on worker processes (station/diagnosis/search/farm.py): each task's
result in the items' order, the workers' simulations joining the main process's cache and
count, and a whole diagnosis on two workers giving the answer it gives on one."""

import math

import numpy as np
import pytest

from station.diagnosis import diagnose
from station.diagnosis.runs.cases import RunCase
from station.diagnosis.runs.cost import Evaluator
from station.diagnosis.search.farm import can_fork, farm

pytestmark = pytest.mark.skipif(not can_fork(), reason="worker processes inherit the search by fork (Linux)")

N = 200


class _Line:
    """A stand-in model: one effect "x"."""

    def __init__(self, x=0.0):
        self.x = x

    def with_effects(self, effects):
        return _Line(effects.get("x", self.x))


def _evaluator():
    case = RunCase("a", None, None, None, True, np.zeros(N), np.zeros(N), 1.0, math.inf)
    return Evaluator([case], _Line(), simulate=lambda c, m: (np.full(N, m.x), np.zeros(N)))


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_each_items_result_comes_in_order_and_the_workers_errors_join_the_cache(workers):
    ev = _evaluator()
    xs = [3.0, 1.0, 2.0, 5.0, 4.0]
    got = list(farm(lambda x: ev.sse({"x": x}, 0)[0], xs, ev, workers))
    assert got == [(i, N * x ** 2) for i, x in enumerate(xs)]  # Σ (0 − x)² over N samples
    assert ev.simulations == len(xs)
    before = ev.simulations
    assert [ev.sse({"x": x}, 0)[0] for x in xs] == [N * x ** 2 for x in xs]
    assert ev.simulations == before, "the workers' simulations were not in the main process's cache"


def test_the_work_since_a_mark_is_what_was_computed_after_it_and_another_evaluator_takes_it_in():
    ev = _evaluator()
    ev.sse({"x": 1.0}, 0)
    mark = ev.mark()
    for x in (2.0, 1.0, 3.0):  # 1.0 is cached before the mark: not new work
        ev.sse({"x": x}, 0)
    work = ev.work_since(mark)
    assert work.simulations == 2 and sorted(v[0] for v in work.errors.values()) == [N * 4.0, N * 9.0]
    other = _evaluator()
    other.take_in(work)
    assert other.simulations == 2
    assert other.sse({"x": 3.0}, 0)[0] == N * 9.0 and other.simulations == 2  # from the taken-in cache


def test_a_task_that_fails_in_a_worker_raises_its_error_here():
    ev = _evaluator()

    def task(x):
        if x == 2:
            raise ValueError("bad item 2")
        return x

    with pytest.raises(ValueError, match="bad item 2"):
        list(farm(task, [1, 2, 3], ev, 2))


@pytest.fixture(scope="module")
def breakaway_logs(tmp_path_factory):
    """Four logs of a breakaway over a sliding level from the independent generator (tests/blind)."""
    from tests.blind.generator import write_case

    return [str(p) for p in write_case(tmp_path_factory.mktemp("logs"), {"static_friction": 15.0,
                                                                          "coulomb_friction": 5.0}, 3)]


def test_two_workers_give_the_answer_one_gives(breakaway_logs):
    candidates = ["coulomb_friction", "static_friction", "viscous_friction", "param:drive_c"]
    answers = []
    for workers in (1, 2):
        doc = diagnose(breakaway_logs, candidates=candidates, workers=workers).to_json()
        for key in ("simulations", "elapsed_s"):
            doc.pop(key)
        answers.append(doc)
    assert answers[0]["causes"] == ["static_friction"]
    assert answers[1] == answers[0]
