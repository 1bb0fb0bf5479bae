"""accel_law's searches given up when nowhere near v: the time changes, never the answer."""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

import station.analysis.accel_law as accel_law
from station.analysis.controller_id import infer_controller
from station.experiment import run_step
from station.logged import LoggedRun
from station.runlog import read_log

RIG = Path(os.environ.get("STATION_RIG_DATA", Path(__file__).resolve().parents[2] / "shared" / "data" / "rig"))
LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"


@pytest.fixture(scope="module")
def no_ga(tmp_path_factory) -> Path:
    """The simulated rig's lead + Ga step whose header names the lead but not its Ga."""
    out = tmp_path_factory.mktemp("budget") / "lead_accel.tsv"
    run_step(controller="lead-accel", amplitude=100, duration=0.4, out=out, figure=False)
    lines = out.read_text().split("\n")
    meta = json.loads(lines[2][2:])
    meta["controller"]["ga"] = None
    path = out.with_name("no_ga.tsv")
    path.write_text("\n".join([lines[0], lines[1], "# " + json.dumps(meta), *lines[3:]]))
    return path


@pytest.fixture(scope="module")
def rig_open_loop(tmp_path_factory) -> Path:
    """The rig's lead + accelerometer step under an open-loop header (the law found in the data)."""
    src = RIG / LEAD_ACCEL
    if not src.is_file():
        pytest.skip(f"the rig's logs are not here ({src}): set STATION_RIG_DATA or put ../shared beside the repo")
    lines = src.read_text().split("\n")
    path = tmp_path_factory.mktemp("budget") / "ol.txt"
    path.write_text("\n".join(["#SLFR RTP OL_Test"] + [x for x in lines[1:] if not x.startswith(("#Gth", "#Ga"))]))
    return path


def identified(path: Path):
    infer_controller.cache_clear()  # (the memo would answer the second run from the first)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return LoggedRun(read_log(path)).identified


def searches(monkeypatch) -> list:
    """Each accel_law search's (parameters, evaluations, largest miss of v at its end, status)."""
    seen = []
    search = scipy.optimize.least_squares

    def recorded(fun, x0, *args, **kwargs):
        fit = search(fun, x0, *args, **kwargs)
        seen.append((np.size(x0), fit.nfev, float(np.max(np.abs(fit.fun))), fit.status))
        return fit

    monkeypatch.setattr(scipy.optimize, "least_squares", recorded)
    return seen


@pytest.mark.parametrize("log", ["no_ga", "rig_open_loop"])
def test_giving_up_changes_the_time_not_the_law(log, request, monkeypatch):
    path = request.getfixturevalue(log)
    found = identified(path)
    with monkeypatch.context() as m:
        m.setattr(accel_law, "GIVE_UP_EVALUATIONS", 10 ** 6)  # scipy's own budget: the searches as before
        before = identified(path)
    assert found.claim.verdict == before.claim.verdict
    assert "with the thesis's accelerometer feedback Ga" in found.claim.data
    assert found.claim.data == before.claim.data and found.fit.alignment == before.fit.alignment
    for tf in ("gth", "ga"):
        a, b = getattr(found.controller, tf), getattr(before.controller, tf)
        assert np.array_equal(a.num, b.num) and np.array_equal(a.den, b.den), tf
    assert np.array_equal(found.fit.v_replayed, before.fit.v_replayed)


def test_a_search_nowhere_near_v_stops_at_its_budget(no_ga, monkeypatch):
    seen = searches(monkeypatch)
    identified(no_ga)
    stopped = [s for s in seen if s[3] == -2]
    assert stopped, seen  # the wrong orders and alignments: given up
    for n, nfev, miss, _ in stopped:
        assert miss > accel_law.GIVE_UP_COUNTS and accel_law.GIVE_UP_EVALUATIONS * n <= nfev
        assert nfev < 2 * accel_law.GIVE_UP_EVALUATIONS * n  # the iteration that crossed it, and no more
    assert any(miss <= 1e-6 for _, _, miss, _ in seen)  # the law's own search ran on to v
