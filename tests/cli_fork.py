"""Run the ``station`` command line in a child process, cheaply: fork the test process (the
station already imported) and call :func:`station.cli.main` there, as the console script
does (``sys.exit(main(argv))``), with the child's stdout and stderr going to files.

The child is a real process: its exit code, what it printed and any traceback an uncaught
exception prints are what a user would see, without paying the interpreter's start-up
and the imports for every case (a fuzzer runs dozens). ``run_station`` (a real
``python -m station``) is there for the cases that need a fresh interpreter.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple


class Outcome(NamedTuple):
    """What one command line did: exit code, stdout, stderr."""

    code: int
    out: str
    err: str


def run_forked(argv: list[str], cwd: str | Path | None = None, timeout: float = 120.0) -> Outcome:
    """``station ARGV`` in a forked child; killed (code -9) after ``timeout`` seconds."""
    import station.cli  # noqa: F401 (imported before the fork: the child need not)

    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        pid = os.fork()
        if pid == 0:  # the child: never returns into pytest
            code = 70
            try:
                os.dup2(out.fileno(), 1)
                os.dup2(err.fileno(), 2)
                sys.stdout = open(1, "w", closefd=False)
                sys.stderr = open(2, "w", closefd=False)
                if cwd is not None:
                    os.chdir(cwd)
                from station.cli import main

                try:
                    code = main(list(argv))
                except SystemExit as exc:
                    code = exc.code if isinstance(exc.code, int) else 1
                except BaseException:  # what the interpreter would print: a traceback, exit 1
                    import traceback

                    traceback.print_exc()
                    code = 1
            finally:
                try:
                    sys.stdout.flush()
                    sys.stderr.flush()
                finally:
                    os._exit(code if isinstance(code, int) else 1)
        code = _wait(pid, timeout)
        out.seek(0)
        err.seek(0)
        return Outcome(code, out.read().decode("utf-8", "replace"), err.read().decode("utf-8", "replace"))


def _wait(pid: int, timeout: float) -> int:
    import time

    deadline = time.monotonic() + timeout
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.waitstatus_to_exitcode(status)
        if time.monotonic() > deadline:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            return -9
        time.sleep(0.005)


def run_station(argv: list[str], cwd: str | Path | None = None, timeout: float = 300.0) -> Outcome:
    """``python -m station ARGV`` in a fresh interpreter (start-up included)."""
    proc = subprocess.run([sys.executable, "-m", "station", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)
    return Outcome(proc.returncode, proc.stdout, proc.stderr)


def one_line_refusal(result: Outcome) -> str:
    """The one error line of a refused command (asserting exit 2, one line, no traceback)."""
    lines = result.err.strip().splitlines()
    assert result.code == 2, result
    assert len(lines) == 1 and "Traceback" not in result.err, result.err
    return lines[0]
