"""scripts/bench_tick.py: the recorded device replays a run byte for byte, and the benchmark
runs end to end (its numbers are the machine's; only their shape is tested)."""

import json
import runpy
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
BENCH = runpy.run_path(str(REPO / "scripts" / "bench_tick.py"), run_name="bench_tick")


@pytest.mark.parametrize("protocol", ["v1", "legacy"])
def test_a_replayed_run_is_the_recorded_run(tmp_path, protocol):
    run, port_cls = BENCH["_run"], BENCH["RecordedPort"]
    rec_report, _, rec = run(protocol, 0.5, tmp_path / "rec.tsv", lambda real, url, *a, **kw: port_cls(inner=real(url, *a, **kw)))
    report, _, port = run(protocol, 0.5, tmp_path / "replay.tsv", lambda real, url, *a, **kw: port_cls(chunks=rec.chunks))
    assert rec_report.result.ok and report.result.ok and report.result.ticks == 250
    assert port.mismatches == 0 and port.k == len(rec.chunks)  # every write the same bytes as recorded
    # the log is the recorded run's, sample for sample (the latency column aside)
    strip = lambda p: [line.rsplit("\t", 1)[0] for line in p.read_text().splitlines() if not line.startswith("#")]
    assert strip(tmp_path / "replay.tsv") == strip(tmp_path / "rec.tsv")


def test_a_replay_that_writes_other_bytes_is_counted():
    port = BENCH["RecordedPort"](chunks=[(b"abc", b"xyz")])
    port.write(b"abd")
    assert port.mismatches == 1 and port.read(10) == b"xyz" and port.in_waiting == 0


def test_bench_tick_runs_and_writes_json(tmp_path):
    out = tmp_path / "tick.json"
    proc = subprocess.run([sys.executable, str(REPO / "scripts" / "bench_tick.py"), "--seconds", "2", "--runs", "1",
                           "--json", str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert set(doc) == {"v1", "legacy"}
    for v in doc.values():
        assert v["ticks"] == 1000 and v["mismatches"] == 0 and 0 < v["p50_us"] <= v["p90_us"]
    assert "compute latency p50" in proc.stdout
