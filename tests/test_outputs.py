"""Nothing a user has is ever overwritten (issue 15, class 1): one output rule for every
command (station.outputs), checked before anything starts; files written whole or not at all.

The command table is tests/output_cases.py (one line per command). Every file option of
every command is set to each of its inputs, to another output, to an existing file
(without and with --force), to a read-only folder and to a full disk; the full disk is a
file object that fails with ENOSPC after 100 bytes, put where station.outputs opens its
temporary files (tests/test_outputs_os.py does the same on a real full and a real read-only
file system where the machine allows it).
"""

from __future__ import annotations

import errno
import os
import shutil
import stat
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from station import outputs
from station.cli import build_parser, main
from station.errors import StationError
from station.outputs import Input, Output, Transaction, check_outputs, unique_names
from tests.output_cases import COMMANDS, default_outputs, make_inputs, parts, snapshot, targets

KEEP = b"keep me\n"


# --- station.outputs on its own -------------------------------------------------------------

def test_an_output_that_is_an_input_is_refused_by_path_hard_link_and_symbolic_link(tmp_path):
    log = tmp_path / "run.txt"
    log.write_bytes(KEEP)
    os.link(log, tmp_path / "hard.txt")
    (tmp_path / "soft.txt").symlink_to(log)
    (tmp_path / "sub").mkdir()
    for alias in (log, tmp_path / "hard.txt", tmp_path / "soft.txt", tmp_path / "sub" / ".." / "run.txt"):
        with pytest.raises(StationError, match=r"^--json .*: is an input of this command \(RUN"):
            check_outputs([Output("--json", alias)], [Input("RUN", log)], force=True)
    assert log.read_bytes() == KEEP


def test_two_outputs_that_are_one_file_are_refused_also_when_new(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "d")
    for a, b in ((tmp_path / "x.json", tmp_path / "d" / ".." / "x.json"),
                 (tmp_path / "d" / "y.png", tmp_path / "link" / "y.png")):
        with pytest.raises(StationError, match="is the same file as --json"):
            check_outputs([Output("--json", a), Output("--png", b)])
    assert sorted(os.listdir(tmp_path)) == ["d", "link"]


def test_an_existing_file_needs_force_a_device_does_not(tmp_path):
    old = tmp_path / "old.json"
    old.write_bytes(KEEP)
    with pytest.raises(StationError, match="exists; use --force"):
        check_outputs([Output("--json", old)])
    check_outputs([Output("--json", old)], force=True)
    check_outputs([Output("--json", "/dev/null")])  # nothing to keep in a device
    with pytest.raises(StationError, match="is a folder"):
        check_outputs([Output("--json", tmp_path)], force=True)
    (tmp_path / "file").write_bytes(KEEP)
    with pytest.raises(StationError, match=r"its folder: .*file is a file, not a folder"):
        check_outputs([Output("--json", tmp_path / "file" / "x.json")])


class _FullDisk:
    """A binary file that takes ``room`` bytes, then fails as a full disk does."""

    def __init__(self, fh, room: int):
        self._fh, self._room = fh, room

    def write(self, data) -> int:
        data = bytes(data)
        if len(data) > self._room:
            self._fh.write(data[:self._room])
            self._room = 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._room -= len(data)
        return self._fh.write(data)

    def __getattr__(self, name):
        return getattr(self._fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._fh.close()


def full_disk(monkeypatch, names: set[str], room: int = 100) -> None:
    """The files station.outputs writes for targets named ``names`` meet a full disk after ``room`` bytes."""
    real_part, real_open, fds = outputs.part_file, open, {}

    def part_file(target):
        fd, path = real_part(target)
        fds[fd] = Path(target).name
        return fd, path

    def fake_open(file, mode="r", *args, **kwargs):
        fh = real_open(file, mode, *args, **kwargs)
        name = fds.pop(file, None) if isinstance(file, int) else Path(file).name
        return _FullDisk(fh, room) if name in names and "w" in mode else fh

    monkeypatch.setattr(outputs, "part_file", part_file)
    monkeypatch.setattr(outputs, "open", fake_open, raising=False)


def test_a_failed_write_leaves_the_old_file_and_no_part(tmp_path, monkeypatch):
    old, new = tmp_path / "a.json", tmp_path / "sub" / "b.json"
    old.write_bytes(KEEP)
    full_disk(monkeypatch, {"b.json"})
    with pytest.raises(StationError, match=r"b.json: cannot write the JSON: No space left on device$"):
        with Transaction() as tx:
            tx.write_json(old, {"x": 1})
            tx.write_json(new, {"y": "z" * 500})
    assert old.read_bytes() == KEEP and not (tmp_path / "sub").exists() and parts(tmp_path) == []


def test_a_signal_during_a_write_leaves_no_part(tmp_path):
    from station.signals import StopSignal

    with pytest.raises(StopSignal):
        with Transaction() as tx:
            with tx.open(tmp_path / "fig.png") as fh:
                fh.write(b"half")
                raise StopSignal(15)
    assert list(tmp_path.iterdir()) == []


def test_a_replaced_file_keeps_its_mode_a_new_one_follows_the_umask(tmp_path):
    old = tmp_path / "old.json"
    old.write_bytes(KEEP)
    old.chmod(0o640)
    outputs.write_json(old, {"a": 1})
    outputs.write_json(tmp_path / "new.json", {"a": 1})
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(old.stat().st_mode) == 0o640
    assert stat.S_IMODE((tmp_path / "new.json").stat().st_mode) == 0o666 & ~umask


def test_a_device_is_written_in_place_and_its_failure_is_one_line():
    outputs.write_bytes("/dev/null", b"x" * 10)
    with pytest.raises(StationError, match=r"^/dev/full: cannot write the JSON: No space left on device$"):
        outputs.write_json("/dev/full", {"x": 1})


@given(st.lists(st.sampled_from(["run", "run-2", "run-3", "a", "a-2-2", "b"]), max_size=12))
def test_made_up_names_are_unique_and_keep_the_first_of_each(names):
    got = unique_names(names)
    assert len(got) == len(names) and len(set(got)) == len(got)
    assert unique_names(names) == got  # deterministic
    for i, (name, new) in enumerate(zip(names, got)):
        assert new == name if name not in names[:i] else new.startswith(name + "-")


# --- every command, from the table ------------------------------------------------------------

def test_every_command_is_in_the_table():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert sorted(sub.choices) == sorted({c.command or n if c else n for n, c in COMMANDS.items()}), \
        "add the new command to tests/output_cases.py"
    for name, cmd in COMMANDS.items():
        options = {o for a in sub.choices[cmd.command or name if cmd else name]._actions for o in a.option_strings}
        if cmd is not None:
            assert set(cmd.files) | set(cmd.folders) <= options and "--force" in options, name


WRITERS = {name: cmd for name, cmd in COMMANDS.items() if cmd is not None}


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    root = tmp_path_factory.mktemp("inputs")
    make_inputs(root)
    return root


@pytest.fixture
def ws(template, tmp_path, monkeypatch):
    """A fresh copy of the inputs as the working folder; the diagnosis tries one candidate
    (its writing is what is tested here, not its search)."""
    shutil.copytree(template / "in", tmp_path / "in")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("station.diagnosis.search.workbench.CANDIDATES", ("coulomb_friction",))  # diagnose and sessions
    return tmp_path


def _inputs(root: Path) -> dict[str, Path]:
    d = root / "in"
    return {"step": d / "step.txt", "step2": d / "step2.txt", "sweep": d / "sweep.txt", "model": d / "model.toml",
            "in": d}


def _run(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _refused(code, err, words):
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert words in lines[0], lines[0]


def _file_cases():
    return [(n, o) for n, c in WRITERS.items() for o in c.files]


def _input_cases():
    return [(n, o, i) for n, c in WRITERS.items() for o in c.files for i in c.inputs]


@pytest.mark.parametrize("name, option, which", _input_cases())
def test_an_output_onto_an_input_is_refused(ws, capsys, name, option, which):
    cmd, inp = WRITERS[name], _inputs(ws)
    before = snapshot(ws)
    code, _, err = _run(cmd.argv(name, inp) + [option, inp[which], "--force"], capsys)
    _refused(code, err, "is an input of this command")
    assert snapshot(ws) == before


def _other_cases():
    cases = []
    for name, cmd in WRITERS.items():
        opts = list(cmd.files) + list(cmd.folders)
        for a in cmd.files:
            for b in opts:
                if a != b:
                    cases.append((name, a, b))
        if cmd.figure_of:
            cases.append((name, cmd.figure_of, "figure"))
    return cases


@pytest.mark.parametrize("name, option, other", _other_cases())
def test_an_output_onto_another_output_is_refused(ws, capsys, name, option, other):
    cmd = WRITERS[name]
    paths = default_outputs(name, cmd, ws)
    if other == "figure":  # --out fig.png: the figure beside the log would be the log
        argv = [option, paths[option].with_suffix(".png")]
    else:
        argv = [other, paths[other], option, targets(cmd, {other: paths[other]})[other][-1]]
    before = snapshot(ws)
    code, _, err = _run(cmd.argv(name, _inputs(ws)) + argv + ["--force"], capsys)
    _refused(code, err, "is the same file as")
    assert snapshot(ws) == before


def _existing_cases():
    cases = [(n, o, 0) for n, c in WRITERS.items() for o in list(c.files) + list(c.folders)]
    return cases + [(n, c.figure_of, 1) for n, c in WRITERS.items() if c.figure_of]  # the figure beside --out


@pytest.mark.parametrize("name, option, which", _existing_cases())
def test_an_existing_file_is_refused_without_force(ws, capsys, name, option, which):
    cmd = WRITERS[name]
    path = default_outputs(name, cmd, ws)[option]
    existing = targets(cmd, {option: path})[option][which]
    existing.parent.mkdir(parents=True, exist_ok=True)
    existing.write_bytes(KEEP)
    before = snapshot(ws)
    code, _, err = _run(cmd.argv(name, _inputs(ws)) + [option, path], capsys)
    _refused(code, err, "exists; use --force to replace it")
    assert snapshot(ws) == before


@pytest.mark.parametrize("name", WRITERS)
def test_with_force_every_existing_output_is_replaced_and_inputs_are_kept(ws, capsys, name):
    cmd = WRITERS[name]
    paths = default_outputs(name, cmd, ws)
    files = [f for fs in targets(cmd, paths).values() for f in fs]
    for f in files:
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_bytes(KEEP)
    ins = {k: v for k, v in snapshot(ws).items() if k.startswith("in/")}
    argv = cmd.argv(name, _inputs(ws)) + [x for opt, p in paths.items() for x in (opt, p)] + ["--force"]
    code, _, err = _run(argv, capsys)
    assert code == 0, err
    assert all(f.read_bytes() != KEEP for f in files), [f.name for f in files if f.read_bytes() == KEEP]
    assert {k: v for k, v in snapshot(ws).items() if k.startswith("in/")} == ins and parts(ws) == []


def _readonly_folder(tmp_path) -> Path:
    """A folder this process cannot write: chmod for a user; for root (who ignores
    permissions) /proc, where nobody creates files."""
    if os.geteuid() != 0:
        d = tmp_path / "ro"
        d.mkdir()
        d.chmod(0o555)
        return d
    return Path("/proc")


@pytest.mark.parametrize("name, option", _file_cases() + [(n, o) for n, c in WRITERS.items() for o in c.folders])
def test_an_output_in_a_read_only_folder_is_refused_before_anything_starts(ws, capsys, name, option):
    cmd = WRITERS[name]
    target = _readonly_folder(ws) / "sub" / default_outputs(name, cmd, ws)[option].name
    before = snapshot(ws)
    code, _, err = _run(cmd.argv(name, _inputs(ws)) + [option, target], capsys)
    _refused(code, err, "is not writable")
    assert snapshot(ws) == before


def _full_cases():
    cases = [(n, o, -1) for n, c in WRITERS.items() for o in list(c.files) + list(c.folders)]
    return cases + [(n, o, 0) for n, c in WRITERS.items() for o in c.folders]  # a folder's first file


@pytest.mark.parametrize("name, option, which", _full_cases())
def test_a_full_disk_leaves_no_part_and_changes_nothing_that_existed(ws, capsys, monkeypatch, name, option, which):
    cmd = WRITERS[name]
    paths = default_outputs(name, cmd, ws)
    failing = targets(cmd, {option: paths[option]})[option][which]
    existing = [] if not cmd.together else [f for fs in targets(cmd, paths).values() for f in fs]
    for f in existing:  # all there before, --force: a failure must leave every one as it was
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_bytes(KEEP)
    before = snapshot(ws)
    full_disk(monkeypatch, {failing.name}, room=16)  # less than any file a command writes
    argv = cmd.argv(name, _inputs(ws)) + [x for opt, p in paths.items() for x in (opt, p)] + ["--force"]
    code, out, err = _run(argv, capsys)
    assert parts(ws) == []
    if failing.suffix == ".png" and option == cmd.figure_of:  # step's figure: a warning, the run is kept
        assert code == 0 and "the run's figure was not written" in err and not failing.exists()
        return
    lines = [line for line in err.strip().splitlines()
             if not line.startswith(f"{cmd.command or name}: ")]  # progress
    assert code == 2 and len(lines) == 1 and "No space left on device" in lines[0], err
    assert "Traceback" not in err
    if cmd.together:
        assert snapshot(ws) == before
    else:
        assert not failing.exists()


# --- generated names -------------------------------------------------------------------------

def test_compare_names_the_figures_of_two_runs_of_one_name_apart(ws, capsys):
    (ws / "a").mkdir()
    (ws / "b").mkdir()
    shutil.copy(ws / "in" / "step.txt", ws / "a" / "run.txt")
    shutil.copy(ws / "in" / "step2.txt", ws / "b" / "run.txt")
    code, out, err = _run(["compare", ws / "a" / "run.txt", ws / "b" / "run.txt", "--out-dir", ws / "figs"], capsys)
    assert code == 0, err
    figs = sorted(p.name for p in (ws / "figs").iterdir())
    assert figs == ["run-2_compare.png", "run_compare.png"]
    assert (ws / "figs" / figs[0]).read_bytes() != (ws / "figs" / figs[1]).read_bytes()


def test_a_diagnosis_report_of_two_runs_of_one_name_keeps_both(ws, capsys):
    (ws / "a").mkdir()
    (ws / "b").mkdir()
    shutil.copy(ws / "in" / "step.txt", ws / "a" / "run.txt")
    shutil.copy(ws / "in" / "step2.txt", ws / "b" / "run.txt")
    code, _, err = _run(["diagnose", ws / "a" / "run.txt", ws / "b" / "run.txt", "--report", ws / "rep", "--quiet"],
                        capsys)
    assert code == 0, err
    assert sorted(p.name for p in (ws / "rep").iterdir()) == [
        "report.html", "run-2_resid.png", "run-2_run.png", "run_resid.png", "run_run.png"]


# --- property: any combination of output options ---------------------------------------------

FAST = ("plot", "modes", "replay", "step", "compare")
"""Commands quick enough to run for every drawn example (bode and diagnose: table cases above)."""


@st.composite
def _choices(draw, name):
    cmd = WRITERS[name]
    pick = {}
    for opt in list(cmd.files) + list(cmd.folders):
        kind = draw(st.sampled_from(["none", "a", "b", "input", "old"] if opt in cmd.files else ["none", "a", "old"]))
        if kind == "input":
            kind = "input:" + draw(st.sampled_from(cmd.inputs))
        pick[opt] = kind
    return pick, draw(st.booleans())


@pytest.mark.parametrize("name", FAST)
def test_any_combination_of_outputs_follows_the_rule(template, tmp_path_factory, monkeypatch, name):
    cmd = WRITERS[name]

    @settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck))
    @given(_choices(name))
    def check(choice):
        pick, force = choice
        root = tmp_path_factory.mktemp(name)
        shutil.copytree(template / "in", root / "in")
        monkeypatch.chdir(root)  # where the defaults of options not given go
        inputs = _inputs(root)
        (root / "old").mkdir()
        chosen = {}
        for opt, kind in pick.items():
            suffix = default_outputs(name, cmd, root)[opt].suffix
            if kind.startswith("input:"):
                chosen[opt] = inputs[kind.split(":")[1]]
            elif kind == "old":
                chosen[opt] = root / "old" / f"o{opt.strip('-')}{suffix}"
            elif kind in ("a", "b"):
                chosen[opt] = root / "new" / f"{kind}{suffix if opt in cmd.folders else '.out'}"
        files = targets(cmd, chosen)
        for opt, kind in pick.items():
            if kind == "old":
                for f in files[opt]:
                    f.parent.mkdir(parents=True, exist_ok=True)
                    f.write_bytes(KEEP)
        # the rule, independently: no output an input, no two outputs one file, no existing file without force
        flat = [os.path.realpath(f) for fs in files.values() for f in fs]
        ins = {os.path.realpath(inputs[i]) for i in cmd.inputs}
        exists = any(os.path.exists(f) for f in flat)
        refused = bool(ins & set(flat)) or len(set(flat)) < len(flat) or (exists and not force)
        before = snapshot(root)
        argv = cmd.argv(name, inputs) + [x for opt, p in chosen.items() for x in (opt, p)] + (["--force"] if force else [])
        code = main([str(a) for a in argv])
        if refused:
            assert code == 2 and snapshot(root) == before, (pick, force)
        else:
            assert code == 0, (pick, force)
            assert all(Path(f).exists() and Path(f).read_bytes() != KEEP for f in flat), (pick, force)
            assert {k: v for k, v in snapshot(root).items() if k.startswith("in/")} == \
                {k: v for k, v in before.items() if k.startswith("in/")}
        assert parts(root) == []
        shutil.rmtree(root)

    check()


# --- names the file system cannot hold (issue 24: OSError tracebacks, refusals after the work) --

NAME_MAX = os.pathconf("/tmp", "PC_NAME_MAX")


def _too_long(kind: str, path: Path) -> Path:
    """``path`` with a name no file system here holds: a folder part of 300 bytes, a last part
    of 300 bytes, or one that fits NAME_MAX but not the temporary name written first."""
    if kind == "folder part":
        return path.parent / ("d" * 300) / path.name
    if kind == "name":
        return path.with_name("n" * 300 + path.suffix)
    return path.with_name("p" * (NAME_MAX - 2 - len(path.suffix)) + path.suffix)  # + .XXXXXXXX.part: too long


LONG_KINDS = ("folder part", "name", "temporary name")


def _long_cases():
    files = [(n, o, k) for n, o in _file_cases() for k in LONG_KINDS]
    # a folder's own name has no temporary name (its files' names are the command's)
    return files + [(n, o, k) for n, c in WRITERS.items() for o in c.folders for k in LONG_KINDS[:2]]


@pytest.mark.parametrize("name, option, kind", _long_cases())
def test_an_output_name_the_file_system_cannot_hold_is_refused_before_anything_starts(ws, capsys, name, option,
                                                                                       kind):
    cmd = WRITERS[name]
    target = _too_long(kind, default_outputs(name, cmd, ws)[option])
    before = snapshot(ws)
    code, _, err = _run(cmd.argv(name, _inputs(ws)) + [option, target], capsys)
    _refused(code, err, "bytes")
    assert option in err.splitlines()[0]
    assert snapshot(ws) == before  # no log, no figure, no report: refused before anything started


@pytest.mark.parametrize("name", ["step", "compare", "bode", "plot"])
@pytest.mark.parametrize("where", ["--out-dir", "station.toml"])
def test_an_output_folder_the_file_system_cannot_hold_is_refused_naming_where_it_came_from(ws, capsys, name, where):
    cmd = WRITERS[name]
    folder = ws / ("o" * 300)
    extra = ["--out-dir", folder] if where == "--out-dir" else []
    if where == "station.toml":
        (ws / "station.toml").write_text(f'out_dir = "{folder}"\n')
    before = snapshot(ws)
    code, _, err = _run(cmd.argv(name, _inputs(ws)) + extra, capsys)
    _refused(code, err, "300 bytes")
    assert ("--out-dir" in err) == (where == "--out-dir") and ("station.toml's out_dir" in err) == (where != "--out-dir")
    assert snapshot(ws) == before


# --- where outputs go: one rule (issue 24 item 7) ----------------------------------------------

NAMED = {"step": None, "compare": "step_compare.png", "bode": "sweep_bode.png", "plot": "step.png"}
"""Commands that name a file themselves, and the name (step's log: made up from the time)."""


@pytest.mark.parametrize("name", NAMED)
@pytest.mark.parametrize("where", ["default", "station.toml", "--out-dir"])
def test_a_file_a_command_names_goes_into_the_output_folder_never_the_working_folder(ws, capsys, name, where):
    cmd = WRITERS[name]
    extra = {"default": [], "station.toml": [], "--out-dir": ["--out-dir", "chosen"]}[where]
    if where == "station.toml":
        (ws / "station.toml").write_text('out_dir = "lab"\n')
    folder = ws / {"default": "runs", "station.toml": "lab", "--out-dir": "chosen"}[where]
    before = {p.name for p in ws.iterdir()}
    code, out, err = _run(cmd.argv(name, _inputs(ws)) + extra, capsys)
    assert code == 0, err
    assert {p.name for p in ws.iterdir()} - before == {folder.name}, "nothing else in the working folder"
    made = sorted(p.name for p in folder.iterdir())
    assert made and (NAMED[name] is None or made == [NAMED[name]]), made
    if NAMED[name] is None:  # step: its log and the figure beside it
        assert len(made) == 2 and {Path(m).suffix for m in made} == {".tsv", ".png"}
    # run again: the figure exists; the refusal names the file and the folder, and the option only when given
    code, _, err = _run(cmd.argv(name, _inputs(ws)) + extra, capsys)
    if NAMED[name] is None:
        assert code == 0  # step makes up a new log name each time
        return
    _refused(code, err, f"{folder.name}/{NAMED[name]}: exists; use --force to replace it")
    line = err.strip()
    assert ("--out-dir chosen" in line) == (where == "--out-dir"), line
    assert ("out_dir lab" in line) == (where == "station.toml"), line
    assert f"another folder than" in line


def test_identify_makes_its_experiments_folder_in_the_output_folder(ws):
    import argparse

    from station.commands.identify import experiments_folder

    (ws / "station.toml").write_text('out_dir = "lab"\n')
    args = build_parser().parse_args(["identify"])
    assert args.out_dir is None and args._config_values["out_dir"] == Path("lab")
    folder = experiments_folder(args)
    assert folder.parent == Path("lab") and folder.name.startswith("identify-")
    args = argparse.Namespace(out_dir=None, force=False, _config_values={})
    assert experiments_folder(args).parent == Path("runs")


# --- files an option or a setting makes a command read are inputs too (issue 24: identify replaced
# the model its sim:// port served, compare/bode/plot the station.toml they read) --------------

SETTINGS = 'out_dir = "runs"\n'


def _readers() -> dict[str, set[str]]:
    """Per source, the table's commands that read it: station.toml when the command takes its
    settings (:func:`station.config.apply_config`), the port's model when it opens a port."""
    import tempfile

    here = os.getcwd()
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "station.toml").write_text(SETTINGS)
        os.chdir(d)
        try:
            sub = next(a for a in build_parser()._actions if a.dest == "command").choices
        finally:
            os.chdir(here)
    parsers = {n: sub[c.command or n] for n, c in WRITERS.items()}
    return {"station.toml": {n for n, p in parsers.items() if p.get_default("_config")},
            "--port's model": {n for n, p in parsers.items() if p.get_default("port") is not None}}


READERS = _readers()


def test_the_readers_are_the_commands_that_take_settings_or_a_port():
    assert READERS == {"station.toml": {"step", "compare", "bode", "plot", "identify"},
                       "--port's model": {"step", "identify"}}


MORE_FILES = {"identify": ("--save-model",)}
"""File options the table leaves out for its full-disk case (output_cases.py), refused here all the same."""


@pytest.mark.parametrize("name, option, source", [(n, o, s) for s, names in READERS.items() for n in sorted(names)
                                                  for o in WRITERS[n].files + MORE_FILES.get(n, ())])
def test_a_file_a_setting_or_the_port_makes_the_command_read_is_never_replaced(ws, capsys, name, option, source):
    cmd, inp = WRITERS[name], _inputs(ws)
    argv = cmd.argv(name, inp)
    (ws / "station.toml").write_text(SETTINGS)
    if source == "station.toml":
        target = ws / "station.toml"
    else:
        target = ws / "served.toml"  # the simulated rig's model, as sim://?model=FILE names it
        shutil.copy(inp["model"], target)
        i = argv.index("--model")  # the port's model in --model's place
        argv = argv[:i] + argv[i + 2:] + ["--port", f"sim://?model={target}"]
    before = snapshot(ws)
    code = main([str(a) for a in argv + [option, target, "--force"]])
    err = "\n".join(line for line in capsys.readouterr().err.splitlines() if not line.startswith("station: note:"))
    _refused(code, err, f"is an input of this command ({source})")
    assert snapshot(ws) == before
