"""The step figures beside the thesis's (python-control step_info) against a response whose
figures are known by hand, and the progress sink's counters against the rows it was fed."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

from station.analysis.metrics import NOT_SETTLED, step_info
from station.progress import ProgressSink
from station.protocol import v1

TAU = 0.1


def _first_order(step_time=0.02, duration=2.0, height=100.0):
    t = np.arange(0, duration, 0.002)
    y = np.where(t >= step_time, height * (1 - np.exp(-(t - step_time) / TAU)), 0.0)
    return t, y


def test_first_order_response_figures_by_hand():
    t, y = _first_order()
    v = np.where(t < 0.1, 200.0, 20.0)
    info = step_info(t, y, 100.0, step_time=0.02, v=v, limit=200.0)
    # 10 %..90 %: tau ln 9; 2 %: tau ln 50 (to the sample grid, 2 ms)
    assert info.rise_time_s == pytest.approx(TAU * math.log(9), abs=0.002)
    assert info.settling_time_2pct_s == pytest.approx(TAU * math.log(50), abs=0.002)
    assert info.steady_state_error == pytest.approx(0.0, abs=1e-4)
    assert info.saturation_time_s == pytest.approx(0.1, abs=1e-9)  # 50 samples at the clamp
    assert info.peak_time_s == pytest.approx(t[-1] - 0.02)  # a first order peaks at the end


def test_a_response_that_never_settles_says_so():
    t = np.arange(0, 2, 0.002)
    y = np.where(t >= 0.02, 100 + 30 * np.cos(2 * np.pi * 2.3 * t), 0.0)  # still 25 counts off at the end
    assert abs(y[-1] - 100) > 20
    info = step_info(t, y, 100.0, step_time=0.02)
    assert info.settling_time_2pct_s is None and NOT_SETTLED in info.summary()


def test_a_response_that_never_reaches_90_percent_has_no_rise_time():
    t, y = _first_order(height=50.0)
    info = step_info(t, y, 100.0, step_time=0.02)
    assert info.rise_time_s is None and info.steady_state_error == pytest.approx(50.0, abs=1e-3)


def test_progress_sink_counts_late_and_dropped_and_draws_one_line():
    out = io.StringIO()
    sink = ProgressSink(2.0, stream=out)
    n = np.array([0, 1, 2, 5, 6], dtype=float)  # 3 and 4 missing
    status = np.array([0, v1.LATE, 0, v1.LATE | v1.SATURATED, 0], dtype=float)
    sink.write_rows({"n": n, "t": n * 0.002, "theta": n * 2, "v": n * 3, "status": status})
    sink.write_rows({"n": np.array([9.0]), "t": np.array([0.018]), "theta": np.array([1.0]),
                     "v": np.array([0.0]), "status": np.array([0.0])})  # 7 and 8 missing across batches
    assert (sink.late, sink.dropped) == (2, 4)
    text = out.getvalue()
    assert text.startswith("\rstep: 0.01 / 2.00 s") and "late 2" in text and "\n" not in text
    sink.close()
    assert out.getvalue().endswith("\r")
