"""The output rule on real file systems (issue 15, class 1): every command's every output
option on a full tmpfs (ENOSPC) and on a read-only one (EROFS), mounted in a user and mount
namespace of its own (``unshare -rm``: no root needed, nothing mounted outside the test).
Skipped where the machine does not allow such namespaces."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.output_cases import COMMANDS

REPO = Path(__file__).resolve().parents[1]


def _namespaces_work() -> bool:
    if shutil.which("unshare") is None or shutil.which("mount") is None:
        return False
    probe = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=4k none /tmp"],
                           capture_output=True)
    return probe.returncode == 0


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    if not _namespaces_work():
        pytest.skip("unshare -rm with a tmpfs mount is not allowed on this machine")
    root = tmp_path_factory.mktemp("os")
    full, ro = root / "full", root / "ro"
    full.mkdir()
    ro.mkdir()
    script = (f"mount -t tmpfs -o size=64k none {full} && mount -t tmpfs -o ro,size=16k none {ro} && "
              f"exec {sys.executable} -m tests.output_cases {root} {full} {ro}")
    done = subprocess.run(["unshare", "-rm", "sh", "-c", script], cwd=REPO, capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_output_option_was_tried(records):
    tried = {(r["command"], r["option"], r["where"]) for r in records}
    for name, cmd in COMMANDS.items():
        for option in list(cmd.files) + list(cmd.folders) if cmd else []:
            assert {(name, option, "full"), (name, option, "ro")} <= tried


def test_a_read_only_file_system_is_refused_before_anything_starts(records):
    for r in records:
        if r["where"] == "ro":
            lines = r["stderr"].strip().splitlines()
            assert r["code"] == 2 and len(lines) == 1 and "is not writable" in lines[0], r


def test_a_full_file_system_is_one_line_and_leaves_no_file(records):
    for r in records:
        if r["where"] != "full":
            continue
        errors = [line for line in r["stderr"].strip().splitlines() if line.startswith("station:")]
        said = "No space left on device" in errors[0] or "GB free" in errors[0]  # step: before the run
        assert r["code"] == 2 and len(errors) == 1 and said, r
        assert "Traceback" not in r["stderr"]
        assert r["left"] == [], r  # no part of a file, no temporary file, not even an empty log
