"""The controller contract: one command guard for the loop and the simulation.

A command is clamped to ±limit and NaN is a controller fault, whether it goes to the
device (station.loop.run_loop) or to the simulated plant (station.plant.simulate for a
controller that is not exactly a Compensator / OpenLoop); a subclass that overrides
``step`` is simulated through its own ``step``.
"""

import math

import numpy as np
import pytest

from station.control import Compensator, ControllerFault, make_controller, step_reference
from station.control.contract import DAC_LIMIT, guard_command, wire_limit
from station.errors import StationError
from station.experiment import run_step
from station.plant import load_model, simulate
from station.runlog import read_log


@pytest.mark.parametrize("v, expected", [
    (0.0, 0.0), (-0.0, -0.0), (119.5, 119.5), (120.0, 120.0), (-120.0, -120.0), (120.00000000000001, 120.0),
    (1000.0, 120.0), (-1000.0, -120.0), (1e300, 120.0), (math.inf, 120.0), (-math.inf, -120.0),
])
def test_guard_clamps_to_the_limit(v, expected):
    out = guard_command(v, 120.0)
    assert out == expected and math.copysign(1.0, out) == math.copysign(1.0, expected)


def test_guard_passes_a_command_within_the_limit_unchanged():
    v = 12.345678901234567
    assert guard_command(v, 200.0) is v


def test_nan_is_a_controller_fault_naming_the_tick():
    with pytest.raises(ControllerFault, match=r"^controller returned NaN at tick 7$"):
        guard_command(math.nan, 200.0, 7)
    with pytest.raises(ControllerFault, match=r"^controller returned NaN$"):
        guard_command(math.nan, 200.0)
    assert issubclass(ControllerFault, StationError)


def test_wire_limit_is_the_controllers_own_then_the_option_then_the_dac():
    class Bare:
        pass

    class Own:
        def __init__(self, limit):
            self.limit = limit

    assert wire_limit(Own(120.0), 200.0) == 120.0  # a compensator file's limit wins over --limit
    assert wire_limit(Own(300.0)) == DAC_LIMIT == 255.0  # never beyond the DAC
    for bad in (None, math.inf, math.nan, 0.0, -5.0, "120"):
        assert wire_limit(Own(bad), 200.0) == 200.0
        assert wire_limit(Own(bad)) == DAC_LIMIT
    assert wire_limit(Bare(), 150.0) == 150.0 and wire_limit(Bare()) == DAC_LIMIT
    assert wire_limit(make_controller("lead"), 100.0) == 200.0


class _Halved(Compensator):
    """A Compensator whose step differs from its parent's: half the command."""

    def step(self, u, theta, a):
        v, thd = super().step(u, theta, a)
        return 0.5 * v, thd


class _Delegate:
    """Not a Compensator: the same law as _Halved through a plain object."""

    def __init__(self, inner):
        self.inner = inner
        self.limit = inner.limit

    def step(self, u, theta, a):
        v, thd = self.inner.step(u, theta, a)
        return 0.5 * v, thd

    def reset(self):
        self.inner.reset()


def test_a_compensator_subclass_is_simulated_with_its_own_step():
    lead = make_controller("lead")
    sub = _Halved(lead.gth, lead.ga, limit=lead.limit, name="halved")
    u = step_reference(100.0, 400, at_tick=10)
    model = load_model()
    halved = simulate(model, sub, u, command="round")
    plain = simulate(model, _Delegate(make_controller("lead")), u, command="round")
    parent = simulate(model, make_controller("lead"), u, command="round")
    np.testing.assert_array_equal(halved["v"], plain["v"])
    np.testing.assert_array_equal(halved["theta"], plain["theta"])
    assert not np.array_equal(halved["v"], parent["v"])


class _Wild:
    """A custom controller that always asks for 1000 DAC counts."""

    spec = {"kind": "test", "name": "wild"}

    def __init__(self, value=1000.0, limit=120.0, nan_on_call=None):
        self.value, self.limit, self.nan_on_call = value, limit, nan_on_call
        self.calls = 0

    def reset(self):
        self.calls = 0

    def step(self, u, theta, a):
        self.calls += 1
        if self.calls == self.nan_on_call:
            return math.nan, u
        return self.value, u


def test_a_custom_command_is_clamped_in_simulate_exactly_as_the_loop_clamps_it(tmp_path):
    path = tmp_path / "wild.tsv"
    report = run_step(port="sim://?noise=0", controller=_Wild(), amplitude=50, duration=0.2, out=path,
                      lean=False, figure=False)
    assert report.result.ok, report.result.message
    log = read_log(path)
    sim = simulate(load_model(), _Wild(), log.data["u"], alignment=1, command="round")
    assert set(log.data["v"][1:]) == {120.0}  # the loop's clamp: the controller's own limit
    np.testing.assert_array_equal(sim["v"], log.data["v"])
    np.testing.assert_array_equal(sim["theta"], log.data["theta"])


def test_without_its_own_limit_simulate_clamps_at_the_dac_range():
    run = simulate(load_model(), _Wild(value=-1e300, limit=None), np.zeros(50))
    assert set(run["v"][1:]) == {-DAC_LIMIT}


def test_nan_is_a_controller_fault_in_simulate_and_in_the_loop_alike(tmp_path):
    with pytest.raises(ControllerFault) as caught:
        simulate(load_model(), _Wild(value=10.0, nan_on_call=30), np.zeros(100))
    report = run_step(port="sim://?noise=0", controller=_Wild(value=10.0, nan_on_call=30), amplitude=50,
                      duration=0.2, out=tmp_path / "nan.tsv", lean=False, figure=False)
    assert report.result.reason == "controller-fault"
    assert str(caught.value) == "controller returned NaN at tick 29"  # sample 29 gave call 30
    assert report.result.message.startswith(str(caught.value))


@pytest.mark.parametrize("recursion", ["trunc", "round", "float-trunc", "float-round"])
@pytest.mark.parametrize("alignment", [0, 1])
def test_an_integer_recursion_runs_compiled_as_its_own_step_runs_it(recursion, alignment):
    # the lab's software stores the whole-count command and recurses on it (or recurses on
    # the float and sends its whole count); the compiled loop (store mode) and the
    # compensator's own step() (Python loop) must agree bit for bit
    from station.control import Compensator, DiscreteTF
    from station.control.reference import step_reference
    from station.plant import simulate
    from station.plant.model import load_model
    from tests.blind.rig import tustin

    num, den = tustin([3.0, 39.0], [1.0, 20.0], 0.002)
    make = lambda: Compensator(DiscreteTF(num, den), limit=200.0, recursion=recursion)  # noqa: E731
    model = load_model("rig")
    u = step_reference(100.0, 800, at_tick=10)
    compiled = simulate(model, make(), u, alignment=alignment, command="trunc")

    class Python(Compensator):  # a subclass runs in the Python loop, through step()
        pass

    slow = make()
    slow.__class__ = Python
    python = simulate(model, slow, u, alignment=alignment, command="trunc")
    for key in ("theta", "a", "v", "theta_d_hat"):
        assert np.array_equal(compiled[key], python[key]), key
    assert np.all(compiled.v == np.round(compiled.v))  # every command a whole count
    plain = simulate(model, Compensator(DiscreteTF(num, den), limit=200.0), u, alignment=alignment, command="trunc")
    assert not np.array_equal(plain.v, compiled.v)  # the float recursion is another law
