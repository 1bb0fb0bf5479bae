#!/usr/bin/env python3
"""Benchmark: the station's own work per tick, on a recorded device (no device, no pty, no clock).

``scripts/bench_loop.py`` measures the loop on a pty against the simulated device at
500 Hz; on a shared 2-core VM its run-to-run spread (p99 190–1156 µs between identical
runs) hides a 5 % change. This benchmark takes the device and the kernel out: it runs a
lead + accelerometer step on the built-in simulated rig in lockstep once, recording every
byte the device sent after each of the station's writes, then replays the run ``--runs``
times from that recording (a pyserial port object whose ``write`` releases the next
recorded chunk, checked byte for byte against what the station wrote then). What is left
per tick is the station's: read and parse a sample, look for a newer one, the compensator,
the clamp, encode and write the command, and hand the row to the log writer. Printed per
protocol: the compute latency the loop itself measures (sample received → command
written, p50 and p90 µs, the median over the runs) and the process CPU time per tick
(its writer thread included; set-up taken off by subtracting a 1 s run's CPU time).

``--against DIR`` runs the same measurement on another checkout's ``station`` package
(e.g. ``git worktree add /tmp/base <commit>``) in a subprocess, alternating with this one
for ``--rounds`` rounds, and prints the medians side by side with the ratio this / other
(issue 14: within 5 % of before), and the best round of each beside it: on this VM a
process runs the same replay at one of two speeds (p50 about 4 or about 6 µs, whichever
checkout, pinned to one core or not), so the median of a few rounds measures which speed
each side drew; the best round compares the code (the ``timeit`` convention).

Usage: ``python scripts/bench_tick.py [--seconds 10] [--runs 5] [--protocols v1 legacy]
[--against DIR [--rounds 3]] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import serial

SHORT_S = 1.0  # the short run whose CPU time (set-up, the first ticks) is taken off


class RecordedPort(serial.SerialBase):
    """A pyserial port that serves a lockstep device's bytes from a recording (or records them).

    Recording (``inner`` given): every ``write`` goes to ``inner``, and everything ``inner``
    then holds is moved into this port's buffer and kept as that write's chunk. Replaying
    (``chunks`` given): the ``k``-th ``write`` appends chunk ``k`` to the buffer, and counts
    a mismatch when the bytes written differ from the recording's (the replay is then not the
    same run). Reads never block: in lockstep nothing arrives between writes.

    Parameters
    ----------
    inner : serial.SerialBase, optional
        The lockstep device's port (recording).
    chunks : list of (bytes, bytes), optional
        ``(written, reply)`` per write (replaying).
    """

    def __init__(self, inner=None, chunks=None):
        self.inner, self.recorded = inner, chunks
        self.chunks: list[tuple[bytes, bytes]] = []
        self.buffer = bytearray()
        self.k = 0
        self.mismatches = 0
        from station.link import LinkLimits  # the sample timeout, in any checkout (station.rig is recent)

        super().__init__(None, timeout=LinkLimits.timeout)
        self.is_open = True

    def open(self):  # noqa: D102 - pyserial's interface
        self.is_open = True

    def close(self):  # noqa: D102
        self.is_open = False
        if self.inner is not None:
            self.inner.close()

    def _reconfigure_port(self):  # noqa: D102
        pass

    @property
    def in_waiting(self) -> int:  # noqa: D102
        return len(self.buffer)

    def read(self, size: int = 1) -> bytes:  # noqa: D102
        out = bytes(self.buffer[:size])
        del self.buffer[:size]
        return out

    def write(self, data) -> int:  # noqa: D102
        data = bytes(data)
        if self.inner is not None:
            self.inner.write(data)
            reply = self.inner.read(self.inner.in_waiting) if self.inner.in_waiting else b""
            self.chunks.append((data, reply))
        else:
            written, reply = self.recorded[self.k] if self.k < len(self.recorded) else (b"", b"")
            self.mismatches += written != data
        self.k += 1
        self.buffer += reply
        return len(data)

    def reset_input_buffer(self):  # noqa: D102
        self.buffer.clear()

    def reset_output_buffer(self):  # noqa: D102
        pass

    def flush(self):  # noqa: D102
        pass


def _run(protocol: str, seconds: float, out: Path, make_port) -> tuple[object, float, RecordedPort]:
    """One lead + accel step with ``serial.serial_for_url`` answering ``make_port(url, **kw)``."""
    from station.experiment import run_step

    real = serial.serial_for_url
    made: list[RecordedPort] = []

    def patched(url, *args, **kwargs):
        made.append(make_port(real, url, *args, **kwargs))
        return made[-1]

    serial.serial_for_url = patched
    try:
        cpu = time.process_time()
        report = run_step(port="sim://", protocol=protocol, controller="lead-accel", amplitude=100,
                          duration=seconds, out=out, lean=True, figure=False)
        cpu = time.process_time() - cpu
    finally:
        serial.serial_for_url = real
    return report, cpu, made[0]


def measure(protocols, seconds: float, runs: int) -> dict:
    """Record once and replay ``runs`` times per protocol (this interpreter's ``station``).

    Parameters
    ----------
    protocols : sequence of str
        "v1" and/or "legacy".
    seconds : float
        Run length, s (500 ticks a second).
    runs : int
        Replays per protocol.

    Returns
    -------
    dict
        ``{protocol: {"p50_us", "p90_us", "cpu_us_per_tick", "ticks", "mismatches"}}``
        (medians over the replays).
    """
    import numpy as np

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for protocol in protocols:
            _, _, rec = _run(protocol, seconds, Path(tmp) / f"{protocol}-rec.tsv",
                             lambda real, url, *a, **kw: RecordedPort(inner=real(url, *a, **kw)))
            _, _, short_rec = _run(protocol, SHORT_S, Path(tmp) / f"{protocol}-short-rec.tsv",
                                   lambda real, url, *a, **kw: RecordedPort(inner=real(url, *a, **kw)))
            for i in range(2):  # warm-up: whatever the first replays of a process pay once
                _run(protocol, SHORT_S, Path(tmp) / f"{protocol}-warm-{i}.tsv",
                     lambda real, url, *a, **kw: RecordedPort(chunks=short_rec.chunks))
            rows = []
            for i in range(runs):
                short, short_cpu, _ = _run(protocol, SHORT_S, Path(tmp) / f"{protocol}-short-{i}.tsv",
                                           lambda real, url, *a, **kw: RecordedPort(chunks=short_rec.chunks))
                report, cpu, port = _run(protocol, seconds, Path(tmp) / f"{protocol}-{i}.tsv",
                                         lambda real, url, *a, **kw: RecordedPort(chunks=rec.chunks))
                res = report.result
                # the loop's own CPU per tick: the long run's less the short run's (set-up cancels)
                cpu = (cpu - short_cpu) * res.ticks / max(res.ticks - short.result.ticks, 1)
                lat = np.asarray(res.latency_us, dtype=float)
                lat = lat[np.isfinite(lat)]
                rows.append({"ok": res.ok, "reason": res.reason, "ticks": res.ticks,
                             "p50_us": float(np.percentile(lat, 50)), "p90_us": float(np.percentile(lat, 90)),
                             "cpu_us_per_tick": 1e6 * cpu / max(res.ticks, 1), "mismatches": port.mismatches})
            bad = [r for r in rows if not r["ok"] or r["mismatches"]]
            if bad:
                raise SystemExit(f"bench_tick: a {protocol} replay was not the recorded run: {bad[0]}")
            out[protocol] = {key: statistics.median(r[key] for r in rows)
                             for key in ("p50_us", "p90_us", "cpu_us_per_tick")}
            out[protocol].update(ticks=rows[0]["ticks"], mismatches=0)
    return out


def compare(other: Path, argv: list[str], rounds: int) -> list[dict]:
    """This checkout's measurement against another checkout's package, alternating rounds.

    Parameters
    ----------
    other : Path
        The other checkout's root (holds ``station/``).
    argv : list of str
        Options both sides run with (without ``--against``/``--json``).
    rounds : int
        Runs of each side, alternating (this one first).

    Returns
    -------
    list of dict
        ``{"case", "this", "other", "ratio"}`` per protocol and figure (medians over rounds).
    """
    from checkout import run_on  # scripts/ is on sys.path in the parent only

    here = Path(__file__).resolve().parents[1]
    got: dict[str, list[dict]] = {"this": [], "other": []}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(rounds):
            for side, root in (("this", here), ("other", Path(other).resolve())):
                got[side].append(run_on(root, Path(__file__), argv, Path(tmp) / f"{side}{k}.json"))
                print(f"  round {k + 1}/{rounds} {side}: " + ", ".join(
                    f"{p} p50 {v['p50_us']:.1f} us" for p, v in got[side][-1].items()), flush=True)
    rows = []
    for protocol in got["this"][0]:
        for key in ("p50_us", "p90_us", "cpu_us_per_tick"):
            mine = [r[protocol][key] for r in got["this"]]
            theirs = [r[protocol][key] for r in got["other"]]
            rows.append({"case": f"{protocol} {key}", "this": statistics.median(mine),
                         "other": statistics.median(theirs),
                         "ratio": statistics.median(mine) / statistics.median(theirs),
                         "this_best": min(mine), "other_best": min(theirs), "ratio_best": min(mine) / min(theirs)})
    return rows


def _write_json(path: Path, doc: dict) -> None:
    path.write_text(json.dumps(doc, indent=1) + "\n")


def main(argv=None) -> int:
    try:
        from station.ranges import number
    except ImportError:  # the child of --against on an older checkout (no station.ranges): the parent checked
        def number(low, high, integer=False, unit=""):
            return int if integer else float
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=number(2 * SHORT_S, 3600, unit="s"), default=10.0,
                    help="run length, s (default 10; longer than the 1 s run taken off)")
    ap.add_argument("--runs", type=number(1, 100, integer=True), default=5,
                    help="replays per protocol (median; default 5)")
    ap.add_argument("--protocols", nargs="+", default=["v1", "legacy"], choices=["v1", "legacy"])
    ap.add_argument("--against", type=Path, metavar="DIR", help="another checkout to compare with")
    ap.add_argument("--rounds", type=number(1, 100, integer=True), default=3,
                    help="alternating rounds with --against (median)")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--force", action="store_true", help="replace a --json file that exists")
    args = ap.parse_args(argv)
    write = _write_json  # a child runs on a checkout that may predate station.outputs
    if __name__ != "bench_child":
        from station.outputs import check_outputs, write_json  # lazy: not in the child (above)
        check_outputs([("--json", args.json)], force=args.force, parser=ap)
        write = write_json
    same = ["--seconds", str(args.seconds), "--runs", str(args.runs), "--protocols", *args.protocols]
    load = os.getloadavg()[0]
    if args.against is not None:
        if not (args.against / "station").is_dir():
            ap.error(f"--against: {args.against} holds no station/ package")
        rows = compare(args.against, same, args.rounds)
        print(f"median of {args.rounds} alternating rounds, {args.runs} replays of {args.seconds:g} s each; "
              f"other: {args.against}")
        print(f"{'case':<24} {'this':>9} {'other':>9} {'this/other':>10}   {'best':>6} {'best':>6} {'ratio':>6}")
        for r in rows:
            print(f"{r['case']:<24} {r['this']:9.1f} {r['other']:9.1f} {r['ratio']:10.3f}   "
                  f"{r['this_best']:6.1f} {r['other_best']:6.1f} {r['ratio_best']:6.3f}")
        result = {"against": str(args.against), "rows": rows}
    else:
        result = measure(args.protocols, args.seconds, args.runs)
        if __name__ == "__main__":
            for protocol, v in result.items():
                print(f"{protocol:7} {v['ticks']} ticks: compute latency p50 {v['p50_us']:.1f} us, "
                      f"p90 {v['p90_us']:.1f} us; CPU {v['cpu_us_per_tick']:.1f} us per tick")
    print(f"load average {load:.1f} before, {os.getloadavg()[0]:.1f} after ({os.cpu_count()} CPUs)")
    if args.json:
        write(args.json, result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
