"""Issue 15, class 2: every file the station reads fails as one line. Each instance the
issue found is a test here, named after it: the command refuses with one line naming the
file (its line and key where known) or the URL option, exit code 2, before anything
starts - never a traceback, a hang or a silently changed value.

The commands run in forked children (tests/cli_fork.py): real processes with their own
exit code and stderr; a few run in a fresh interpreter where start-up matters (--help).
"""

from __future__ import annotations

import math
import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cli_fork import one_line_refusal, run_forked, run_station  # noqa: E402

from station.errors import StationError  # noqa: E402
from station.plant.model import load_model  # noqa: E402
from station.plant.parameters import PARAM_RANGES, PARAMS_DIR, load_params  # noqa: E402

TMM_FIT = (PARAMS_DIR / "tmm-fit.toml").read_text()
P_LOG = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
LEAD_LOG = "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt"
LEAD_ACCEL_LOG = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"
SWEEP_LOG = "swept_sine_kp_1_amp_50.txt"


@pytest.fixture(scope="module", autouse=True)
def _imported():
    """Import what the commands load lazily once, before the children fork (each then costs
    milliseconds, not the imports)."""
    import station.commands.step  # noqa: F401
    import station.compare  # noqa: F401
    import station.diagnosis  # noqa: F401
    import station.experiment  # noqa: F401
    import station.plant  # noqa: F401
    import station.replay  # noqa: F401
    import station.sim.protocol_sim  # noqa: F401
    import station.sim.pty_server  # noqa: F401


def _model_commands(model: Path, rig: Path, tmp: Path) -> dict[str, list[str]]:
    """Every command that takes a model, with ``model`` (the issue's list)."""
    p, lead, sweep = str(rig / P_LOG), str(rig / LEAD_LOG), str(rig / SWEEP_LOG)
    return {
        "step": ["step", "--model", str(model), "--duration", "0.1", "--out", str(tmp / "s.tsv")],
        "compare": ["compare", "--model", str(model), p],
        "replay": ["replay", "--model", str(model), p],
        "diagnose": ["diagnose", "--model", str(model), p, lead],
        "bode": ["bode", "--model", str(model), sweep],
        "modes": ["modes", "--model", str(model), "--elements", "4"],
        "sim-device": ["sim-device", "--pty", "--model", str(model)],
        "sim://?model=": ["step", "--port", f"sim://?model={model}", "--duration", "0.1", "--out", str(tmp / "u.tsv")],
    }


def _refused_everywhere(model: Path, rig: Path, tmp: Path, *expected: str) -> None:
    for name, argv in _model_commands(model, rig, tmp).items():
        line = one_line_refusal(run_forked(argv, cwd=tmp))
        for text in expected:
            assert text in line, (name, line)
    assert not [f for f in os.listdir(tmp) if f.endswith((".tsv", ".png", ".json"))]  # nothing started


# --- model files ---------------------------------------------------------------------------

def test_model_nested_5000_deep_is_one_line_in_every_command(rig_data, tmp_path):
    model = tmp_path / "deep.toml"
    model.write_text('name = "deep"\nx = ' + "[" * 5000 + "]" * 5000 + "\n")
    _refused_everywhere(model, rig_data, tmp_path, str(model), "nested too deeply")


def test_model_not_utf8_names_file_and_line_in_every_command(rig_data, tmp_path):
    model = tmp_path / "latin1.toml"
    model.write_bytes(b'# a model\nname = "caf\xe9"\nparams = "tmm-fit"\n')
    _refused_everywhere(model, rig_data, tmp_path, f"{model}: line 2: not UTF-8")


def test_model_params_pointing_at_a_folder_names_both_files(rig_data, tmp_path):
    (tmp_path / "sets").mkdir()
    model = tmp_path / "m.toml"
    model.write_text('params = "sets/"\n')
    _refused_everywhere(model, rig_data, tmp_path, f"{model}: line 1: params:", "is a folder")


@pytest.mark.parametrize("value, word", [("1e-300", "1e-300"), ("1e300", "1e+300")])
def test_parameter_L_extreme_names_the_field_not_a_zero_division(rig_data, tmp_path, value, word):
    (tmp_path / "set.toml").write_text(TMM_FIT.replace("L = 0.41354375", f"L = {value}"))
    model = tmp_path / "m.toml"
    model.write_text('params = "set.toml"\n')
    _refused_everywhere(model, rig_data, tmp_path, f"{tmp_path / 'set.toml'}: line 9: field 'L': {word} is out of range")


@pytest.mark.parametrize("field", sorted(PARAM_RANGES))
@pytest.mark.parametrize("value", [1e-300, 1e300, -1.0, math.inf])
def test_every_parameter_at_an_extreme_value_names_its_field_and_line(tmp_path, field, value):
    """The issue's 13 other extreme values (``array must not contain infs or NaNs``): every
    field, both extremes, named with its line before anything is computed; a value in the
    field's range (1e-300 where 0 is allowed) gives a model that is computed."""
    text = re.sub(rf"(?m)^{field} = \S+", f"{field} = {'inf' if value == math.inf else repr(value)}", TMM_FIT)
    assert text != TMM_FIT
    path = tmp_path / "set.toml"
    path.write_text(text)
    if PARAM_RANGES[field].low <= value <= PARAM_RANGES[field].high:
        (tmp_path / "m.toml").write_text('params = "set.toml"\n')
        assert np.isfinite(load_model(tmp_path / "m.toml").linear_form().lam).all()
        return
    line = next(i for i, t in enumerate(text.splitlines(), 1) if t.startswith(f"{field} ="))
    with pytest.raises(StationError) as err:
        load_params(path)
    assert str(err.value).startswith(f"{path}: line {line}: field '{field}': ") and err.value.key == field
    assert "\n" not in str(err.value)


def test_sim_url_model_dev_zero_is_refused_without_reading_it(tmp_path):
    line = one_line_refusal(run_forked(["step", "--port", "sim://?model=/dev/zero", "--out", str(tmp_path / "r.tsv")],
                                       timeout=60))
    assert "sim:// option model='/dev/zero'" in line and "is a character device, not a model file" in line
    for path in ("/dev/zero", str(tmp_path)):
        with pytest.raises(StationError, match="not a model file"):
            load_model(path)
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)  # opening it would block until a writer came
    with pytest.raises(StationError, match="FIFO"):
        load_model(fifo)


def test_beam_damping_below_the_sets_own_zeta_is_refused_not_ignored(tmp_path):
    model = tmp_path / "m.toml"
    model.write_text('name = "stiff clamp"\n[effects]\n"param:clamp_c" = 3.0\nbeam_damping = 0.01\n')
    nominal = load_model().with_effects({"param:clamp_c": 3.0})
    assert nominal.beam_damping_floor() > 0.01  # the set's own first-mode ζ with that clamp damper
    with pytest.raises(StationError) as err:
        load_model(model)
    assert f"{model}: line 4: [effects].beam_damping: 0.01 is below" in str(err.value)
    line = one_line_refusal(run_forked(["step", "--model", str(model), "--out", str(tmp_path / "r.tsv")]))
    assert "beam_damping" in line and not (tmp_path / "r.tsv").exists()
    # a parameter set whose own clamp damper gives more than asked: refused likewise
    (tmp_path / "set.toml").write_text(TMM_FIT.replace("clamp_c = 0.003897076", "clamp_c = 0.012"))
    model.write_text('params = "set.toml"\n[effects]\nbeam_damping = 0.01\n')
    with pytest.raises(StationError, match="beam_damping: 0.01 is below"):
        load_model(model)
    # and what is accepted is what runs: the first mode has the asked damping
    model.write_text('params = "set.toml"\n[effects]\nbeam_damping = 0.05\n')
    from station.plant.modes import modal_summary

    m = load_model(model)
    assert modal_summary(m.linear_params(), 4).antiresonance_damping[0] == pytest.approx(0.05, rel=1e-6)


def test_beam_damping_floor_depends_on_the_element_count(tmp_path):
    """At one element the set's own ζ is above tmm-fit's 4-element value (the effect's lower
    bound): a value between them would have been ignored."""
    one = load_model(n_elements=1).beam_damping_floor()
    four = load_model().beam_damping_floor()
    assert one > four
    model = tmp_path / "m.toml"
    model.write_text(f"n_elements = 1\n[effects]\nbeam_damping = {(one + four) / 2!r}\n")
    with pytest.raises(StationError, match="line 3: .effects..beam_damping: .* is below"):
        load_model(model)


# --- station.toml ---------------------------------------------------------------------------

def test_deeply_nested_station_toml_keeps_help_and_refuses_with_one_line(tmp_path):
    (tmp_path / "station.toml").write_text("port = " + "[" * 5000 + "]" * 5000 + "\n")
    help_ = run_station(["--help"], cwd=tmp_path)  # a fresh interpreter: the parser is built at start-up
    assert help_.code == 0 and "step" in help_.out and "Traceback" not in help_.err
    assert run_station(["step", "--help"], cwd=tmp_path).code == 0
    line = one_line_refusal(run_forked(["step", "--duration", "0.1"], cwd=tmp_path))
    assert "station.toml: not a config file: tables or arrays nested too deeply" in line
    assert not (tmp_path / "runs").exists()


def test_station_toml_that_is_a_folder_or_fifo_is_refused_not_skipped(tmp_path):
    (tmp_path / "station.toml").mkdir()
    line = one_line_refusal(run_forked(["step", "--duration", "0.1"], cwd=tmp_path))
    assert "station.toml: is a folder, not a config file" in line


# --- compensator files ----------------------------------------------------------------------

def test_compensator_of_order_10000_is_refused_before_any_arithmetic(tmp_path):
    comp = tmp_path / "c.toml"
    comp.write_text("[gth]\nnum = [1.0]\nden = [" + ", ".join(["1.0"] * 10001) + ']\ndomain = "s"\n')
    line = one_line_refusal(run_forked(["step", "--controller", str(comp), "--out", str(tmp_path / "r.tsv")],
                                       timeout=60))  # (it took 14 minutes, and ignored SIGTERM)
    assert f"{comp}: line 3: [gth].den: 10001 coefficients: a filter is of order at most 20" in line


def test_s_domain_pole_at_2_over_dt_names_the_denominator(tmp_path):
    comp = tmp_path / "c.toml"
    comp.write_text('[gth]\nnum = [1.0]\nden = [1.0, -1000.0]\ndomain = "s"\n')  # s = 1000 = 2/dt
    line = one_line_refusal(run_forked(["step", "--controller", str(comp), "--out", str(tmp_path / "r.tsv")]))
    assert f"{comp}: [gth].den: a pole at s = 2/dt = 1000 rad/s" in line and "singular" not in line


@pytest.mark.parametrize("num, den, domain", [("[1e308, 1e308]", "[1.0, 1.0]", "s"),
                                              ("[1e308, 1e308]", "[1e-300, 1.0]", "s"),
                                              ("[1.0]", "[1e-308, 1e308]", "z")])
def test_huge_coefficients_name_the_filter(tmp_path, num, den, domain):
    comp = tmp_path / "c.toml"
    comp.write_text(f'[gth]\nnum = {num}\nden = {den}\ndomain = "{domain}"\n')
    line = one_line_refusal(run_forked(["step", "--controller", str(comp), "--out", str(tmp_path / "r.tsv")]))
    assert f"{comp}: [gth]: " in line


@pytest.mark.parametrize("limit", ["1e9", "false", "0", "-5", '"200"', "255.5", "nan"])
def test_compensator_limit_outside_0_255_or_not_a_number_is_refused(tmp_path, limit):
    comp = tmp_path / "c.toml"
    comp.write_text(f'limit = {limit}\n[gth]\nnum = [2.0]\nden = [1.0]\ndomain = "z"\n')
    line = one_line_refusal(run_forked(["step", "--controller", str(comp), "--out", str(tmp_path / "r.tsv")]))
    assert f"{comp}: line 1: limit: " in line and "0..255 DAC counts" in line


def test_compensator_limit_runs_as_written(tmp_path):
    """What the file asks for is what runs: the header records 150 and no command exceeds it."""
    from station.runlog import read_log

    comp = tmp_path / "c.toml"
    comp.write_text('limit = 150\n[gth]\nnum = [50.0]\nden = [1.0]\ndomain = "z"\n')
    log = tmp_path / "r.tsv"
    assert run_forked(["step", "--controller", str(comp), "--amplitude", "200", "--duration", "0.3",
                       "--out", str(log)], cwd=tmp_path).code == 0
    run = read_log(log)
    assert run.meta["controller"]["limit"] == 150.0
    v = run.data["v"]
    assert np.nanmax(np.abs(v)) == 150.0  # it saturated, at the file's clamp


# --- sim:// URLs ----------------------------------------------------------------------------

@pytest.mark.parametrize("query, option", [("seed=1&seed=2", "seed"), ("model=rig&model=tmm-fit", "model"),
                                           ("seed=", "seed"), ("noise=", "noise"), ("elements", "elements")])
def test_sim_url_repeated_or_blank_option_is_refused_naming_it(tmp_path, query, option):
    line = one_line_refusal(run_forked(["step", "--port", f"sim://?{query}", "--out", str(tmp_path / "r.tsv")]))
    assert f"sim:// option {option}" in line
    assert not (tmp_path / "r.tsv").exists()


def test_sim_url_repeats_reach_the_handler_through_open_session():
    from station.link import open_session

    with pytest.raises(StationError, match="sim:// option seed: given twice"):
        open_session("sim://?seed=1&seed=2")


def test_seed_option_and_url_seed_together_is_an_error_naming_both(tmp_path):
    line = one_line_refusal(run_forked(["step", "--seed", "5", "--port", "sim://?seed=3",
                                        "--out", str(tmp_path / "r.tsv")]))
    assert "--seed 5" in line and "sim://?seed=3" in line
    line = one_line_refusal(run_forked(["step", "--elements", "6", "--port", "sim://?elements=4",
                                        "--out", str(tmp_path / "r.tsv")]))
    assert "--elements 6" in line and "sim://?elements=4" in line


def test_sim_url_noise_inf_is_bad_input_before_the_run(tmp_path):
    log = tmp_path / "r.tsv"
    line = one_line_refusal(run_forked(["step", "--port", "sim://?noise=inf", "--out", str(log)]))
    assert "sim:// option noise='inf'" in line and "not a finite number" in line
    assert not log.exists()


def test_sim_url_elements_101_names_the_url_option(tmp_path):
    line = one_line_refusal(run_forked(["step", "--port", "sim://?elements=101", "--out", str(tmp_path / "r.tsv")]))
    assert "sim:// option elements='101'" in line and "n_elements" not in line


def test_url_options_and_command_line_options_share_one_range():
    """--seed and --elements (every command that has them) and sim://?seed=/elements= check
    the same station.ranges.SIM_RIG entries."""
    import argparse

    from station.cli import build_parser
    from station.ranges import SIM_RIG
    from station.sim.protocol_sim import _OPTIONS

    for name, rng in SIM_RIG.items():
        assert _OPTIONS[name][0] is rng
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    seen = 0
    for parser in sub.choices.values():
        for action in parser._actions:
            if action.dest in ("seed", "elements") and action.option_strings:
                assert action.type is SIM_RIG[action.dest], (parser.prog, action.dest)
                seen += 1
    assert seen >= 4


# --- logs -----------------------------------------------------------------------------------

def _without(rig: Path, name: str, column: str, out: Path) -> Path:
    """A copy of a rig log without one column (its header line and every row)."""
    lines = (rig / name).read_text().split("\n")
    header = max(i for i, t in enumerate(lines) if t.startswith("#"))
    idx = lines[header][1:].split("\t").index({"theta": "$\\theta$"}.get(column, column))
    kept = []
    for i, text in enumerate(lines):
        if (i < header) or not text:
            kept.append(text)
            continue
        body = text[1:] if i == header else text
        parts = body.split("\t")
        del parts[idx]
        kept.append(("#" if i == header else "") + "\t".join(parts))
    out.write_text("\n".join(kept))
    return out


def test_log_without_a_column_is_fitted_on_theta(rig_data, tmp_path):
    # a lead loop never reads a: replay and compare simulate it and fit θ (tests/test_no_accel_column.py);
    # a diagnosis fits its θ alone (tests/test_theta_only.py), but a law that feeds a back needs a:
    # one line
    noa = _without(rig_data, LEAD_LOG, "a", tmp_path / "no_a.txt")
    no_ga_a = _without(rig_data, LEAD_ACCEL_LOG, "a", tmp_path / "no_a_ga.txt")
    line = one_line_refusal(run_forked(["diagnose", str(noa), str(no_ga_a)]))
    assert f"{no_ga_a}: no 'a' column" in line and "NaN" not in line, line
    for argv in (["replay", str(noa)], ["compare", "--out-dir", str(tmp_path / "runs"), str(noa)]):
        rep = run_forked(argv)
        assert rep.code == 0 and "NaN" not in rep.out and "nan" not in rep.out, rep
    assert "accel n/a" in run_forked(["replay", str(noa)]).out
    rep = run_forked(["replay", "--no-model", str(noa)])  # the commands alone need no a (lead, no Ga)
    assert rep.code == 0 and "reproduces the logged v" in rep.out


def test_log_with_a_controller_and_no_reference_is_not_simulated_on_nan(rig_data, tmp_path):
    nou = _without(rig_data, LEAD_LOG, "u", tmp_path / "no_u.txt")
    other = str(rig_data / P_LOG)
    for argv in (["replay", str(nou)], ["replay", "--no-model", str(nou)], ["compare", str(nou)],
                 ["diagnose", str(nou), other]):
        line = one_line_refusal(run_forked(argv))
        assert f"{nou}: no 'u' column: " in line and "needs u" in line, line
        if argv[0] == "replay":
            assert "replaying its controller (lead)" in line


def test_log_that_is_not_a_regular_file_or_has_endless_lines_is_refused(tmp_path):
    from station.runlog import RunLogError, read_log

    fifo = tmp_path / "fifo.txt"
    os.mkfifo(fifo)
    for path, what in ((fifo, "FIFO"), (Path("/dev/zero"), "character device"), (tmp_path, "folder")):
        with pytest.raises(RunLogError, match=what):
            read_log(path)
    (tmp_path / "long.txt").write_text("x" * 3_000_000)
    with pytest.raises(RunLogError, match="line 1: longer than"):
        read_log(tmp_path / "long.txt")
    (tmp_path / "comments.txt").write_text("#x\n" * 5000 + "#t\tv\n0\t1\n")
    with pytest.raises(RunLogError, match="header lines"):
        read_log(tmp_path / "comments.txt")


def test_log_header_controller_of_high_order_is_refused_not_replayed(tmp_path):
    """Our header's controller spec goes through the same order bound as a compensator file."""
    import json

    from station.runlog import read_log
    from station.logged import LoggedRun

    src = tmp_path / "ok.tsv"
    assert run_forked(["step", "--duration", "0.1", "--out", str(src)], cwd=tmp_path).code == 0
    lines = src.read_text().split("\n")
    j = next(i for i, t in enumerate(lines) if t.startswith("# {"))
    meta = json.loads(lines[j][2:])
    meta["controller"]["gth"]["den_z"] = [1.0] + [0.0] * 5000
    lines[j] = "# " + json.dumps(meta)
    bad = tmp_path / "bad.tsv"
    bad.write_text("\n".join(lines))
    with pytest.raises(StationError, match=rf"{re.escape(str(bad))}: controller spec in log header: .*of order at most 20"):
        LoggedRun(read_log(bad)).controller
    line = one_line_refusal(run_forked(["replay", str(bad)]))
    assert str(bad) in line


@pytest.mark.parametrize("argv", [["step", "--model", "{long}"], ["step", "--model", "{long}.toml"],
                                  ["step", "--controller", "{long}.toml"], ["step", "--reference", "{long}"],
                                  ["step", "--port", "{long}"], ["replay", "{long}"],
                                  ["modes", "--params", "{long}.toml"], ["modes", "--params", "{long}"]])
def test_a_name_too_long_for_the_system_is_one_line(tmp_path, argv):
    """Found by tests/test_input_fuzz.py: a built-in name or path longer than the system's
    limit made Path.exists() raise (``OSError: File name too long``)."""
    long = "x" * 5000
    argv = [a.format(long=long) for a in argv]
    if argv[0] == "step":
        argv += ["--out", str(tmp_path / "r.tsv")]
    line = one_line_refusal(run_forked(argv, cwd=tmp_path))
    assert "xxxx" in line and "Traceback" not in line


def test_rig_header_filter_of_high_order_is_refused_with_its_line(rig_data, tmp_path):
    """A rig header's printed filter goes through the order bound of a compensator file (an
    order in the thousands made every replay of every row cost that much)."""
    lines = (rig_data / LEAD_LOG).read_text().split("\n")
    lines[1] = "#Gth num=[ " + " ".join(["0.001"] * 3000) + "]"
    lines[2] = "#Gth den=[ 1. " + " ".join(["0.0"] * 3000) + "]"
    bad = tmp_path / "order.txt"
    bad.write_text("\n".join(lines))
    line = one_line_refusal(run_forked(["replay", "--no-model", str(bad)]))
    assert f"{bad}: line 2: Gth: 3001 coefficients; a filter is of order at most 20" in line
