"""scripts/bench_loop.py runs end to end (shape of its output; no timing assertions)."""

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_bench_loop_runs_both_protocols_and_writes_json(tmp_path):
    out = tmp_path / "bench.json"
    proc = subprocess.run([sys.executable, str(REPO / "scripts" / "bench_loop.py"), "--seconds", "1",
                           "--no-baseline", "--max-lag", "100", "--json", str(out)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    cases = json.loads(out.read_text())["cases"]
    assert [(c["protocol"], c["loop"]) for c in cases] == [("v1", "lean"), ("legacy", "lean")]
    for c in cases:
        assert c["ok"] and c["ticks"] == 500 and c["dropped"] == 0
        assert set(c) >= {"p50_us", "p99_us", "max_us", "late", "late_per_1000", "device"}
        assert c["device"]["ticks"] >= 500  # the device's own summary was parsed
    assert "x target 200 us" in proc.stdout
