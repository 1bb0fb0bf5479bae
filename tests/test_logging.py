"""`station -v` / `-vv`: the link's, loop's and simulated device's loggers on stderr."""

import subprocess
import sys


def _step(tmp_path, *flags):
    return subprocess.run([sys.executable, "-m", "station", *flags, "step", "--duration", "0.04",
                           "--out", str(tmp_path / f"r{''.join(flags)}.tsv")], capture_output=True, text=True, timeout=120)


def test_verbose_levels(tmp_path):
    quiet, info, debug = _step(tmp_path), _step(tmp_path, "-v"), _step(tmp_path, "-vv")
    assert quiet.returncode == info.returncode == debug.returncode == 0
    assert "station.link" not in quiet.stderr
    assert "station.link: opened sim://" in info.stderr and "station.loop: run ended" in info.stderr
    assert " rx " not in info.stderr
    assert "station.link: sim://?protocol=v1 rx 02 01" in debug.stderr  # the first SAMPLE's bytes
    assert "tx COMMAND seq 0" in debug.stderr
