"""scripts/bench_sim.py: JSON shape, stability flags and the baseline's agreement (no
timing assertions)."""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "bench_sim.py"


@pytest.fixture(scope="module")
def bench_sim():
    spec = importlib.util.spec_from_file_location("bench_sim", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_json_shape_and_stability(bench_sim, tmp_path):
    out = tmp_path / "bench.json"
    assert bench_sim.main(["--elements", "4", "--baseline-max", "4", "--repeats", "1", "--json", str(out)]) == 0
    cases = json.loads(out.read_text())["cases"]
    assert {c["controller"] for c in cases} == {"lead-accel", "p", "open-loop"}
    keys = {"n_elements", "controller", "seconds", "baseline_seconds", "realtime_factor", "baseline_ratio", "stable"}
    for c in cases:
        assert set(c) == keys and c["n_elements"] == 4 and c["stable"] is True
        assert c["seconds"] > 0 and c["baseline_seconds"] > 0


def test_rates_come_from_the_best_measured_time(bench_sim, monkeypatch):
    """On a scripted clock the times are known: best of the repeats, 2 s of simulated time
    (module docstring) over it, baseline over it."""
    import types

    # per case: two timed runs of simulate (6 ms, then 4 ms), then the baseline (0.4 s)
    clock = iter([0.0, 0.006, 1.0, 1.004, 2.0, 2.4] * 2)
    monkeypatch.setattr(bench_sim, "time", types.SimpleNamespace(perf_counter=lambda: next(clock)))
    cases = bench_sim.bench(elements=(2,), controllers=("p", "open-loop"), baseline_max=2, repeats=2,
                            out=None)["cases"]
    for c in cases:
        assert c["seconds"] == pytest.approx(0.004)
        assert c["realtime_factor"] == pytest.approx(500.0)  # 2 s simulated in 4 ms
        assert c["baseline_seconds"] == pytest.approx(0.4)
        assert c["baseline_ratio"] == pytest.approx(100.0)  # the baseline is 100x slower


def test_baseline_fields_null_when_not_run(bench_sim):
    cases = bench_sim.bench(elements=(2,), controllers=("p",), baseline_max=0, repeats=1, out=None)["cases"]
    assert cases[0]["baseline_seconds"] is None and cases[0]["baseline_ratio"] is None


def test_baseline_simulates_the_same_plant(bench_sim):
    # the odeint-per-sample baseline and the ZOH kernel are the same model: same hub angle
    from station.control import make_controller
    from station.plant import DiscretePlant, simulate

    plant = DiscretePlant(n_elements=2)
    u = bench_sim.CASES["p"](300)
    fast = simulate(plant, make_controller("p"), u)["theta"]
    slow = bench_sim.baseline_run(plant, make_controller("p"), u)
    assert np.abs(fast - slow).max() <= 1.0  # rounding flips at most (odeint tolerance)
    assert fast.max() > 50
