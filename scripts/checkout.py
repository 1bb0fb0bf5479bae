"""Run a benchmark script on another checkout's ``station`` package (``--against DIR``).

The benchmarks compare this checkout with another (e.g. the commit before a change, made
with ``git worktree add``) side by side: each side runs in its own interpreter with that
checkout's ``station`` first on ``sys.path`` (an editable install of this one is set aside),
and writes its numbers as JSON.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

_CHILD = """import runpy, sys
root, script = sys.argv[1], sys.argv[2]
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f)]
sys.path.insert(0, root)
import station
assert station.__file__.startswith(root), station.__file__
runpy.run_path(script, run_name="bench_child")["main"](sys.argv[3:])
"""


def run_on(root: Path, script: Path, argv: list[str], json_path: Path) -> dict:
    """Run ``script``'s ``main(argv + ["--json", json_path])`` on ``root``'s ``station``; its JSON.

    Parameters
    ----------
    root : Path
        The checkout whose ``station/`` package is imported.
    script : Path
        The benchmark script (this checkout's or the other's own).
    argv : list of str
        The script's options (without ``--json``).
    json_path : Path
        Where the script writes its JSON.
    """
    subprocess.run([sys.executable, "-c", _CHILD, str(root), str(script), *argv, "--json", str(json_path)],
                   check=True, stdout=subprocess.DEVNULL)
    return json.loads(Path(json_path).read_text())
