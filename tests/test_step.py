"""``station step`` end to end on the built-in simulated rig."""

import json
import subprocess
import sys

import numpy as np
import pytest

from station.cli import main
from station.experiment import run_step
from station.protocol import PROTOCOLS
from station.runlog import read_log


def test_p_step_shows_thesis_fem_overshoot_plus_one_sample_delay(tmp_path):
    # thesis FEM 38.20 % without delay; protocol v1's one sample of computational delay adds ~2 points
    out = tmp_path / "r.json"
    assert main(["step", "--controller", "p", "--amplitude", "50", "--out", str(tmp_path / "p.tsv"),
                 "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["metrics"]["overshoot_pct"] == pytest.approx(40.0, abs=2.0)
    assert result["timing"]["dropped"] == 0 and result["timing"]["late"] == 0
    assert set(result) >= {"log", "metrics", "timing"}
    assert set(result["timing"]) == {"p50_us", "p99_us", "max_us", "late", "dropped", "skipped", "max_lag_ms",
                                     "first_tick_s", "first_tick_cpu_s", "setup_s"}
    assert result["timing"]["skipped"] == result["outcome"]["skipped"] == 0  # lockstep: nothing ever waits
    assert 0 < result["timing"]["setup_s"] < result["timing"]["first_tick_s"]


@pytest.mark.parametrize("protocol", PROTOCOLS)
def test_default_step_logs_every_tick_with_alignment_1(tmp_path, protocol):
    report = run_step(protocol=protocol, out=tmp_path / "lead.tsv")
    assert report.result.ok, report.result.message
    log = read_log(tmp_path / "lead.tsv")
    d = log.data
    assert np.array_equal(d["n"], np.arange(1000))
    assert np.allclose(d["t"], d["n"] * 0.002)
    assert d["u"][9] == 0 and np.all(d["u"][10:] == 100)          # step at tick 10
    assert log.meta["alignment"] == 1 and log.meta["protocol"] == protocol
    assert log.meta["controller"]["kind"] == "lead"
    # replaying the logged controller on the logged sensors with d = 1 gives the logged v
    from station.control import make_controller
    ctrl = make_controller("lead")
    v = [0.0] + [ctrl.step(d["u"][k], d["theta"][k - 1], d["a"][k - 1])[0] for k in range(1, 1000)]
    assert np.max(np.abs(np.array(v) - d["v"])) < 1e-9
    if protocol == "v1":  # the device applied exactly what was sent, rounded
        assert np.array_equal(d["v_applied"], np.sign(d["v"]) * np.floor(np.abs(d["v"]) + 0.5))
    # lead step on the model (d = 1): the thesis FEM shows 18.85 %; ours ~19 %
    assert report.metrics.overshoot_pct == pytest.approx(19.0, abs=2.0)


def test_step_is_reproducible_for_a_seed(tmp_path):
    a = run_step(port="sim://?seed=7", controller="lead-accel", amplitude=200, out=tmp_path / "a.tsv")
    b = run_step(port="sim://?seed=7", controller="lead-accel", amplitude=200, out=tmp_path / "b.tsv")
    da, db = read_log(a.log_path).data, read_log(b.log_path).data
    assert np.array_equal(da["a"], db["a"]) and np.array_equal(da["theta"], db["theta"])
    assert np.any(da["a"] != 0)  # the accelerometer is live


def test_console_script_and_module_both_run(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "station", "step", "--duration", "0.2", "--out",
                           str(tmp_path / "s.tsv")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "overshoot" in proc.stdout and "latency p50" in proc.stdout and str(tmp_path / "s.tsv") in proc.stdout


def test_spawn_without_a_display_fails_before_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    log = tmp_path / "never.tsv"
    assert main(["step", "--spawn", "--out", str(log)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--spawn needs a display" in err and "--rrd" in err
    assert not log.exists()  # nothing started


def test_rrd_recording_holds_the_run(tmp_path):
    """The .rrd that --rrd writes holds the logged run itself (read back through rerun), not just bytes."""
    from tests.test_viz import _series

    rrd = tmp_path / "run.rrd"
    assert main(["step", "--duration", "0.3", "--rrd", str(rrd), "--out", str(tmp_path / "r.tsv")]) == 0
    d = read_log(tmp_path / "r.tsv").data
    assert d["n"].size == 150
    for entity, column in (("/theta/measured", "theta"), ("/a/measured", "a"), ("/v/command", "v"),
                           ("/theta/reference", "u")):
        samples, values = _series(rrd, entity)
        np.testing.assert_array_equal(samples, d["n"], err_msg=entity)
        np.testing.assert_array_equal(values, d[column], err_msg=entity)
    assert np.abs(d["theta"]).max() > 0  # a run that moved: the comparison is not of zeros


def test_swept_sine_reference_is_the_rig_law(tmp_path, rig_data):
    report = run_step(controller="p", kp=1.0, reference="swept-sine", amplitude=50, out=tmp_path / "sw.tsv")
    assert report.result.ok and report.metrics is None  # no step metrics for a sweep
    ours = read_log(tmp_path / "sw.tsv").data["u"]
    rig = read_log(rig_data / "swept_sine_kp_1_amp_50.txt").data["u"]
    assert np.array_equal(ours, rig)  # 22 s by default, trunc(50 sin(2π(t−1)²)) for 1 < t ≤ 21 s


def test_file_reference_replays_the_rig_pulse_test_open_loop(tmp_path, rig_data):
    src = rig_data / "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"
    report = run_step(controller="open-loop", reference=f"{src}:u", out=tmp_path / "ol.tsv")
    d = read_log(tmp_path / "ol.tsv").data
    assert report.result.ok and np.array_equal(d["u"], read_log(src).data["u"])
    assert np.array_equal(d["v"][1:], d["u"][1:])  # open loop: v[k] = u[k] (tick 0 outputs 0)
    assert np.array_equal(d["v_applied"], d["v"])


def test_a_step_taken_from_a_log_has_the_step_metrics_of_the_same_step_planned(tmp_path, rig_data):
    """A new user's contradiction: the rig's P step replayed as a reference printed no metrics,
    where `station replay` of its own log said 40 %. The metrics are the planned step's: the
    rig's reference is 50 counts from tick 50, so the same run planned gives the same numbers."""
    src = rig_data / "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    logged = run_step(controller="p", reference=f"{src}:u", out=tmp_path / "file.tsv")
    planned = run_step(controller="p", amplitude=50, step_tick=50, out=tmp_path / "plan.tsv")
    assert logged.metrics is not None and logged.metrics == planned.metrics
    assert logged.info == planned.info
    sweep = run_step(controller="p", kp=1.0, reference=f"{rig_data / 'swept_sine_kp_1_amp_50.txt'}:u",
                     out=tmp_path / "sweep.tsv", duration=2.0)
    assert sweep.result.ok and sweep.metrics is None  # not a step: no step metrics


def test_pulse_reference_and_bad_reference(tmp_path, capsys):
    report = run_step(controller="open-loop", reference="pulse", amplitude=80, duration=0.5, out=tmp_path / "p.tsv")
    u = read_log(report.log_path).data["u"]
    assert np.array_equal(np.flatnonzero(u), np.arange(10, 60)) and set(u[u != 0]) == {80.0}
    assert main(["step", "--reference", "triangle"]) == 2
    assert "expected one of step, pulse, swept-sine or FILE[:COLUMN]" in capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["--limit", "-5"], "argument --limit: -5 is out of range"),
    (["--controller", "p", "--kp", "nan"], "argument --kp: nan is not a finite number"),
    (["--duration", "0.001"], "argument --duration: 0.001 is out of range"),
    (["--controller", "no/such/missing.toml"], "missing.toml"),
    (["--controller", "open-loop", "--limit", "0"], "argument --limit: 0 is out of range"),
    (["--out", "/proc/no-such-dir/x.tsv"], "--out /proc/no-such-dir/x.tsv: its folder: /proc is not writable"),
    (["--duration", "0.1", "--json", "/proc/no-such-dir/r.json"], "--json /proc/no-such-dir/r.json"),
    (["--protocol", "legacy", "--duration", "70"], "at most 32767 ticks"),
])
def test_bad_options_are_one_line_errors(tmp_path, capsys, args, message):
    if "--out" not in args:
        args = args + ["--out", str(tmp_path / "x.tsv")]
    assert main(["step", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(("station: error: ", "station step: error: ")) and message in err, err
    assert err.count("\n") == 1, err


def test_legacy_lead_accel_settles_like_v1(tmp_path):
    # without zeroing, the -2 count offset fed through Ga drives θ to ~210 and never settles
    v1_run = run_step(controller="lead-accel", amplitude=200, out=tmp_path / "v1.tsv")
    legacy_run = run_step(protocol="legacy", controller="lead-accel", amplitude=200, out=tmp_path / "lg.tsv")
    theta = read_log(legacy_run.log_path).data["theta"]
    assert abs(theta[-50:].mean() - 200) < 1.5
    assert legacy_run.metrics.settling_time_s is not None
    assert legacy_run.metrics.overshoot_pct == pytest.approx(v1_run.metrics.overshoot_pct, abs=1.0)


# --- one plan for the command line and Python --------------------------------------------------

SHAPED = ('limit = 200\n[gth]\nnum = [2.0]\nden = [1.0]\ndomain = "z"\n'
          '[shaper]\ntimes = [0.0, 0.1]\namplitudes = [1.5, -0.5]\n')
"""A compensator whose reference shaper overshoots its reference by half (1.5 u, then u)."""


def _plan_inputs(root):
    """The files the refusal cases read: a model file, a reference log, an open-loop reference
    above the DAC's range, a compensator with a shaper."""
    from station.plant.model import load_model

    load_model().save(root / "m.toml")
    (root / "ref.tsv").write_text("t\tu\n0\t0\n0.002\t10\n0.004\t10\n")
    (root / "big.tsv").write_text("t\tu\n0\t0\n0.002\t300\n0.004\t300\n")
    (root / "shaped.toml").write_text(SHAPED)
    (root / "exists.tsv").write_text("keep me\n")


# (command-line options, run_step keywords, words of the one-line refusal); {d} is the folder
PLAN_REFUSALS = [
    (["--amplitude", "3000"], dict(amplitude=3000), "--amplitude 3000: the step would pass --soft-limit 2048"),
    (["--amplitude", "300", "--soft-limit", "300"], dict(amplitude=300, soft_limit=300), "--soft-limit 300"),
    (["--controller", "open-loop", "--amplitude", "300"], dict(controller="open-loop", amplitude=300),
     "--amplitude 300: open loop the reference is the command, at most 255 DAC counts"),
    (["--controller", "open-loop", "--reference", "{d}/big.tsv"], dict(controller="open-loop", reference="{d}/big.tsv"),
     "at most 255 DAC counts"),
    (["--controller", "{d}/shaped.toml", "--amplitude", "1500"], dict(controller="{d}/shaped.toml", amplitude=1500),
     "its reference shaper takes the step to 2250 counts (--amplitude 1500), past --soft-limit 2048"),
    (["--protocol", "legacy", "--duration", "70"], dict(protocol="legacy", duration=70),
     "--duration 70 s: the legacy protocol counts ticks in int16: at most 32767 ticks"),
    (["--port", "sim://?model={d}/m.toml", "--out", "{d}/m.toml", "--force"],
     dict(port="sim://?model={d}/m.toml", out="{d}/m.toml", force=True), "is an input of this command (--port's model)"),
    (["--model", "{d}/m.toml", "--out", "{d}/m.toml", "--force"], dict(model="{d}/m.toml", out="{d}/m.toml", force=True),
     "is an input of this command (--model)"),
    (["--model", "{d}/m.toml", "--json", "{d}/m.toml", "--force"], None, "--json {d}/m.toml: is an input"),
    (["--reference", "{d}/ref.tsv", "--out", "{d}/ref.tsv", "--force"],
     dict(reference="{d}/ref.tsv", out="{d}/ref.tsv", force=True), "is an input of this command (--reference)"),
    (["--out", "{d}/exists.tsv"], dict(out="{d}/exists.tsv"), "exists; use --force"),
    (["--kp", "3"], dict(kp=3), "--kp: the P gain applies to --controller p only, not lead"),
    (["--amplitude", "50", "--reference", "{d}/ref.tsv"], dict(amplitude=50, reference="{d}/ref.tsv"),
     "--amplitude: not with a file reference"),
    (["--step-time", "2.5"], dict(step_time=2.5), "--step-time 2.5 s: the step must start before the run ends (2 s)"),
    (["--reference", "swept-sine", "--step-time", "0.5"], dict(reference="swept-sine", step_time=0.5),
     "--step-time: not with the swept-sine reference"),
    (["--amplitude", "nan"], dict(amplitude=float("nan")), "nan is not a finite number"),
    (["--duration", "1e9"], dict(duration=1e9), "is out of range (expected range 0.004..8589934.59 s)"),
    (["--port", "/dev/no-such-port-7"], dict(port="/dev/no-such-port-7"), "no such device"),
    (["--model", "{d}/m.toml", "--port", "/dev/null"], dict(model="{d}/m.toml", port="/dev/null"),
     "--model: only for the simulated rig"),
]


def _fill(value, root):
    if isinstance(value, str):
        return value.replace("{d}", str(root))
    if isinstance(value, list):
        return [_fill(v, root) for v in value]
    if isinstance(value, dict):
        return {k: _fill(v, root) for k, v in value.items()}
    return value


@pytest.fixture
def no_port(monkeypatch):
    """Opening any port fails the test: a refused plan must not get that far."""
    import serial

    def refuse(*args, **kwargs):
        raise AssertionError("a port was opened")

    monkeypatch.setattr(serial, "serial_for_url", refuse)
    monkeypatch.setattr(serial, "Serial", refuse)


def _snapshot(root):
    return {p.relative_to(root): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("argv, kwargs, words", PLAN_REFUSALS, ids=[" ".join(c[0]) for c in PLAN_REFUSALS])
def test_the_plan_refuses_before_anything_starts_from_the_cli_and_from_python(argv, kwargs, words, tmp_path,
                                                                               monkeypatch, capsys, no_port):
    from station.errors import StationError

    monkeypatch.chdir(tmp_path)
    _plan_inputs(tmp_path)
    before = _snapshot(tmp_path)
    words = _fill(words, tmp_path)
    argv = _fill(argv, tmp_path)
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "new.tsv")]
    assert main(["step", "--quiet", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err, err
    assert _snapshot(tmp_path) == before and not (tmp_path / "runs").exists()
    if kwargs is None:
        return
    kwargs = {"out": tmp_path / "new.tsv", **_fill(kwargs, tmp_path)}
    with pytest.raises(StationError) as caught:
        run_step(**kwargs)
    assert words in str(caught.value) and "\n" not in str(caught.value), caught.value
    assert _snapshot(tmp_path) == before and not (tmp_path / "runs").exists()


def test_a_plan_is_run_as_planned_and_not_twice_over_its_log(tmp_path):
    from station.errors import StationError
    from station.plan import plan_step

    plan = plan_step(controller="p", amplitude=40, duration=0.3, step_time=0.05, out=tmp_path / "p.tsv",
                     figure=False, lean=False)
    assert (plan.step_tick, plan.n_ticks, plan.step_time) == (25, 150, 0.05)
    report = run_step(plan)
    log = read_log(report.log_path)
    assert report.result.ok and log.meta["reference"]["step_tick"] == 25
    assert np.flatnonzero(log.data["u"])[0] == 25 and log.data["n"].size == 150
    with pytest.raises(StationError, match="exists; use --force"):  # the first run's log is kept
        run_step(plan)
    with pytest.raises(StationError, match="a plan or its settings"):
        run_step(plan, amplitude=50)
    assert read_log(report.log_path).data["theta"].tolist() == log.data["theta"].tolist()


def test_the_clamp_in_force_is_the_headers_and_the_metrics(tmp_path):
    # a compensator file's own limit wins over the default 200: the header, the wire and the
    # time at the clamp all use 150
    path = tmp_path / "c.toml"
    path.write_text('limit = 150\n[gth]\nnum = [20.0]\nden = [1.0]\ndomain = "z"\n')
    report = run_step(controller=str(path), amplitude=100, duration=0.4, out=tmp_path / "r.tsv", figure=False,
                      lean=False)
    log = read_log(report.log_path)
    assert log.meta["limit"] == log.meta["controller"]["limit"] == 150.0
    v = log.data["v"]
    assert np.abs(v).max() == 150.0
    assert report.info.saturation_time_s == pytest.approx(np.count_nonzero(np.abs(v) >= 150) * 0.002)
    assert report.info.saturation_time_s > 0


def test_the_log_is_read_back_once(tmp_path, monkeypatch):
    import station.experiment as ex

    reads = []
    real = ex.read_log
    monkeypatch.setattr(ex, "read_log", lambda path: reads.append(path) or real(path))
    report = run_step(controller="p", amplitude=50, duration=0.3, out=tmp_path / "p.tsv", lean=False)
    assert reads == [tmp_path / "p.tsv"]
    assert report.metrics is not None and report.figure_path == tmp_path / "p.png" and report.figure_path.exists()


def test_a_run_logged_to_a_device_ends_with_its_report(capsys):
    # /dev/null cannot be read back: no metrics, no figure, and no error after a completed run
    assert main(["step", "--duration", "0.1", "--quiet", "--out", "/dev/null"]) == 0
    out = capsys.readouterr().out
    assert "run completed, 50 samples" in out and "overshoot" not in out and "figure" not in out


# --- what a step prints, and StepReport in a notebook ----------------------------------------------


def test_the_first_step_names_each_band_and_says_not_settled_once(tmp_path, capsys):
    # the README's first command: lead, 100 counts, 2 s; on tmm-fit it settles in neither band
    assert main(["step", "--quiet", "--out", str(tmp_path / "s.tsv")]) == 0
    out = capsys.readouterr().out
    assert out.count("not settled within the run") <= 1
    assert "settling (1 %)" in out and "settling (2 %)" in out
    assert "settling time" not in out and "2 % band" not in out  # no settling time without its band


@pytest.mark.parametrize("one, two, expect", [
    (None, None, ["settling (1 %) not settled within the run", "settling (2 %) not settled either"]),
    (None, 0.42, ["settling (1 %) not settled within the run", "settling (2 %) 0.420 s"]),
    (0.804, 0.5, ["settling (1 %) 0.804 s", "settling (2 %) 0.500 s"]),
    (0.804, None, ["settling (1 %) 0.804 s", "settling (2 %) not settled within the run"]),
])
def test_each_settling_time_is_named_by_its_band(tmp_path, one, two, expect):
    from dataclasses import replace

    from station.analysis.metrics import StepInfo, StepMetrics
    from station.experiment import format_report

    report = run_step(controller="p", amplitude=50, duration=0.2, out=tmp_path / "p.tsv", figure=False, lean=False)
    report.metrics = StepMetrics(19.0, one)
    report.info = replace(report.info or StepInfo(0.1, 0.2, None, 0.0, None), settling_time_2pct_s=two)
    text = format_report(report)
    for words in expect:
        assert words in text, text
    assert text.count("not settled within the run") == (one is None or two is None)


def test_step_report_repr_is_short_and_to_pandas_keeps_integers(tmp_path):
    report = run_step(controller="p", amplitude=50, duration=0.3, out=tmp_path / "p.tsv", figure=False, lean=False)
    text = repr(report)
    assert len(text) < 400 and "array" not in text and "\n" not in text, text
    assert str(tmp_path / "p.tsv") in text and "reason='completed'" in text and "overshoot_pct=" in text
    assert "latency_us=(p50 " in text
    df = report.to_pandas()
    assert {c: str(df[c].dtype) for c in ("n", "status", "v_applied", "theta", "t")} == {
        "n": "int64", "status": "int64", "v_applied": "int64", "theta": "float64", "t": "float64"}
    log = read_log(report.log_path)
    assert np.array_equal(df["n"].to_numpy(), log.data["n"]) and np.array_equal(df["v_applied"], log.data["v_applied"])
    legacy = run_step(protocol="legacy", controller="p", amplitude=50, duration=0.1, out=tmp_path / "l.tsv",
                      figure=False, lean=False)
    ldf = legacy.to_pandas()  # the legacy device reports no v_applied: NaN, so floats
    assert str(ldf["n"].dtype) == "int64" and str(ldf["v_applied"].dtype) == "float64" and ldf["v_applied"].isna().all()


@pytest.mark.parametrize("name", ["station.experiment.run_step", "station.plan.plan_step"])
def test_the_examples_run(name, tmp_path, monkeypatch):
    import doctest
    import importlib
    import io

    module, attr = name.rsplit(".", 1)
    func = getattr(importlib.import_module(module), attr)
    monkeypatch.chdir(tmp_path)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    out = io.StringIO()
    for test in doctest.DocTestFinder().find(func, attr, globs={}):
        runner.run(test, out=out.write)
    assert runner.tries >= 2 and runner.failures == 0, out.getvalue()
