#!/usr/bin/env python3
"""Benchmark: peak memory of reading (and optionally replaying) a large run log.

Generates a station-format log of about ``--mb`` MB (default 100; a realistic mix: the
lead + accel step response of the simulated rig repeated, latency in µs, our header and
end record) unless ``--file`` is given, then reads it with ``station.runlog.read_log``
in a fresh child process and reports that process's peak resident memory (VmHWM),
its resident memory after the imports (the baseline) and the read time.

Target (issue "A day in the lab"): peak memory under 3x the file size + 150 MB.

Usage: ``python scripts/bench_read.py [--mb 100] [--file LOG] [--replay] [--keep] [--json OUT]``.
``--replay`` also measures ``station.replay.replay`` without and with the model, each in its own child.
JSON: ``{"file_mb", "rows", "read": {"peak_mb", "baseline_mb", "seconds"}, "replay": {...} | null,
"replay_model": {...} | null, "bound_mb", "ok"}`` (ok: every peak under the bound).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from station.outputs import FORCE_HELP, check_outputs, write_json

REPO = Path(__file__).resolve().parents[1]

_CHILD = r"""
import json, sys, time
sys.path.insert(0, {repo!r})

def hwm_mb():
    # VmHWM: this process's peak resident memory (a fresh mm at exec; ru_maxrss can carry the parent's)
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024

import numpy as np
from station.runlog import read_log
if {what!r} != "read":
    from station import replay as _replay
base = hwm_mb()
t0 = time.perf_counter()
if {what!r} == "read":
    log = read_log({path!r})
    rows = len(log)
else:
    rep = _replay.replay({path!r}, model={what!r} == "replay-model")
    rows = len(rep.log)
dt = time.perf_counter() - t0
peak = hwm_mb()
print(json.dumps({{"peak_mb": peak, "baseline_mb": base, "seconds": dt, "rows": rows}}))
"""


def generate(path: Path, mb: float) -> int:
    """Write a station-format log of about ``mb`` MB; returns its row count."""
    import numpy as np

    from station.experiment import run_step
    from station.rig import DT
    from station.runlog import COLUMNS, END_PREFIX, MAGIC, format_lines

    with tempfile.TemporaryDirectory() as tmp:
        base = run_step(controller="lead-accel", amplitude=200, duration=2.0, out=Path(tmp) / "b.tsv",
                        figure=False)
        lines = Path(base.log_path).read_text().split("\n")
    header = [ln for ln in lines[:3]]
    body = [ln for ln in lines[3:] if ln and not ln.startswith("#")]
    block = np.array([[float(x) for x in ln.split("\t")] for ln in body])
    target = int(mb * 1e6)
    rows = 0
    rng = np.random.default_rng(0)
    with open(path, "w") as fh:
        fh.write("\n".join(header) + "\n")
        size = fh.tell()
        k = 0
        while size < target:
            chunk = block.copy()
            chunk[:, COLUMNS.index("n")] += k * len(block)
            chunk[:, COLUMNS.index("t")] = chunk[:, COLUMNS.index("n")] * DT
            chunk[:, COLUMNS.index("latency_us")] = np.round(rng.uniform(15, 80, len(block)), 1)
            out = []
            for row in chunk:
                out.append(tuple(int(x) if i in (1, 4, 5, 7, 8) else float(x) for i, x in enumerate(row)))
            text = "\n".join(format_lines(out)) + "\n"
            fh.write(text)
            size += len(text)
            rows += len(block)
            k += 1
        fh.write(END_PREFIX + json.dumps({"reason": "completed", "message": "bench", "ticks": rows}) + "\n")
    assert MAGIC in header
    return rows


def measure(path: Path, what: str) -> dict:
    code = _CHILD.format(repo=str(REPO), path=str(path), what=what)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mb", type=float, default=100.0, help="size of the generated log, MB (default 100)")
    parser.add_argument("--file", type=Path, default=None, help="measure this log instead of generating one")
    parser.add_argument("--replay", action="store_true", help="also measure replay(model=False)")
    parser.add_argument("--keep", action="store_true", help="keep the generated log (printed)")
    parser.add_argument("--json", type=Path, default=None, help="write the results as JSON")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    args = parser.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=parser)
    tmp = None
    if args.file is None:
        tmp = tempfile.mkdtemp(prefix="bench_read-")
        path = Path(tmp) / "big.tsv"
        generate(path, args.mb)
    else:
        path = args.file
    file_mb = path.stat().st_size / 1e6
    read = measure(path, "read")
    rep = measure(path, "replay") if args.replay else None
    rep_model = measure(path, "replay-model") if args.replay else None
    bound = 3 * file_mb + 150
    worst = max(read["peak_mb"], rep["peak_mb"] if rep else 0.0, rep_model["peak_mb"] if rep_model else 0.0)
    result = {"file_mb": round(file_mb, 1), "rows": read["rows"], "read": read, "replay": rep,
              "replay_model": rep_model,
              "bound_mb": round(bound, 1), "ok": worst < bound}
    print(f"log {path} ({file_mb:.1f} MB, {read['rows']} rows)")
    print(f"read_log: peak {read['peak_mb']:.0f} MB (baseline after imports {read['baseline_mb']:.0f} MB), "
          f"{read['seconds']:.1f} s")
    if rep:
        print(f"replay (no model): peak {rep['peak_mb']:.0f} MB, {rep['seconds']:.1f} s")
        print(f"replay (tmm-fit model): peak {rep_model['peak_mb']:.0f} MB, {rep_model['seconds']:.1f} s")
    print(f"bound 3 x size + 150 MB = {bound:.0f} MB: {'met' if result['ok'] else 'NOT met'}")
    if args.json is not None:
        write_json(args.json, result)
    if tmp is not None:
        if args.keep:
            print(f"kept: {path}")
        else:
            path.unlink()
            Path(tmp).rmdir()
    return 0 if result["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
