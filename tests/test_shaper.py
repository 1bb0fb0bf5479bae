"""The reference shaper: ZV/ZVD against an oscillator's own residual vibration, one shaping rule
for the loop, the compiled simulation and replay, and the compensator file's [shaper]."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal

from station.control import step_reference
from station.control.designs import controller_from_spec, read_compensator_file
from station.control.rerun import replay_commands
from station.control.shaper import ReferenceShaper, check_shaper, make_shaper, zv_shaper, zvd_shaper
from station.errors import StationError
from station.plant import load_model, simulate


def _residual(times, amps, f_hz, zeta, dt=1e-4):
    """Peak |y − 1| after the last impulse of a unit-gain second-order mode driven by the shaped
    step (scipy.signal.lsim: an integrator independent of the shaper's formulas)."""
    wn = 2 * math.pi * f_hz
    sys = scipy.signal.lti([wn ** 2], [1.0, 2 * zeta * wn, wn ** 2])
    t = np.arange(0.0, times[-1] + 3.0, dt)
    u = sum(a * (t >= ti - 1e-12) for ti, a in zip(times, amps))
    _, y, _ = scipy.signal.lsim(sys, u, t)
    return float(np.max(np.abs(y[t > times[-1] + dt] - 1.0)))


@pytest.mark.parametrize("f_hz, zeta", [(2.55, 0.0054), (2.55, 0.1), (18.0, 0.02)])
def test_zv_and_zvd_leave_no_residual_vibration(f_hz, zeta):
    unshaped = _residual([0.0], [1.0], f_hz, zeta)
    zv, zvd = zv_shaper(f_hz, zeta), zvd_shaper(f_hz, zeta)
    assert math.isclose(sum(zv.amplitudes), 1.0) and math.isclose(sum(zvd.amplitudes), 1.0)
    # what is left is lsim's grid (impulse times between its 0.1 ms samples)
    assert _residual(*zv, f_hz, zeta) < 5e-3 * unshaped
    assert _residual(*zvd, f_hz, zeta) < 5e-3 * unshaped


def test_zvd_is_less_sensitive_to_a_frequency_error_than_zv():
    f, zeta = 2.55, 0.0054
    for wrong in (0.9 * f, 1.1 * f):  # the shaper made for f, the mode at ±10 %
        assert _residual(*zvd_shaper(f, zeta), wrong, zeta) < 0.3 * _residual(*zv_shaper(f, zeta), wrong, zeta)


def test_zv_of_the_first_beam_mode_is_the_design_example():
    # DESIGN.md's example shaper: times [0, 0.196] s, half the period of the 2.55 Hz first mode
    assert zv_shaper(2.55, 0.0054).times[1] == pytest.approx(0.196, abs=5e-4)


@pytest.mark.parametrize("seed", range(40))
def test_step_and_apply_give_the_same_floats(seed):
    rng = np.random.default_rng(seed)
    delays = sorted(rng.choice(41, size=rng.integers(1, 6), replace=False).tolist())
    start = int(rng.integers(0, 4))
    amps = rng.normal(size=len(delays))
    amps[-1] = 1.0 - amps[:-1].sum()
    sh = ReferenceShaper(delays, amps)
    u = rng.normal(scale=100.0, size=120)
    whole = sh.apply(u, start=start)
    sh.reset()
    ticks = [sh.step(float(x)) for x in u[start:]]
    assert np.array_equal(whole[start:], np.array(ticks))  # bit for bit
    assert np.array_equal(whole[:start], u[:start])


def test_a_step_is_split_into_its_impulses():
    sh = make_shaper([0.0, 0.1], [0.25, 0.75], dt=0.002)
    r = sh.apply(step_reference(100.0, 200, at_tick=10))
    assert sh.delays == (0, 50)
    assert np.all(r[:10] == 0) and np.all(r[10:60] == 25.0) and np.all(r[60:] == 100.0)


@pytest.mark.parametrize("times, amps, words", [
    ([0.0, 0.2], [0.5, 0.4], "amplitudes: expected a sum of 1"),
    ([0.0, -0.1], [0.5, 0.5], "times[1]: expected increasing"),
    ([-0.1, 0.2], [0.5, 0.5], "times[0]: expected a time >= 0"),
    ([0.0, 0.2], [0.5], "amplitudes: 1 amplitudes for 2 times"),
    ([0.0, float("nan")], [0.5, 0.5], "times[1]: expected a finite number"),
    ([], [], "times: expected a list"),
    ([0.0, 20.0], [0.5, 0.5], "later than 10 s"),
])
def test_bad_shapers_are_one_line_naming_the_field(times, amps, words):
    with pytest.raises(StationError) as err:
        check_shaper(times, amps, "c.toml: [shaper]")
    assert words in str(err.value) and "c.toml: [shaper]" in str(err.value) and "\n" not in str(err.value)


def test_times_are_rounded_to_the_sample_grid_and_a_collision_is_refused():
    assert make_shaper([0.0, 0.1967], [0.5, 0.5]).delays == (0, 98)
    with pytest.raises(StationError, match=r"times\[1\].*same sample"):
        make_shaper([0.0, 0.0004], [0.5, 0.5])


LEAD = '[gth]\ndomain = "s"\nnum = [20.0, 628.3185307179587]\nden = [1.0, 125.66370614359172]\n'


def test_compensator_file_shaper_reads_writes_and_refuses(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(LEAD + "[shaper]\ntimes = [0.0, 0.196]\namplitudes = [0.52, 0.48]\n")
    cf = read_compensator_file(path)
    assert cf.shaper.times == (0.0, 0.196) and cf.shaper.amplitudes == (0.52, 0.48)
    again = tmp_path / "again.toml"
    again.write_text(cf.to_toml())
    back = read_compensator_file(again)
    assert back[1:] == cf[1:]  # name, stages, limit (none set), shaper
    for body, words in (("[shaper]\ntimes = [0.0, 0.2]\namplitudes = [0.5, 0.6]\n", "[shaper].amplitudes"),
                        ("[shaper]\ntimes = [0.0, 0.2]\n", "[shaper].amplitudes: missing"),
                        ("[shaper]\ntimes = [0.0, 0.2]\namplitudes = [0.5, 0.5]\nwidth = 1\n", "[shaper].width"),
                        ("shaper = 1\n", "[shaper]: expected a table")):
        path.write_text(LEAD + body if body.startswith("[") else body + LEAD)
        with pytest.raises(StationError) as err:
            read_compensator_file(path)
        assert words in str(err.value) and str(path) in str(err.value)


@pytest.mark.parametrize("alignment", [0, 1])
def test_loop_simulation_and_replay_shape_alike(tmp_path, alignment):
    path = tmp_path / "c.toml"
    path.write_text(LEAD + "[shaper]\ntimes = [0.0, 0.1, 0.196]\namplitudes = [0.3, 0.3, 0.4]\n")
    comp = read_compensator_file(path).compensator()
    model = load_model("rig")
    u = step_reference(100.0, 600, at_tick=10)
    compiled = simulate(model, comp, u, alignment=alignment, command="round")

    class Python(type(comp)):  # a subclass runs in the Python loop, through step()
        pass

    slow = read_compensator_file(path).compensator()
    slow.__class__ = Python
    python = simulate(model, slow, u, alignment=alignment, command="round")
    for key in ("theta", "a", "v", "theta_d_hat"):
        assert np.array_equal(compiled[key], python[key]), key
    assert np.array_equal(compiled.u, u)  # the log's u is the user's reference, not the shaped one
    v, hat = replay_commands(controller_from_spec(comp.spec), u, compiled.theta, compiled.a, alignment)
    assert np.array_equal(v, compiled.v) and np.array_equal(hat, compiled.theta_d_hat)
    unshaped = simulate(model, _unshaped(comp), u, alignment=alignment, command="round")
    assert not np.array_equal(compiled.theta, unshaped.theta)


def _unshaped(comp):
    spec = {k: v for k, v in comp.spec.items() if k != "shaper"}
    return controller_from_spec(spec)


def test_a_shaped_step_replays_bit_exact_from_its_log(tmp_path):
    from station.experiment import run_step
    from station.replay import replay

    path = tmp_path / "c.toml"
    path.write_text(LEAD + "[shaper]\ntimes = [0.0, 0.196]\namplitudes = [0.52, 0.48]\n")
    report = run_step(controller=str(path), amplitude=100, duration=0.8, out=tmp_path / "run.tsv", figure=False)
    assert report.result.ok
    rep = replay(tmp_path / "run.tsv", model=False)
    assert rep.max_abs_dv == 0.0
    assert rep.controller_spec["shaper"]["delays"] == [0, 98]


def test_readme_shaper_example_loads(tmp_path):
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "compensator-files.md").read_text()
    block = next(b for b in re.findall(r"```toml\n(.*?)```", page, re.S) if "[shaper]" in b)
    path = tmp_path / "c.toml"
    path.write_text(LEAD + block)
    comp = read_compensator_file(path).compensator()
    assert comp.shaper.delays == (0, 98) and comp.shaper.amplitudes == (0.52, 0.48)
