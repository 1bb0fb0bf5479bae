"""station.viz: a RerunSink fed by the run-log writer produces an .rrd that reads back."""

import numpy as np
import pytest

from station.errors import StationError
from station.runlog import RunLogWriter

rerun_chunk = pytest.importorskip("rerun.chunk")


def _series(rrd, entity):
    """(sample, value) arrays of one scalar entity read back from an .rrd file."""
    samples, values = [], []
    for chunk in rerun_chunk.RrdReader(rrd).stream().collect().stream():
        if chunk.entity_path != entity:
            continue
        rb = chunk.to_record_batch()
        samples += rb.column("sample").to_pylist()
        values += [v[0] for v in rb.column("Scalars:scalars").to_pylist()]
    order = np.argsort(samples)
    return np.asarray(samples)[order], np.asarray(values, dtype=float)[order]


def test_rrd_from_run_log_rows_reads_back(tmp_path):
    from station.viz import RerunSink

    rrd = tmp_path / "run.rrd"
    sink = RerunSink(rrd_path=rrd, name="test")
    n = np.arange(300)
    theta = np.round(50 * (1 - np.cos(n / 30)))
    with RunLogWriter(tmp_path / "run.tsv", {"test": True}, sinks=[sink]) as w:
        for k in n:
            w.append((k * 0.002, int(k), 50.0, 2.0 * (50 - theta[k]), int(theta[k]), int(k % 5) - 2,
                      float("nan"), 0, 0, 40.0))
    sink.log_prediction({"t": n * 0.002, "theta": theta + 0.5, "a": np.zeros(n.size), "v": np.ones(n.size)})
    sink.close()
    assert not w.sink_errors
    assert rrd.stat().st_size > 0
    s, v = _series(rrd, "/theta/measured")
    np.testing.assert_array_equal(s, n)
    np.testing.assert_array_equal(v, theta)
    s, v = _series(rrd, "/theta/model")
    np.testing.assert_array_equal(v, theta + 0.5)
    _, v = _series(rrd, "/a/measured")
    np.testing.assert_array_equal(v, n % 5 - 2)
    # theta_d_hat was all NaN: nothing recorded for it
    assert _series(rrd, "/theta/theta_d_hat")[0].size == 0


def test_rrd_and_spawn_are_exclusive(tmp_path):
    from station.viz import RerunSink

    with pytest.raises(StationError, match="not both"):
        RerunSink(rrd_path=tmp_path / "x.rrd", spawn=True)
