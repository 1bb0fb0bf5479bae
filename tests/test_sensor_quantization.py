"""The sensors' quantization has one definition (station.rounding.sensor_count), halves away
from zero, and every simulated sensor uses it: the plant's Sensors and quantize, the
stand-in sensors, the compiled simulate kernel and its Python loop."""

import math

import numpy as np
import pytest

from station.plant import Sensors, quantize, simulate
from station.rounding import half_away, sensor_count, sensor_count_compiled
from station.sim.standin import RoundingSensors

HALVES = [0.5, 1.5, 2.5, 1023.5, 32767.5, 4503599627370495.5]
EDGES = [0.0, -0.0, 1e-300, -1e-300, 0.3, -0.3, 3.0, 1e15 + 0.5, 2.0**53 + 2, 1e300]
EDGES += [s * h for h in HALVES for s in (1.0, -1.0)]
EDGES += [s * np.nextafter(h, d) for h in HALVES for d in (0.0, math.inf) for s in (1.0, -1.0)]
EDGES = [float(x) for x in EDGES]

# the rule worked out by hand on the values the brief names
BY_HAND = [(0.5, 1.0), (-0.5, -1.0), (1.5, 2.0), (-1.5, -2.0), (2.5, 3.0), (-2.5, -3.0),
           (0.49999999999999994, 0.0), (-0.49999999999999994, 0.0), (0.5000000000000001, 1.0),
           (-0.5000000000000001, -1.0), (2.4999999999999996, 2.0), (-2.5000000000000004, -3.0),
           (-0.0, 0.0), (-0.3, 0.0), (1e300, 1e300), (-1e300, -1e300)]


@pytest.mark.parametrize("x, expected", BY_HAND)
def test_by_hand(x, expected):
    for f in (sensor_count, sensor_count_compiled):
        out = f(x)
        assert out == expected and math.copysign(1.0, out) == math.copysign(1.0, expected), (f, x, out)


@pytest.mark.parametrize("x", EDGES)
def test_python_and_compiled_agree_and_follow_half_away(x):
    out = sensor_count(x)
    twin = sensor_count_compiled(x)
    assert out == twin and math.copysign(1.0, out) == math.copysign(1.0, twin)
    assert out == half_away(x)
    assert out != 0.0 or math.copysign(1.0, out) == 1.0  # a zero reading has no sign


def test_non_finite_values_pass_through():
    assert sensor_count(math.inf) == math.inf and sensor_count_compiled(-math.inf) == -math.inf
    assert math.isnan(sensor_count(math.nan)) and math.isnan(sensor_count_compiled(math.nan))


@pytest.mark.parametrize("x", EDGES[:-1])  # 1e300 is no int a sensor reports
def test_every_python_sensor_reads_by_the_rule(x):
    expected = int(sensor_count(x))
    assert quantize(x) == expected
    assert Sensors(accel_noise_std=0.0).read(x, x) == (expected, expected)
    assert RoundingSensors(0, 0.0).read(x, x) == (expected, expected)


class _Echo:
    """A one-state plant whose outputs at tick k are exactly the command of tick k - 1
    (z <- 0·z + v, theta = a = Re(z)): it shows the kernel's quantization of any value."""

    dt = 0.002
    x = np.zeros(1)

    def modal_form(self):
        one = np.ones(1, complex)
        return np.zeros(1, complex), one, np.ones((2, 1), complex), np.eye(1, dtype=complex)


class _Unused:
    """A controller object that is not a Compensator: simulate runs its Python loop."""

    def reset(self):
        pass

    def step(self, u, theta, a):
        raise AssertionError("v_open is given: the controller is not stepped")


def test_the_simulate_kernel_and_its_python_loop_read_by_the_rule():
    xs = np.array(EDGES[:-1])
    expected = np.array([sensor_count(x) for x in xs])
    compiled = simulate(_Echo(), None, np.zeros(xs.size + 1), v_open=np.append(xs, 0.0))
    np.testing.assert_array_equal(compiled["theta"][1:], expected)
    np.testing.assert_array_equal(compiled["a"][1:], expected)
    assert not np.signbit(compiled["theta"][1:][expected == 0]).any()
    python = simulate(_Echo(), _Unused(), np.zeros(xs.size + 1), v_open=np.append(xs, 0.0))
    np.testing.assert_array_equal(python["theta"][1:], expected)
    np.testing.assert_array_equal(python["a"][1:], expected)
    assert not np.signbit(python["theta"][1:][expected == 0]).any()
