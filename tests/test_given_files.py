"""What the station is given, by class (issue 24's hostile round): every file a command reads
is opened one way (``station.inputs.open_regular``), so nothing that is not a regular file
is read (a FIFO blocked ``diagnose`` and ``survey``, ``/dev/zero`` spun ``diagnose``); every
JSON it reads is bounded in depth; every number of a log is finite and within a counter's
range before any arithmetic; a log with no rows is nothing to work on; a settings file that
is a broken link is refused, not skipped; a compensator's shaper lies inside the run.

Each class is a table that reaches its members: every command and option that reads a file
against every kind of non-regular file, every JSON reader against deep documents, every
column of a log against numbers past the bound. Commands run in forked children
(tests/cli_fork.py): a hang is a kill after ``HANG_S``, not a slow test.
"""

from __future__ import annotations

import ast
import json
import os
import socket
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cli_fork import run_forked  # noqa: E402

from station.errors import StationError  # noqa: E402
from station.inputs import MAX_JSON_DEPTH, load_json, open_regular, parse_json  # noqa: E402
from station.runlog import RunLogError, read_log  # noqa: E402
from station.runlog.schema import COLUMNS, MAX_ABS_VALUE  # noqa: E402
from tests.output_cases import make_inputs, write_p_log  # noqa: E402

HANG_S = 60
"""A command still running after this long has hung (every refusal here takes well under a second)."""

STATION = Path(__file__).resolve().parents[1] / "station"


@pytest.fixture(scope="module", autouse=True)
def _imported():
    """What the commands import lazily, imported before the children fork (each child is quick)."""
    import station.commands.step  # noqa: F401
    import station.compare  # noqa: F401
    import station.design.tuning  # noqa: F401
    import station.diagnosis  # noqa: F401
    import station.experiment  # noqa: F401
    import station.replay  # noqa: F401
    import station.sim.protocol_sim  # noqa: F401


# --- the kinds of file that are no file ---------------------------------------------------------

def make_kind(folder: Path, kind: str, name: str) -> Path:
    """``folder/name`` as a thing of ``kind`` that the station must refuse to read."""
    path = folder / name
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":
        path.symlink_to("/dev/zero")  # a link to a device: followed, then refused
    elif kind == "folder":
        path.mkdir()
    elif kind == "socket":
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(path))
        sock.close()
    elif kind == "dangling link":
        path.symlink_to(folder / "nowhere")
    elif kind == "looping link":
        path.symlink_to(path)
    return path


KINDS = ("fifo", "device", "folder", "socket", "dangling link", "looping link")
WORDS = {"fifo": "FIFO", "device": "character device", "folder": "folder", "socket": "socket",
         "dangling link": "does not exist", "looping link": "loops"}
"""What the one line says of each kind."""


@pytest.mark.parametrize("kind", KINDS)
def test_the_one_opener_refuses_each_kind_naming_the_file(tmp_path, kind):
    path = make_kind(tmp_path, kind, "x.toml")
    with pytest.raises(StationError) as err:
        open_regular(path, "model file")
    msg = str(err.value)
    assert str(path) in msg and WORDS[kind] in msg and len(msg.splitlines()) == 1, msg
    regular = tmp_path / "ok.txt"
    regular.write_text("fine\n")
    with open_regular(regular, "run log", text=True) as fh:  # a regular file reads as usual, blocking
        assert fh.read() == "fine\n" and os.get_blocking(fh.fileno())


FILE_ARGS = {
    "replay": ["replay", "{f}"],
    "compare": ["compare", "{f}"],
    "plot": ["plot", "{f}"],
    "bode": ["bode", "{f}"],
    "diagnose RUN": ["diagnose", "{f}", "{step}", "--quiet"],
    "diagnose --validate": ["diagnose", "{step}", "{step2}", "--validate", "{f}", "--quiet"],
    "diagnose --model": ["diagnose", "{step}", "{step2}", "--model", "{f}.toml", "--quiet"],
    "survey": ["survey", "{f}", "--no-model"],
    "survey --diagnose": ["survey", "--diagnose", "{f}"],
    "step --controller": ["step", "--duration", "0.1", "--controller", "{f}.toml"],
    "step --reference": ["step", "--reference", "{f}"],
    "step --model": ["step", "--duration", "0.1", "--model", "{f}.toml"],
    "step sim://?model=": ["step", "--duration", "0.1", "--port", "sim://?model={f}.toml"],
    "modes --model": ["modes", "--model", "{f}.toml"],
    "modes --params": ["modes", "--params", "{f}.toml"],
    "identify --model": ["identify", "--model", "{f}.toml", "--quiet"],
    "tune --model": ["tune", "--model", "{f}.toml", "--quiet"],
    "tune --model JSON": ["tune", "--model", "{f}.json", "--quiet"],
    "tune --robust": ["tune", "--robust", "{f}.json", "--samples", "0", "--quiet"],
}
"""Every command and option that reads a file the user names; ``{f}`` the file (with the
suffix that makes it a path rather than a built-in name)."""

SURVEY_LIST = ("survey",)
"""Commands that list a file they cannot use as a row (exit 0) instead of refusing."""


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    return make_inputs(tmp_path_factory.mktemp("given"))


def _one_line(result, *names):
    assert result.code != -9, "hung"
    assert "Traceback" not in result.err, result.err
    lines = [ln for ln in result.err.strip().splitlines() if ln.startswith("station")]
    assert result.code == 2 and len(lines) == 1, result
    for name in names:
        assert name in lines[0], (name, lines[0])
    return lines[0]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("case", FILE_ARGS)
def test_every_command_refuses_what_is_not_a_regular_file_in_one_line(tmp_path, logs, case, kind):
    argv = FILE_ARGS[case]
    suffix = ".toml" if "{f}.toml" in " ".join(argv) else ".json" if "{f}.json" in " ".join(argv) else ""
    bad = make_kind(tmp_path, kind, "bad" + suffix)
    fill = {"f": str(bad.with_suffix("")), "step": logs["step"], "step2": logs["step2"]}
    argv = [a.format(**fill) for a in argv]
    result = run_forked(argv, cwd=tmp_path, timeout=HANG_S)
    if case.startswith("survey") and kind == "folder":  # a folder is what a survey takes: this one is empty
        _one_line(result, "bad: no ")  # (no files to survey, no logs to diagnose)
        return
    if case in SURVEY_LIST:  # a row of its own, the survey goes on
        assert result.code == 0 and "Traceback" not in result.err, result
        assert "UNUSABLE" in result.out and WORDS[kind] in result.out, result.out
        return
    _one_line(result, WORDS[kind])


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("command", [["step", "--duration", "0.1"], ["compare", "{step}"], ["identify", "--quiet"]])
def test_a_settings_file_that_is_no_file_is_refused_not_skipped(tmp_path, logs, command, kind):
    make_kind(tmp_path, kind, "station.toml")
    argv = [a.format(step=logs["step"]) for a in command]
    line = _one_line(run_forked(argv, cwd=tmp_path, timeout=HANG_S), "station.toml", WORDS[kind])
    assert "config file" in line
    assert not (tmp_path / "runs").exists()


# --- no other way in: every open() in the package is the opener's or on the station's own files --

OWN_FILES = {
    ("cli.py", "_silence_stdout"): "/dev/null for a closed stdout",
    ("commands/tune.py", "run"): "its verification log, in its own temporary folder",
    ("inputs.py", "open_regular"): "the opener",
    ("link/port.py", "latency_timer"): "the USB adapter's sysfs file",
    ("outputs.py", "open"): "writing outputs",
    ("plan.py", "_available_memory"): "/proc/meminfo",
    ("plant/diskcache.py", "_code_digest"): "the package's own sources",
    ("plant/diskcache.py", "cached_arrays"): "its own cache files",
    ("plant/diskcache.py", "_store"): "its own cache files",
    ("realtime.py", "process_age"): "/proc/self/stat",
    ("runlog/rows.py", "load_rows"): "numpy parsing lines of a file opened by the opener",
    ("runlog/writer.py", "__init__"): "writing the run log",
    ("runlog/writer.py", "_rescue"): "writing the rescue file",
}
"""(module, function) -> why it may open a file without :func:`station.inputs.open_regular`."""

READERS = {"open", "read_text", "read_bytes", "loadtxt", "genfromtxt", "load", "fdopen", "read_csv"}


def _file_calls():
    for path in sorted(STATION.rglob("*.py")):
        tree = ast.parse(path.read_text())
        owner = {}
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for sub in ast.walk(node):
                    owner.setdefault(id(sub), node.name)
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call):
                continue
            f = node.func
            if isinstance(f, ast.Name):  # the builtin open(); a bare read_text() is the station's own
                hit = f.id == "open"
            elif isinstance(f, ast.Attribute):  # Path.read_text(), np.loadtxt(), os.open() ... (not tx.open())
                hit = f.attr in READERS and (f.attr != "open" or isinstance(f.value, ast.Name)
                                             and f.value.id in ("os", "io"))
            else:
                hit = False
            if hit:
                yield str(path.relative_to(STATION)), owner.get(id(node), "<module>"), node.lineno


def test_no_file_is_opened_but_through_the_opener_or_the_stations_own():
    found = list(_file_calls())
    assert found, "the scan finds the opener itself"
    stray = [f"station/{m}:{line} in {fn}()" for m, fn, line in found if (m, fn) not in OWN_FILES]
    assert not stray, ("read a given file with station.inputs.open_regular (or list the station's own file "
                       f"in OWN_FILES): {stray}")
    gone = set(OWN_FILES) - {(m, fn) for m, fn, _ in found}
    assert not gone, f"OWN_FILES lists what no longer opens a file: {gone}"


# --- JSON, bounded ----------------------------------------------------------------------------

@pytest.mark.parametrize("depth", [MAX_JSON_DEPTH + 1, 1000, 5000, 100_000])
@pytest.mark.parametrize("shape", ["array", "object"])
def test_json_past_the_depth_is_one_line_whatever_the_depth(tmp_path, depth, shape):
    text = "[" * depth + "]" * depth if shape == "array" else '{"a":' * depth + "1" + "}" * depth
    path = tmp_path / "deep.json"
    path.write_text(text)
    with pytest.raises(StationError, match=r"deep.json: JSON nested .*(too deeply|levels deep)"):
        load_json(path, "diagnosis JSON")
    ok = "[" * MAX_JSON_DEPTH + "]" * MAX_JSON_DEPTH
    assert parse_json(ok, "x") is not None


@pytest.mark.parametrize("depth", [100, 5000])
@pytest.mark.parametrize("case", ["tune --robust", "tune --model JSON"])
def test_tune_refuses_a_deep_json_in_one_line(tmp_path, case, depth):
    bad = tmp_path / "bad.json"
    bad.write_text('{"extended_model": ' + "[" * depth + "]" * depth + "}")
    argv = [a.format(f=tmp_path / "bad") for a in FILE_ARGS[case]]
    _one_line(run_forked(argv, cwd=tmp_path, timeout=HANG_S), "bad.json", "nested")


@pytest.mark.parametrize("where", ["header", "end record"])
def test_a_log_whose_json_is_nested_deep_is_refused_naming_the_line(tmp_path, where):
    deep = "[" * 500 + "]" * 500
    lines = ["\t".join(COLUMNS), "# station-runlog 1", '# {"dt": 0.002, "x": ' + deep + "}" if where == "header"
             else '# {"dt": 0.002}', "0.0\t0\t0\t0\t0\t0\t0\t0\t0\tnan", "0.002\t1\t0\t0\t0\t0\t0\t0\t0\tnan"]
    if where == "end record":
        lines.append('# end {"reason": ' + deep + "}")
    path = tmp_path / "deep.tsv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunLogError, match=r"deep.tsv: line \d+: .*nested too deeply"):
        read_log(path)


# --- a log's numbers: finite and within a counter's range, refused at reading ---------------------

def _rig_log(path: Path, column: int, row: int, value: str) -> Path:
    u = np.where(np.arange(120) >= 10, 50.0, 0.0)
    write_p_log(path, u)
    lines = path.read_text().splitlines()
    first = 3  # the rig's header: title, kp, column names
    cells = lines[first + row].split("\t")
    cells[column] = value
    lines[first + row] = "\t".join(cells)
    path.write_text("\n".join(lines) + "\n")
    return path


RIG_COLUMNS = ("t", "n", "u", "v", "theta", "a")


@settings(max_examples=60, deadline=None, database=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(column=st.integers(0, 5), row=st.integers(0, 119), exponent=st.floats(9.5, 308.2),
       sign=st.sampled_from(["", "-"]))
def test_a_number_past_the_bound_anywhere_in_a_log_is_refused_naming_line_and_field(tmp_path, column, row, exponent,
                                                                                     sign):
    value = f"{sign}{10 ** min(exponent, 308.25):.6g}" if exponent < 308.25 else f"{sign}1e308"
    path = _rig_log(tmp_path / "big.txt", column, row, value)
    with pytest.raises(RunLogError) as err:
        read_log(path)
    msg = str(err.value)
    assert f"line {4 + row}:" in msg and msg.split(": ")[2].startswith(RIG_COLUMNS[column]), msg
    assert len(msg.splitlines()) == 1


def test_a_number_at_the_bound_is_read_as_written(tmp_path):
    at = MAX_ABS_VALUE - 1
    log = read_log(_rig_log(tmp_path / "at.txt", 4, 60, f"{at:.0f}"))
    assert log.data["theta"][60] == at


@pytest.mark.parametrize("value", ["1e308", "1e200", "1e160", "-1e308", "inf", "nan"])
@pytest.mark.parametrize("command", [["diagnose", "{bad}", "{step}", "--quiet"], ["survey", "--diagnose", "{dir}"],
                                     ["replay", "{bad}"], ["compare", "{bad}"], ["plot", "{bad}"]])
def test_every_command_refuses_a_log_value_past_the_bound_in_one_line(tmp_path, logs, command, value):
    (tmp_path / "runs").mkdir()
    bad = _rig_log(tmp_path / "runs" / "bad.txt", 4, 60, value)
    write_p_log(tmp_path / "runs" / "other.txt", np.where(np.arange(120) >= 10, 50.0, 0.0), seed=3)
    argv = [a.format(bad=bad, step=logs["step"], dir=tmp_path / "runs") for a in command]
    result = run_forked(argv, cwd=tmp_path, timeout=HANG_S)
    # survey sets the file aside; one usable run left is the refusal, which says why the other was set aside
    _one_line(result, "bad.txt", "line 64", "theta")


def test_the_lab_truncated_command_keeps_infinities_and_nan():
    from station.rounding import half_away, toward_zero

    for x in (np.inf, -np.inf, 1e308, -2.0 ** 60):
        assert toward_zero(x) == x and half_away(x) == x
    assert np.isnan(toward_zero(np.nan))
    rng = np.random.default_rng(7)
    for x in rng.normal(0, 1e6, 200):
        assert toward_zero(x) == float(np.trunc(x))


def test_a_header_gain_of_1e308_is_replayed_not_a_traceback(tmp_path):
    path = tmp_path / "kp.txt"
    write_p_log(path, np.where(np.arange(300) >= 10, 50.0, 0.0))
    path.write_text(path.read_text().replace("#kp=2.0", "#kp=1e308"))
    result = run_forked(["replay", str(path)], cwd=tmp_path, timeout=HANG_S)
    assert result.code in (0, 1) and "Traceback" not in result.err, result
    assert "does not reproduce" in result.out or "contradict" in result.out


# --- a log with no rows is nothing to work on -----------------------------------------------------

@pytest.mark.parametrize("command", [["replay", "{f}"], ["compare", "{f}"], ["plot", "{f}"], ["bode", "{f}"],
                                     ["diagnose", "{f}", "{f2}"]])
def test_a_log_with_a_header_and_no_rows_is_refused_exit_2(tmp_path, command):
    header = "\t".join(COLUMNS) + "\n# station-runlog 1\n" + '# {"dt": 0.002}\n'
    (tmp_path / "h.tsv").write_text(header)
    (tmp_path / "h2.tsv").write_text(header + "# \n")
    argv = [a.format(f=tmp_path / "h.tsv", f2=tmp_path / "h2.tsv") for a in command]
    _one_line(run_forked(argv, cwd=tmp_path, timeout=HANG_S), "h.tsv")


# --- a compensator's shaper: inside the run --------------------------------------------------------

SHAPED = """limit = 200
[gth]
domain = "s"
num = [20.0, 628.3185307179587]
den = [1.0, 125.66370614359172]
[shaper]
times = {times}
amplitudes = {amplitudes}
"""


@pytest.mark.parametrize("last, duration", [(0.5, 2.0), (1.97, 2.0), (1.98, 2.0), (5.0, 2.0), (5.0, 5.1), (9.9, 4.0)])
def test_a_shaper_impulse_past_the_runs_end_is_refused_before_the_run(tmp_path, last, duration):
    from station.plan import plan_step

    comp = tmp_path / "c.toml"
    comp.write_text(SHAPED.format(times=f"[0.0, {last}]", amplitudes="[0.5, 0.5]"))
    step_tick = 10
    inside = step_tick + round(last / 0.002) < round(duration / 0.002)
    if inside:
        plan_step(controller=str(comp), duration=duration, out=os.devnull)
        return
    with pytest.raises(StationError, match=r"c.toml: its reference shaper's last impulse .* past the run's end"):
        plan_step(controller=str(comp), duration=duration, out=os.devnull)


@pytest.mark.parametrize("big", [1e9, 1e6, 3e3])
def test_opposing_shaper_amplitudes_past_the_soft_limit_are_refused(tmp_path, big):
    from station.plan import plan_step

    comp = tmp_path / "c.toml"
    comp.write_text(SHAPED.format(times="[0.0, 0.1]", amplitudes=f"[{big!r}, {1 - big!r}]"))
    with pytest.raises(StationError, match="past --soft-limit"):
        plan_step(controller=str(comp), out=os.devnull)
