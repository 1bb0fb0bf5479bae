"""Start-up stays light: building the CLI (every command's parser, as each run does before
its first tick) and loading the default model import none of the heavy libraries.

docs/benchmarks.md "Start-up" (bench_startup.py) promises a warm ``station step`` that imports neither
scipy, python-control, matplotlib nor numba before the first tick; a command whose parser
pulled in its own package's heavy modules once cost every command 1 s of CPU. Checked in
a fresh interpreter (this test process has imported everything already).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

HEAVY = ("scipy", "control", "matplotlib", "numba")

PROBE = """
import json, sys
from station.cli import build_parser
build_parser().parse_args(["step", "--duration", "0.1"])
from station.plant.model import load_model
load_model("tmm-fit")
print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in %r)))
""" % (HEAVY,)


def test_the_parser_and_the_default_model_import_nothing_heavy(tmp_path):
    # a warm modal-form cache: the first run stores the default model's form
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    env.pop("STATION_NO_CACHE", None)
    subprocess.run([sys.executable, "-c", PROBE], env=env, check=True, capture_output=True, text=True)
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, check=True, capture_output=True, text=True)
    heavy = json.loads(out.stdout.strip().splitlines()[-1])
    assert heavy == [], f"imported before the first tick: {', '.join(heavy[:10])}"
