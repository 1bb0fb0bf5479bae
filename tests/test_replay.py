"""station.replay against the rig logs (DESIGN.md: the designs reproduce the logged v) and
against logs of the simulated plant with a known alignment."""

import argparse
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.control import Compensator, DiscreteTF, make_controller
from station.errors import StationError
from station.logged import LoggedRun
from station.protocol import PROTOCOLS
from station.control.rerun import detect_alignment, replay_commands
from station.logged import rig_controller
from station.replay import format_report, replay
from station.runlog import RunLogWriter, read_log
from station.runlog.timebase import restart_rows, run_start
from tests.rig_logs import ACCEL_LOG, LEAD_LOG, PULSE_LOG, P_LOG, SWEEP_LOG


@pytest.mark.parametrize("name, controller, kp", [
    (P_LOG, "p", 2.0), (LEAD_LOG, "lead", None), (ACCEL_LOG, "lead-accel", None), (SWEEP_LOG, "p", 1.0)])
def test_rig_closed_loop_logs_reproduce(rig_data, name, controller, kp):
    r = replay(rig_data / name, model=False)
    assert r.format == "rig"
    assert r.controller == controller
    if kp is not None:
        assert r.controller_spec["kp"] == kp
    assert r.alignment == 1
    assert r.max_abs_dv < 1e-6
    assert r.reproduced
    # the report names a P law by its gain (it printed "controller: p (named by the log)")
    line = next(x for x in format_report(r).splitlines() if x.startswith("  controller: "))
    assert line == ("  controller: " + (f"P, kp = {kp:g}" if kp is not None else controller) + " (named by the log)")


def test_ol_pulse_is_v_equals_u(rig_data):
    r = replay(rig_data / PULSE_LOG, model=False)
    assert r.controller == "open-loop" and r.alignment is None
    assert r.max_abs_dv == 0.0
    assert r.metrics is None
    assert any("v = u" in note for note in r.notes)


@pytest.mark.parametrize("name, overshoot, settling", [
    (P_LOG, 24.00, 1.250), (LEAD_LOG, 10.00, None), (ACCEL_LOG, 21.50, 0.608)])
def test_step_metrics_in_report(rig_data, name, overshoot, settling):
    m = replay(rig_data / name, model=False).to_json()["metrics"]
    assert round(m["overshoot_pct"], 2) == overshoot
    assert m["settling_thesis_s"] == (None if settling is None else pytest.approx(settling))


def test_sweep_has_no_step_metrics(rig_data):
    r = replay(rig_data / SWEEP_LOG, model=False)
    assert r.reference == {"kind": "other"} and r.metrics is None


def test_printed_ga_alone_is_not_enough(rig_data):
    """DESIGN.md: the header's 8-digit Ga replays the accel run only to ~0.03 counts,
    so replay must use the unrounded design; a perturbed header falls back to the print."""
    log = read_log(rig_data / ACCEL_LOG)
    d = log.data
    exact, notes = rig_controller(log.meta)
    assert exact.name == "lead-accel" and any("unrounded" in n for n in notes)
    # one coefficient off by 2 units in the 8th decimal: not the design any more
    other = dict(log.meta, Ga=dict(log.meta["Ga"], num=[log.meta["Ga"]["num"][0] + 2e-8] + log.meta["Ga"]["num"][1:]))
    ctrl, notes = rig_controller(other)
    assert ctrl.name == "rig-printed" and any("as printed" in n for n in notes)
    printed = Compensator(exact.gth, DiscreteTF(log.meta["Ga"]["num"], log.meta["Ga"]["den"]), limit=200.0)
    v, _ = replay_commands(printed, d["u"], d["theta"], d["a"], 1)
    assert np.max(np.abs(v - d["v"])) > 1e-3
    v, _ = replay_commands(exact, d["u"], d["theta"], d["a"], 1)
    assert np.max(np.abs(v - d["v"])) < 1e-6


def _simulated_log(path, kind, alignment, amplitude=100.0, meta_controller=True):
    """A station-format log of the FEM plant (station.plant.simulate) under `kind`."""
    import station.plant as plant_mod
    ctrl = make_controller(kind)
    u = np.zeros(600)
    u[10:] = amplitude
    plant = plant_mod.DiscretePlant()
    plant.reset()
    sim = plant_mod.simulate(plant, ctrl, u, alignment=alignment)
    meta = {"alignment": alignment, "dt": 0.002}
    if meta_controller:
        meta["controller"] = ctrl.spec
    with RunLogWriter(path, meta) as w:
        for k in range(u.size):
            w.append((sim["t"][k], k, sim["u"][k], sim["v"][k], sim["theta"][k], sim["a"][k],
                      sim["theta_d_hat"][k], sim["v"][k], 0, math.nan))  # no device: v acted unrounded
    return sim


@pytest.mark.parametrize("kind, alignment", [("p", 0), ("lead", 1), ("lead-accel", 0), ("lead-accel", 1)])
def test_our_logs_replay_and_alignment_is_detected(tmp_path, kind, alignment):
    path = tmp_path / "sim.tsv"
    _simulated_log(path, kind, alignment)
    r = replay(path, model=True)
    assert r.format == "station" and r.controller == kind
    assert r.alignment == alignment
    assert r.max_abs_dv < 1e-6
    # The model is the plant that made the log, run the same way: a perfect fit.
    assert r.fit_pct["theta"] == pytest.approx(100.0, abs=1e-9)
    assert r.fit_pct["accel"] == pytest.approx(100.0, abs=1e-9)


def test_log_without_controller_gets_it_inferred(tmp_path):
    path = tmp_path / "anon.tsv"
    _simulated_log(path, "lead", 1, meta_controller=False)
    r = replay(path)
    assert r.controller_source == "inferred" and r.alignment == 1 and r.max_abs_dv <= 1e-6
    lead = make_controller("lead")
    np.testing.assert_allclose(r.controller_spec["gth"]["num_z"], lead.gth.num, rtol=1e-9)
    np.testing.assert_allclose(r.controller_spec["gth"]["den_z"], lead.gth.den, rtol=1e-9)
    assert any("inferred from the data" in n for n in r.notes)
    # closed loop with the inferred law on the plant that made the log: a perfect fit
    assert r.fit_pct["theta"] == pytest.approx(100.0, abs=1e-6)


def test_log_with_accelerometer_feedback_and_no_controller_gets_gth_and_ga_inferred(tmp_path):
    from station.logged.controller import same_law

    path = tmp_path / "anon.tsv"
    _simulated_log(path, "lead-accel", 1, meta_controller=False)  # v depends on a too: not e -> v alone
    r = replay(path)
    assert r.controller_source == "inferred" and r.alignment == 1 and r.max_abs_dv <= 1e-6
    assert same_law(make_controller("lead-accel"), LoggedRun.from_path(path).controller)
    assert r.fit_pct["theta"] == pytest.approx(100.0, abs=1e-6)


class _Nonlinear:
    """v = sat(e + e·|e|/50): no linear law, with or without a."""

    spec = {"kind": "custom"}

    def reset(self):
        pass

    def step(self, u, theta, a):
        e = u - theta
        return max(-200.0, min(200.0, e + e * abs(e) / 50.0)), u


def test_log_without_an_inferable_controller_is_model_only(tmp_path):
    import station.plant as plant_mod

    u = np.zeros(600)
    u[10:] = 100.0
    sim = plant_mod.simulate(plant_mod.DiscretePlant(), _Nonlinear(), u, alignment=1)
    path = tmp_path / "anon.tsv"
    with RunLogWriter(path, {"alignment": 1, "dt": 0.002}) as w:
        for k in range(u.size):
            w.append((sim["t"][k], k, sim["u"][k], sim["v"][k], sim["theta"][k], sim["a"][k],
                      sim["theta_d_hat"][k], sim["v"][k], 0, math.nan))
    r = replay(path)
    assert r.controller is None and r.max_abs_dv is None and r.controller_source is None
    assert r.to_json()["controller_source"] is None
    assert any("none could be inferred" in n for n in r.notes)
    # open loop on the logged v reproduces the closed-loop run of the same plant exactly
    assert r.fit_pct["theta"] == pytest.approx(100.0, abs=1e-9)


def test_model_fit_on_rig_step_logs(rig_data):
    """The thesis's FEM predicts the rig's step responses well in theta (not perfectly)."""
    for name in (P_LOG, LEAD_LOG, ACCEL_LOG):
        fit = replay(rig_data / name).fit_pct
        assert 50.0 < fit["theta"] < 100.0, name
        assert fit["accel"] < fit["theta"], name  # noisy accelerometer, unmodelled friction


def _args(file, **kw):
    from station.commands import replay as cmd

    parser = argparse.ArgumentParser()
    cmd.configure(parser)
    argv = [str(file)]
    for key, value in kw.items():
        argv += [f"--{key}", str(value)]
    return cmd, parser.parse_args(argv)


def test_command_writes_json_and_rrd(rig_data, tmp_path, capsys):
    out, rrd = tmp_path / "r.json", tmp_path / "r.rrd"
    cmd, args = _args(rig_data / ACCEL_LOG, json=out, rrd=rrd)
    assert cmd.run(args) == 0
    text = capsys.readouterr().out
    assert "lead-accel" in text and "21.50 %" in text and "alignment d = 1" in text
    rep = json.loads(out.read_text())
    assert {"file", "format", "controller", "alignment", "samples", "max_abs_dv", "metrics", "model"} <= set(rep)
    assert rep["samples"] == 1000 and rep["alignment"] == 1 and rep["max_abs_dv"] < 1e-6
    assert set(rep["metrics"]) == {"overshoot_pct", "settling_thesis_s"}
    assert set(rep["model"]["fit_pct"]) == {"theta", "accel"}
    assert rrd.stat().st_size > 0


def test_command_exit_code_when_not_reproduced(rig_data, tmp_path, capsys):
    text = (rig_data / P_LOG).read_text().splitlines()
    parts = text[500].split("\t")
    parts[3] = str(float(parts[3]) + 1.0)  # tamper with one logged v
    text[500] = "\t".join(parts)
    bad = tmp_path / "tampered.txt"
    bad.write_text("\n".join(text) + "\n")
    cmd, args = _args(bad)
    args.model = False
    assert cmd.run(args) == 1
    assert "does NOT reproduce" in capsys.readouterr().out


def test_command_bad_file_is_a_station_error(tmp_path):
    cmd, args = _args(tmp_path / "missing.tsv")
    with pytest.raises(StationError, match="missing.tsv"):
        cmd.run(args)


def test_bad_element_count_is_a_station_error(rig_data):
    with pytest.raises(StationError, match="n_elements"):
        replay(rig_data / P_LOG, n_elements=500)


@pytest.mark.parametrize("protocol", PROTOCOLS)
@pytest.mark.parametrize("kind", ["p", "open-loop", "lead", "lead-accel"])
def test_loop_log_with_step_at_tick_0_replays_with_d1_and_the_model_is_the_loop(tmp_path, kind, protocol):
    """Row 0 of a d = 1 run: v[0] = 0 (the device's tick 0) and the controller is first
    stepped on sample 0 for v[1]. Replay and the model must follow the same convention,
    also when u[0] != 0 (a step at tick 0), and quantize the commands as the device did
    (v1 rounds, legacy truncates)."""
    from station.experiment import run_step

    rep = run_step(port="sim://?noise=0", protocol=protocol, controller=kind, amplitude=50.0, step_tick=0,
                   duration=0.6, out=tmp_path / "t0.tsv", lean=False)
    assert rep.result.ok, rep.result.message
    r = replay(tmp_path / "t0.tsv", model=True)
    assert r.log.data["u"][0] == 50.0 and r.log.data["v"][0] == 0.0
    assert r.reproduced, r.notes
    assert r.reference == {"kind": "step", "amplitude": 50.0, "tick": 0}
    if kind == "p":  # the same metrics as station step reported
        assert r.metrics == rep.metrics
    if kind == "p":
        assert r.alignment == 1
    # noise-free simulated rig: the model is the loop + device, exactly
    np.testing.assert_array_equal(r.prediction["v"], r.log.data["v"])
    np.testing.assert_array_equal(r.prediction["theta"], r.log.data["theta"])
    np.testing.assert_array_equal(r.prediction["a"], r.log.data["a"])


def test_rig_header_gain_that_is_not_a_number_names_file_and_line(tmp_path):
    path = tmp_path / "bad_kp.txt"
    path.write_text("#SLFR RTP PID_control_Test\n#kp = 2.0\n#ki = x1\n#t\tn\tu\tv\t$\\theta$\ta\n0\t0\t0\t0\t0\t0\n")
    with pytest.raises(StationError, match=rf"{path}: line 3: ki: expected a number, got 'x1'"):
        replay(path)


@settings(max_examples=40, deadline=None)
@given(order=st.integers(0, 3), d=st.integers(0, 1), seed=st.integers(0, 2**31 - 1),
       cuts=st.lists(st.tuples(st.integers(5, 360), st.integers(1, 30)), min_size=1, max_size=3))
def test_a_law_replayed_again_from_each_jump_of_n_reproduces_the_rows_left(order, d, seed, cuts):
    # A log of a linear law (order 0..3) with spans of rows deleted: replayed again from each
    # jump of n with its memory taken as logged, it gives every row it can judge as the whole
    # log had it (the independent truth: the whole log's own commands). Every cut ends at least
    # 10 rows before the log does: a cut at the end leaves no jump (CI drew (370, 30) of 400)
    rng = np.random.default_rng(seed)
    poles = rng.uniform(-0.9, 0.9, order)
    den = np.poly(poles) if order else np.array([1.0])
    num = rng.normal(0.0, 3.0, order + 1)
    law = Compensator(DiscreteTF(num, den), limit=None)
    n = 400
    u = np.where(np.arange(n) >= 10, 100.0, 0.0)
    theta = np.round(np.cumsum(rng.normal(0.0, 2.0, n)))
    v_whole, _ = replay_commands(law, u, theta, np.zeros(n), d)
    drop = np.zeros(n, dtype=bool)
    for start, width in cuts:
        drop[start:start + width] = True
    kept = np.flatnonzero(~drop)
    restarts = restart_rows(kept)
    assert len(restarts) >= 1
    fit = detect_alignment(law, u[kept], theta[kept], np.zeros(kept.size), v_whole[kept], (d,),
                           restarts=restarts)
    assert fit.max_abs_dv <= 1e-9 * max(1.0, float(np.max(np.abs(v_whole))))


@pytest.mark.parametrize("every, start, said", [(1, 0, "at tick 50"), (2, 0, "at tick 50 (row 25)"),
                                               (3, 1, "at tick 52 (row 17)")])
def test_the_steps_tick_is_the_devices_where_rows_skip_ticks(rig_data, tmp_path, every, start, said):
    """The P step (its u steps at tick 50) kept every k-th row, n as logged: the report's tick
    is n's, the row beside it (before: "at tick 25", the row, on the copy of every other row)."""
    lines = (rig_data / P_LOG).read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    path = tmp_path / "every.txt"
    path.write_text("\n".join(head + lines[len(head):][start::every]) + "\n")
    text = format_report(replay(path, model=False))
    assert f"  reference: step of 50 {said}\n" in text + "\n", text


def _rows_of(rig_data, name, first, rezero=False):
    """The rig's log from row ``first`` on: t and n as the loop counted them, or (``rezero``)
    t from 0 and n from 0, as the lab's ``_trunc`` copies renumbered them."""
    lines = (rig_data / name).read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln.split("\t") for ln in lines[len(head):]][first:]
    if rezero:
        t0 = float(rows[0][0])
        rows = [[f"{float(r[0]) - t0:.6g}", str(k)] + r[2:] for k, r in enumerate(rows)]
    return "\n".join(head + ["\t".join(r) for r in rows]) + "\n"


@pytest.mark.parametrize("first", [10, 30, 49])
def test_a_copy_cut_at_rest_with_its_clock_kept_settles_when_the_whole_run_does(rig_data, tmp_path, first):
    """The P step from row 30, t and n as logged (t = 0.06 s at n = 30): the settling time is
    from the run's t = 0, 1.250 s as on the whole log, and compare's step at 0.100 s (before:
    "settling (1 %) 1.190 s" beside "this log's step at 0.100 s", from a first row it called
    t = 0). A copy whose t and n were renumbered from 0 starts its own clock there."""
    whole = LoggedRun.from_path(rig_data / P_LOG).step_metrics()
    path = tmp_path / "kept.txt"
    path.write_text(_rows_of(rig_data, P_LOG, first))
    kept = LoggedRun.from_path(path)
    assert kept.step_metrics() == whole
    assert "settling (1 %) 1.250 s from t = 0" in format_report(replay(path, model=False))
    path.write_text(_rows_of(rig_data, P_LOG, first, rezero=True))
    renumbered = LoggedRun.from_path(path).step_metrics()
    assert renumbered.overshoot_pct == whole.overshoot_pct
    assert renumbered.settling_time_s == pytest.approx(whole.settling_time_s - first * 0.002)


def test_the_runs_start_is_said_by_t_and_n_together():
    n = np.arange(30, 40)
    assert run_start(n * 0.002, n, 0.002) == pytest.approx(0.06)         # a copy with its clock kept
    assert run_start((n - 30) * 0.002, n, 0.002) == 0.0                 # t re-zeroed: t's word
    assert run_start(1764072000.0 + n * 0.002, n, 0.002) == 0.0         # a host's wall clock
    assert run_start(np.arange(10) * 0.002, np.arange(10), 0.002) == 0.0
    assert run_start(n[::2] * 0.002, n[::2], 0.004) == pytest.approx(0.06)  # every other tick
    assert run_start([], [], 0.002) == 0.0


def test_a_copy_cut_after_its_step_says_u_from_the_first_row_not_a_step_there(rig_data, tmp_path):
    path = tmp_path / "moving.txt"
    path.write_text(_rows_of(rig_data, P_LOG, 80))
    text = format_report(replay(path, model=False))
    assert "  reference: u = 50 from the first row (tick 80): the step is at or before it" in text
    assert "step of 50 at tick 80" not in text


@pytest.mark.parametrize("level, mirror", [(20.0, False), (70.0, True), (50.0, True)])
def test_a_step_from_a_held_position_has_the_runs_metrics(rig_data, tmp_path, level, mirror):
    """The thesis's P step moved to start from a held position: u and θ shifted by 20 (a step
    of 50 from u = 20), or mirrored about 70 or 50 (u, θ to level − u, level − θ; v and a
    negated: a step down of 50, the last one back to 0). The P law holds on each as on the
    log, so the run is the same run: its overshoot and settling are the log's own (24.00 %,
    1.250 s), the model's fit too, and nothing is contradicted (θ starts where u holds it).
    Before, the reference was "other": no overshoot, no settling time, and "the encoder not
    zeroed" was said against it."""
    from station.compare import compare_run
    from station.plant import load_model

    src = rig_data / P_LOG
    lines = src.read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    rows = []
    for line in lines[len(head):]:
        t, n, u, v, theta, a = (float(x) for x in line.split("\t"))
        u, v, theta, a = (level - u, -v, level - theta, -a) if mirror else (u + level, v, theta + level, a)
        rows.append("\t".join(f"{x:g}" for x in (t, n, u, v, theta, a)))
    path = tmp_path / "held.txt"
    path.write_text("\n".join(head + rows) + "\n")
    run, clean = LoggedRun.from_path(path), LoggedRun.from_path(src)
    assert run.reference.is_step and run.reference.initial == level
    assert run.reference.height == (-50.0 if mirror else 50.0)
    assert run.step_metrics() == clean.step_metrics()
    assert run.audit.lines() == []
    text = format_report(replay(path))
    assert f"reference: step of {run.reference.height:g} from u = {level:g} at tick 50" in text, text
    assert "overshoot 24.00 %, settling (1 %) 1.250 s" in text and "theta 69.4 %" in text, text
    c = compare_run(path, load_model("tmm-fit"))
    assert c.rig == clean.step_metrics() and c.step_from == level and c.thesis_experiment is None
